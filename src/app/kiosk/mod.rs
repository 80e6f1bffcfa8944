//! `marionette run`: the kiosk. Fullscreen on a KMS output, reading every
//! touchscreen through evdev, stepping the character with the real time
//! and showing a frame per vblank; idle, it returns to rest and performs
//! an attract recording; panels come and go, a VT switch or a lost GPU
//! pause it and it carries on; SIGTERM/SIGINT end it cleanly within a
//! second. systemd hears READY=1 after the first page flip and WATCHDOG=1
//! from the loop.
//!
//! The loop's timing decisions are in [`timers`], tested with a made-up
//! clock; the attract loop is [`attract`]; the touchscreens are read on
//! the thread in [`input_thread`].

mod attract;
mod input_thread;
mod service;
pub(crate) mod timers;
mod vitals;

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use thiserror::Error;

use super::config::Config;
use crate::control::character::Character;
use crate::control::stage::Stage;
use crate::display::error::ErrorClass;
use crate::display::present::{OutputChoice, PresentError, PresenterKind};
use crate::display::screen::Screen;
use crate::input::hub::{HubEvent, LiveError};
use crate::input::touch::ScreenFrame;
use crate::platform::clock::{Clock, Monotonic};
use crate::platform::notify::Notifier;
use crate::render::gpu::{AdapterChoice, GpuError};

use self::attract::Attract;
pub(crate) use self::input_thread::InputThread;
use self::service::ServiceView;
use self::timers::{ATTRACT_DELAY_S, Timers};
use self::vitals::Vitals;
use super::frame::{self, Backend, Flow, Since};

/// Why the kiosk stopped.
#[derive(Debug, Error)]
pub enum RunError {
    #[error(transparent)]
    Present(#[from] PresentError),
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error(transparent)]
    Input(#[from] LiveError),
    #[error("attract recording {path}: {message} (fix or empty `kiosk.attract`)")]
    Attract { path: PathBuf, message: String },
}

/// How `run` runs.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Where the DRM card nodes are.
    pub dri_dir: PathBuf,
    /// Stop after this long (for tests); `None` runs until a signal.
    pub seconds: Option<f64>,
    pub adapter: AdapterChoice,
}

impl Default for RunOptions {
    fn default() -> Self {
        Self {
            dri_dir: PathBuf::from("/dev/dri"),
            seconds: None,
            adapter: AdapterChoice::Auto,
        }
    }
}

/// What a run did, logged when it stops.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunStats {
    pub seconds: f64,
    pub frames: u64,
    pub flips: u64,
    pub touch_frames: u64,
    pub gpu_rebuilds: u64,
    pub display_losses: u64,
    /// Render plus readback plus copy, per frame (ms).
    pub render_ms_mean: f64,
    pub render_ms_max: f64,
    /// From a touch to the flip that first showed it, over the run (ms),
    /// and how many touches that is of.
    pub touch_to_flip_ms_mean: f64,
    pub touch_to_flip_n: u64,
}

fn load_attract(config: &Config) -> Result<Option<Vec<ScreenFrame>>, RunError> {
    let path = &config.kiosk.attract;
    if path.as_os_str().is_empty() {
        return Ok(None);
    }
    let err = |message: String| RunError::Attract {
        path: path.clone(),
        message,
    };
    let rec = crate::input::evemu::Recording::read_file(path).map_err(|e| err(e.to_string()))?;
    let frames = crate::input::pipeline::replay(&rec, &config.input, config.display.picture())
        .map_err(|e| err(e.to_string()))?;
    if frames.is_empty() {
        return Err(err("it has no touches".to_owned()));
    }
    tracing::info!(path = %path.display(), frames = frames.len(), "attract recording loaded");
    Ok(Some(frames))
}

/// Whether two postures are the same to the eye.
fn same_pose(a: &crate::character::skeleton::Pose, b: &crate::character::skeleton::Pose) -> bool {
    a.rotations
        .iter()
        .zip(&b.rotations)
        .all(|(p, q)| p.abs_diff_eq(*q, 1e-6))
        && a.translations
            .iter()
            .zip(&b.translations)
            .all(|(p, q)| p.abs_diff_eq(*q, 1e-6))
}

