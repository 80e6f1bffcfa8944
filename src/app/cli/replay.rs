//! Recordings through the whole pipeline: `demo`, `replay --headless`,
//! `replay --metrics`, `export-bvh`.

use std::io::Write;
use std::path::Path;

use super::{Failure, stdout_error, write_atomically};
use crate::app::config::Config;
use crate::app::exit::{self};
use crate::input::evemu::Recording;
use crate::input::pipeline;

/// The configured library's character.
pub(super) fn character(
    config: &Config,
) -> Result<std::sync::Arc<crate::control::character::Character>, Failure> {
    let dir = config.library_dir();
    // A folder the configuration names that is no library is the
    // configuration's fault: fix the file, restarting will not help.
    if let Some(why) = crate::app::character::library_problem(config, &dir, "character.library") {
        return Err(Failure::new(exit::CONFIG, why));
    }
    Ok(crate::app::character::load(&dir)?)
}

/// Every configured character (`[[character]]`), in order; characters of
/// one library share it.
pub(super) fn cast(
    config: &Config,
) -> Result<Vec<std::sync::Arc<crate::control::character::Character>>, Failure> {
    let dirs = config.library_dirs();
    let mut loaded: Vec<(
        std::path::PathBuf,
        std::sync::Arc<crate::control::character::Character>,
    )> = Vec::new();
    let mut out = Vec::new();
    for (k, dir) in dirs.iter().enumerate() {
        if let Some((_, ch)) = loaded.iter().find(|(d, _)| d == dir) {
            out.push(ch.clone());
            continue;
        }
        let key = if dirs.len() > 1 {
            format!("character[{k}].library")
        } else {
            "character.library".to_owned()
        };
        if let Some(why) = crate::app::character::library_problem(config, dir, &key) {
            return Err(Failure::new(exit::CONFIG, why));
        }
        let ch = crate::app::character::load(dir)?;
        loaded.push((dir.clone(), ch.clone()));
        out.push(ch);
    }
    // Each configured mesh is read now: a broken one stops the start here,
    // as a broken library does.
    for (c, ch) in config.character.0.iter().zip(&out) {
        crate::app::character::figure(&c.mesh, &c.mesh_roles, ch)?;
    }
    Ok(out)
}

/// A recording through the whole pipeline into images.
pub(super) fn show(
    config: &Config,
    rec: &Recording,
    out: &Path,
    fps: f64,
    max_frames: u64,
) -> Result<(), Failure> {
    let summary = render(config, rec, out, fps, max_frames)?;
    writeln!(std::io::stdout(), "{summary}").map_err(stdout_error)
}

/// [`show`] without printing: the replay's summary.
fn render(
    config: &Config,
    rec: &Recording,
    out: &Path,
    fps: f64,
    max_frames: u64,
) -> Result<crate::app::headless::Summary, Failure> {
    use crate::app::headless;
    check_fps(fps)?;
    let (summary, _) = pipeline::summarize(rec);
    // Every 1/fps of recording, and the contact sheet's thumbnails.
    let frames_out = (summary.replay_s * fps).floor() as u64
        + 1
        + headless::Options::default().sheet_frames as u64;
    if frames_out > max_frames {
        return Err(Failure::new(
            exit::USAGE,
            format!(
                "the replay would write {frames_out} frames ({:.1} s of recording at --fps {fps}), more than --max-frames {max_frames}: pass --max-frames {frames_out} to write them all, or a lower --fps",
                summary.replay_s
            ),
        ));
    }
    let cast = cast(config)?;
    let frames = pipeline::replay(rec, &config.input, config.display.picture())
        .map_err(|e| Failure::new(exit::DATAERR, e))?;
    let opts = headless::Options {
        out: Some(out.to_owned()),
        fps,
        until: Some(summary.replay_s),
        ..headless::Options::default()
    };
    headless::run_table(cast, config, frames, &opts).map_err(|e| naming_file(config, e))
}

/// Frames are written at most once per controller step.
fn check_fps(fps: f64) -> Result<(), Failure> {
    let tick_hz = crate::app::headless::Options::default().tick_hz;
    if fps > 0.0 && fps <= tick_hz {
        return Ok(());
    }
    Err(Failure::new(
        exit::USAGE,
        format!(
            "--fps must be above 0 and at most {tick_hz} (the controller's steps per second of recording), found {fps}"
        ),
    ))
}

pub(super) fn demo(
    config: &Config,
    out_dir: &Path,
    fps: f64,
    scene: super::args::Scene,
) -> Result<(), Failure> {
    check_fps(fps)?;
    // The recordings are built into the binary: the demo works from
    // anywhere.
    let (text, name, config) = match scene {
        super::args::Scene::Solo => (
            DEMO_RECORDING,
            "assets/recordings/demo.evemu",
            config.clone(),
        ),
        super::args::Scene::Duel => (
            DUEL_RECORDING,
            "assets/recordings/duel.evemu",
            config.duel(),
        ),
    };
    let rec = Recording::parse(text, Path::new(name))?;
    let (summary, _) = pipeline::summarize(&rec);
    writeln!(
        std::io::stdout(),
        "demo: {name} ({:.1} s, {} finger contacts, {} character{})",
        summary.duration_s,
        summary.touch_sequences,
        config.character.len(),
        if config.character.len() == 1 { "" } else { "s" }
    )
    .map_err(stdout_error)?;
    show(&config, &rec, out_dir, fps, u64::MAX)
}

