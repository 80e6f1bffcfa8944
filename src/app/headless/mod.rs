//! The headless presenter: a recording replayed through the whole pipeline
//! (tracker, calibration, controller, renderer) into PNG frames, a contact
//! sheet and a summary. `marionette demo` and `marionette replay
//! --headless` use it; so do the tests.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use thiserror::Error;

mod summary;

pub use self::summary::{ActionRecord, CharacterSummary, HitRecord, NearMissRecord, Summary};
use super::config::Config;
use super::frame::{Backend, Flow, Steps};
use crate::control::character::Character;
use crate::control::stage::{Actor, Stage};
use crate::control::stage::{Took, TouchEvent};
use crate::control::ticker::Ticker;
use crate::input::touch::ScreenFrame;
use crate::render::contact;
use crate::render::gpu::{AdapterChoice, Gpu, GpuError};
use crate::render::headless::{Headless, Image};

/// Why a headless run stopped.
#[derive(Debug, Error)]
pub enum HeadlessError {
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error("cannot write {path}: {source}")]
    Write {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

/// How to run.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// Where frames, the contact sheet and the summary go; `None` steps the
    /// controller without rendering (poses only).
    pub out: Option<PathBuf>,
    /// Controller steps per second.
    pub tick_hz: f64,
    /// Frames written per second of recording.
    pub fps: f64,
    /// Keep going this long after the last touch (s)...
    pub tail_s: f64,
    /// ...and at least until this time (the recording's end, s).
    pub until: Option<f64>,
    /// Thumbnails on the contact sheet.
    pub sheet_frames: usize,
    pub adapter: AdapterChoice,
    /// Keep every stepped posture in [`Summary::poses`].
    pub keep_poses: bool,
    /// Measure motion quality as the replay runs, into
    /// [`Summary::metrics`] (bounded memory, however long the recording).
    pub measure: bool,
    /// Tracking control on (off: the output is the synthesised posture).
    pub tracking: bool,
    /// Record what the recording's visitors do into this database
    /// (`replay --visits`).
    pub visits: Option<PathBuf>,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            out: None,
            tick_hz: 30.0,
            fps: 10.0,
            tail_s: 1.0,
            until: None,
            sheet_frames: 16,
            adapter: AdapterChoice::Auto,
            keep_poses: false,
            measure: false,
            tracking: true,
            visits: None,
        }
    }
}

fn digest(hash: &mut u64, stage: &Stage) {
    for a in stage.actors() {
        digest_pose(hash, a.ctl.pose());
    }
}