/// Run the kiosk until SIGTERM/SIGINT (or `opts.seconds`), on the
/// monotonic clock.
pub fn run(
    cast: Vec<Arc<Character>>,
    config: &Config,
    opts: &RunOptions,
) -> Result<RunStats, RunError> {
    run_with_clock(cast, config, opts, &Monotonic)
}

/// [`run`] on any clock: the loop reads the time only through `clock`,
/// and every timing decision is made by [`Timers`].
pub fn run_with_clock(
    cast: Vec<Arc<Character>>,
    config: &Config,
    opts: &RunOptions,
    clock: &dyn Clock,
) -> Result<RunStats, RunError> {
    crate::platform::signals::install_stop_handler();
    let notifier = Notifier::from_env();
    let choice = OutputChoice::from_config(&config.display);
    let kind = PresenterKind::parse(&config.display.presenter).unwrap_or_default();
    let screen = Screen::open(
        &opts.dri_dir,
        &choice,
        kind,
        opts.adapter,
        config.display.samples,
    )?;
    // The picture fills the output: touches are mapped to its size.
    let (ow, oh) = screen.size();
    let mut config = config.clone();
    config.display.width = ow;
    config.display.height = oh;
    let attract_frames = load_attract(&config)?;
    let dev_dir = &config.input.dev_dir;
    if !dev_dir.is_dir() {
        return Err(LiveError::NoDeviceDir(dev_dir.clone()).into());
    }
    let mut frames = Since::new(clock);
    let input = InputThread::start(config.clone(), frames.epoch_us())?;
    let mut ctl = crate::app::headless::table(cast, &config, true, 0.0);
    tracing::info!(characters = ctl.actors().len(), "characters on the table");
    let timers = Timers::new(
        config.kiosk.idle_after_s,
        opts.seconds,
        notifier.watchdog_interval().map(|d| d.as_secs_f64()),
    );
    let frame_s = 1.0 / f64::from(screen.refresh_hz());
    let textfile =
        Some(config.kiosk.metrics_textfile.clone()).filter(|p| !p.as_os_str().is_empty());
    // This start's number: one more than the metrics file says.
    let starts = textfile
        .as_ref()
        .and_then(|p| crate::reading::read_text(p, 1 << 20).ok())
        .map_or(0, |t| vitals::starts_before(&t))
        + 1;
    let service = ServiceView::new(config.display.service_view);
    let visits = crate::app::visits::Recording::configured(&config, crate::app::visits::unix_now());
    let mut kiosk = Kiosk {
        start: frames,
        screen,
        input,
        notifier,
        config,
        attract_frames,
        attract: None,
        timers,
        stats: RunStats::default(),
        events: Vec::new(),
        last_shown: None,
        ready: false,
        frame_s,
        vitals: Vitals::new(0.0, starts),
        service,
        flips_seen: 0,
        textfile,
        textfile_written: false,
        no_panel_since: None,
        no_panel_said: false,
        no_panel_shown: false,
        visits,
    };
    frame::run(&mut ctl, &mut frames, &mut kiosk)?;
    Ok(kiosk.stopped(frames.now()))
}

impl Kiosk<'_> {
    /// The kiosk stopped after `seconds`: its input thread ended, its
    /// figures (the means taken) logged and returned.
    fn stopped(self, seconds: f64) -> RunStats {
        let Kiosk {
            input,
            screen,
            mut stats,
            vitals,
            visits,
            ..
        } = self;
        if let Some(v) = visits {
            v.finish();
        }
        (stats.touch_to_flip_ms_mean, stats.touch_to_flip_n) = vitals.run_latency();
        input.stop();
        stats.seconds = seconds;
        stats.flips = screen.flips();
        if stats.frames > 0 {
            stats.render_ms_mean /= stats.frames as f64;
        }
        tracing::info!(
            seconds = stats.seconds,
            frames = stats.frames,
            flips = stats.flips,
            touch_frames = stats.touch_frames,
            gpu_rebuilds = stats.gpu_rebuilds,
            display_losses = stats.display_losses,
            render_ms_mean = stats.render_ms_mean,
            render_ms_max = stats.render_ms_max,
            touch_to_flip_ms_mean = stats.touch_to_flip_ms_mean,
            touch_to_flip_n = stats.touch_to_flip_n,
            "stopped"
        );
        stats
    }
}

