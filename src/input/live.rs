//! Live input devices: evdev nodes read non-blocking, hotplug, resync ioctls.
//!
//! Devices are reached only through a [`DeviceOpener`], so the hub's logic
//! (which devices to read, unplug and replug, lifting every finger of a
//! device that vanished, re-applying calibration when it returns) is tested
//! without devices. [`EvdevOpener`] is the real one: it opens
//! `/dev/input/event*` with `O_NONBLOCK`, switches the device's clock to
//! `CLOCK_MONOTONIC` and reads the kernel's slot state with `EVIOCGMTSLOTS`
//! after `SYN_DROPPED` (an ioctl the evdev crate keeps private).

use std::collections::{BTreeMap, HashSet};
use std::fmt;
use std::fs::OpenOptions;
use std::io;
use std::os::fd::{AsFd, AsRawFd, BorrowedFd, OwnedFd};
use std::os::unix::fs::OpenOptionsExt;
use std::path::{Path, PathBuf};
use std::time::{Duration, UNIX_EPOCH};

use serde::Serialize;
use thiserror::Error;

use super::calibration::{Calibration, Matrix};
use super::config::InputConfig;
use super::device::{AbsInfo, DeviceDescription, DeviceKind, InputId};
use super::event::{
    ABS_MT_POSITION_X, ABS_MT_POSITION_Y, ABS_MT_SLOT, ABS_MT_TOOL_TYPE, ABS_MT_TRACKING_ID, ABS_X,
    ABS_Y, BTN_TOUCH, EV_KEY, EV_LED, EV_MSC, EV_REL, EV_SW, RawEvent,
};
use super::pipeline::screen_contacts;
use super::tracker::{ContactTracker, KernelState, ResyncSource, SlotState, TouchFrame};
use crate::app::exit;
use crate::input::device::device_label;
use crate::input::touch::ScreenContact;
use crate::screen::Picture;

/// Errors of live devices.
#[derive(Debug, Error)]
pub enum LiveError {
    /// The device is gone (unplugged).
    #[error("device {0} is gone")]
    Gone(PathBuf),
    /// Opening or reading failed.
    #[error("{path}: {source}{hint}", hint = hint_for(source))]
    Io {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
    /// The device folder does not exist (no input subsystem, or a wrong
    /// `input.dev_dir`).
    #[error(
        "there is no input device folder {0}; this machine has no evdev devices, or `input.dev_dir` in the configuration is wrong"
    )]
    NoDeviceDir(PathBuf),
    /// No touchscreen to use.
    #[error("no touchscreen found in {0}; `marionette list-devices` shows what is there")]
    NoTouchscreen(PathBuf),
    /// Writing a file failed.
    #[error("cannot write {path}: {source}")]
    Write {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
}

fn hint_for(e: &io::Error) -> &'static str {
    match e.kind() {
        io::ErrorKind::PermissionDenied => {
            " (permission denied: run as a member of the `input` group, as the shipped systemd unit does)"
        }
        io::ErrorKind::NotFound => " (no such device)",
        _ => "",
    }
}

impl LiveError {
    /// The exit code this error deserves.
    #[must_use]
    pub fn exit_code(&self) -> u8 {
        match self {
            LiveError::Gone(_) | LiveError::NoTouchscreen(_) | LiveError::NoDeviceDir(_) => {
                exit::UNAVAILABLE
            }
            LiveError::Io { source, .. } if source.kind() == io::ErrorKind::PermissionDenied => {
                exit::NOPERM
            }
            LiveError::Io { source, .. } if source.kind() == io::ErrorKind::NotFound => {
                exit::NOINPUT
            }
            LiveError::Io { .. } => exit::IOERR,
            LiveError::Write { .. } => exit::CANTCREAT,
        }
    }
}

