//! The long run: the kiosk's path from a panel to a picture, on a made-up
//! clock, driven by hours of random multi-touch. A protocol-B panel of ten
//! slots (the real tracker, calibration and hub behind an injected device
//! opener) gets one to four fingers at a time, dragging body parts and
//! empty space for 0.2 to 6 s, with `SYN_DROPPED` about every two minutes
//! and the panel unplugged for 3 s about every seven; two characters stand
//! side by side so that they meet; the table steps at 30 Hz and one frame
//! in 30 is drawn for real (wgpu; lavapipe where there is no GPU).
//!
//! Sampled each simulated minute: resident memory, open descriptors, the
//! wall time of a step and of a drawn frame; every posture is checked for
//! NaN. After a warm-up of ten simulated minutes, memory must grow by at
//! most 2 MB per simulated hour, with no descriptor more and no NaN; the
//! run exits 1 otherwise.
//!
//! `cargo bench --bench soak -- --hours 2` (default 1).

#![allow(
    clippy::print_stdout,
    clippy::print_stderr,
    clippy::disallowed_methods,
    reason = "the figures are printed for the reader, and steps are timed with the wall clock"
)]

use std::cell::RefCell;
use std::io;
use std::os::fd::BorrowedFd;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::time::Instant;

use marionette::app::config::Config;
use marionette::input::device::DeviceDescription;
use marionette::input::event::{
    ABS_MT_POSITION_X, ABS_MT_POSITION_Y, ABS_MT_SLOT, ABS_MT_TRACKING_ID, BTN_TOUCH, EV_ABS,
    EV_KEY, EV_SYN, RawEvent, SYN_DROPPED, SYN_REPORT,
};
use marionette::input::hub::{DeviceOpener, EventDevice, HubEvent, InputHub, LiveError};
use marionette::input::touch::{KernelState, SlotState};
use marionette::render::gpu::{AdapterChoice, Gpu};
use marionette::render::headless::Headless;
use marionette::screen::Rotation;

const SLOTS: usize = 10;
const MAX: i32 = 4095;
/// The panel's frame interval (60 Hz).
const FRAME_US: i64 = 16_667;
const TICK_HZ: f64 = 30.0;
const DRAW_EVERY: u64 = 30;
const WARM_UP_S: f64 = 600.0;

/// A small deterministic generator.
struct Lcg(u64);