fn digest_pose(hash: &mut u64, pose: &crate::character::skeleton::Pose) {
    let values = pose
        .rotations
        .iter()
        .flat_map(|q| q.to_array())
        .chain(pose.translations.iter().flat_map(|t| t.to_array()));
    for v in values {
        for b in v.to_bits().to_le_bytes() {
            *hash ^= u64::from(b);
            *hash = hash.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
}

/// The status line for the picture: recording time, mode, held parts.
fn status(ctl: &Stage, t: f64) -> String {
    let held: Vec<&str> = ctl.held().iter().map(|r| r.name()).collect();
    let mode = match ctl.action() {
        Some((name, time)) => format!("action {name} {:>3.0}%", time * 100.0),
        None => "posing".to_owned(),
    };
    let mut s = format!("{t:6.2} s | {mode}");
    if !held.is_empty() {
        s.push_str(" | holding ");
        s.push_str(&held.join(", "));
    }
    s
}

fn label(ctl: &Stage, t: f64) -> String {
    match ctl.action() {
        Some((name, _)) => format!("{t:.1}s {name}"),
        None if !ctl.held().is_empty() => format!("{t:.1}s posing {}", ctl.held().len()),
        None if ctl.touching_camera() => format!("{t:.1}s camera"),
        None => format!("{t:.1}s"),
    }
}

fn write(path: &Path, img: &Image) -> Result<(), HeadlessError> {
    img.write_png(path).map_err(|source| HeadlessError::Write {
        path: path.to_owned(),
        source,
    })
}

/// What a step shows, for choosing the contact sheet's frames.
#[derive(Clone, Debug, PartialEq)]
enum Shows {
    Rest,
    Action(String),
    Posing(usize),
    Camera,
}

/// Steps worth a thumbnail: a dry run of the same controller finds the
/// stretches where something happens (an action, a pose held, the camera
/// moving) and takes one step from each (60% into it), plus the first and
/// last steps; at most `max`, every action's stretch first, the others
/// evenly thinned.
fn key_steps(ctl: &Stage, ticker: &Ticker, end: f64, max: usize) -> Vec<usize> {
    let (mut ctl, mut ticker) = (ctl.clone(), ticker.clone());
    let mut runs: Vec<(Shows, usize, usize)> = Vec::new();
    let mut step = 0;
    let mut orbit = ctl.rig().orbit;
    loop {
        let t = ticker.step(&mut ctl);
        step += 1;
        let shows = match ctl.action() {
            Some((name, _)) => Shows::Action(name),
            None if !ctl.held().is_empty() => Shows::Posing(ctl.held().len()),
            None if ctl.rig().orbit != orbit => Shows::Camera,
            None => Shows::Rest,
        };
        orbit = ctl.rig().orbit;
        match runs.last_mut() {
            Some((s, _, last)) if *s == shows => *last = step,
            _ => runs.push((shows, step, step)),
        }
        if t >= end {
            break;
        }
    }
    let shown: Vec<(bool, usize)> = runs
        .iter()
        .filter(|(s, a, b)| *s != Shows::Rest && b - a >= 3)
        .map(|(s, a, b)| (matches!(s, Shows::Action(_)), a + (b - a) * 6 / 10))
        .collect();
    let m = max.max(2);
    let mut keys = vec![1, step];
    // Every action first (the sheet is there to show them), then the
    // other stretches evenly thinned to fill the sheet.
    let actions: Vec<usize> = shown.iter().filter(|s| s.0).map(|s| s.1).collect();
    let others: Vec<usize> = shown.iter().filter(|s| !s.0).map(|s| s.1).collect();
    let take = |from: &[usize], n: usize| -> Vec<usize> {
        if from.len() <= n {
            from.to_vec()
        } else if n == 0 {
            Vec::new()
        } else if n == 1 {
            vec![from[from.len() / 2]]
        } else {
            (0..n)
                .map(|i| from[i * (from.len() - 1) / (n - 1)])
                .collect()
        }
    };
    keys.extend(take(&actions, m - 2));
    let room = m.saturating_sub(keys.len());
    keys.extend(take(&others, room));
    keys.sort_unstable();
    keys.dedup();
    keys
}

/// The headless backend: touches from a recording, every stepped posture
/// digested and summarised, every `every`-th step (and each key step)
/// rendered into a PNG.
struct Replay<'a> {
    config: &'a Config,
    opts: &'a Options,
    touches: Ticker,
    end: f64,
    every: usize,
    key: Vec<usize>,
    home: crate::control::rig::Orbit,
    headless: Option<Headless>,
    summary: Summary,
    hash: u64,
    held_ever: BTreeSet<String>,
    thumbs: Vec<(Image, String, f64)>,
    times: Vec<f64>,
    meter: Option<crate::tools::metrics::Meter<'a>>,
    held_by: Vec<BTreeSet<String>>,
    recording: Option<crate::app::visits::Recording>,
}

impl Replay<'_> {
    /// The frame at `t` rendered and written, when one is due (and kept
    /// for the contact sheet at a key step).
    fn render(&mut self, ctl: &Stage, t: f64) -> Result<(), HeadlessError> {
        if let (Some(h), Some(dir)) = (self.headless.as_mut(), self.opts.out.as_ref()) {
            let is_key = self.key.binary_search(&self.summary.steps).is_ok();
            if self.summary.steps % self.every == 0 || is_key {
                let display = &self.config.display;
                let mut marks = ctl.marks(display.trajectories);
                if display.status_line {
                    marks.status = Some(status(ctl, t));
                }
                let list = super::frame::compose(ctl, display.rotation(), &marks);
                let started = std::time::Instant::now();
                let img = h.render(&list)?;
                self.times.push(started.elapsed().as_secs_f64() * 1e3);
                let n = self.summary.frames_written;
                write(&dir.join(format!("frames/frame-{n:05}.png")), &img)?;
                if is_key {
                    self.thumbs.push((img, label(ctl, t), t));
                }
                self.summary.frames_written += 1;
            }
        }
        Ok(())
    }
}

