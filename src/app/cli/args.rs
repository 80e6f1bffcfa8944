//! The command line's arguments (clap).

use std::path::PathBuf;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "marionette",
    version,
    about = "Touch-table character puppeteering kiosk"
)]
pub(super) struct Cli {
    /// Configuration file [default: /etc/marionette/marionette.toml if it
    /// exists, else built-in defaults]
    #[arg(long, global = true, value_name = "PATH")]
    pub(super) config: Option<PathBuf>,
    #[command(subcommand)]
    pub(super) command: Command,
}

#[derive(Subcommand)]
pub(super) enum Command {
    /// Replay the bundled demo recording through the input stack and print
    /// what it does
    Demo {
        /// Where the frames, contact sheet and summary go.
        #[arg(long, default_value = "demo-out")]
        out: PathBuf,
        /// Frames written per second of recording.
        #[arg(long, default_value_t = 10.0)]
        fps: f64,
        /// Which bundled scene: `solo` (one character, one visitor) or
        /// `duel` (two characters, two visitors, hits).
        #[arg(long, value_enum, default_value = "solo")]
        scene: Scene,
        /// A library to show instead of the default character: a recording
        /// is authored against it (every action dragged, posing, the
        /// camera) and written as `recording.evemu` beside the frames.
        #[arg(long, value_name = "DIR", conflicts_with = "scene")]
        library: Option<PathBuf>,
        /// An exhibit's own character (.glb, .gltf, .vrm) to show instead
        /// of the configuration's, its roles found from the file alone.
        #[arg(long, value_name = "FILE")]
        mesh: Option<PathBuf>,
    },
    Inspect {
        /// An evemu recording, a BVH file or a character (glTF, GLB, VRM): told by its content, whatever its name
        file: PathBuf,
    },
    /// Replay a recording through the input stack
    Replay {
        file: PathBuf,
        /// Print every touch frame as a JSON line (a replay of its own:
        /// not with --headless or --metrics).
        #[arg(long, conflicts_with_all = ["headless", "metrics"])]
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
        /// With --headless: refuse to write more frames than this (a long
        /// recording at a high --fps fills a disk)
        #[arg(long, default_value_t = 18_000)]
        max_frames: u64,
        /// Run the whole pipeline without rendering and write motion
        /// quality metrics (JSON) to this file.
        #[arg(long, value_name = "OUT.json", conflicts_with = "headless")]
        metrics: Option<PathBuf>,
        /// With --metrics: turn tracking control off, to compare.
        #[arg(long, requires = "metrics")]
        no_tracking: bool,
        /// Replay with this library's character instead of the
        /// configuration's (a recording `demo --library DIR` authored).
        #[arg(long, value_name = "DIR")]
        library: Option<PathBuf>,
        /// With --headless: an exhibit's own character (.glb, .gltf,
        /// .vrm) to show instead of the configuration's.
        #[arg(long, value_name = "FILE", requires = "headless")]
        mesh: Option<PathBuf>,
        /// Run the whole pipeline without rendering and record what the
        /// recording's visitors do into this visits database (as the
        /// kiosk does), for `marionette report`.
        #[arg(long, value_name = "PATH", conflicts_with_all = ["headless", "metrics", "contacts"])]
        visits: Option<PathBuf>,
    },
    /// What visitors did at the table, from the visits record: report.html
    /// (charts, no script) and report.json
    Report {
        /// The visits database [default: the configuration's kiosk.visits]
        #[arg(long, value_name = "PATH")]
        db: Option<PathBuf>,
        /// How far back: 7d, 24h, 90m or all
        #[arg(long, default_value = "7d")]
        since: crate::app::report::Since,
        /// Where report.html and report.json go
        #[arg(long, default_value = "report")]
        out: PathBuf,
    },
    /// Write the motion the character performs for a recording as BVH
    /// (the library's skeleton, at its frame rate).
    ExportBvh {
        file: PathBuf,
        #[arg(long)]
        out: PathBuf,
        /// Replay with this library's character instead of the
        /// configuration's (a recording `demo --library DIR` authored).
        #[arg(long, value_name = "DIR")]
        library: Option<PathBuf>,
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
        #[arg(long, value_parser = metres_per_unit)]
        scale_to_m: Option<f64>,
    },
    /// Build the learned models of a library and cache them (run and demo
    /// use the cache when it matches the library, and bake when it does not)
    Bake {
        /// Library folder (with library.toml) [default: the configuration's
        /// character.library, else the shipped library]
        #[arg(long)]
        library: Option<PathBuf>,
        /// Bake even if a matching cache exists
        #[arg(long)]
        force: bool,
    },
    /// Motion libraries of an exhibit's own capture
    Library {
        #[command(subcommand)]
        what: LibraryCommand,
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
    /// Write a recording of random multi-finger abuse of the table (fast
    /// flicks of grabbed parts, drags, holds, up to five fingers, lost
    /// events), the same for a seed; replay it with `replay --metrics`
    AuthorAbuse {
        /// The recording to write (evemu)
        #[arg(long)]
        out: PathBuf,
        /// How long (s, at most 3600)
        #[arg(long, default_value_t = 600.0)]
        seconds: f64,
        /// Seed of the fingers' moves
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Library folder whose character the fingers aim at [default: the
        /// configuration's character.library, else the shipped library]
        #[arg(long)]
        library: Option<PathBuf>,
    },
    /// Draw each clip of a library as a contact sheet (stick figures, front
    /// and side views) and report foot sliding, floor contact and joint limits
    ContactSheet {
        /// Library folder (with library.toml) [default: the configuration's
        /// character.library, else the shipped library]
        #[arg(long)]
        library: Option<PathBuf>,
        /// Output folder for the PNG files
        #[arg(long, default_value = "contact-sheets")]
        out: PathBuf,
        /// Frames per sheet (at least 1)
        #[arg(long, default_value_t = 10, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..))]
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
pub(super) enum EvalCommand {
    /// Posing control: reconstruct held-out frames from N constrained parts
    /// and print one JSON object (mpjpe_cm, constraint_err_px,
    /// constraint_err_cm, ms_per_pose, poses; with --leave-one-out, their
    /// means and each clip's)
    Pose {
        /// Library folder (with library.toml) [default: the configuration's
        /// character.library, else the shipped library]
        #[arg(long)]
        library: Option<PathBuf>,
        /// Held-out BVH clips of the library's skeleton
        #[arg(long, num_args = 1.., required_unless_present = "leave_one_out")]
        test: Vec<PathBuf>,
        /// Test each posing clip of the library in turn on a model of the
        /// others (instead of --test; --frames per clip)
        #[arg(long, conflicts_with = "test")]
        leave_one_out: bool,
        /// Follow each test clip frame by frame from its first frame
        /// (--frames of each), the character continuing from its own last
        /// posture as in use; prints the frame-by-frame and single-frame
        /// results
        #[arg(long, conflicts_with = "leave_one_out")]
        sequence: bool,
        /// Constrained parts, first N of right_hand, left_hand, right_foot, left_foot, head
        #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u8).range(1..=5))]
        parts: u8,
        #[arg(long, value_enum, default_value = "touch")]
        mode: EvalMode,
        #[arg(long, value_enum, default_value = "model")]
        method: EvalMethod,
        /// Frames sampled evenly from the test clips (from each clip with
        /// --leave-one-out)
        #[arg(long, default_value_t = 200, value_parser = at_least_one)]
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
    /// A skinned glTF character playing the library's clips: prints one
    /// JSON object (mean_pct, max_pct of body height between its mapped
    /// parts and the library's, penetration_mm, skate_mm against the
    /// library's own library_skate_mm, bad_frames)
    Character {
        /// The character (.glb or .gltf)
        #[arg(long)]
        mesh: PathBuf,
        /// Library folder (with library.toml) [default: the configuration's
        /// character.library, else the shipped library]
        #[arg(long)]
        library: Option<PathBuf>,
    },
    /// Walking where a finger leads: drag the pelvis along floor paths
    /// through the controller (touch frames from the home view) and print
    /// one JSON object (paths, followed, arrival_cm, arrival_worst_cm,
    /// deviation_cm, skate_mm, skate_max_mm, pops, start_s, start_worst_s,
    /// speed_ratio, stood, families: a row per family, rows: one per path;
    /// with --layer, layered)
    Walk {
        /// Library folder (with library.toml) [default: the configuration's
        /// character.library, else the shipped library]
        #[arg(long)]
        library: Option<PathBuf>,
        /// JSON file of paths: {"paths": [{"points": [[x, z], ...],
        /// "speed_mps": v}]}, metres in the character's frame (x to its
        /// right, z ahead) from its pelvis, optionally "pauses": [[m, s],
        /// ...] where the finger stops and "family" [default: random paths
        /// of --family]
        #[arg(long)]
        paths: Option<PathBuf>,
        /// Seed of the random paths
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// How many random paths (of all families: taken in turn)
        #[arg(long, default_value_t = 28, value_parser = clap::value_parser!(u32).range(1..=1000))]
        count: u32,
        /// The family of random paths: curve (smooth, 0.6-1.4 m/s),
        /// turn_back, loop, zig_zag (0.3-2 m/s), stop_and_go (stops of 1.5-3
        /// s on the way), slow (0.3-0.6 m/s), fast (1.5-2 m/s), or all in
        /// turn
        #[arg(long, default_value = "all", value_parser = ["all", "curve", "turn_back", "loop", "zig_zag", "stop_and_go", "slow", "fast"])]
        family: String,
        /// Write the paths walked to this file, as --paths reads them (to
        /// walk one again alone)
        #[arg(long, value_name = "FILE.json")]
        save_paths: Option<PathBuf>,
        /// An action of the arms or head that a second finger drags over
        /// each walk (layered on the upper body); its figures are printed
        /// as `layered` (started, part_cm, part_max_cm, shown_cm)
        #[arg(long, value_name = "ACTION")]
        layer: Option<String>,
    },
    /// Action control: replay held-out clips' primary-part paths as drags
    /// through the controller (touch frames, as live input) and print one
    /// JSON object (trials, correct, wrong_action, missed,
    /// false_trigger_slow, decided_at)
    Actions {
        /// Library folder (with library.toml) [default: the configuration's
        /// character.library, else the shipped library]
        #[arg(long)]
        library: Option<PathBuf>,
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
        /// Write every drag explained to this file, one JSON object a line
        /// (the template recogniser alone, as --models-only): at each point
        /// the leading action and the next with their costs, the margin,
        /// the leader's coverage and tempo, and the rule that held the
        /// decision back (not_moving, coverage, cost, margin, no_template;
        /// starts where it started)
        #[arg(long, value_name = "FILE.jsonl")]
        explain: Option<PathBuf>,
    },
}

/// The bundled demo scenes.
#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(super) enum Scene {
    Solo,
    Duel,
}

#[derive(Clone, Copy, clap::ValueEnum)]
pub(super) enum EvalMode {
    Touch,
    Targets,
}

#[derive(Clone, Copy, clap::ValueEnum)]
pub(super) enum EvalMethod {
    Model,
    Scan,
    Nearest,
    CcdRest,
}

#[derive(Debug, Subcommand)]
pub enum LibraryCommand {
    /// Build a library from a folder of takes: `<action>_<anything>.bvh`
    /// gives action `<action>`, `pose_*.bvh` is posing only, every clip
    /// feeds posing. Units, roles, each action's primary part, cuts of long
    /// takes and condition segments are measured from the motion and
    /// written, commented, to DIR/library.toml (the clips stay where they
    /// are)
    Init {
        /// Folder of BVH takes
        src: PathBuf,
        /// Library folder to write library.toml in (made if missing)
        #[arg(long)]
        out: PathBuf,
        /// Replace an existing library.toml there
        #[arg(long)]
        force: bool,
        /// Copy the takes into DIR/clips, so that the library folder can be
        /// moved, copied or packaged on its own (without it, DIR refers to
        /// the takes where they are)
        #[arg(long)]
        copy_clips: bool,
    },
    /// Leave each clip of a library out in turn and replay it as drags
    /// from two views against the others: how often each action's drags
    /// start it, start nothing or start another action, and what to do
    /// about it (record more takes, merge actions a drag cannot tell
    /// apart). Exit 0 whatever it finds; 65 for a library that does not
    /// load
    Check {
        /// Library folder (with library.toml)
        dir: PathBuf,
        /// Print JSON instead of a table
        #[arg(long)]
        json: bool,
        /// Write every left-out drag explained to this file, one JSON
        /// object a line (as `eval actions --explain` does)
        #[arg(long, value_name = "FILE.jsonl")]
        explain: Option<PathBuf>,
    },
}

/// `--scale-to-m`: metres per file unit, a positive number no file unit is
/// smaller than a micrometre or larger than a kilometre.
fn metres_per_unit(s: &str) -> Result<f64, String> {
    let v: f64 = s.parse().map_err(|_| {
        format!(
            "{} is not a number (metres per file unit: 0.01 for centimetres)",
            crate::reading::quote(s)
        )
    })?;
    if v.is_finite() && (1e-6..=1e3).contains(&v) {
        Ok(v)
    } else {
        Err(format!(
            "{v} metres per file unit is no unit: give 0.01 for centimetres, 0.0254 for inches, 1 for metres"
        ))
    }
}

/// A count of at least one.
fn at_least_one(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(n) if n >= 1 => Ok(n),
        _ => Err(format!(
            "{} is not a count of at least 1",
            crate::reading::quote(s)
        )),
    }
}
