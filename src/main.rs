//! The `marionette` command line. Output meant for people or scripts goes to
//! stdout; logs go to stderr (the journal under systemd). Exit codes follow
//! sysexits.h, see `app::exit`.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use marionette::app::config::{self, Config, ConfigError};
use marionette::app::exit::{self, ExitStatus};
use marionette::app::logging;
use marionette::input::evemu::{EvemuError, Recording};
use marionette::input::pipeline;
use marionette::platform::evdev as live;
use marionette::platform::{record, uinput};

#[derive(Parser)]
#[command(
    name = "marionette",
    version,
    about = "Touch-table character puppeteering kiosk"
)]
struct Cli {
    /// Configuration file [default: /etc/marionette/marionette.toml if it
    /// exists, else built-in defaults]
    #[arg(long, global = true, value_name = "PATH")]
    config: Option<PathBuf>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Replay the bundled demo recording through the input stack and print
    /// what it does
    Demo {
        /// Where the frames, contact sheet and summary go.
        #[arg(long, default_value = "demo-out")]
        out: PathBuf,
        /// Frames written per second of recording.
        #[arg(long, default_value_t = 10.0)]
        fps: f64,
    },
    Inspect {
        /// An evemu recording, or a .bvh file
        file: PathBuf,
    },
    /// Replay a recording through the input stack
    Replay {
        file: PathBuf,
        /// Print every touch frame as a JSON line.
        #[arg(long)]
        contacts: bool,
        /// Run the whole pipeline into images (needs --out).
        #[arg(long, requires = "out")]
        headless: bool,
        /// Where the frames, contact sheet and summary go.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Frames written per second of recording.
        #[arg(long, default_value_t = 10.0)]
        fps: f64,
        /// Run the whole pipeline without rendering and write motion
        /// quality metrics (JSON) to this file.
        #[arg(long, value_name = "OUT.json", conflicts_with = "headless")]
        metrics: Option<PathBuf>,
        /// With --metrics: turn tracking control off, to compare.
        #[arg(long, requires = "metrics")]
        no_tracking: bool,
    },
    /// Write the motion the character performs for a recording as BVH
    /// (the library's skeleton, at its frame rate).
    ExportBvh {
        file: PathBuf,
        #[arg(long)]
        out: PathBuf,
    },
    Record {
        /// Device node [default: the first touchscreen found]
        #[arg(long)]
        device: Option<PathBuf>,
        /// Output file
        #[arg(long)]
        out: PathBuf,
        /// Stop after this many seconds
        #[arg(long)]
        seconds: Option<f64>,
    },
    /// Replay a recording through a virtual (uinput) device with its timing
    Play {
        /// An evemu recording
        file: PathBuf,
        /// Wait this long after creating the device before the first event,
        /// so that readers can open it
        #[arg(long, default_value_t = 500)]
        settle_ms: u64,
    },
    /// Read the touchscreens as the kiosk does and print what they report
    /// (devices added and removed, touches in screen pixels) as JSON lines
    Watch {
        /// Stop after this many seconds [default: until Ctrl-C]
        #[arg(long)]
        seconds: Option<f64>,
    },
    /// Rewrite a BVH file in metres with a conventional channel layout
    /// (a converter's T-pose frame dropped)
    ConvertBvh {
        /// Input BVH file
        file: PathBuf,
        /// Output BVH file
        #[arg(long)]
        out: PathBuf,
        /// File units to metres [default: detected]
        #[arg(long)]
        scale_to_m: Option<f64>,
    },
    /// Build the learned models of a library and cache them (run and demo
    /// use the cache when it matches the library, and bake when it does not)
    Bake {
        /// Library folder (with library.toml)
        #[arg(long, default_value = "assets/library")]
        library: PathBuf,
        /// Bake even if a matching cache exists
        #[arg(long)]
        force: bool,
    },
    /// Measure the character controllers on held-out motion capture
    Eval {
        #[command(subcommand)]
        what: EvalCommand,
    },
    /// Compile the default library's scores (keyframes) into BVH clips and
    /// library.toml
    AuthorLibrary {
        /// Folder of score files (*.toml)
        #[arg(long, default_value = "assets/library-src")]
        src: PathBuf,
        /// Output folder for the BVH files and library.toml
        #[arg(long, default_value = "assets/library")]
        out: PathBuf,
    },
    /// Draw each clip of a library as a contact sheet (stick figures, front
    /// and side views) and report foot sliding, floor contact and joint limits
    ContactSheet {
        /// Library folder (with library.toml)
        #[arg(long, default_value = "assets/library")]
        library: PathBuf,
        /// Output folder for the PNG files
        #[arg(long, default_value = "contact-sheets")]
        out: PathBuf,
        /// Frames per sheet
        #[arg(long, default_value_t = 10)]
        frames: usize,
    },
    /// List the input devices and what marionette makes of each
    ListDevices {
        /// One JSON object per line instead of a table
        #[arg(long)]
        json: bool,
    },
    /// The kiosk: fullscreen on the KMS output, reading every touchscreen,
    /// until SIGTERM/SIGINT (what systemd starts)
    Run {
        /// Where the DRM device nodes are
        #[arg(long, default_value = "/dev/dri")]
        dri: PathBuf,
        /// Stop after this many seconds (for tests)
        #[arg(long)]
        seconds: Option<f64>,
    },
    /// Calibrate a touchscreen on the KMS display: touch the targets shown;
    /// the device's calibration is written into the configuration file
    Calibrate {
        /// The touchscreen's name (see list-devices); needed when there
        /// are several
        #[arg(long)]
        device: Option<String>,
        /// Where the DRM device nodes are
        #[arg(long, default_value = "/dev/dri")]
        dri: PathBuf,
        /// Give up when a target is not touched within this many seconds
        #[arg(long, default_value_t = 60)]
        timeout: u64,
    },
    /// List the DRM/KMS outputs: cards, connectors, their state and modes
    ListOutputs {
        /// One JSON object per connector
        #[arg(long)]
        json: bool,
        /// Where the DRM device nodes are
        #[arg(long, default_value = "/dev/dri")]
        dir: PathBuf,
    },
}