impl Replay<'_> {
    /// The replay's summary, with the table's hits and each character's
    /// parts and actions, and the contact sheet's thumbnails.
    fn finish(self, ctl: &Stage) -> (Summary, Vec<(Image, String, f64)>) {
        let Replay {
            mut summary,
            hash,
            held_ever,
            thumbs,
            times,
            meter,
            held_by,
            recording,
            ..
        } = self;
        summary.visits = recording.map(crate::app::visits::Recording::finish);
        let mut per = std::mem::take(&mut summary.characters);
        for ((c, held), a) in per.iter_mut().zip(held_by).zip(ctl.actors()) {
            c.parts_held = held.into_iter().collect();
            c.hits_landed = a.hits_landed;
            c.hits_taken = a.hits_taken;
        }
        if !per.is_empty() {
            let mut all: Vec<ActionRecord> = per.iter().flat_map(|c| c.actions.clone()).collect();
            all.sort_by(|a, b| a.started_s.total_cmp(&b.started_s));
            summary.actions = all;
        }
        summary.characters = per;
        summary.metrics = meter.map(crate::tools::metrics::Meter::finish);
        summary.parts_held = held_ever.into_iter().collect();
        summary.pose_digest = format!("{hash:016x}");
        if !times.is_empty() {
            summary.frame_ms_mean = times.iter().sum::<f64>() / times.len() as f64;
            summary.frame_ms_max = times.iter().copied().fold(0.0, f64::max);
        }
        (summary, thumbs)
    }
}

/// The output folder `dir` ready for frames (its old frames cleared), and
/// a renderer on `adapter` of `size` pixels with up to `samples` a pixel.
fn open_output(
    dir: &Path,
    adapter: AdapterChoice,
    (width, height): (u32, u32),
    samples: u32,
) -> Result<Headless, HeadlessError> {
    // Frames are written and old ones removed only in a folder of the
    // output's own: a `frames` that links elsewhere is refused, what it
    // links to left as it was.
    if dir
        .join("frames")
        .symlink_metadata()
        .is_ok_and(|m| m.file_type().is_symlink())
    {
        return Err(HeadlessError::Write {
            path: dir.join("frames"),
            source: std::io::Error::other(
                "it is a symbolic link: frames are written only into a folder of the output's own; remove the link",
            ),
        });
    }
    std::fs::create_dir_all(dir.join("frames")).map_err(|source| HeadlessError::Write {
        path: dir.join("frames"),
        source,
    })?;
    clear_old_frames(&dir.join("frames"))?;
    let h = Headless::new(Gpu::new(adapter)?, width, height, samples)?;
    tracing::info!(
        width,
        height,
        samples = h.renderer.samples(),
        "rendering headless"
    );
    Ok(h)
}

