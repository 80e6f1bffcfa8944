//! The input hub: every touchscreen marionette reads, through hotplug and
//! `SYN_DROPPED`, turned into touch frames in screen pixels.
//!
//! Devices are reached only through a [`DeviceOpener`], so the hub's logic
//! (which devices to read, unplug and replug, lifting every finger of a
//! device that vanished, re-applying calibration when it returns) is tested
//! without devices. The real opener is `platform::evdev::EvdevOpener`; the
//! hub polls the descriptors its devices give it and opens nothing itself.

use std::collections::{BTreeMap, HashSet};
use std::fmt;
use std::io;
use std::os::fd::BorrowedFd;
use std::path::{Path, PathBuf};
use std::time::Duration;

use serde::Serialize;
use thiserror::Error;

use super::calibration::{Calibration, Matrix};
use super::config::InputConfig;
use super::device::{DeviceDescription, DeviceKind};
use super::event::{ABS_MT_SLOT, RawEvent};
use super::pipeline::to_screen;
use super::remap::Remap;
use super::tracker::{ContactTracker, KernelState, ResyncSource, TouchFrame};
use crate::input::device::device_label;
use crate::input::touch::ScreenFrame;
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

/// Finds and opens devices. The real one is `EvdevOpener`.
pub trait DeviceOpener {
    /// The candidate device nodes, in a stable order.
    fn scan(&self, dir: &Path) -> io::Result<Vec<PathBuf>>;
    fn open(&self, path: &Path) -> io::Result<Box<dyn EventDevice>>;
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
    /// A finished frame of contacts in screen pixels, as the controller
    /// takes it: each contact's id unique across panels (the panel's
    /// instance in its high 32 bits, given by its tracker), its time in
    /// seconds since the hub's epoch ([`InputHub::since`]).
    Touch {
        device: u32,
        #[serde(flatten)]
        frame: ScreenFrame,
    },
}

struct OpenDevice {
    instance: u32,
    path: PathBuf,
    label: String,
    dev: Box<dyn EventDevice>,
    tracker: ContactTracker,
    calibration: Calibration,
    /// The configuration's overrides of its axes and tool.
    remap: Option<Remap>,
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
    /// The instant (µs on the devices' clock) touch frames count their
    /// time from.
    epoch_us: i64,
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
            epoch_us: 0,
            events: Vec::new(),
            frames: Vec::new(),
        }
    }

    /// Touch frames' times in seconds since `epoch_us` on the devices'
    /// clock (the monotonic clock): the caller's time 0.
    #[must_use]
    pub fn since(mut self, epoch_us: i64) -> Self {
        self.epoch_us = epoch_us;
        self
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

    #[tracing::instrument(level = "debug", skip(self, out), fields(path = %path.display()))]
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
        let remap = match self.input.remap_for(&desc) {
            Ok(r) => r,
            Err(e) => {
                tracing::error!(path = %path.display(), device = %label, error = %e, "cannot apply the [[input.device]] axes; device not used");
                self.skipped.insert(path.to_owned());
                return;
            }
        };
        let desc = match &remap {
            Some(r) => r.description(&desc),
            None => desc,
        };
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
            remap,
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
            let _span = tracing::debug_span!("input_device", device = %d.label).entered();
            self.events.clear();
            let result = d.dev.read(&mut self.events);
            for e in &self.events {
                let remapped;
                let e = match &d.remap {
                    None => e,
                    Some(r) => match r.event(e) {
                        Some(m) => {
                            remapped = m;
                            &remapped
                        }
                        None => continue,
                    },
                };
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
                    frame: to_screen(&f, &d.calibration, self.epoch_us),
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
                frame: to_screen(&f, &d.calibration, self.epoch_us),
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
            crate::reading::quote_bare(self.name.as_deref().unwrap_or("")),
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
    // As the configuration's overrides make it read.
    let remapped = input
        .remap_for(desc)
        .ok()
        .flatten()
        .map(|r| r.description(desc));
    let desc = remapped.as_ref().unwrap_or(desc);
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

/// `list_devices` through any opener.
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
