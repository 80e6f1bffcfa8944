//! Logging setup: tracing to stderr (the journal, under systemd).

use tracing_subscriber::EnvFilter;

/// Install the global subscriber. `RUST_LOG` wins over `default_level`.
/// Lines carry no timestamps under systemd (the journal adds its own).
pub fn init(default_level: &str) {
    let filter =
        EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new(default_level));
    let under_journal = std::env::var_os("JOURNAL_STREAM").is_some();
    let builder = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_target(false);
    let ansi = std::io::IsTerminal::is_terminal(&std::io::stderr());
    let builder = builder.with_ansi(ansi && !under_journal);
    let result = if under_journal {
        builder.without_time().try_init()
    } else {
        builder.try_init()
    };
    // A second init (tests) keeps the first subscriber.
    let _ = result;
}