/// `demo --library DIR`: a recording authored against the library's own
/// character (every action dragged, posing, the camera, the table at
/// rest), written as `OUT/recording.evemu`, then replayed into frames and
/// a contact sheet; `summary.json` adds which actions were dragged and
/// which of them started.
pub(super) fn demo_library(
    config: &Config,
    dir: std::path::PathBuf,
    out_dir: &Path,
    fps: f64,
) -> Result<(), Failure> {
    check_fps(fps)?;
    let config = config.with_library(&dir);
    let ch = crate::app::character::load(&dir)?;
    let (synth, dragged) = crate::tools::demo::author_library_demo(
        ch,
        config.control_settings(),
        &config.input,
        config.display.picture(),
    );
    let rec = synth.finish();
    let mut text = Vec::new();
    rec.write(&mut text)
        .map_err(|e| Failure::new(exit::FAILURE, e))?;
    std::fs::create_dir_all(out_dir).map_err(|e| {
        Failure::new(
            exit::CANTCREAT,
            format!("cannot create {}: {e}", out_dir.display()),
        )
    })?;
    let recording = out_dir.join("recording.evemu");
    crate::output::replace_file(&recording, &text).map_err(|e| {
        Failure::new(
            exit::CANTCREAT,
            format!("cannot write {}: {e}", recording.display()),
        )
    })?;
    let (length, _) = pipeline::summarize(&rec);
    writeln!(
        std::io::stdout(),
        "demo: {} ({:.1} s authored against it, {} actions dragged), recording in {}",
        dir.display(),
        length.duration_s,
        dragged.len(),
        recording.display()
    )
    .map_err(stdout_error)?;
    let summary = render(&config, &rec, out_dir, fps, u64::MAX)?;
    let started: Vec<&str> = dragged
        .iter()
        .filter(|d| summary.actions.iter().any(|a| &a.action == *d))
        .map(String::as_str)
        .collect();
    let missed: Vec<&str> = dragged
        .iter()
        .filter(|d| !started.contains(&d.as_str()))
        .map(String::as_str)
        .collect();
    let mut json = serde_json::to_value(&summary).map_err(|e| Failure::new(exit::FAILURE, e))?;
    json["library"] = serde_json::json!(dir.display().to_string());
    json["dragged"] = serde_json::json!(dragged);
    json["dragged_started"] = serde_json::json!(started);
    json["dragged_not_started"] = serde_json::json!(missed);
    let text = serde_json::to_string_pretty(&json).map_err(|e| Failure::new(exit::FAILURE, e))?;
    write_atomically(&out_dir.join("summary.json"), &(text + "\n"))?;
    writeln!(
        std::io::stdout(),
        "{summary}\n{} of {} dragged actions started{}",
        started.len(),
        dragged.len(),
        if missed.is_empty() {
            String::new()
        } else {
            format!(
                " (not: {}; `marionette library check {}` says why)",
                missed.join(", "),
                dir.display()
            )
        }
    )
    .map_err(stdout_error)
}

/// What a replay without rendering keeps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Keep {
    Poses,
    Metrics,
}

/// A recording replayed without rendering, the controller stepped at
/// `tick_hz` (0: the library's frame rate) up to the recording's end:
/// every posture kept (`Keep::Poses`), or measured as it goes in bounded
/// memory (`Keep::Metrics`).
pub(super) fn replay_poses(
    config: &Config,
    file: &Path,
    tick_hz: f64,
    tracking: bool,
    keep: Keep,
) -> Result<
    (
        std::sync::Arc<crate::control::character::Character>,
        crate::app::headless::Summary,
        f64,
    ),
    Failure,
> {
    use crate::app::headless;
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
        keep_poses: keep == Keep::Poses,
        measure: keep == Keep::Metrics,
        until: Some(pipeline::summarize(&rec).0.replay_s),
        tracking,
        ..headless::Options::default()
    };
    let summary =
        headless::run(ch.clone(), config, frames, &opts).map_err(|e| naming_file(config, e))?;
    Ok((ch, summary, tick_hz))
}