#[derive(Subcommand)]
enum EvalCommand {
    /// Posing control: reconstruct held-out frames from N constrained parts
    /// and print one JSON object (mpjpe_cm, constraint_err_px,
    /// constraint_err_cm, ms_per_pose, poses; with --leave-one-out, their
    /// means and each clip's)
    Pose {
        /// Library folder (with library.toml)
        #[arg(long)]
        library: PathBuf,
        /// Held-out BVH clips of the library's skeleton
        #[arg(long, num_args = 1.., required_unless_present = "leave_one_out")]
        test: Vec<PathBuf>,
        /// Test each posing clip of the library in turn on a model of the
        /// others (instead of --test; --frames per clip)
        #[arg(long, conflicts_with = "test")]
        leave_one_out: bool,
        /// Constrained parts, first N of right_hand, left_hand, right_foot, left_foot, head
        #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u8).range(1..=5))]
        parts: u8,
        #[arg(long, value_enum, default_value = "touch")]
        mode: EvalMode,
        #[arg(long, value_enum, default_value = "model")]
        method: EvalMethod,
        /// Frames sampled evenly from the test clips (from each clip with
        /// --leave-one-out)
        #[arg(long, default_value_t = 200)]
        frames: usize,
        /// Blocks of cells the grid search looks into, the best first
        /// (--method model; 0: every cell) [default: the synthesis's, 16]
        #[arg(long, value_parser = clap::value_parser!(u32).range(0..=1_000_000))]
        blocks: Option<u32>,
        /// Cells whose samples the grid search scores (--method model)
        /// [default: the synthesis's, 16]
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
        cells: Option<u32>,
    },
    /// Action control: replay held-out clips' primary-part paths as drags
    /// through the controller (touch frames, as live input) and print one
    /// JSON object (trials, correct, wrong_action, missed,
    /// false_trigger_slow, decided_at)
    Actions {
        /// Library folder (with library.toml)
        #[arg(long)]
        library: PathBuf,
        /// Folder of held-out clips named <action>_*.bvh
        #[arg(long)]
        test: PathBuf,
        /// Seed of the noise and the slow drags
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Judge the drags with the action models alone (faster; no
        /// controller, no posing model)
        #[arg(long)]
        models_only: bool,
    },
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum EvalMode {
    Touch,
    Targets,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum EvalMethod {
    Model,
    Scan,
    Nearest,
    CcdRest,
}

/// An error with the exit code it deserves.
struct Failure {
    code: u8,
    message: String,
}

impl Failure {
    fn new(code: u8, message: impl std::fmt::Display) -> Self {
        Self {
            code,
            message: message.to_string(),
        }
    }
}

impl From<ConfigError> for Failure {
    fn from(e: ConfigError) -> Self {
        Self::new(exit::CONFIG, e)
    }
}

impl From<EvemuError> for Failure {
    fn from(e: EvemuError) -> Self {
        let code = match &e {
            EvemuError::Io { source, .. } if source.kind() == std::io::ErrorKind::NotFound => {
                exit::NOINPUT
            }
            EvemuError::Io { source, .. }
                if source.kind() == std::io::ErrorKind::PermissionDenied =>
            {
                exit::NOINPUT
            }
            EvemuError::Io { .. } => exit::IOERR,
            _ => exit::DATAERR,
        };
        Self::new(code, e)
    }
}

fn main() -> ExitCode {
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
    let config = match load_config(cli.config.as_deref()) {
        Ok(c) => c,
        Err(e) => {
            logging::init("info");
            eprintln!("marionette: {e}");
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
            eprintln!("marionette: {}", f.message);
            ExitCode::from(f.code)
        }
    }
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

fn run(command: Command, config: &Config, config_path: &Path) -> Result<(), Failure> {
    match command {
        Command::Demo { out, fps } => demo(config, &out, fps),
        Command::Inspect { file } => inspect(&file),
        Command::Replay {
            file,
            headless: true,
            out: Some(out),
            fps,
            ..
        } => {
            let rec = Recording::read_file(&file)?;
            show(config, &rec, &out, fps)
        }
        Command::Replay {
            file,
            metrics: Some(out),
            no_tracking,
            ..
        } => replay_metrics(config, &file, &out, no_tracking),
        Command::Replay { file, contacts, .. } => replay(config, &file, contacts),
        Command::ExportBvh { file, out } => export_bvh(config, &file, &out),
        Command::Record {
            device,
            out,
            seconds,
        } => record::record(&config.input, device.as_deref(), &out, seconds)
            .map_err(|e| Failure::new(e.exit_code(), e)),
        Command::Play { file, settle_ms } => {
            let rec = Recording::read_file(&file)?;
            uinput::play(&rec, std::time::Duration::from_millis(settle_ms))
                .map_err(|e| Failure::new(e.exit_code(), e))
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
        Command::Bake { library, force } => bake(&library, force),
        Command::Eval {
            what:
                EvalCommand::Actions {
                    library,
                    test,
                    seed,
                    models_only,
                },
        } => eval_actions(config, &library, &test, seed, models_only),
        Command::Eval {
            what:
                EvalCommand::Pose {
                    library,
                    test,
                    leave_one_out,
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
            let mut setup = pose_setup(parts, mode, method, frames);
            setup.blocks = blocks.map(|b| b as usize);
            setup.cells = cells.map(|c| c as usize);
            if leave_one_out {
                eval_pose_leave_one_out(&library, setup)
            } else {
                eval_pose(&library, &test, setup)
            }
        }
        Command::AuthorLibrary { src, out } => {
            let n = marionette::tools::author::author_library(&src, &out).map_err(|e| {
                let code = match &e {
                    marionette::tools::author::compile::AuthorError::Write { .. } => {
                        exit::CANTCREAT
                    }
                    marionette::tools::author::compile::AuthorError::List { .. } => exit::NOINPUT,
                    _ => exit::DATAERR,
                };
                Failure::new(code, e)
            })?;
            writeln!(std::io::stdout(), "wrote {n} files to {}", out.display())
                .map_err(stdout_error)
        }
        Command::ContactSheet {
            library,
            out,
            frames,
        } => contact_sheets(&library, &out, frames),
        Command::Watch { seconds } => live::watch(
            &config.input,
            config.display.picture(),
            seconds,
            &mut std::io::stdout().lock(),
        )
        .map_err(|e| Failure::new(e.exit_code(), e)),
    }
}

fn stdout_error(e: std::io::Error) -> Failure {
    Failure::new(exit::IOERR, format!("cannot write to stdout: {e}"))
}

fn inspect(file: &Path) -> Result<(), Failure> {
    if file
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("bvh"))
    {
        return inspect_bvh(file);
    }
    let rec = Recording::read_file(file)?;
    let (summary, _) = pipeline::summarize(&rec);
    let json = serde_json::to_string(&summary).map_err(|e| Failure::new(exit::FAILURE, e))?;
    writeln!(std::io::stdout(), "{json}").map_err(stdout_error)
}

/// What `inspect FILE.bvh` prints.
#[derive(serde::Serialize)]
struct BvhSummary {
    joints: usize,
    frames: usize,
    frame_time: f64,
    height_m: f64,
    scale_to_m: f64,
    roles: std::collections::BTreeMap<String, String>,
}

/// Read and import a BVH file, with exit codes for its errors.
fn read_clip(
    file: &Path,
    scale_to_m: Option<f64>,
) -> Result<(usize, marionette::character::motion::Clip), Failure> {
    read_clip_with(file, |_| scale_to_m)
}

fn read_clip_with(
    file: &Path,
    scale_to_m: impl FnOnce(&marionette::character::bvh::BvhFile) -> Option<f64>,
) -> Result<(usize, marionette::character::motion::Clip), Failure> {
    use marionette::character::bvh::{self, BvhError};
    use marionette::character::motion::{Clip, ImportSettings};
    let parsed = bvh::read_file(file).map_err(|e| {
        let code = match &e {
            BvhError::Io { source, .. } if source.kind() == std::io::ErrorKind::NotFound => {
                exit::NOINPUT
            }
            BvhError::Io { .. } => exit::IOERR,
            BvhError::Syntax { .. } => exit::DATAERR,
        };
        Failure::new(code, e)
    })?;
    let frames = parsed.frames.len();
    let settings = ImportSettings {
        scale_to_m: scale_to_m(&parsed),
        ..ImportSettings::default()
    };
    let clip = Clip::from_bvh(parsed, &settings)
        .map_err(|e| Failure::new(exit::DATAERR, format!("{}: {e}", file.display())))?;
    Ok((frames, clip))
}

fn convert_bvh(file: &Path, out: &Path, scale_to_m: Option<f64>) -> Result<(), Failure> {
    let (_, clip) = read_clip(file, scale_to_m)?;
    let text = marionette::character::bvh::write(
        &clip.skeleton,
        &clip.translates,
        &clip.frames,
        clip.frame_time,
    );
    std::fs::write(out, text).map_err(|e| {
        Failure::new(
            exit::CANTCREAT,
            format!("cannot write {}: {e}", out.display()),
        )
    })?;
    writeln!(
        std::io::stdout(),
        "wrote {} ({} frames, {} joints, unit {} m{})",
        out.display(),
        clip.frames.len(),
        clip.skeleton.len(),
        clip.scale_to_m,
        if clip.dropped_tpose {
            ", T-pose frame dropped"
        } else {
            ""
        }
    )
    .map_err(stdout_error)
}

/// Load a library and its posing model (from the cache when it matches).
fn load_model(
    library: &Path,
    force: bool,
) -> Result<
    (
        marionette::character::library::Library,
        marionette::control::posing::model::LearnedModel,
    ),
    Failure,
> {
    use marionette::app::cache::{self, Source};
    use marionette::character::library::Library;
    use std::io::IsTerminal;
    let lib = Library::load(library).map_err(|e| Failure::new(exit::DATAERR, e))?;
    let dir = cache::cache_dir();
    let tty = std::io::stderr().is_terminal();
    let mut last = -1i32;
    let mut progress = |f: f64| {
        let pct = (f * 100.0) as i32;
        if tty {
            eprint!("\rbaking the posing model: {pct:3}%");
        } else if pct / 25 != last / 25 {
            tracing::info!(percent = pct, "baking the posing model");
        }
        last = pct;
    };
    let (model, source) = cache::posing_model(&lib, &dir, force, &mut progress).map_err(|e| {
        Failure::new(
            exit::IOERR,
            format!("cannot bake or cache {}: {e}", library.display()),
        )
    })?;
    if tty && last >= 0 {
        eprintln!();
    }
    match source {
        Source::Cache(path) => {
            tracing::info!(cache = %path.display(), samples = model.samples.len(), "posing model loaded from the cache")
        }
        Source::Baked { reason } => {
            tracing::info!(%reason, samples = model.samples.len(), cells = model.cells.len(), cache = %dir.display(), "posing model baked")
        }
    }
    Ok((lib, model))
}

fn eval_actions(
    config: &Config,
    library: &Path,
    test_dir: &Path,
    seed: u64,
    models_only: bool,
) -> Result<(), Failure> {
    use marionette::character::library::Library;
    use marionette::control::action::model::ActionModel;
    use marionette::tools::eval::actions as eval;
    let lib = Library::load(library).map_err(|e| Failure::new(exit::DATAERR, e))?;
    let actions: Vec<ActionModel> = lib
        .actions
        .iter()
        .map(|a| ActionModel::build(&lib, a))
        .collect();
    let mut files: Vec<PathBuf> = std::fs::read_dir(test_dir)
        .map_err(|e| {
            Failure::new(
                exit::NOINPUT,
                format!("cannot list {}: {e}", test_dir.display()),
            )
        })?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x.eq_ignore_ascii_case("bvh")))
        .collect();
    files.sort();
    let mut clips = Vec::new();
    for f in &files {
        let stem = f
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let Some(action) = actions
            .iter()
            .map(|a| a.def.name.clone())
            .filter(|n| stem.starts_with(&format!("{n}_")))
            .max_by_key(String::len)
        else {
            tracing::warn!(file = %f.display(), "not named after an action of the library (<action>_*.bvh); skipped");
            continue;
        };
        // Any rig in any unit will do: only the primary part's path is
        // used, in metres as its bone lengths say.
        let (_, clip) = read_clip(f, None)?;
        clips.push((action, clip));
    }
    let tests: Vec<(String, &marionette::character::motion::Clip)> =
        clips.iter().map(|(a, c)| (a.clone(), c)).collect();
    let result = if models_only {
        eval::eval_actions(&actions, &tests, &config.action.rule(), seed)
    } else {
        use marionette::control::controller::Character;
        let (lib, model) = load_model(library, false)?;
        let ch = std::sync::Arc::new(Character::new(lib, model));
        let settings = config.control_settings();
        eval::eval_with(&eval::with_primary(&actions, &tests), seed, &mut |d| {
            marionette::tools::eval::live::judge(&ch, &settings, d)
        })
    };
    let json = serde_json::to_string(&result).map_err(|e| Failure::new(exit::FAILURE, e))?;
    writeln!(std::io::stdout(), "{json}").map_err(stdout_error)
}

fn bake(library: &Path, force: bool) -> Result<(), Failure> {
    let started = std::time::Instant::now();
    let (lib, model) = load_model(library, force)?;
    writeln!(
        std::io::stdout(),
        "{}: posing model of {} samples from {} clips in {} cells ({:.1} s)",
        lib.dir.display(),
        model.samples.len(),
        lib.clips.len(),
        model.cells.len(),
        started.elapsed().as_secs_f64()
    )
    .map_err(stdout_error)
}

fn pose_setup(
    parts: u8,
    mode: EvalMode,
    method: EvalMethod,
    frames: usize,
) -> marionette::tools::eval::posing::EvalSetup {
    use marionette::tools::eval::posing as eval;
    eval::EvalSetup {
        parts: usize::from(parts),
        mode: match mode {
            EvalMode::Touch => eval::Mode::Touch,
            EvalMode::Targets => eval::Mode::Targets,
        },
        method: match method {
            EvalMethod::Model => eval::Method::Model,
            EvalMethod::Scan => eval::Method::Scan,
            EvalMethod::Nearest => eval::Method::Nearest,
            EvalMethod::CcdRest => eval::Method::CcdRest,
        },
        frames,
        blocks: None,
        cells: None,
    }
}

fn print_json(value: &impl serde::Serialize) -> Result<(), Failure> {
    let json = serde_json::to_string(value).map_err(|e| Failure::new(exit::FAILURE, e))?;
    writeln!(std::io::stdout(), "{json}").map_err(stdout_error)
}

fn eval_pose(
    library: &Path,
    tests: &[PathBuf],
    setup: marionette::tools::eval::posing::EvalSetup,
) -> Result<(), Failure> {
    use marionette::tools::eval::posing as eval;
    let (lib, learned) = load_model(library, false)?;
    let mut clips = Vec::new();
    for t in tests {
        let (_, clip) = read_clip(t, lib.clips.values().next().map(|c| c.scale_to_m))?;
        if let Some(why) =
            marionette::character::library::hierarchy_difference(&lib.skeleton, &clip.skeleton)
        {
            return Err(Failure::new(
                exit::DATAERR,
                format!("{}: not the library's skeleton ({why})", t.display()),
            ));
        }
        clips.push(clip);
    }
    if learned.samples.is_empty() {
        return Err(Failure::new(
            exit::DATAERR,
            format!("{}: the library has no posing samples", library.display()),
        ));
    }
    let rest = lib
        .clips
        .get(&lib.posing[0])
        .or_else(|| lib.clips.values().next())
        .expect("library has clips");
    let refs: Vec<&marionette::character::motion::Clip> = clips.iter().collect();
    print_json(&eval::eval_pose(
        &lib.skeleton,
        &learned,
        rest,
        &refs,
        setup,
    ))
}

fn eval_pose_leave_one_out(
    library: &Path,
    setup: marionette::tools::eval::posing::EvalSetup,
) -> Result<(), Failure> {
    use marionette::character::library::Library;
    use marionette::tools::eval::posing as eval;
    let lib = Library::load(library).map_err(|e| Failure::new(exit::DATAERR, e))?;
    let mut progress = |done: usize, of: usize| {
        tracing::info!(done, of, "leave one out: clips tested");
    };
    let result = eval::leave_one_out(&lib, setup, &mut progress).ok_or_else(|| {
        Failure::new(
            exit::DATAERR,
            format!(
                "{}: leaving one clip out needs at least two posing clips, the library has {}",
                library.display(),
                lib.posing.len()
            ),
        )
    })?;
    print_json(&result)
}

fn inspect_bvh(file: &Path) -> Result<(), Failure> {
    let (frames, clip) = read_clip(file, None)?;
    let summary = BvhSummary {
        joints: clip.skeleton.len(),
        frames,
        frame_time: clip.frame_time,
        height_m: (clip.height_m * 1e4).round() / 1e4,
        scale_to_m: clip.scale_to_m,
        roles: clip.roles.names(&clip.skeleton),
    };
    let json = serde_json::to_string(&summary).map_err(|e| Failure::new(exit::FAILURE, e))?;
    writeln!(std::io::stdout(), "{json}").map_err(stdout_error)
}

fn replay(config: &Config, file: &Path, contacts: bool) -> Result<(), Failure> {
    let rec = Recording::read_file(file)?;
    let frames = pipeline::replay(&rec, &config.input, config.display.picture())
        .map_err(|e| Failure::new(exit::DATAERR, e))?;
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    if contacts {
        for f in &frames {
            let line = serde_json::to_string(f).map_err(|e| Failure::new(exit::FAILURE, e))?;
            writeln!(out, "{line}").map_err(stdout_error)?;
        }
    } else {
        let (summary, _) = pipeline::summarize(&rec);
        writeln!(
            out,
            "{}: {} frames, {} touch frames, {} finger contacts (at most {} at once), {:.1} s",
            summary.device,
            summary.frames,
            frames.len(),
            summary.touch_sequences,
            summary.max_contacts,
            summary.duration_s
        )
        .map_err(stdout_error)?;
    }
    out.flush().map_err(stdout_error)
}

/// The character: the configured library, its posing model (baked or from
/// the cache) and its action models.
fn character(
    config: &Config,
) -> Result<std::sync::Arc<marionette::control::controller::Character>, Failure> {
    let dir = config.library_dir();
    let (lib, model) = load_model(&dir, false)?;
    Ok(std::sync::Arc::new(
        marionette::control::controller::Character::new(lib, model),
    ))
}

/// `marionette calibrate`: targets on the display, the solved matrix into
/// the configuration file.
fn calibrate(
    config: &Config,
    config_path: &Path,
    device: Option<String>,
    dri: PathBuf,
    timeout: u64,
) -> Result<(), Failure> {
    use marionette::app::calibrate;
    let opts = calibrate::CalibrateOptions {
        dri_dir: dri,
        device,
        config_path: config_path.to_owned(),
        touch_timeout: std::time::Duration::from_secs(timeout.max(1)),
    };
    let done = calibrate::calibrate(config, &opts).map_err(|e| Failure::new(e.exit_code(), e))?;
    let m = done.solution.matrix.0;
    writeln!(
        std::io::stdout(),
        "{}: calibration [{:.6}, {:.6}, {:.6}, {:.6}, {:.6}, {:.6}]; fit {:.1} px, check point off by {:.1} px; written to {}{}",
        done.device,
        m[0],
        m[1],
        m[2],
        m[3],
        m[4],
        m[5],
        done.solution.rms_px,
        done.solution.check_error_px,
        done.written.display(),
        done.backup
            .map(|b| format!(" (the old file kept as {})", b.display()))
            .unwrap_or_default()
    )
    .map_err(stdout_error)
}

/// `marionette run`: the kiosk.
fn run_kiosk(config: &Config, dri: PathBuf, seconds: Option<f64>) -> Result<(), Failure> {
    use marionette::app::run;
    let ch = character(config)?;
    let opts = run::RunOptions {
        dri_dir: dri,
        seconds,
        ..run::RunOptions::default()
    };
    run::run(ch, config, &opts)
        .map(|_| ())
        .map_err(|e| Failure::new(e.exit_code(), e))
}

/// A recording through the whole pipeline into images.
fn show(config: &Config, rec: &Recording, out: &Path, fps: f64) -> Result<(), Failure> {
    use marionette::app::headless;
    let ch = character(config)?;
    let frames = pipeline::replay(rec, &config.input, config.display.picture())
        .map_err(|e| Failure::new(exit::DATAERR, e))?;
    let opts = headless::Options {
        out: Some(out.to_owned()),
        fps,
        until: Some(pipeline::summarize(rec).0.duration_s),
        ..headless::Options::default()
    };
    let summary =
        headless::run(ch, config, frames, &opts).map_err(|e| Failure::new(e.exit_code(), e))?;
    writeln!(std::io::stdout(), "{summary}").map_err(stdout_error)
}

fn demo(config: &Config, out_dir: &Path, fps: f64) -> Result<(), Failure> {
    // The recording is built into the binary: the demo works from anywhere.
    let rec = Recording::parse(DEMO_RECORDING, Path::new("assets/recordings/demo.evemu"))?;
    let (summary, _) = pipeline::summarize(&rec);
    writeln!(
        std::io::stdout(),
        "demo: assets/recordings/demo.evemu ({:.1} s, {} finger contacts)",
        summary.duration_s,
        summary.touch_sequences
    )
    .map_err(stdout_error)?;
    show(config, &rec, out_dir, fps)
}

/// A recording's postures, the controller stepped at `tick_hz` (0: the
/// library's frame rate) up to the recording's end, without rendering.
fn replay_poses(
    config: &Config,
    file: &Path,
    tick_hz: f64,
    tracking: bool,
) -> Result<
    (
        std::sync::Arc<marionette::control::controller::Character>,
        marionette::app::headless::Summary,
        f64,
    ),
    Failure,
> {
    use marionette::app::headless;
    let rec = Recording::read_file(file)?;
    let ch = character(config)?;
    let frames = pipeline::replay(&rec, &config.input, config.display.picture())
        .map_err(|e| Failure::new(exit::DATAERR, e))?;
    let tick_hz = if tick_hz > 0.0 {
        tick_hz
    } else {
        1.0 / ch
            .lib
            .clips
            .values()
            .next()
            .map_or(1.0 / 30.0, |c| c.frame_time)
    };
    let opts = headless::Options {
        tick_hz,
        keep_poses: true,
        until: Some(pipeline::summarize(&rec).0.duration_s),
        tracking,
        ..headless::Options::default()
    };
    let summary = headless::run(ch.clone(), config, frames, &opts)
        .map_err(|e| Failure::new(e.exit_code(), e))?;
    Ok((ch, summary, tick_hz))
}

/// Write `text` to `out` through a temporary file renamed into place.
fn write_atomically(out: &Path, text: &str) -> Result<(), Failure> {
    let mut tmp = out.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    std::fs::write(&tmp, text)
        .and_then(|()| std::fs::rename(&tmp, out))
        .map_err(|e| {
            Failure::new(
                exit::CANTCREAT,
                format!("cannot write {}: {e}", out.display()),
            )
        })
}

fn replay_metrics(
    config: &Config,
    file: &Path,
    out: &Path,
    no_tracking: bool,
) -> Result<(), Failure> {
    let (ch, summary, tick_hz) = replay_poses(config, file, 30.0, !no_tracking)?;
    let m = marionette::tools::metrics::measure(
        &ch.lib.skeleton,
        &ch.roles,
        &summary.poses,
        1.0 / tick_hz,
    );
    let mut json = serde_json::to_value(&m).map_err(|e| Failure::new(exit::FAILURE, e))?;
    json["tracking"] = serde_json::Value::Bool(!no_tracking);
    json["actions"] = summary
        .actions
        .iter()
        .map(|a| {
            serde_json::json!({
                "name": a.action,
                "start_s": a.started_s,
                "end_s": a.ended_s,
                "outcome": a.outcome,
            })
        })
        .collect();
    let text = serde_json::to_string_pretty(&json).map_err(|e| Failure::new(exit::FAILURE, e))?;
    write_atomically(out, &(text + "\n"))?;
    writeln!(
        std::io::stdout(),
        "{} frames, {} with NaN, largest joint speed jump {:.2} rad/s ({}; {} pops over {} rad/s), foot skate {:.2} mm/frame (max {:.2}, {}), ground penetration {:.1} mm ({}), {} actions; written to {}",
        m.frames,
        m.nan_frames,
        m.max_joint_speed_jump_rad_s,
        m.worst_jump,
        m.pops,
        marionette::tools::metrics::POP_RAD_S,
        m.foot_skate_mm_per_frame,
        m.foot_skate_max_mm,
        m.worst_skate,
        m.ground_penetration_mm,
        m.worst_penetration,
        summary.actions.len(),
        out.display()
    )
    .map_err(stdout_error)
}

fn export_bvh(config: &Config, file: &Path, out: &Path) -> Result<(), Failure> {
    let (ch, summary, tick_hz) = replay_poses(config, file, 0.0, true)?;
    let translates: Vec<bool> = (0..ch.lib.skeleton.len()).map(|j| j == 0).collect();
    let text = marionette::character::bvh::write(
        &ch.lib.skeleton,
        &translates,
        &summary.poses,
        1.0 / tick_hz,
    );
    write_atomically(out, &text)?;
    writeln!(
        std::io::stdout(),
        "wrote {} frames ({:.1} s at {:.0} fps, {} actions) to {}",
        summary.poses.len(),
        summary.duration_s,
        tick_hz,
        summary.actions.len(),
        out.display()
    )
    .map_err(stdout_error)
}

fn contact_sheets(library: &Path, out: &Path, frames: usize) -> Result<(), Failure> {
    use marionette::character::library::Library;
    use marionette::tools::{checks, sheet};
    let lib = Library::load(library).map_err(|e| Failure::new(exit::DATAERR, e))?;
    std::fs::create_dir_all(out).map_err(|e| {
        Failure::new(
            exit::CANTCREAT,
            format!("cannot create {}: {e}", out.display()),
        )
    })?;
    let mut stdout = std::io::stdout().lock();
    for (name, clip) in &lib.clips {
        let png = out.join(name.replace(".bvh", ".png"));
        sheet::write_sheet(&png, &clip.skeleton, &clip.roles, &clip.frames, frames).map_err(
            |e| {
                Failure::new(
                    exit::CANTCREAT,
                    format!("cannot write {}: {e}", png.display()),
                )
            },
        )?;
        let r = checks::check(
            &clip.skeleton,
            &clip.roles,
            &clip.frames,
            0.0,
            &checks::Limits::default(),
        );
        writeln!(
            stdout,
            "{name}: {} frames, slide {:.2} mm/frame ({}), below floor {:.1} mm, {} limit problems{}",
            clip.frames.len(),
            r.max_slide_mm,
            r.worst_slide,
            r.max_penetration_mm,
            r.violations.len(),
            r.violations.first().map(|v| format!(" ({v})")).unwrap_or_default()
        )
        .map_err(stdout_error)?;
    }
    writeln!(stdout, "sheets written to {}", out.display()).map_err(stdout_error)
}

const DEMO_RECORDING: &str = include_str!("../assets/recordings/demo.evemu");

fn list_outputs(dir: &Path, json: bool) -> Result<(), Failure> {
    let found =
        marionette::platform::kms::list_outputs(dir).map_err(|e| Failure::new(e.exit_code(), e))?;
    let mut out = std::io::stdout().lock();
    for o in &found {
        let line = if json {
            serde_json::to_string(o).map_err(|e| Failure::new(exit::FAILURE, e))?
        } else {
            o.to_string()
        };
        writeln!(out, "{line}").map_err(stdout_error)?;
    }
    Ok(())
}

fn list_devices(config: &Config, json: bool) -> Result<(), Failure> {
    let found = live::list_devices(&config.input).map_err(|e| Failure::new(e.exit_code(), e))?;
    let mut out = std::io::stdout().lock();
    if found.is_empty() {
        writeln!(
            out,
            "no input devices in {}",
            config.input.dev_dir.display()
        )
        .map_err(stdout_error)?;
    }
    for d in &found {
        let line = if json {
            serde_json::to_string(d).map_err(|e| Failure::new(exit::FAILURE, e))?
        } else {
            d.to_string()
        };
        writeln!(out, "{line}").map_err(stdout_error)?;
    }
    Ok(())
}