impl Lcg {
    fn unit(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// One finger on the panel: where it is, where it goes, until when.
#[derive(Clone, Copy)]
struct Finger {
    id: i32,
    x: f64,
    y: f64,
    vx: f64,
    vy: f64,
    until_us: i64,
}

/// The panel's fingers, shared by the device and the opener.
struct Panel {
    rng: Lcg,
    fingers: [Option<Finger>; SLOTS],
    next_id: i32,
    time_us: i64,
    plugged: bool,
    /// The next `SYN_DROPPED` and the next unplug (µs).
    drop_at: i64,
    unplug_at: i64,
    replug_at: Option<i64>,
    /// Where characters stand on the panel (device units): fingers go
    /// there more often than to empty space.
    targets: Vec<(f64, f64)>,
    drops: u64,
    unplugs: u64,
}

impl Panel {
    fn new(seed: u64) -> Self {
        Self {
            rng: Lcg(seed),
            fingers: [None; SLOTS],
            next_id: 1,
            time_us: 0,
            plugged: true,
            drop_at: 120_000_000,
            unplug_at: 420_000_000,
            replug_at: None,
            targets: Vec::new(),
            drops: 0,
            unplugs: 0,
        }
    }

    /// One panel frame: fingers land, move and lift; events for it.
    fn frame(&mut self, out: &mut Vec<RawEvent>) {
        self.time_us += FRAME_US;
        let t = self.time_us;
        let ev = |kind, code, value| RawEvent::new(t, kind, code, value);
        if t >= self.drop_at {
            self.drop_at = t + (60.0e6 + self.rng.unit() * 120.0e6) as i64;
            self.drops += 1;
            out.push(ev(EV_SYN, SYN_DROPPED, 0));
            // The kernel's state is read back; then it carries on.
        }
        let down = self.fingers.iter().flatten().count();
        // Someone puts a finger down now and then, up to four at once.
        let land = down < 4 && self.rng.unit() < if down == 0 { 0.02 } else { 0.01 };
        let mut changed = false;
        for slot in 0..SLOTS {
            match self.fingers[slot] {
                Some(f) if t >= f.until_us => {
                    self.fingers[slot] = None;
                    changed = true;
                    out.push(ev(EV_ABS, ABS_MT_SLOT, slot as i32));
                    out.push(ev(EV_ABS, ABS_MT_TRACKING_ID, -1));
                }
                Some(mut f) => {
                    // A drag: smooth, bounded, turning now and then.
                    if self.rng.unit() < 0.03 {
                        f.vx = (self.rng.unit() - 0.5) * 3000.0;
                        f.vy = (self.rng.unit() - 0.5) * 3000.0;
                    }
                    let dt = FRAME_US as f64 / 1e6;
                    f.x = (f.x + f.vx * dt).clamp(0.0, f64::from(MAX));
                    f.y = (f.y + f.vy * dt).clamp(0.0, f64::from(MAX));
                    self.fingers[slot] = Some(f);
                    changed = true;
                    out.push(ev(EV_ABS, ABS_MT_SLOT, slot as i32));
                    out.push(ev(EV_ABS, ABS_MT_POSITION_X, f.x.round() as i32));
                    out.push(ev(EV_ABS, ABS_MT_POSITION_Y, f.y.round() as i32));
                }
                None if land => {
                    let (x, y) = if !self.targets.is_empty() && self.rng.unit() < 0.8 {
                        let k = (self.rng.unit() * self.targets.len() as f64) as usize;
                        let (tx, ty) = self.targets[k.min(self.targets.len() - 1)];
                        (
                            tx + (self.rng.unit() - 0.5) * 500.0,
                            ty + (self.rng.unit() - 0.5) * 900.0,
                        )
                    } else {
                        (
                            self.rng.unit() * f64::from(MAX),
                            self.rng.unit() * f64::from(MAX),
                        )
                    };
                    let f = Finger {
                        id: self.next_id,
                        x: x.clamp(0.0, f64::from(MAX)),
                        y: y.clamp(0.0, f64::from(MAX)),
                        vx: (self.rng.unit() - 0.5) * 2000.0,
                        vy: (self.rng.unit() - 0.5) * 2000.0,
                        until_us: t + (0.2e6 + self.rng.unit() * 5.8e6) as i64,
                    };
                    self.next_id = self.next_id % 65_535 + 1;
                    self.fingers[slot] = Some(f);
                    changed = true;
                    out.push(ev(EV_ABS, ABS_MT_SLOT, slot as i32));
                    out.push(ev(EV_ABS, ABS_MT_TRACKING_ID, f.id));
                    out.push(ev(EV_ABS, ABS_MT_POSITION_X, f.x.round() as i32));
                    out.push(ev(EV_ABS, ABS_MT_POSITION_Y, f.y.round() as i32));
                    break;
                }
                None => {}
            }
        }
        let now_down = self.fingers.iter().flatten().count();
        if (down == 0) != (now_down == 0) {
            out.push(ev(EV_KEY, BTN_TOUCH, i32::from(now_down > 0)));
        }
        if changed || now_down > 0 {
            out.push(ev(EV_SYN, SYN_REPORT, 0));
        }
    }

    fn kernel_state(&self) -> KernelState {
        let mut slots = vec![SlotState::default(); SLOTS];
        for (s, f) in slots.iter_mut().zip(&self.fingers) {
            s.tracking_id = -1;
            if let Some(f) = f {
                s.tracking_id = f.id;
                s.x = f.x.round() as i32;
                s.y = f.y.round() as i32;
            }
        }
        KernelState {
            current_slot: 0,
            slots,
            touch: Some(self.fingers.iter().any(Option::is_some)),
            x: 0,
            y: 0,
        }
    }
}

struct Device {
    panel: Rc<RefCell<Panel>>,
    desc: DeviceDescription,
    /// Panel frames owed up to the hub's `now_us`.
    due_us: Rc<RefCell<i64>>,
}

impl EventDevice for Device {
    fn description(&self) -> &DeviceDescription {
        &self.desc
    }
    fn poll_fd(&self) -> Option<BorrowedFd<'_>> {
        None
    }
    fn read(&mut self, out: &mut Vec<RawEvent>) -> Result<(), LiveError> {
        let mut p = self.panel.borrow_mut();
        if !p.plugged {
            return Err(LiveError::Gone(PathBuf::from("/dev/input/event7")));
        }
        let due = *self.due_us.borrow();
        while p.time_us + FRAME_US <= due {
            p.frame(out);
        }
        Ok(())
    }
    fn kernel_state(&self) -> io::Result<KernelState> {
        Ok(self.panel.borrow().kernel_state())
    }
    fn grab(&mut self) -> io::Result<()> {
        Ok(())
    }
}

#[derive(Clone)]
struct Opener {
    panel: Rc<RefCell<Panel>>,
    desc: DeviceDescription,
    due_us: Rc<RefCell<i64>>,
}

impl DeviceOpener for Opener {
    fn scan(&self, _dir: &Path) -> io::Result<Vec<PathBuf>> {
        Ok(if self.panel.borrow().plugged {
            vec![PathBuf::from("/dev/input/event7")]
        } else {
            Vec::new()
        })
    }
    fn open(&self, _path: &Path) -> io::Result<Box<dyn EventDevice>> {
        if !self.panel.borrow().plugged {
            return Err(io::Error::from(io::ErrorKind::NotFound));
        }
        Ok(Box::new(Device {
            panel: self.panel.clone(),
            desc: self.desc.clone(),
            due_us: self.due_us.clone(),
        }))
    }
}

/// Resident memory (MB) and open descriptors of this process.
fn rss_mb() -> f64 {
    let statm = std::fs::read_to_string("/proc/self/statm").unwrap_or_default();
    let pages: f64 = statm
        .split_whitespace()
        .nth(1)
        .and_then(|p| p.parse().ok())
        .unwrap_or(0.0);
    pages * 4096.0 / 1e6
}

fn fds() -> usize {
    std::fs::read_dir("/proc/self/fd").map_or(0, Iterator::count)
}

/// Least-squares slope of `y` over `x`.
fn slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    if n < 2.0 {
        return 0.0;
    }
    let (mx, my) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x / n, b + y / n));
    let (sxy, sxx) = points.iter().fold((0.0, 0.0), |(a, b), (x, y)| {
        (a + (x - mx) * (y - my), b + (x - mx) * (x - mx))
    });
    if sxx > 0.0 { sxy / sxx } else { 0.0 }
}