impl Backend for Replay<'_> {
    type Error = HeadlessError;

    fn feed(&mut self, ctl: &mut Stage, t: f64) {
        self.touches.feed(ctl, t);
    }

    fn frame(&mut self, ctl: &mut Stage, t: f64) -> Result<Flow, HeadlessError> {
        let summary = &mut self.summary;
        summary.steps += 1;
        digest(&mut self.hash, ctl);
        if self.opts.keep_poses {
            summary.poses.push(ctl.pose().clone());
        }
        if let Some(m) = &mut self.meter {
            m.push(ctl.pose(), &ctl.actors()[0].ctl.held());
        }
        let held = ctl.held();
        summary.most_held_at_once = summary.most_held_at_once.max(held.len());
        self.held_ever
            .extend(held.iter().map(|r| r.name().to_owned()));
        let home = self.home;
        let orbit = ctl.rig().orbit;
        if orbit != home && !ctl.any_action() {
            summary.camera_moved |= (orbit.yaw - home.yaw).abs() > 0.05
                || (orbit.distance - home.distance).abs() > 0.05;
        }
        for (k, a) in ctl.actors().iter().enumerate() {
            if let Some(set) = self.held_by.get_mut(k) {
                set.extend(a.ctl.held().iter().map(|r| r.name().to_owned()));
            }
        }
        for h in ctl.take_hits() {
            self.summary.hit(&h);
        }
        let touches = ctl.take_touches();
        self.summary.grabs += touches
            .iter()
            .filter(|e| {
                matches!(
                    e,
                    TouchEvent::Down {
                        took: Took::Part { .. },
                        ..
                    }
                )
            })
            .count();
        let events = ctl.take_events();
        if let Some(r) = &mut self.recording {
            r.frame(&touches, &events, t, true);
        }
        for (k, e) in events {
            self.summary.event(k, e);
        }
        self.render(ctl, t)?;
        if t >= self.end {
            self.summary.duration_s = t;
            return Ok(Flow::Stop);
        }
        Ok(Flow::Continue)
    }
}

/// Remove the frames an earlier run left in `frames` (`frame-NNNNN.png`
/// only: nothing else in the folder is touched), so that the folder holds
/// this run's frames alone.
fn clear_old_frames(frames: &Path) -> Result<(), HeadlessError> {
    let err = |source| HeadlessError::Write {
        path: frames.to_owned(),
        source,
    };
    let mut removed = 0usize;
    for entry in std::fs::read_dir(frames).map_err(err)? {
        let path = entry.map_err(err)?.path();
        let ours = path
            .file_name()
            .and_then(|n| n.to_str())
            .and_then(|n| n.strip_prefix("frame-"))
            .and_then(|n| n.strip_suffix(".png"))
            .is_some_and(|n| n.len() == 5 && n.bytes().all(|b| b.is_ascii_digit()));
        if ours {
            std::fs::remove_file(&path).map_err(|source| HeadlessError::Write {
                path: path.clone(),
                source,
            })?;
            removed += 1;
        }
    }
    if removed > 0 {
        tracing::info!(removed, folder = %frames.display(), "frames of an earlier run removed");
    }
    Ok(())
}

/// Replay `frames` (touch frames in picture pixels, times in seconds).
pub fn run(
    ch: Arc<Character>,
    config: &Config,
    frames: Vec<ScreenFrame>,
    opts: &Options,
) -> Result<Summary, HeadlessError> {
    run_table(vec![ch], config, frames, opts)
}

/// The table the configuration describes: `cast[k]` stands where
/// `[[character]]` number `k` says, in its tint.
#[must_use]
pub fn table(cast: Vec<Arc<Character>>, config: &Config, tracking: bool, t: f64) -> Stage {
    let mut settings = config.control_settings();
    if !tracking {
        settings.settle_s = 0.0;
    }
    let (pw, ph) = config.display.size();
    let (w, h) = (f64::from(pw), f64::from(ph));
    let places = config.character.placements();
    let tints = config.character.tints();
    let actors: Vec<Actor> = cast
        .into_iter()
        .enumerate()
        .map(|(k, ch)| {
            let (x, z, yaw) = places.get(k).copied().unwrap_or((k as f64 * 1.2, 0.0, 0.0));
            // Checked when the cast was loaded; should it fail now, the
            // capsule figure stands in and the log says why.
            let figure = config
                .character
                .0
                .get(k)
                .and_then(|c| {
                    crate::app::character::figure(&c.mesh, &c.mesh_roles, &ch)
                        .map_err(|e| tracing::error!("{e}: the capsule figure is shown instead"))
                        .ok()
                        .flatten()
                })
                .or_else(|| crate::app::character::own_body(&config.display.body, &ch));
            let mut actor = Actor::standing(
                ch,
                settings,
                glam::DVec3::new(x, 0.0, z),
                yaw,
                tints.get(k).copied().flatten(),
            );
            actor.set_figure(figure);
            actor
        })
        .collect();
    Stage::new(actors, w, h, t)
}