/// What was last shown: the posture, the camera's yaw, pitch and
/// distance, and how many fingers had marks.
type Shown = (Vec<crate::character::skeleton::Pose>, f64, f64, f64, usize);

/// The kiosk's backend of the frame loop: touches from the panels (and
/// the attract loop when idle), frames to the KMS output.
struct Kiosk<'a> {
    /// The frames' time 0, for the events' stamps.
    start: Since<'a>,
    screen: Screen,
    input: InputThread,
    notifier: Notifier,
    config: Config,
    attract_frames: Option<Vec<ScreenFrame>>,
    attract: Option<Attract>,
    timers: Timers,
    stats: RunStats,
    events: Vec<HubEvent>,
    last_shown: Option<Shown>,
    ready: bool,
    frame_s: f64,
    vitals: Vitals,
    service: ServiceView,
    /// Page flips counted so far (the screen's count).
    flips_seen: u64,
    /// Where the vital signs go every minute, if anywhere.
    textfile: Option<PathBuf>,
    textfile_written: bool,
    /// Since when no touchscreen is read, whether the log said so, and
    /// whether the display shows it.
    no_panel_since: Option<f64>,
    no_panel_said: bool,
    no_panel_shown: bool,
    /// The record of what visitors do, if one is configured.
    visits: Option<crate::app::visits::Recording>,
}

/// After this long without a touchscreen the display says so (s).
const NO_PANEL_NOTICE_S: f64 = 5.0;
const NO_PANEL_NOTICE: &str = "No touchscreen found: plug one in";

impl Backend for Kiosk<'_> {
    type Error = RunError;

    fn stop(&mut self, t: f64) -> bool {
        let stop = crate::platform::signals::stop_requested() || self.timers.stop_due(t);
        if stop {
            self.notifier.notify("STOPPING=1");
            tracing::info!("stopping");
        }
        stop
    }

    fn feed(&mut self, ctl: &mut Stage, t: f64) {
        // Touches: real ones first end the attract loop.
        self.input.drain(&mut self.events);
        for e in self.events.drain(..) {
            match e {
                HubEvent::Touch { mut frame, .. } => {
                    if let Some(mut a) = self.attract.take() {
                        tracing::info!("touched: attract loop ends");
                        if let Some(f) = a.lift(t) {
                            ctl.touch(&f);
                        }
                    }
                    self.stats.touch_frames += 1;
                    let downs = frame
                        .contacts
                        .iter()
                        .filter(|c| c.phase == crate::input::touch::Phase::Down)
                        .count();
                    self.vitals.touched(frame.t, downs);
                    frame.t = self.timers.touch(frame.t, t);
                    self.service.touch(&frame, t);
                    ctl.touch(&frame);
                }
                HubEvent::Added { device, path, name } => {
                    tracing::info!(path = %path.display(), %name, "touchscreen added");
                    self.service
                        .panels
                        .insert(device, format!("{} \"{name}\"", path.display()));
                }
                HubEvent::Removed { device, path, name } => {
                    tracing::info!(path = %path.display(), %name, "touchscreen removed");
                    self.service.panels.remove(&device);
                }
            }
        }
        // Idle: rest, then the attract loop.
        if self.timers.rest_due(ctl.idle_s()) {
            tracing::info!(idle_s = ctl.idle_s(), "nobody touched: back to rest");
            ctl.go_to_rest();
            self.attract = self
                .attract_frames
                .as_ref()
                .map(|frames| Attract::new(frames.clone(), t + ATTRACT_DELAY_S));
        }
        if let Some(a) = self.attract.as_mut() {
            let mut due = Vec::new();
            a.due(t, &mut due);
            for f in &due {
                ctl.touch(f);
            }
        }
    }

    fn frame(&mut self, ctl: &mut Stage, t: f64) -> Result<Flow, RunError> {
        let events = ctl.take_events();
        for (_, e) in &events {
            if let crate::control::action::timeline::ActionEvent::Started { action, .. } = e {
                tracing::info!(%action, "action started");
                self.vitals.action_started();
            }
        }
        let touches = ctl.take_touches();
        if let Some(v) = &mut self.visits {
            v.frame(&touches, &events, t, self.attract.is_none());
            self.vitals.totals.today = Some(v.writer().today());
        }
        self.service.today = self.vitals.totals.today;
        self.service.tick(t);
        self.vital_signs(t);
        self.recover_display(t);
        for h in ctl.take_hits() {
            self.vitals.hit(h.impulse_ns);
        }
        let orbit = ctl.rig().orbit;
        let marks = ctl.marks(self.config.display.trajectories);
        let key = (
            ctl.actors()
                .iter()
                .map(|a| a.ctl.pose().clone())
                .collect::<Vec<_>>(),
            orbit.yaw,
            orbit.pitch,
            orbit.distance,
            marks.fingers.len(),
        );
        let no_panel = self.no_panel(t);
        let changed = self.service.on
            || no_panel != self.no_panel_shown
            || self.last_shown.as_ref().is_none_or(|s| {
                s.0.len() != key.0.len()
                    || s.0.iter().zip(&key.0).any(|(a, b)| !same_pose(a, b))
                    || (s.1, s.2, s.3, s.4) != (key.1, key.2, key.3, key.4)
                    || !marks.fingers.is_empty()
                    || ctl.action().is_some()
            });
        if self.timers.can_draw() && !self.screen.flip_pending() && changed {
            self.draw(ctl, t, marks, key, no_panel)?;
        }
        let screen = &mut self.screen;
        if !self.ready && screen.flip_pending() {
            // The first frame reaches the screen at this flip.
            if screen.wait_flip(Duration::from_millis(500))? {
                self.ready = true;
                self.notifier
                    .notify("READY=1\nSTATUS=showing the character");
                tracing::info!(output = screen.name(), "first frame on screen: ready");
            }
        }
        if self.timers.watchdog_due(t) {
            self.notifier.notify("WATCHDOG=1");
        }
        // Wait for a flip, a touch, or the next frame's time; longer when
        // nothing moves (no busy-wait when idle).
        let moving = changed || self.attract.is_some();
        let wait_s = timers::wait_s(moving, screen.fd().is_none(), self.frame_s);
        wait(&self.input, screen, Duration::from_secs_f64(wait_s))?;
        if screen.fd().is_some() && screen.flips() > self.flips_seen {
            self.flips_seen = screen.flips();
            self.vitals.flipped(self.start.now());
        }
        Ok(Flow::Continue)
    }
}

