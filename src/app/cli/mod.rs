//! The `marionette` command line. Output meant for people or scripts goes to
//! stdout; logs go to stderr (the journal under systemd). Exit codes follow
//! sysexits.h, see `exit`. One file per command group:
//! `input` (recordings and panels), `motion` (BVH and libraries),
//! `eval`, `replay` (recordings through the whole pipeline) and
//! `kiosk` (the display).

#![allow(
    clippy::print_stderr,
    reason = "the command line says why it stopped on stderr"
)]

mod args;
mod eval;
mod input;
mod kiosk;
mod motion;
mod replay;

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::Parser;

use self::args::{Cli, Command, EvalCommand, EvalMethod, LibraryCommand};
use self::eval::{eval_actions, eval_pose, eval_pose_leave_one_out, pose_setup};
use self::input::{inspect, list_devices, replay};
use self::kiosk::{calibrate, list_outputs, run_kiosk};
use self::motion::{bake, contact_sheets, convert_bvh};
use self::replay::{demo, demo_library, export_bvh, replay_metrics, show};
use crate::app::config::{self, Config, ConfigError};
use crate::app::exit::{self, ExitStatus};
use crate::app::logging;
use crate::input::evemu::Recording;
use crate::platform::evdev as live;
use crate::platform::{record, uinput};

/// An error with the exit code it deserves.
struct Failure {
    code: u8,
    message: String,
}

/// Every typed error converts with the exit code [`ExitStatus`] gives it.
impl<E: ExitStatus + std::fmt::Display> From<E> for Failure {
    fn from(e: E) -> Self {
        Self::new(e.exit_code(), e)
    }
}

impl Failure {
    fn new(code: u8, message: impl std::fmt::Display) -> Self {
        Self {
            code,
            message: message.to_string(),
        }
    }
}

/// Parse the command line, load the configuration, run the command and
/// say how it ended.
pub fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let _ = e.print();
            return ExitCode::from(if e.use_stderr() {
                exit::USAGE
            } else {
                exit::OK
            });
        }
    };
    // `run` shows why it cannot start on the display before it exits.
    let kiosk_dri = match &cli.command {
        Command::Run { dri, .. } => Some(dri.clone()),
        _ => None,
    };
    let config = match load_config(cli.config.as_deref()) {
        Ok(c) => c,
        Err(e) => {
            logging::init("info");
            eprintln!("marionette: {}", shown(&e.to_string()));
            if let Some(dri) = &kiosk_dri {
                let defaults = Config::default();
                crate::app::fault::show(
                    &defaults.display,
                    dri,
                    exit::CONFIG,
                    &e.to_string(),
                    std::time::Duration::from_secs_f64(defaults.kiosk.error_screen_s),
                );
            }
            return ExitCode::from(exit::CONFIG);
        }
    };
    logging::init(&config.log.level);
    let config_path = cli
        .config
        .clone()
        .unwrap_or_else(|| PathBuf::from(config::DEFAULT_PATH));
    match run(cli.command, &config, &config_path) {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => {
            eprintln!("marionette: {}", shown(&f.message));
            if let (Some(dri), exit::CONFIG | exit::DATAERR) = (&kiosk_dri, f.code) {
                crate::app::fault::show(
                    &config.display,
                    dri,
                    f.code,
                    &f.message,
                    std::time::Duration::from_secs_f64(config.kiosk.error_screen_s),
                );
            }
            ExitCode::from(f.code)
        }
    }
}

/// The last message, as the terminal and the journal get it: its lines
/// kept, any other control character (a path given with an ESC in it)
/// escaped.
fn shown(message: &str) -> String {
    message
        .split('\n')
        .map(crate::reading::escape_controls)
        .collect::<Vec<_>>()
        .join("\n")
}

fn load_config(path: Option<&Path>) -> Result<Config, ConfigError> {
    match path {
        Some(p) => Config::load(p),
        None if Path::new(config::DEFAULT_PATH).exists() => {
            Config::load(Path::new(config::DEFAULT_PATH))
        }
        None => Ok(Config::default()),
    }
}

/// The output a command would write over one of its inputs (the file it
/// reads, or the configuration), refused before any work: exit 73.
fn output_is_input(command: &Command, config_path: &Path) -> Result<(), Failure> {
    let pairs: Vec<(&Path, &Path)> = match command {
        Command::Replay {
            file,
            metrics: Some(out),
            ..
        }
        | Command::ExportBvh { file, out, .. }
        | Command::ConvertBvh { file, out, .. } => vec![(file, out)],
        _ => Vec::new(),
    };
    let pairs = pairs
        .into_iter()
        .chain(command_outputs(command).map(|out| (config_path, out)));
    for (input, out) in pairs {
        if crate::output::same_file(input, out) {
            return Err(Failure::new(
                exit::CANTCREAT,
                format!(
                    "{} is the file being read ({}): writing it would replace it; give another output (nothing was done)",
                    out.display(),
                    input.display()
                ),
            ));
        }
    }
    Ok(())
}

