//! `marionette run`: the kiosk. Fullscreen on a KMS output, reading every
//! touchscreen through evdev, stepping the character with the real time
//! and showing a frame per vblank; idle, it returns to rest and performs
//! an attract recording; panels come and go, a VT switch or a lost GPU
//! pause it and it carries on; SIGTERM/SIGINT end it cleanly within a
//! second. systemd hears READY=1 after the first page flip and WATCHDOG=1
//! from the loop.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use thiserror::Error;

use super::config::Config;
use crate::control::controller::{Character, Controller};
use crate::display::present::{OutputChoice, PresentError, PresenterKind};
use crate::display::screen::Screen;
use crate::input::hub::{HubEvent, InputHub, LiveError};
use crate::input::touch::Phase;
use crate::input::touch::{ScreenContact, ScreenFrame};
use crate::platform::clock::monotonic_us;
use crate::platform::evdev::EvdevOpener;
use crate::platform::notify::Notifier;
use crate::render::gpu::{AdapterChoice, GpuError};
use crate::render::scene::{self, View};

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
}

/// Contacts from the attract recording are kept apart from real ones.
const ATTRACT_ID: u64 = 1 << 48;

/// The attract recording playing in a loop.
struct Attract {
    frames: Vec<ScreenFrame>,
    /// Controller time at which the recording's time 0 plays.
    start: f64,
    next: usize,
    down: std::collections::BTreeSet<u64>,
}

impl Attract {
    /// Frames due by `t`, shifted to controller time; the recording starts
    /// over a second after it ends.
    fn due(&mut self, t: f64, out: &mut Vec<ScreenFrame>) {
        while let Some(f) = self.frames.get(self.next) {
            if self.start + f.t > t {
                return;
            }
            let mut f = f.clone();
            f.t += self.start;
            for c in &mut f.contacts {
                c.id += ATTRACT_ID;
                if c.phase.is_down() {
                    self.down.insert(c.id);
                } else {
                    self.down.remove(&c.id);
                }
            }
            out.push(f);
            self.next += 1;
        }
        let end = self.frames.last().map_or(0.0, |f| f.t);
        if t > self.start + end + 1.0 {
            self.start = t;
            self.next = 0;
        }
    }