impl Kiosk<'_> {
    /// The display taken back once it is ours again, and the GPU rebuilt
    /// once it can be, each when its retry is due.
    fn recover_display(&mut self, t: f64) {
        let (screen, timers) = (&mut self.screen, &mut self.timers);
        if timers.display_retry_due(t) && screen.reacquire() {
            tracing::info!("display back: showing again");
            timers.display_back();
            self.last_shown = None;
        }
        if timers.gpu_retry_due(t) {
            match screen.rebuild() {
                Ok(()) => {
                    self.stats.gpu_rebuilds += 1;
                    timers.gpu_back();
                    self.last_shown = None;
                    tracing::info!("GPU device rebuilt");
                }
                Err(e) => {
                    tracing::warn!(error = %e, "GPU still unavailable; retrying");
                }
            }
        }
    }

    /// Whether no touchscreen has been read for a while (the display then
    /// says so; the kiosk goes on and picks one up when it is plugged
    /// in), said in the journal once.
    fn no_panel(&mut self, t: f64) -> bool {
        let no_panel = self.service.panels.is_empty() && {
            let since = *self.no_panel_since.get_or_insert(t);
            t - since >= NO_PANEL_NOTICE_S
        };
        if self.service.panels.is_empty() {
            if no_panel && !self.no_panel_said {
                tracing::warn!(dir = %self.config.input.dev_dir.display(), "no touchscreen is read: the display says so until one is plugged in (marionette list-devices says what each input is)");
                self.no_panel_said = true;
            }
        } else {
            self.no_panel_since = None;
            self.no_panel_said = false;
        }
        no_panel
    }

    /// Draw the table with `marks` (and the status line, the notice of no
    /// touchscreen, the service view) and show it; a display error is
    /// answered as its class says.
    fn draw(
        &mut self,
        ctl: &Stage,
        t: f64,
        mut marks: crate::control::marks::Marks,
        key: Shown,
        no_panel: bool,
    ) -> Result<(), RunError> {
        let display = &self.config.display;
        if display.status_line {
            marks.status = status_line(ctl);
        }
        if no_panel {
            marks.status = Some(NO_PANEL_NOTICE.to_owned());
        }
        if self.service.on {
            let now = self.vitals.summary(t);
            let figures = match self.vitals.last {
                Some(last) if now.frames < 30 => last,
                _ => now,
            };
            marks.service = self
                .service
                .marks(&figures, self.screen.name(), display.size());
        }
        let list = frame::compose(ctl, display.rotation(), &marks);
        let started = std::time::Instant::now();
        match self.screen.draw(&list) {
            Ok(true) => {
                let ms = started.elapsed().as_secs_f64() * 1e3;
                self.shown(t, ms, key, no_panel);
            }
            Ok(false) => {}
            Err(e) => match e.class() {
                ErrorClass::TryAgain => {
                    self.stats.display_losses += 1;
                    tracing::warn!(error = %e, "the display is not ours for now (VT switch?): paused until it comes back");
                    self.timers.display_lost(t);
                }
                ErrorClass::GpuGone => {
                    tracing::error!(error = %e, "rendering failed: rebuilding the GPU device");
                    self.timers.gpu_lost(t);
                }
                ErrorClass::Fatal => return Err(e.into()),
            },
        }
        Ok(())
    }

    /// A frame drawn in `ms` went out showing `key`.
    fn shown(&mut self, t: f64, ms: f64, key: Shown, no_panel: bool) {
        let stats = &mut self.stats;
        stats.render_ms_mean += ms;
        stats.render_ms_max = stats.render_ms_max.max(ms);
        stats.frames += 1;
        self.vitals.drawn(ms);
        self.no_panel_shown = no_panel;
        if self.screen.fd().is_none() {
            // The swapchain shows it at the next vblank.
            self.vitals.flipped(t + self.frame_s);
        }
        self.last_shown = Some(key);
        if !self.ready && self.screen.fd().is_none() {
            // The swapchain shows it at the next vblank.
            self.ready = true;
            self.notifier
                .notify("READY=1\nSTATUS=showing the character");
            tracing::info!(
                output = self.screen.name(),
                "first frame queued to the display: ready"
            );
        }
    }
}