/// An open input device.
pub trait EventDevice {
    fn description(&self) -> &DeviceDescription;
    /// For poll(2); `None` if the device cannot be polled.
    fn poll_fd(&self) -> Option<BorrowedFd<'_>>;
    /// Append every event available now; never blocks. `Err(Gone)` when
    /// the device was unplugged.
    fn read(&mut self, out: &mut Vec<RawEvent>) -> Result<(), LiveError>;
    /// The kernel's current slot/axis/key state (after `SYN_DROPPED`).
    fn kernel_state(&self) -> io::Result<KernelState>;
    /// Take the device exclusively (`EVIOCGRAB`).
    fn grab(&mut self) -> io::Result<()>;
}

/// Finds and opens devices. The real one is [`EvdevOpener`].
pub trait DeviceOpener {
    /// The candidate device nodes, in a stable order.
    fn scan(&self, dir: &Path) -> io::Result<Vec<PathBuf>>;
    fn open(&self, path: &Path) -> io::Result<Box<dyn EventDevice>>;
}

/// Opens real `/dev/input/event*` nodes.
#[derive(Clone, Copy, Debug, Default)]
pub struct EvdevOpener;

impl DeviceOpener for EvdevOpener {
    fn scan(&self, dir: &Path) -> io::Result<Vec<PathBuf>> {
        let mut found: Vec<(u32, PathBuf)> = std::fs::read_dir(dir)?
            .filter_map(Result::ok)
            .filter_map(|e| {
                let name = e.file_name();
                let n = name.to_str()?.strip_prefix("event")?.parse().ok()?;
                Some((n, e.path()))
            })
            .collect();
        found.sort();
        Ok(found.into_iter().map(|(_, p)| p).collect())
    }

    fn open(&self, path: &Path) -> io::Result<Box<dyn EventDevice>> {
        Ok(Box::new(EvdevDevice::open(path)?))
    }
}

/// A real evdev device.
pub struct EvdevDevice {
    path: PathBuf,
    dev: evdev::raw_stream::RawDevice,
    desc: DeviceDescription,
}

nix::ioctl_write_ptr!(eviocsclockid, b'E', 0xa0, libc::c_int);

impl EvdevDevice {
    /// Open a device node non-blocking and read its description.
    pub fn open(path: &Path) -> io::Result<Self> {
        let file = OpenOptions::new()
            .read(true)
            .custom_flags(libc::O_NONBLOCK | libc::O_CLOEXEC)
            .open(path)?;
        let fd: OwnedFd = file.into();
        let dev = evdev::raw_stream::RawDevice::from_fd(fd)?;
        // Event times on the monotonic clock, like the rest of the program.
        let clock: libc::c_int = libc::CLOCK_MONOTONIC;
        // SAFETY: EVIOCSCLOCKID reads one int from the pointer we pass.
        if let Err(e) = unsafe { eviocsclockid(dev.as_raw_fd(), &clock) } {
            tracing::debug!(path = %path.display(), error = %e, "cannot switch the device clock to CLOCK_MONOTONIC");
        }
        let desc = describe(&dev)?;
        Ok(Self {
            path: path.to_owned(),
            dev,
            desc,
        })
    }
}

impl EvdevDevice {
    /// The device's file descriptor, for poll(2).
    #[must_use]
    pub fn fd(&self) -> BorrowedFd<'_> {
        self.dev.as_fd()
    }
}