    /// A frame that lifts what the recording still holds.
    fn lift(&mut self, t: f64) -> Option<ScreenFrame> {
        if self.down.is_empty() {
            return None;
        }
        let contacts = std::mem::take(&mut self.down)
            .into_iter()
            .map(|id| ScreenContact {
                id,
                phase: Phase::Cancel,
                tool: crate::input::touch::Tool::Finger,
                raw: crate::input::calibration::RawPoint { x: 0, y: 0 },
                screen: crate::screen::ScreenPoint::new(0.0, 0.0),
            })
            .collect();
        Some(ScreenFrame { t, contacts })
    }
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

/// Run the kiosk until SIGTERM/SIGINT (or `opts.seconds`).
pub fn run(ch: Arc<Character>, config: &Config, opts: &RunOptions) -> Result<RunStats, RunError> {
    crate::platform::signals::install_stop_handler();
    let notifier = Notifier::from_env();
    let choice = OutputChoice::from_config(&config.display);
    let kind = PresenterKind::parse(&config.display.presenter).unwrap_or_default();
    let mut screen = Screen::open(
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
    let (pw, ph) = config.display.size();
    let attract_frames = load_attract(&config)?;
    let dev_dir = &config.input.dev_dir;
    if !dev_dir.is_dir() {
        return Err(LiveError::NoDeviceDir(dev_dir.clone()).into());
    }
    let input = InputThread::start(config.clone())?;
    let start_us = monotonic_us();
    let clock = |us: i64| (us - start_us) as f64 / 1e6;
    let mut ctl = Controller::new(
        ch,
        config.control_settings(),
        f64::from(pw),
        f64::from(ph),
        0.0,
    );
    let mut stats = RunStats::default();
    let mut events = Vec::new();
    let mut attract: Option<Attract> = None;
    let mut resting = false;
    let mut ready = false;
    let mut last_watchdog = 0.0f64;
    let watchdog = notifier.watchdog_interval().map(|d| d.as_secs_f64());
    let mut last_shown: Option<(crate::character::skeleton::Pose, f64, f64, f64, usize)> = None;
    let mut paused_at: Option<f64> = None;
    let mut gpu_lost_at: Option<f64> = None;
    let mut last_touch_t = 0.0f64;
    let frame_s = 1.0 / f64::from(screen.refresh_hz());
    loop {
        let now_us = monotonic_us();
        let t = clock(now_us);
        if crate::platform::signals::stop_requested() || opts.seconds.is_some_and(|s| t >= s) {
            notifier.notify("STOPPING=1");
            tracing::info!("stopping");
            break;
        }
        // Touches: real ones first end the attract loop.
        input.drain(&mut events);
        for e in events.drain(..) {
            match e {
                HubEvent::Touch {
                    device,
                    time_us,
                    mut contacts,
                } => {
                    if let Some(mut a) = attract.take() {
                        tracing::info!("touched: attract loop ends");
                        if let Some(f) = a.lift(t) {
                            ctl.touch(&f);
                        }
                    }
                    resting = false;
                    stats.touch_frames += 1;
                    for c in &mut contacts {
                        c.id += u64::from(device) << 32;
                    }
                    let ft = clock(time_us).clamp(last_touch_t, t);
                    last_touch_t = ft;
                    ctl.touch(&ScreenFrame { t: ft, contacts });
                }
                HubEvent::Added { path, name, .. } => {
                    tracing::info!(path = %path.display(), %name, "touchscreen added");
                }
                HubEvent::Removed { path, name, .. } => {
                    tracing::info!(path = %path.display(), %name, "touchscreen removed");
                }
            }
        }
        // Idle: rest, then the attract loop.
        if !resting && ctl.idle_s() > config.kiosk.idle_after_s {
            tracing::info!(idle_s = ctl.idle_s(), "nobody touched: back to rest");
            ctl.go_to_rest();
            resting = true;
            attract = attract_frames.as_ref().map(|frames| Attract {
                frames: frames.clone(),
                start: t + 2.0,
                next: 0,
                down: std::collections::BTreeSet::new(),
            });
        }
        if let Some(a) = attract.as_mut() {
            let mut due = Vec::new();
            a.due(t, &mut due);
            for f in &due {
                ctl.touch(f);
            }
        }
        ctl.advance(t);
        // Show it, unless the display is another program's for now.
        if let Some(since) = paused_at {
            if t - since > 0.5 {
                if screen.reacquire() {
                    tracing::info!("display back: showing again");
                    paused_at = None;
                    last_shown = None;
                } else {
                    paused_at = Some(t);
                }
            }
        }
        if let Some(since) = gpu_lost_at {
            if t - since > 1.0 {
                match screen.rebuild() {
                    Ok(()) => {
                        stats.gpu_rebuilds += 1;
                        gpu_lost_at = None;
                        last_shown = None;
                        tracing::info!("GPU device rebuilt");
                    }
                    Err(e) => {
                        tracing::warn!(error = %e, "GPU still unavailable; retrying");
                        gpu_lost_at = Some(t);
                    }
                }
            }
        }
        let orbit = ctl.rig.orbit;
        let marks = ctl.marks(config.display.trajectories);
        let key = (
            ctl.pose().clone(),
            orbit.yaw,
            orbit.pitch,
            orbit.distance,
            marks.fingers.len(),
        );
        let changed = last_shown.as_ref().is_none_or(|s| {
            !same_pose(&s.0, &key.0)
                || (s.1, s.2, s.3, s.4) != (key.1, key.2, key.3, key.4)
                || !marks.fingers.is_empty()
                || ctl.action().is_some()
        });
        if paused_at.is_none() && gpu_lost_at.is_none() && !screen.flip_pending() && changed {
            let view = View {
                camera: ctl.rig.camera(),
                rotation: config.display.rotation(),
            };
            let mut marks = marks;
            if config.display.status_line {
                let held: Vec<&str> = ctl.held().iter().map(|r| r.name()).collect();
                marks.status = Some(match ctl.action() {
                    Some((name, time)) => format!("{name} {:>3.0}%", time * 100.0),
                    None if held.is_empty() => String::new(),
                    None => format!("holding {}", held.join(", ")),
                })
                .filter(|s| !s.is_empty());
            }
            let c = ctl.character();
            let list = scene::compose(
                &view,
                &c.lib.skeleton,
                &c.roles,
                ctl.world(),
                &ctl.held(),
                &marks,
            );
            let started = std::time::Instant::now();
            match screen.draw(&list) {
                Ok(shown) => {
                    if shown {
                        let ms = started.elapsed().as_secs_f64() * 1e3;
                        stats.render_ms_mean += ms;
                        stats.render_ms_max = stats.render_ms_max.max(ms);
                        stats.frames += 1;
                        last_shown = Some(key);
                        if !ready && screen.fd().is_none() {
                            // The swapchain shows it at the next vblank.
                            ready = true;
                            notifier.notify("READY=1\nSTATUS=showing the character");
                            tracing::info!(
                                output = screen.name(),
                                "first frame queued to the display: ready"
                            );
                        }
                    }
                }
                Err(PresentError::LostMaster(card)) => {
                    stats.display_losses += 1;
                    tracing::warn!(card = %card.display(), "the display was taken (VT switch?): paused until it comes back");
                    paused_at = Some(t);
                }
                Err(PresentError::Gpu(e)) => {
                    tracing::error!(error = %e, "rendering failed: rebuilding the GPU device");
                    gpu_lost_at = Some(t);
                }
                Err(e) => return Err(e.into()),
            }
        }
        if !ready && screen.flip_pending() {
            // The first frame reaches the screen at this flip.
            if screen.wait_flip(Duration::from_millis(500))? {
                ready = true;
                notifier.notify("READY=1\nSTATUS=showing the character");
                tracing::info!(output = screen.name(), "first frame on screen: ready");
            }
        }
        if let Some(w) = watchdog {
            if t - last_watchdog >= w {
                notifier.notify("WATCHDOG=1");
                last_watchdog = t;
            }
        }
        // Wait for a flip, a touch, or the next frame's time; longer when
        // nothing moves (no busy-wait when idle).
        let wait_s = if (changed || attract.is_some()) && screen.fd().is_none() {
            // The direct presenter's swapchain already waited for vblank.
            0.0
        } else if changed || attract.is_some() {
            frame_s
        } else {
            0.1
        };
        wait(
            &input,
            &mut screen,
            Duration::from_secs_f64(wait_s.min(0.1)),
        )?;
    }
    input.stop();
    stats.seconds = clock(monotonic_us());
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
        "stopped"
    );
    Ok(stats)
}

/// The touchscreens are read on their own thread, so that a slow frame
/// (a CPU renderer under load) never lets the kernel's event buffers
/// overflow; it wakes the render loop through a socket.
pub(crate) struct InputThread {
    events: std::sync::mpsc::Receiver<HubEvent>,
    wake: std::os::unix::net::UnixStream,
    stop: Arc<std::sync::atomic::AtomicBool>,
    handle: Option<std::thread::JoinHandle<()>>,
}

impl InputThread {
    pub(crate) fn start(config: Config) -> Result<Self, LiveError> {
        use std::io::Write as _;
        let (tx, rx) = std::sync::mpsc::channel();
        let (wake, mut waker) =
            std::os::unix::net::UnixStream::pair().map_err(|source| LiveError::Io {
                path: PathBuf::from("socketpair"),
                source,
            })?;
        wake.set_nonblocking(true).ok();
        waker.set_nonblocking(true).ok();
        let stop = Arc::new(std::sync::atomic::AtomicBool::new(false));
        let stopping = stop.clone();
        let handle = std::thread::Builder::new()
            .name("input".into())
            .spawn(move || {
                let mut hub =
                    InputHub::new(EvdevOpener, config.input.clone(), config.display.picture());
                let mut events = Vec::new();
                let wait = Duration::from_millis(50.min(config.input.rescan_interval_ms));
                while !stopping.load(std::sync::atomic::Ordering::SeqCst) {
                    hub.dispatch(monotonic_us(), &mut events);
                    if !events.is_empty() {
                        for e in events.drain(..) {
                            if tx.send(e).is_err() {
                                return;
                            }
                        }
                        // A full socket already has a wake-up pending.
                        let _ = waker.write(&[1]);
                    }
                    if let Err(e) = hub.wait(wait) {
                        tracing::warn!(error = %e, "waiting for input failed");
                        std::thread::sleep(wait);
                    }
                }
            })
            .map_err(|source| LiveError::Io {
                path: PathBuf::from("input thread"),
                source,
            })?;
        Ok(Self {
            events: rx,
            wake,
            stop,
            handle: Some(handle),
        })
    }

