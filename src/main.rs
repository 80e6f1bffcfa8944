//! The `marionette` binary: the command line lives in `app::cli`.

fn main() -> std::process::ExitCode {
    marionette::app::cli::main()
}
