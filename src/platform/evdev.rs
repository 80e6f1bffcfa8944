//! evdev: the real `/dev/input/event*` devices behind the hub's
//! [`DeviceOpener`]. Nodes are opened with `O_NONBLOCK`, the device's clock
//! is switched to `CLOCK_MONOTONIC`, and the kernel's slot state is read
//! with `EVIOCGMTSLOTS` after `SYN_DROPPED` (an ioctl the evdev crate keeps
//! private). `list-devices` and `watch` read through it.

use std::fs::OpenOptions;
use std::io;
use std::os::fd::{AsFd, AsRawFd, BorrowedFd, OwnedFd};
use std::os::unix::fs::OpenOptionsExt;
use std::path::{Path, PathBuf};
use std::time::{Duration, UNIX_EPOCH};

use crate::input::config::InputConfig;
use crate::input::device::{AbsInfo, DeviceDescription, InputId};
use crate::input::event::{
    ABS_MT_POSITION_X, ABS_MT_POSITION_Y, ABS_MT_SLOT, ABS_MT_TOOL_TYPE, ABS_MT_TRACKING_ID, ABS_X,
    ABS_Y, BTN_TOUCH, EV_KEY, EV_LED, EV_MSC, EV_REL, EV_SW, RawEvent,
};
use crate::input::hub::{
    DeviceListing, DeviceOpener, EventDevice, InputHub, LiveError, list_devices_with,
};
use crate::input::tracker::{KernelState, SlotState};
use crate::screen::Picture;

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
    #[tracing::instrument(level = "debug", name = "evdev_device", err(level = "debug"))]
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
        crate::input::event::SYN_REPORT,
        crate::input::event::SYN_CONFIG,
        crate::input::event::SYN_DROPPED,
    ] {
        d.set_bit(crate::input::event::EV_SYN, code);
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
            let n = self.desc.slot_count().min(crate::input::tracker::MAX_SLOTS);
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

/// Every device node and what marionette makes of it.
pub fn list_devices(input: &InputConfig) -> Result<Vec<DeviceListing>, LiveError> {
    list_devices_with(&EvdevOpener, input)
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
    crate::platform::signals::install_stop_handler();
    let started = std::time::Instant::now();
    let deadline = seconds.map(|s| Duration::from_secs_f64(s.max(0.0)));
    // Touches are stamped in seconds since the watch began.
    let mut hub = InputHub::new(EvdevOpener, input.clone(), picture)
        .since(crate::platform::clock::monotonic_us());
    let mut events = Vec::new();
    let stdout_err = |source| LiveError::Write {
        path: PathBuf::from("stdout"),
        source,
    };
    // Whether the last line said no touchscreen is read: said once, and
    // again after the last one goes.
    let mut said_none = false;
    while !crate::platform::signals::stop_requested()
        && deadline.is_none_or(|d| started.elapsed() < d)
    {
        let now_us = i64::try_from(started.elapsed().as_micros()).unwrap_or(i64::MAX);
        hub.dispatch(now_us, &mut events);
        for e in events.drain(..) {
            let line = serde_json::to_string(&e).map_err(|e| stdout_err(e.into()))?;
            writeln!(out, "{line}").map_err(stdout_err)?;
        }
        if hub.device_count() == 0 && !said_none {
            let status = serde_json::json!({
                "event": "no_touchscreen",
                "dir": dir.display().to_string(),
                "hint": "waiting for one to be plugged in; `marionette list-devices` says what each node is and why it is not used",
            });
            writeln!(out, "{status}").map_err(stdout_err)?;
            tracing::warn!(dir = %dir.display(), "no touchscreen is read; waiting for one (see `marionette list-devices`)");
            said_none = true;
        } else if hub.device_count() > 0 {
            said_none = false;
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