/// A [`DeviceDescription`] from a live device's ioctls.
fn describe(dev: &evdev::raw_stream::RawDevice) -> io::Result<DeviceDescription> {
    let id = dev.input_id();
    let mut d = DeviceDescription {
        name: dev.name().unwrap_or("").to_owned(),
        id: InputId {
            bustype: id.bus_type().0,
            vendor: id.vendor(),
            product: id.product(),
            version: id.version(),
        },
        ..DeviceDescription::default()
    };
    for p in dev.properties().iter() {
        d.properties.insert(p.0);
    }
    if let Some(keys) = dev.supported_keys() {
        for k in keys.iter() {
            d.set_bit(EV_KEY, k.code());
        }
    }
    if let Some(rel) = dev.supported_relative_axes() {
        for r in rel.iter() {
            d.set_bit(EV_REL, r.0);
        }
    }
    if let Some(msc) = dev.misc_properties() {
        for m in msc.iter() {
            d.set_bit(EV_MSC, m.0);
        }
    }
    if let Some(sw) = dev.supported_switches() {
        for s in sw.iter() {
            d.set_bit(EV_SW, s.0);
        }
    }
    if let Some(leds) = dev.supported_leds() {
        for l in leds.iter() {
            d.set_bit(EV_LED, l.0);
        }
    }
    if let Some(axes) = dev.supported_absolute_axes() {
        let state = dev.get_abs_state()?;
        for a in axes.iter() {
            if let Some(s) = state.get(usize::from(a.0)) {
                d.set_abs(
                    a.0,
                    AbsInfo {
                        value: s.value,
                        minimum: s.minimum,
                        maximum: s.maximum,
                        fuzz: s.fuzz,
                        flat: s.flat,
                        resolution: s.resolution,
                    },
                );
            }
        }
    }
    // Every evdev device reports these EV_SYN codes.
    for code in [
        super::event::SYN_REPORT,
        super::event::SYN_CONFIG,
        super::event::SYN_DROPPED,
    ] {
        d.set_bit(super::event::EV_SYN, code);
    }
    Ok(d)
}

/// `EVIOCGMTSLOTS(len)`: the kernel's value of one `ABS_MT_*` code for
/// every slot.
fn mt_slot_values(fd: BorrowedFd<'_>, code: u16, slots: usize) -> io::Result<Vec<i32>> {
    let mut buf = vec![0i32; slots + 1];
    buf[0] = i32::from(code);
    let len = std::mem::size_of_val(buf.as_slice());
    let request = nix::request_code_read!(b'E', 0x0a, len);
    // SAFETY: the buffer is `len` bytes, the size encoded in the request;
    // the kernel writes at most that many.
    let rc = unsafe { libc::ioctl(fd.as_raw_fd(), request as _, buf.as_mut_ptr()) };
    if rc < 0 {
        return Err(io::Error::last_os_error());
    }
    buf.remove(0);
    Ok(buf)
}

impl EventDevice for EvdevDevice {
    fn description(&self) -> &DeviceDescription {
        &self.desc
    }

    fn poll_fd(&self) -> Option<BorrowedFd<'_>> {
        Some(self.dev.as_fd())
    }

    fn read(&mut self, out: &mut Vec<RawEvent>) -> Result<(), LiveError> {
        loop {
            match self.dev.fetch_events() {
                Ok(events) => {
                    let mut n = 0;
                    for e in events {
                        n += 1;
                        let t = e.timestamp().duration_since(UNIX_EPOCH).unwrap_or_default();
                        out.push(RawEvent::new(
                            i64::try_from(t.as_micros()).unwrap_or(i64::MAX),
                            e.event_type().0,
                            e.code(),
                            e.value(),
                        ));
                    }
                    if n == 0 {
                        return Ok(());
                    }
                }
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => return Ok(()),
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) if e.raw_os_error() == Some(libc::ENODEV) => {
                    return Err(LiveError::Gone(self.path.clone()));
                }
                Err(source) => {
                    return Err(LiveError::Io {
                        path: self.path.clone(),
                        source,
                    });
                }
            }
        }
    }

    fn kernel_state(&self) -> io::Result<KernelState> {
        let fd = self.dev.as_fd();
        let abs = self.dev.get_abs_state()?;
        let keys = self.dev.get_key_state()?;
        let mut state = KernelState {
            current_slot: abs[usize::from(ABS_MT_SLOT)].value,
            slots: Vec::new(),
            touch: self
                .desc
                .has(EV_KEY, BTN_TOUCH)
                .then(|| keys.contains(evdev::KeyCode(BTN_TOUCH))),
            x: abs[usize::from(ABS_X)].value,
            y: abs[usize::from(ABS_Y)].value,
        };
        if self.desc.has_abs(ABS_MT_SLOT) {
            let n = self.desc.slot_count().min(super::tracker::MAX_SLOTS);
            let ids = mt_slot_values(fd, ABS_MT_TRACKING_ID, n)?;
            let xs = mt_slot_values(fd, ABS_MT_POSITION_X, n)?;
            let ys = mt_slot_values(fd, ABS_MT_POSITION_Y, n)?;
            let tools = if self.desc.has_abs(ABS_MT_TOOL_TYPE) {
                mt_slot_values(fd, ABS_MT_TOOL_TYPE, n)?
            } else {
                vec![0; n]
            };
            state.slots = (0..n)
                .map(|i| SlotState {
                    tracking_id: ids[i],
                    x: xs[i],
                    y: ys[i],
                    tool_type: tools[i],
                })
                .collect();
        }
        Ok(state)
    }

    fn grab(&mut self) -> io::Result<()> {
        self.dev.grab()
    }
}