const CONFIG: &str = r"
[display]
width = 960
height = 540

[[character]]
place = [-0.45, 0.0]
facing_deg = 90.0

[[character]]
place = [0.45, 0.0]
facing_deg = -90.0
";

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let hours: f64 = args
        .iter()
        .position(|a| a == "--hours")
        .and_then(|i| args.get(i + 1))
        .and_then(|h| h.parse().ok())
        .unwrap_or(1.0);
    let config = Config::parse(CONFIG, Path::new("soak.toml")).expect("the soak configuration");
    let lib = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/library");
    let lib = marionette::character::library::Library::load(&lib).expect("the default library");
    let ch = std::sync::Arc::new(marionette::control::character::Character::from_library(lib));
    let mut stage = marionette::app::headless::table(vec![ch.clone(), ch], &config, true, 0.0);
    let (w, h) = config.display.size();
    let gpu = Gpu::new(AdapterChoice::Auto).expect("an adapter (lavapipe: mesa-vulkan-drivers)");
    let mut headless = Headless::new(gpu, w, h, 1).expect("an offscreen target");

    let panel = Rc::new(RefCell::new(Panel::new(7)));
    // Fingers go where the characters stand (device units).
    for a in stage.actors() {
        let cam = stage.rig().camera();
        let p = a.ctl.world().positions[0];
        if let Some(s) = cam.project(p) {
            panel.borrow_mut().targets.push((
                s.x / f64::from(w) * f64::from(MAX),
                s.y / f64::from(h) * f64::from(MAX),
            ));
        }
    }
    let due_us = Rc::new(RefCell::new(0i64));
    let opener = Opener {
        panel: panel.clone(),
        desc: marionette::tools::synth::panel("soak panel", SLOTS as i32, MAX),
        due_us: due_us.clone(),
    };
    let mut hub = InputHub::new(opener, config.input.clone(), config.display.picture());
    let mut events = Vec::new();
    hub.rescan(0, &mut events);

    let end_s = hours * 3600.0;
    let mut tick: u64 = 0;
    let mut samples: Vec<(f64, f64, usize)> = Vec::new();
    let (mut step_ms, mut draw_ms) = (Vec::new(), Vec::new());
    let (mut nan, mut touch_frames, mut started, mut added, mut removed) =
        (0u64, 0u64, 0u64, 0u64, 0u64);
    let wall = Instant::now();
    println!(
        "simulated_min  rss_mb  fds  step_ms_mean  step_ms_max  draw_ms_mean  touch_frames  actions"
    );
    loop {
        tick += 1;
        let t = tick as f64 / TICK_HZ;
        if t > end_s {
            break;
        }
        let now_us = (t * 1e6) as i64;
        *due_us.borrow_mut() = now_us;
        {
            let mut p = panel.borrow_mut();
            if p.plugged && now_us >= p.unplug_at {
                p.plugged = false;
                p.unplugs += 1;
                p.fingers = [None; SLOTS];
                p.replug_at = Some(now_us + 3_000_000);
            } else if p.replug_at.is_some_and(|r| now_us >= r) {
                p.plugged = true;
                p.replug_at = None;
                p.time_us = now_us;
                p.unplug_at = now_us + (300.0e6 + p.rng.unit() * 240.0e6) as i64;
            }
        }
        if tick % (TICK_HZ as u64) == 0 {
            hub.rescan(now_us, &mut events);
        }
        hub.dispatch(now_us, &mut events);
        for e in events.drain(..) {
            match e {
                HubEvent::Touch { frame, .. } => {
                    touch_frames += 1;
                    stage.touch(&frame);
                }
                HubEvent::Added { .. } => added += 1,
                HubEvent::Removed { .. } => removed += 1,
            }
        }
        let s0 = Instant::now();
        stage.advance(t);
        step_ms.push(s0.elapsed().as_secs_f64() * 1e3);
        started += stage.take_events().len() as u64;
        for a in stage.actors() {
            if a.ctl.world().positions.iter().any(|p| !p.is_finite()) {
                nan += 1;
            }
        }
        if tick % DRAW_EVERY == 0 {
            let d0 = Instant::now();
            let marks = stage.marks(true);
            let list = marionette::app::frame::compose(&stage, Rotation::R0, &marks);
            headless.render(&list).expect("a frame");
            draw_ms.push(d0.elapsed().as_secs_f64() * 1e3);
        }
        if tick % (60 * TICK_HZ as u64) == 0 {
            let (rss, fd) = (rss_mb(), fds());
            samples.push((t, rss, fd));
            let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
            println!(
                "{:>13.0}  {rss:>6.1}  {fd:>3}  {:>12.2}  {:>11.2}  {:>12.1}  {touch_frames:>12}  {started:>7}",
                t / 60.0,
                mean(&step_ms),
                step_ms.iter().copied().fold(0.0, f64::max),
                mean(&draw_ms),
            );
            step_ms.clear();
            draw_ms.clear();
        }
    }
    let after: Vec<(f64, f64)> = samples
        .iter()
        .filter(|s| s.0 >= WARM_UP_S)
        .map(|s| (s.0 / 3600.0, s.1))
        .collect();
    let growth = slope(&after);
    let fd_first = samples.iter().find(|s| s.0 >= WARM_UP_S).map_or(0, |s| s.2);
    let fd_last = samples.last().map_or(0, |s| s.2);
    let p = panel.borrow();
    println!(
        "soak: {hours} simulated h in {:.0} s: rss {:.1} -> {:.1} MB, growth after warm-up {growth:.2} MB per simulated hour, descriptors {fd_first} -> {fd_last}, NaN postures {nan}, {touch_frames} touch frames, {} SYN_DROPPED, {} unplugs ({added} added, {removed} removed), {started} action events",
        wall.elapsed().as_secs_f64(),
        after.first().map_or(0.0, |s| s.1),
        after.last().map_or(0.0, |s| s.1),
        p.drops,
        p.unplugs,
    );
    let ok = growth <= 2.0 && fd_last <= fd_first && nan == 0;
    if !ok {
        eprintln!("soak: FAILED (growth over 2 MB/h, a descriptor more, or NaN)");
        std::process::exit(1);
    }
}