impl Kiosk<'_> {
    /// Every minute: the vital signs to the journal and to the textfile
    /// (once as soon as the kiosk shows the character: a start counts at
    /// once).
    fn vital_signs(&mut self, t: f64) {
        let first = self.ready && !self.textfile_written;
        let panels = self.service.panels.len();
        self.textfile_written |= self.vitals.tell(t, first, panels, self.textfile.as_deref());
    }
}

/// The kiosk's status line: the action and its progress, or the held
/// parts; nothing when nothing is held.
fn status_line(ctl: &Stage) -> Option<String> {
    let held: Vec<&str> = ctl.held().iter().map(|r| r.name()).collect();
    Some(match ctl.action() {
        Some((name, time)) => format!("{name} {:>3.0}%", time * 100.0),
        None if held.is_empty() => String::new(),
        None => format!("holding {}", held.join(", ")),
    })
    .filter(|s| !s.is_empty())
}

/// Wait for the card (a page flip) or the input thread, up to `timeout`.
fn wait(input: &InputThread, screen: &mut Screen, timeout: Duration) -> Result<(), RunError> {
    use nix::poll::{PollFd, PollFlags, PollTimeout, poll};
    let card_ready = {
        let mut fds = vec![PollFd::new(input.wake_fd(), PollFlags::POLLIN)];
        if let Some(fd) = screen.fd() {
            fds.push(PollFd::new(fd, PollFlags::POLLIN));
        }
        let ms = u16::try_from(timeout.as_millis()).unwrap_or(u16::MAX);
        match poll(&mut fds, PollTimeout::from(ms)) {
            Ok(_) | Err(nix::errno::Errno::EINTR) => {}
            Err(e) => {
                tracing::warn!(error = %e, "poll failed");
                std::thread::sleep(timeout);
            }
        }
        fds.get(1)
            .and_then(PollFd::revents)
            .is_some_and(|r| r.contains(PollFlags::POLLIN))
    };
    if card_ready {
        screen.dispatch()?;
    }
    Ok(())
}