/// What the hub reports.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "event", rename_all = "snake_case")]
pub enum HubEvent {
    /// A touchscreen is being read.
    Added {
        device: u32,
        path: PathBuf,
        name: String,
    },
    /// A touchscreen went away; its contacts were cancelled first.
    Removed {
        device: u32,
        path: PathBuf,
        name: String,
    },
    /// A frame of contacts in screen pixels.
    Touch {
        device: u32,
        time_us: i64,
        contacts: Vec<ScreenContact>,
    },
}

struct OpenDevice {
    instance: u32,
    path: PathBuf,
    label: String,
    dev: Box<dyn EventDevice>,
    tracker: ContactTracker,
    calibration: Calibration,
}

/// Every touchscreen marionette reads, kept open across unplug and replug.
///
/// The hub owns no clock: callers pass `now_us` (monotonic microseconds)
/// for rescans and for the time of frames it makes itself.
pub struct InputHub<O: DeviceOpener> {
    opener: O,
    input: InputConfig,
    /// The picture touches are mapped onto.
    picture: Picture,
    open: Vec<OpenDevice>,
    /// Nodes that are not touchscreens (or are ignored), so they are not
    /// reopened on every scan; forgotten when the node disappears.
    skipped: HashSet<PathBuf>,
    /// Nodes that failed to open, with the error, logged once.
    failed: BTreeMap<PathBuf, String>,
    next_instance: u32,
    last_scan_us: Option<i64>,
    events: Vec<RawEvent>,
    frames: Vec<TouchFrame>,
}

impl<O: DeviceOpener> InputHub<O> {
    #[must_use]
    pub fn new(opener: O, input: InputConfig, picture: Picture) -> Self {
        Self {
            opener,
            input,
            picture,
            open: Vec::new(),
            skipped: HashSet::new(),
            failed: BTreeMap::new(),
            next_instance: 1,
            last_scan_us: None,
            events: Vec::new(),
            frames: Vec::new(),
        }
    }

    /// Number of touchscreens being read.
    #[must_use]
    pub fn device_count(&self) -> usize {
        self.open.len()
    }