/// The contact sheet of `thumbs` (where there are any) and the summary
/// written into `dir`, the summary saying where.
fn write_sheet_and_summary(
    dir: &Path,
    thumbs: &[(Image, String, f64)],
    summary: &mut Summary,
) -> Result<(), HeadlessError> {
    if !thumbs.is_empty() {
        let list: Vec<(&Image, String)> = thumbs.iter().map(|(i, l, _)| (i, l.clone())).collect();
        let sheet_img = contact::sheet(&list, 4, 4);
        let path = dir.join("contact-sheet.png");
        write(&path, &sheet_img)?;
        summary.sheet = Some(path);
    }
    summary.out = Some(dir.to_owned());
    let path = dir.join("summary.json");
    let json = serde_json::to_string_pretty(&summary).unwrap_or_default();
    crate::output::replace_file(&path, (json + "\n").as_bytes())
        .map_err(|source| HeadlessError::Write { path, source })?;
    Ok(())
}

/// Replay `frames` on a table of `cast` (one character or several).
///
/// # Panics
/// With an empty cast.
pub fn run_table(
    cast: Vec<Arc<Character>>,
    config: &Config,
    frames: Vec<ScreenFrame>,
    opts: &Options,
) -> Result<Summary, HeadlessError> {
    let (ow, oh) = config.display.output_size();
    let measured = cast[0].clone();
    let libraries: Vec<String> = config
        .library_dirs()
        .iter()
        .map(|d| d.display().to_string())
        .collect();
    let n = cast.len();
    let mut ctl = table(cast, config, opts.tracking, 0.0);
    let touch_frames = frames.len();
    let ticker = Ticker::new(frames, opts.tick_hz);
    let end = (ticker.end() + opts.tail_s).max(opts.until.unwrap_or(0.0));
    let headless = match &opts.out {
        Some(dir) => Some(open_output(
            dir,
            opts.adapter,
            (ow, oh),
            config.display.samples,
        )?),
        None => None,
    };
    let key = if opts.out.is_some() {
        key_steps(&ctl, &ticker, end, opts.sheet_frames)
    } else {
        Vec::new()
    };
    let mut replay = Replay {
        config,
        opts,
        touches: ticker,
        end,
        every: (opts.tick_hz / opts.fps.max(1e-3)).round().max(1.0) as usize,
        key,
        home: ctl.rig().orbit,
        headless,
        summary: Summary {
            touch_frames,
            // Each character's actions, hits and held parts (a table of
            // several).
            characters: if n > 1 {
                (0..n)
                    .map(|k| CharacterSummary {
                        library: libraries.get(k).cloned().unwrap_or_default(),
                        ..CharacterSummary::default()
                    })
                    .collect()
            } else {
                Vec::new()
            },
            ..Summary::default()
        },
        hash: 0xcbf2_9ce4_8422_2325u64,
        held_ever: BTreeSet::new(),
        thumbs: Vec::new(),
        times: Vec::new(),
        held_by: vec![BTreeSet::new(); n],
        recording: opts.visits.as_ref().map(|path| {
            crate::app::visits::Recording::into_file(
                path.clone(),
                config,
                crate::app::visits::unix_now(),
            )
        }),
        meter: opts.measure.then(|| {
            crate::tools::metrics::Meter::new(
                &measured.lib.skeleton,
                &measured.roles,
                1.0 / opts.tick_hz,
            )
        }),
    };
    super::frame::run(&mut ctl, &mut Steps::new(opts.tick_hz), &mut replay)?;
    let (mut summary, thumbs) = replay.finish(&ctl);
    if let Some(dir) = &opts.out {
        write_sheet_and_summary(dir, &thumbs, &mut summary)?;
    }
    Ok(summary)
}