/// `replay FILE --visits DB`: the whole pipeline without rendering, what
/// its visitors do recorded into `db`; the summary printed.
pub(super) fn replay_visits(config: &Config, file: &Path, db: &Path) -> Result<(), Failure> {
    use crate::app::headless;
    let rec = Recording::read_file(file)?;
    // A file there that is not a visits record is refused, never set
    // aside as the kiosk would.
    if let Some(folder) = db.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(folder)
            .map_err(|e| Failure::new(exit::CANTCREAT, format!("{}: {e}", folder.display())))?;
    }
    drop(crate::app::visits::store::open(db)?);
    let ch = character(config)?;
    let frames = pipeline::replay(&rec, &config.input, config.display.picture())
        .map_err(|e| Failure::new(exit::DATAERR, e))?;
    let opts = headless::Options {
        until: Some(pipeline::summarize(&rec).0.replay_s),
        visits: Some(db.to_owned()),
        ..headless::Options::default()
    };
    let summary = headless::run(ch, config, frames, &opts).map_err(|e| naming_file(config, e))?;
    let (c, written) = summary.visits.unwrap_or_default();
    if !written.all() {
        return Err(Failure::new(
            exit::CANTCREAT,
            format!(
                "{}: {} of {} rows of visits could not be written (the log above says why)",
                db.display(),
                (written.sent + written.dropped).saturating_sub(written.committed + written.merged),
                written.sent + written.dropped
            ),
        ));
    }
    writeln!(
        std::io::stdout(),
        "{summary}\nvisits recorded into {}: {} sessions, {} touches ({} grabs), {} actions, {} near misses",
        db.display(),
        c.sessions,
        c.touches,
        c.grabs,
        c.actions,
        c.near_misses
    )
    .map_err(stdout_error)
}

pub(super) fn replay_metrics(
    config: &Config,
    file: &Path,
    out: &Path,
    no_tracking: bool,
) -> Result<(), Failure> {
    let (_, summary, _) = replay_poses(config, file, 30.0, !no_tracking, Keep::Metrics)?;
    let m = summary.metrics.clone().unwrap_or_default();
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
        "{} frames, {} with NaN, largest joint speed jump {:.2} rad/s ({}{} pops over {} rad/s), foot skate {:.2} mm/frame (max {:.2}{}), ground penetration {:.1} mm{}, {} actions; written to {}",
        m.frames,
        m.nan_frames,
        m.max_joint_speed_jump_rad_s,
        where_(&m.worst_jump, "; "),
        m.pops,
        crate::tools::metrics::POP_RAD_S,
        m.foot_skate_mm_per_frame,
        m.foot_skate_max_mm,
        if m.worst_skate.is_empty() {
            String::new()
        } else {
            format!(", {}", m.worst_skate)
        },
        m.ground_penetration_mm,
        if m.worst_penetration.is_empty() {
            String::new()
        } else {
            format!(" ({})", m.worst_penetration)
        },
        summary.actions.len(),
        out.display()
    )
    .map_err(stdout_error)
}

pub(super) fn export_bvh(config: &Config, file: &Path, out: &Path) -> Result<(), Failure> {
    let (ch, summary, tick_hz) = replay_poses(config, file, 0.0, true, Keep::Poses)?;
    let translates: Vec<bool> = (0..ch.lib.skeleton.len()).map(|j| j == 0).collect();
    let text =
        crate::character::bvh::write(&ch.lib.skeleton, &translates, &summary.poses, 1.0 / tick_hz);
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

pub(super) const DEMO_RECORDING: &str = include_str!("../../../assets/recordings/demo.evemu");
pub(super) const DUEL_RECORDING: &str = include_str!("../../../assets/recordings/duel.evemu");

/// Where a worst value happened, followed by `sep`; nothing when no place
/// is known (no foot slid, nothing went below the floor).
fn where_(place: &str, sep: &str) -> String {
    if place.is_empty() {
        String::new()
    } else {
        format!("{place}{sep}")
    }
}

/// `author-abuse`: a recording of `seconds` of random multi-finger abuse,
/// the fingers aimed at where the library's character stands in the home
/// view, written whole to `out`.
pub(super) fn author_abuse(
    config: &Config,
    library: &Path,
    out: &Path,
    seconds: f64,
    seed: u64,
) -> Result<(), Failure> {
    // An hour is about 160 MB of evemu text, built in memory.
    if !(seconds.is_finite() && (1.0..=3600.0).contains(&seconds)) {
        return Err(Failure::new(
            exit::USAGE,
            format!(
                "--seconds {seconds}: give 1 to 3600 (an hour is about 160 MB of recording); for longer, write several seeds"
            ),
        ));
    }
    let ch = crate::app::character::load(library)?;
    let synth = crate::tools::abuse::author_abuse(
        &ch,
        config.control_settings(),
        config.display.picture(),
        seconds,
        seed,
    );
    let mut text = Vec::new();
    synth
        .finish()
        .write(&mut text)
        .map_err(|e| Failure::new(exit::FAILURE, e))?;
    crate::output::replace_file(out, &text).map_err(|e| {
        Failure::new(
            exit::CANTCREAT,
            format!("cannot write {}: {e}", out.display()),
        )
    })?;
    writeln!(
        std::io::stdout(),
        "{:.0} s of abuse (seed {seed}) written to {}; measure it with `marionette replay {} --metrics OUT.json`",
        seconds,
        out.display(),
        out.display()
    )
    .map_err(stdout_error)
}

/// A headless run's failure; one that the configuration caused (a picture
/// larger than the adapter renders) names the configuration's file.
fn naming_file(config: &Config, e: crate::app::headless::HeadlessError) -> Failure {
    let mut f = Failure::from(e);
    if f.code == exit::CONFIG && !config.source.as_os_str().is_empty() {
        f.message = format!("configuration {}: {}", config.source.display(), f.message);
    }
    f
}