    /// File descriptors to poll for input.
    pub fn poll_fds(&self) -> impl Iterator<Item = BorrowedFd<'_>> {
        self.open.iter().filter_map(|d| d.dev.poll_fd())
    }

    /// Wait up to `timeout` for input on any device (no busy-wait).
    pub fn wait(&self, timeout: Duration) -> io::Result<()> {
        use nix::poll::{PollFd, PollFlags, PollTimeout, poll};
        let mut fds: Vec<PollFd<'_>> = self
            .poll_fds()
            .map(|fd| PollFd::new(fd, PollFlags::POLLIN))
            .collect();
        let ms = u16::try_from(timeout.as_millis()).unwrap_or(u16::MAX);
        if fds.is_empty() {
            std::thread::sleep(timeout);
            return Ok(());
        }
        match poll(&mut fds, PollTimeout::from(ms)) {
            Ok(_) | Err(nix::errno::Errno::EINTR) => Ok(()),
            Err(e) => Err(e.into()),
        }
    }

    /// Look for new devices now, whatever the interval.
    pub fn rescan(&mut self, now_us: i64, out: &mut Vec<HubEvent>) {
        self.last_scan_us = Some(now_us);
        let dir = self.input.dev_dir.clone();
        let paths = match self.opener.scan(&dir) {
            Ok(p) => p,
            Err(e) => {
                if self.failed.insert(dir.clone(), e.to_string()).is_none() {
                    tracing::warn!(dir = %dir.display(), error = %e, "cannot list input devices");
                }
                return;
            }
        };
        self.failed.remove(&dir);
        let present: HashSet<&PathBuf> = paths.iter().collect();
        self.skipped.retain(|p| present.contains(p));
        self.failed.retain(|p, _| present.contains(p) || *p == dir);
        for path in &paths {
            if self.skipped.contains(path) || self.open.iter().any(|d| d.path == *path) {
                continue;
            }
            self.try_open(path, out);
        }
    }

    fn try_open(&mut self, path: &Path, out: &mut Vec<HubEvent>) {
        let mut dev = match self.opener.open(path) {
            Ok(d) => d,
            Err(e) => {
                let msg = e.to_string();
                if self.failed.get(path) != Some(&msg) {
                    tracing::warn!(path = %path.display(), error = %msg, hint = hint_for(&e), "cannot open input device; will retry");
                    self.failed.insert(path.to_owned(), msg);
                }
                return;
            }
        };
        self.failed.remove(path);
        let desc = dev.description().clone();
        let label = device_label(&desc.name, desc.id);
        let settings = self.input.device_for(&desc).cloned();
        let kind = desc.kind();
        if kind != DeviceKind::Touchscreen || settings.as_ref().is_some_and(|s| s.ignore) {
            let why = if kind == DeviceKind::Touchscreen {
                "ignored by the configuration".to_owned()
            } else {
                format!("a {kind}, not a touchscreen")
            };
            tracing::debug!(path = %path.display(), device = %label, "skipping: {why}");
            self.skipped.insert(path.to_owned());
            return;
        }
        let matrix = settings.as_ref().map_or(Matrix::IDENTITY, |s| s.matrix());
        let instance = self.next_instance;
        let tracker = ContactTracker::new(&desc, ResyncSource::Kernel, instance);
        let calibration = desc.position_axes().ok_or(()).and_then(|(x, y)| {
            Calibration::new(&x, &y, matrix, self.picture.rotation, self.picture.size()).map_err(|e| {
                tracing::error!(path = %path.display(), device = %label, error = %e, "cannot calibrate; device not used");
            })
        });
        let (Ok(tracker), Ok(calibration)) = (tracker, calibration) else {
            self.skipped.insert(path.to_owned());
            return;
        };
        if self.input.grab {
            if let Err(e) = dev.grab() {
                tracing::warn!(path = %path.display(), device = %label, error = %e, "cannot grab the device; other programs will see its touches too");
            }
        }
        self.next_instance = self.next_instance.wrapping_add(1).max(1);
        tracing::info!(
            path = %path.display(),
            device = %label,
            protocol = %tracker.protocol(),
            calibration = ?matrix.0,
            configured = settings.is_some(),
            "touchscreen added"
        );
        out.push(HubEvent::Added {
            device: instance,
            path: path.to_owned(),
            name: desc.name.clone(),
        });
        self.open.push(OpenDevice {
            instance,
            path: path.to_owned(),
            label,
            dev,
            tracker,
            calibration,
        });
    }

    /// Read every device, rescanning first when the interval has passed.
    pub fn dispatch(&mut self, now_us: i64, out: &mut Vec<HubEvent>) {
        let interval = i64::try_from(self.input.rescan_interval_ms).unwrap_or(1000) * 1000;
        if self
            .last_scan_us
            .is_none_or(|t| now_us - t >= interval || now_us < t)
        {
            self.rescan(now_us, out);
        }
        let mut i = 0;
        while i < self.open.len() {
            let d = &mut self.open[i];
            self.events.clear();
            let result = d.dev.read(&mut self.events);
            for e in &self.events {
                d.tracker.push(e, &mut self.frames);
                if d.tracker.needs_resync() {
                    match d.dev.kernel_state() {
                        Ok(state) => d.tracker.resync(&state, e.time_us, &mut self.frames),
                        Err(err) => {
                            tracing::warn!(device = %d.label, error = %err, "cannot read the kernel's touch state after SYN_DROPPED; lifting all contacts");
                            d.tracker
                                .resync(&KernelState::default(), e.time_us, &mut self.frames);
                        }
                    }
                }
            }
            for f in self.frames.drain(..) {
                out.push(HubEvent::Touch {
                    device: d.instance,
                    time_us: f.time_us,
                    contacts: screen_contacts(&f, &d.calibration),
                });
            }
            match result {
                Ok(()) => i += 1,
                Err(e) => {
                    let d = self.open.remove(i);
                    self.remove(d, now_us, &e, out);
                }
            }
        }
    }

    fn remove(&mut self, mut d: OpenDevice, now_us: i64, why: &LiveError, out: &mut Vec<HubEvent>) {
        match why {
            LiveError::Gone(_) => {
                tracing::warn!(path = %d.path.display(), device = %d.label, "touchscreen unplugged; waiting for it to return")
            }
            e => {
                tracing::error!(path = %d.path.display(), device = %d.label, error = %e, "touchscreen failed; closing it and retrying")
            }
        }
        if let Some(f) = d.tracker.cancel_all(now_us) {
            out.push(HubEvent::Touch {
                device: d.instance,
                time_us: f.time_us,
                contacts: screen_contacts(&f, &d.calibration),
            });
        }
        out.push(HubEvent::Removed {
            device: d.instance,
            path: d.path,
            name: d.dev.description().name.clone(),
        });
    }
}

