//! `marionette play`: recreate a recorded device with uinput and replay its
//! events with their timing, as `evemu-play` does.

use std::io;
use std::thread::sleep;
use std::time::{Duration, Instant};

use thiserror::Error;

use crate::input::device::DeviceDescription;
use crate::input::evemu::Recording;
use crate::input::event::{EV_KEY, EV_MSC, EV_REL, EV_SW, RawEvent};

/// Errors of `play`.
#[derive(Debug, Error)]
pub enum PlayError {
    /// /dev/uinput cannot be opened.
    #[error(
        "cannot open /dev/uinput: {0} (load the module with `modprobe uinput`; writing it needs root or the uinput group)"
    )]
    Uinput(#[source] io::Error),
    /// The kernel refused the device.
    #[error("cannot create the virtual device \"{name}\": {source}")]
    Create {
        name: String,
        #[source]
        source: io::Error,
    },
    /// Writing events failed.
    #[error("cannot write events to the virtual device: {0}")]
    Write(#[source] io::Error),
}

/// Create a uinput device that looks like `d`.
#[tracing::instrument(level = "debug", skip(d), fields(name = %d.name), err(level = "debug"))]
pub fn create_device(d: &DeviceDescription) -> Result<evdev::uinput::VirtualDevice, PlayError> {
    use evdev::{
        AbsInfo, AbsoluteAxisCode, AttributeSet, BusType, InputId, KeyCode, MiscCode, PropType,
        RelativeAxisCode, SwitchCode, UinputAbsSetup,
    };
    let create = |source| PlayError::Create {
        name: d.name.clone(),
        source,
    };
    let mut b = evdev::uinput::VirtualDevice::builder().map_err(PlayError::Uinput)?;
    let name = if d.name.is_empty() {
        "marionette virtual device"
    } else {
        d.name.as_str()
    };
    b = b.name(name).input_id(InputId::new(
        BusType(d.id.bustype),
        d.id.vendor,
        d.id.product,
        d.id.version,
    ));
    let props: AttributeSet<PropType> = d.properties.iter().map(PropType).collect();
    b = b.with_properties(&props).map_err(create)?;
    let keys: AttributeSet<KeyCode> = d.codes(EV_KEY).iter().map(KeyCode).collect();
    if keys.iter().next().is_some() {
        b = b.with_keys(&keys).map_err(create)?;
    }
    let rel: AttributeSet<RelativeAxisCode> =
        d.codes(EV_REL).iter().map(RelativeAxisCode).collect();
    if rel.iter().next().is_some() {
        b = b.with_relative_axes(&rel).map_err(create)?;
    }
    let msc: AttributeSet<MiscCode> = d.codes(EV_MSC).iter().map(MiscCode).collect();
    if msc.iter().next().is_some() {
        b = b.with_msc(&msc).map_err(create)?;
    }
    let sw: AttributeSet<SwitchCode> = d.codes(EV_SW).iter().map(SwitchCode).collect();
    if sw.iter().next().is_some() {
        b = b.with_switches(&sw).map_err(create)?;
    }
    for (code, a) in &d.abs {
        let setup = UinputAbsSetup::new(
            AbsoluteAxisCode(*code),
            AbsInfo::new(a.value, a.minimum, a.maximum, a.fuzz, a.flat, a.resolution),
        );
        b = b.with_absolute_axis(&setup).map_err(create)?;
    }
    b.build().map_err(create)
}

/// Replay a recording through a new virtual device, with its timing.
pub fn play(rec: &Recording, settle: Duration) -> Result<(), PlayError> {
    let mut dev = create_device(&rec.device)?;
    if let Ok(p) = dev.get_syspath() {
        tracing::info!(syspath = %p.display(), name = %rec.device.name, "virtual device created");
    }
    sleep(settle);
    let start = Instant::now();
    let t0 = rec.events.first().map_or(0, |e| e.time_us);
    let mut frame: Vec<evdev::InputEvent> = Vec::new();
    for e in &rec.events {
        if e.is_syn_report() {
            let due = Duration::from_micros(u64::try_from(e.time_us - t0).unwrap_or(0));
            if let Some(wait) = due.checked_sub(start.elapsed()) {
                sleep(wait);
            }
            // emit() appends the SYN_REPORT itself.
            dev.emit(&frame).map_err(PlayError::Write)?;
            frame.clear();
        } else {
            frame.push(to_evdev(e));
        }
    }
    tracing::info!(
        frames = rec.frame_count(),
        seconds = rec.duration_s(),
        "replay finished"
    );
    Ok(())
}

fn to_evdev(e: &RawEvent) -> evdev::InputEvent {
    evdev::InputEvent::new(e.kind, e.code, e.value)
}