    /// Everything read since the last call.
    pub(crate) fn drain(&self, out: &mut Vec<HubEvent>) {
        use std::io::Read as _;
        let mut buf = [0u8; 64];
        while matches!((&self.wake).read(&mut buf), Ok(n) if n > 0) {}
        out.extend(self.events.try_iter());
    }

    pub(crate) fn stop(mut self) {
        self.stop.store(true, std::sync::atomic::Ordering::SeqCst);
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}

/// Wait for the card (a page flip) or the input thread, up to `timeout`.
fn wait(input: &InputThread, screen: &mut Screen, timeout: Duration) -> Result<(), RunError> {
    use nix::poll::{PollFd, PollFlags, PollTimeout, poll};
    use std::os::fd::AsFd as _;
    let card_ready = {
        let mut fds = vec![PollFd::new(input.wake.as_fd(), PollFlags::POLLIN)];
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::calibration::RawPoint;
    use crate::input::touch::Tool;
    use crate::screen::ScreenPoint;

    fn frame(t: f64, id: u64, phase: Phase) -> ScreenFrame {
        ScreenFrame {
            t,
            contacts: vec![ScreenContact {
                id,
                phase,
                tool: Tool::Finger,
                raw: RawPoint { x: 0, y: 0 },
                screen: ScreenPoint::new(10.0, 20.0),
            }],
        }
    }

    #[test]
    fn attract_plays_in_a_loop_and_lets_go_when_touched() {
        let mut a = Attract {
            frames: vec![
                frame(0.0, 1, Phase::Down),
                frame(0.5, 1, Phase::Move),
                frame(1.0, 1, Phase::Up),
            ],
            start: 10.0,
            next: 0,
            down: std::collections::BTreeSet::new(),
        };
        let mut out = Vec::new();
        a.due(9.9, &mut out);
        assert!(out.is_empty(), "nothing before its start");
        a.due(10.6, &mut out);
        assert_eq!(out.len(), 2);
        assert!((out[1].t - 10.5).abs() < 1e-9, "shifted to the loop's time");
        assert_eq!(
            out[0].contacts[0].id,
            1 + ATTRACT_ID,
            "kept apart from real ids"
        );
        // A touch now: the recording's finger is cancelled.
        let lift = a.lift(10.7).unwrap();
        assert_eq!(lift.contacts[0].phase, Phase::Cancel);
        assert!(a.lift(10.8).is_none());
        // Played to its end, it starts over a second later.
        out.clear();
        a.due(11.1, &mut out);
        a.due(12.2, &mut out);
        assert_eq!(a.next, 0);
        assert!((a.start - 12.2).abs() < 1e-9);
        out.clear();
        a.due(12.2, &mut out);
        assert_eq!(out[0].contacts[0].phase, Phase::Down);
    }
}