/// One line of `marionette list-devices`.
#[derive(Clone, Debug, Serialize)]
pub struct DeviceListing {
    pub path: PathBuf,
    pub name: Option<String>,
    pub usb: Option<String>,
    pub kind: Option<DeviceKind>,
    pub protocol: Option<String>,
    pub slots: Option<usize>,
    pub x_range: Option<(i32, i32)>,
    pub y_range: Option<(i32, i32)>,
    /// What marionette does with it.
    pub verdict: String,
    pub error: Option<String>,
}

impl fmt::Display for DeviceListing {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.path.display())?;
        if let Some(e) = &self.error {
            return write!(f, "  cannot open: {e}");
        }
        write!(
            f,
            "  \"{}\" [{}] {}",
            self.name.as_deref().unwrap_or(""),
            self.usb.as_deref().unwrap_or("?"),
            self.kind.map_or("?".to_owned(), |k| k.to_string())
        )?;
        if let Some(p) = &self.protocol {
            write!(f, ", protocol {p}")?;
        }
        if let Some(s) = self.slots {
            write!(f, ", {s} slots")?;
        }
        if let (Some(x), Some(y)) = (self.x_range, self.y_range) {
            write!(f, ", x {}..{} y {}..{}", x.0, x.1, y.0, y.1)?;
        }
        write!(f, "  => {}", self.verdict)
    }
}