/// The files a command writes that are named on its command line.
fn command_outputs(command: &Command) -> impl Iterator<Item = &Path> {
    let out: Option<&Path> = match command {
        Command::Replay {
            metrics: Some(out), ..
        }
        | Command::Replay {
            visits: Some(out), ..
        }
        | Command::ExportBvh { out, .. }
        | Command::ConvertBvh { out, .. }
        | Command::Record { out, .. } => Some(out),
        _ => None,
    };
    out.into_iter()
}

/// `marionette report`: report.json and report.html from the visits
/// record, and a line saying what they hold.
fn report(
    config: &Config,
    db: Option<std::path::PathBuf>,
    since: crate::app::report::Since,
    out: &Path,
) -> Result<(), Failure> {
    let db = db.unwrap_or_else(|| config.kiosk.visits.clone());
    if db.as_os_str().is_empty() {
        return Err(Failure::new(
            exit::USAGE,
            "no visits database: give --db PATH (kiosk.visits is empty)",
        ));
    }
    let now_ms = (crate::app::visits::unix_now() * 1e3) as i64;
    let r = crate::app::report::gather(&db, since, now_ms)?;
    let (json, page) = crate::app::report::write(&r, out).map_err(|e| {
        Failure::new(
            exit::CANTCREAT,
            format!("cannot write the report into {}: {e}", out.display()),
        )
    })?;
    writeln!(
        std::io::stdout(),
        "{} sessions, {} grabs, {} actions started ({} finished), {} near misses; integrity {}; written to {} and {}",
        r.sessions,
        r.grabs,
        r.actions_started,
        r.actions_finished,
        r.near_misses,
        r.integrity,
        page.display(),
        json.display()
    )
    .map_err(stdout_error)?;
    for a in &r.advice {
        writeln!(std::io::stdout(), "  {a}").map_err(stdout_error)?;
    }
    Ok(())
}

fn run(command: Command, config: &Config, config_path: &Path) -> Result<(), Failure> {
    output_is_input(&command, config_path)?;
    // A replay's `--library` stands for the configuration's.
    let replayed;
    let config = match &command {
        Command::Replay {
            library: Some(dir), ..
        }
        | Command::ExportBvh {
            library: Some(dir), ..
        } => {
            replayed = config.with_library(&chosen_library(config, Some(dir.clone()))?);
            &replayed
        }
        _ => config,
    };
    // `--mesh` stands for the configuration's character mesh.
    let meshed;
    let config = match &command {
        Command::Demo { mesh: Some(m), .. } | Command::Replay { mesh: Some(m), .. } => {
            meshed = config.with_mesh(m);
            &meshed
        }
        _ => config,
    };
    match command {
        Command::Demo {
            out,
            fps,
            library: Some(dir),
            ..
        } => demo_library(config, chosen_library(config, Some(dir))?, &out, fps),
        Command::Demo {
            out, fps, scene, ..
        } => demo(config, &out, fps, scene),
        Command::Inspect { file } => inspect(config, &file),
        Command::Replay {
            file,
            headless: true,
            out: Some(out),
            fps,
            max_frames,
            ..
        } => {
            let rec = Recording::read_file(&file)?;
            show(config, &rec, &out, fps, max_frames)
        }
        Command::Replay {
            file,
            metrics: Some(out),
            no_tracking,
            ..
        } => replay_metrics(config, &file, &out, no_tracking),
        Command::Replay {
            file,
            visits: Some(db),
            ..
        } => self::replay::replay_visits(config, &file, &db),
        Command::Report { db, since, out } => report(config, db, since, &out),
        Command::Replay { file, contacts, .. } => replay(config, &file, contacts),
        Command::ExportBvh { file, out, .. } => export_bvh(config, &file, &out),
        Command::Record {
            device,
            out,
            seconds,
        } => record::record(&config.input, device.as_deref(), &out, seconds).map_err(Failure::from),
        Command::Play { file, settle_ms } => {
            let rec = Recording::read_file(&file)?;
            uinput::play(&rec, std::time::Duration::from_millis(settle_ms)).map_err(Failure::from)
        }
        Command::ListDevices { json } => list_devices(config, json),
        Command::ListOutputs { json, dir } => list_outputs(&dir, json),
        Command::Run { dri, seconds } => run_kiosk(config, dri, seconds),
        Command::Calibrate {
            device,
            dri,
            timeout,
        } => calibrate(config, config_path, device, dri, timeout),
        Command::ConvertBvh {
            file,
            out,
            scale_to_m,
        } => convert_bvh(&file, &out, scale_to_m),
        Command::Bake { library, force } => bake(&chosen_library(config, library)?, force),
        Command::Library {
            what:
                LibraryCommand::Init {
                    src,
                    out,
                    force,
                    copy_clips,
                },
        } => motion::library_init(&src, &out, force, copy_clips),
        Command::Library {
            what: LibraryCommand::Check { dir, json, explain },
        } => motion::library_check(config, &dir, json, explain.as_deref()),
        Command::Eval {
            what:
                EvalCommand::Walk {
                    library,
                    paths,
                    seed,
                    count,
                    family,
                    save_paths,
                    layer,
                },
        } => eval::eval_walk(
            &chosen_library(config, library)?,
            (paths.as_deref(), save_paths.as_deref()),
            (seed, count, &family),
            layer.as_deref(),
        ),
        Command::Eval {
            what: EvalCommand::Character { mesh, library },
        } => eval::eval_character(&mesh, &chosen_library(config, library)?),
        Command::Eval {
            what:
                EvalCommand::Actions {
                    library,
                    test,
                    seed,
                    models_only,
                    explain,
                },
        } => eval_actions(
            config,
            &chosen_library(config, library)?,
            &test,
            seed,
            (models_only, explain.as_deref()),
        ),
        Command::Eval {
            what:
                EvalCommand::Pose {
                    library,
                    test,
                    leave_one_out,
                    sequence,
                    parts,
                    mode,
                    method,
                    frames,
                    blocks,
                    cells,
                },
        } => {
            if !matches!(method, EvalMethod::Model) && (blocks.is_some() || cells.is_some()) {
                return Err(Failure::new(
                    exit::USAGE,
                    "--blocks and --cells size the grid search of --method model; \
                     the other methods do not search the grid",
                ));
            }
            let library = chosen_library(config, library)?;
            let mut setup = pose_setup(parts, mode, method, frames);
            setup.blocks = blocks.map(|b| b as usize);
            setup.cells = cells.map(|c| c as usize);
            if leave_one_out {
                eval_pose_leave_one_out(&library, setup)
            } else {
                eval_pose(
                    &library,
                    &test,
                    setup,
                    sequence.then_some(config.control_settings().settle_s),
                )
            }
        }
        Command::AuthorLibrary { src, out } => {
            let n = crate::tools::author::author_library(&src, &out).map_err(|e| {
                let code = match &e {
                    crate::tools::author::compile::AuthorError::Write { .. } => exit::CANTCREAT,
                    crate::tools::author::compile::AuthorError::List { .. }
                    | crate::tools::author::compile::AuthorError::NoScores(_) => exit::NOINPUT,
                    _ => exit::DATAERR,
                };
                Failure::new(code, e)
            })?;
            writeln!(std::io::stdout(), "wrote {n} files to {}", out.display())
                .map_err(stdout_error)
        }
        Command::AuthorAbuse {
            out,
            seconds,
            seed,
            library,
        } => replay::author_abuse(
            config,
            &chosen_library(config, library)?,
            &out,
            seconds,
            seed,
        ),
        Command::ContactSheet {
            library,
            out,
            frames,
        } => contact_sheets(&chosen_library(config, library)?, &out, frames),
        Command::Watch { seconds } => live::watch(
            &config.input,
            config.display.picture(),
            seconds,
            &mut std::io::stdout().lock(),
        )
        .map_err(Failure::from),
    }
}