/// Describe a device for `list-devices`.
#[must_use]
pub fn listing(path: &Path, desc: &DeviceDescription, input: &InputConfig) -> DeviceListing {
    let kind = desc.kind();
    let settings = input.device_for(desc);
    let verdict = match (kind, settings) {
        (DeviceKind::Touchscreen, Some(s)) if s.ignore => "ignored (configuration)".to_owned(),
        (DeviceKind::Touchscreen, Some(s)) => format!("used, calibration {:?}", s.calibration),
        (DeviceKind::Touchscreen, None) => {
            "used, identity calibration (no [[input.device]] entry)".to_owned()
        }
        (DeviceKind::Pen, _) => "not used (pen; fingers only)".to_owned(),
        (DeviceKind::Touchpad, _) => "not used (touchpad: not on the screen)".to_owned(),
        (DeviceKind::Other, _) => "not used".to_owned(),
    };
    let axes = desc.position_axes();
    DeviceListing {
        path: path.to_owned(),
        name: Some(desc.name.clone()),
        usb: Some(desc.id.to_string()),
        kind: Some(kind),
        protocol: desc.protocol().map(|p| p.to_string()),
        slots: desc.has_abs(ABS_MT_SLOT).then(|| desc.slot_count()),
        x_range: axes.map(|(x, _)| (x.minimum, x.maximum)),
        y_range: axes.map(|(_, y)| (y.minimum, y.maximum)),
        verdict,
        error: None,
    }
}

pub(crate) fn scan_error(dir: &Path, source: io::Error) -> LiveError {
    if source.kind() == io::ErrorKind::NotFound {
        LiveError::NoDeviceDir(dir.to_owned())
    } else {
        LiveError::Io {
            path: dir.to_owned(),
            source,
        }
    }
}

/// Every device node and what marionette makes of it.
pub fn list_devices(input: &InputConfig) -> Result<Vec<DeviceListing>, LiveError> {
    list_devices_with(&EvdevOpener, input)
}

/// [`list_devices`] through any opener.
pub fn list_devices_with(
    opener: &dyn DeviceOpener,
    input: &InputConfig,
) -> Result<Vec<DeviceListing>, LiveError> {
    let dir = &input.dev_dir;
    let paths = opener.scan(dir).map_err(|source| scan_error(dir, source))?;
    Ok(paths
        .iter()
        .map(|p| match opener.open(p) {
            Ok(d) => listing(p, d.description(), input),
            Err(e) => DeviceListing {
                path: p.clone(),
                name: None,
                usb: None,
                kind: None,
                protocol: None,
                slots: None,
                x_range: None,
                y_range: None,
                verdict: "not used".to_owned(),
                error: Some(format!("{e}{}", hint_for(&e))),
            },
        })
        .collect())
}

/// `marionette watch`: read every touchscreen as the kiosk will and print
/// what the hub reports, one JSON object per line, until SIGINT/SIGTERM or
/// `seconds`. For operators checking a panel and its calibration.
pub fn watch(
    input: &InputConfig,
    picture: Picture,
    seconds: Option<f64>,
    out: &mut dyn io::Write,
) -> Result<(), LiveError> {
    let dir = &input.dev_dir;
    if !dir.is_dir() {
        return Err(LiveError::NoDeviceDir(dir.clone()));
    }
    crate::app::signals::install_stop_handler();
    let started = std::time::Instant::now();
    let deadline = seconds.map(|s| Duration::from_secs_f64(s.max(0.0)));
    let mut hub = InputHub::new(EvdevOpener, input.clone(), picture);
    let mut events = Vec::new();
    let stdout_err = |source| LiveError::Write {
        path: PathBuf::from("stdout"),
        source,
    };
    while !crate::app::signals::stop_requested() && deadline.is_none_or(|d| started.elapsed() < d) {
        let now_us = i64::try_from(started.elapsed().as_micros()).unwrap_or(i64::MAX);
        hub.dispatch(now_us, &mut events);
        for e in events.drain(..) {
            let line = serde_json::to_string(&e).map_err(|e| stdout_err(e.into()))?;
            writeln!(out, "{line}").map_err(stdout_err)?;
        }
        out.flush().map_err(stdout_err)?;
        let wait = Duration::from_millis(100.min(input.rescan_interval_ms));
        hub.wait(wait).map_err(|source| LiveError::Io {
            path: dir.clone(),
            source,
        })?;
    }
    Ok(())
}