/// The library a command works on: `--library`, else the configuration's
/// `character.library`, else the shipped library; the log says which.
fn chosen_library(config: &Config, given: Option<PathBuf>) -> Result<PathBuf, Failure> {
    let flag = given.is_some();
    let (dir, from) = match given {
        Some(d) => (d, "--library"),
        None if !config.character.first().library.as_os_str().is_empty() => (
            config.library_dir(),
            "the configuration's character.library",
        ),
        None => (
            config.library_dir(),
            "the shipped library (no --library, none configured)",
        ),
    };
    tracing::info!(library = %dir.display(), "library from {from}");
    // A wrong flag is the command line's (66); a wrong key the file's (78).
    let (key, code) = if flag {
        ("--library", exit::NOINPUT)
    } else {
        ("character.library", exit::CONFIG)
    };
    match crate::app::character::library_problem(config, &dir, key) {
        Some(why) => Err(Failure::new(code, why)),
        None => Ok(dir),
    }
}

fn stdout_error(e: std::io::Error) -> Failure {
    Failure::new(exit::IOERR, format!("cannot write to stdout: {e}"))
}

fn print_json(value: &impl serde::Serialize) -> Result<(), Failure> {
    let json = serde_json::to_string_pretty(value).map_err(|e| Failure::new(exit::FAILURE, e))?;
    writeln!(std::io::stdout(), "{json}").map_err(stdout_error)
}

/// Write `items` to `out` as JSON lines, one object a line (atomically).
fn write_jsonl<T: serde::Serialize>(out: &Path, items: &[T]) -> Result<(), Failure> {
    let mut text = String::new();
    for t in items {
        text.push_str(&serde_json::to_string(t).map_err(|e| Failure::new(exit::FAILURE, e))?);
        text.push('\n');
    }
    write_atomically(out, &text)
}

/// Write `text` to `out` whole, over a regular file only
/// ([`crate::output::replace_file`]).
fn write_atomically(out: &Path, text: &str) -> Result<(), Failure> {
    crate::output::replace_file(out, text.as_bytes()).map_err(|e| {
        Failure::new(
            exit::CANTCREAT,
            format!("cannot write {}: {e}", out.display()),
        )
    })
}
