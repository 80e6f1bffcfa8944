//! Per-device overrides of what a panel says (`axes` and `tool` in
//! `[[input.device]]`), applied to its description and to each of its
//! events before anything else reads them, live and in replays alike.
//!
//! Some panels report in odd places: eGalax 0eef:0001 single-touch
//! controllers put the position on `ABS_Z`/`ABS_RX` and announce
//! `BTN_TOOL_PEN` for a finger. `axes = { x = "ABS_Z", y = "ABS_RX" }`
//! moves those axes to where a single-touch panel has them (`ABS_X`,
//! `ABS_Y`; `ABS_MT_POSITION_X`/`Y` when the named axes are multitouch
//! ones), and `tool = "finger"` makes the pen bits a finger's: they are
//! dropped, and stand for `BTN_TOUCH` on a panel that has none.

use super::device::{BitSet, DeviceDescription};
use super::event::{
    ABS_MT_POSITION_X, ABS_MT_POSITION_Y, ABS_MT_SLOT, ABS_X, ABS_Y, BTN_STYLUS, BTN_TOOL_PEN,
    BTN_TOOL_RUBBER, BTN_TOUCH, EV_ABS, EV_KEY, RawEvent,
};

/// The kernel's names of the absolute axes an override may name.
pub const AXIS_NAMES: [(&str, u16); 14] = [
    ("ABS_X", 0x00),
    ("ABS_Y", 0x01),
    ("ABS_Z", 0x02),
    ("ABS_RX", 0x03),
    ("ABS_RY", 0x04),
    ("ABS_RZ", 0x05),
    ("ABS_THROTTLE", 0x06),
    ("ABS_RUDDER", 0x07),
    ("ABS_WHEEL", 0x08),
    ("ABS_GAS", 0x09),
    ("ABS_BRAKE", 0x0a),
    ("ABS_MISC", 0x28),
    ("ABS_MT_POSITION_X", ABS_MT_POSITION_X),
    ("ABS_MT_POSITION_Y", ABS_MT_POSITION_Y),
];

/// The code of an axis named as the kernel names it.
#[must_use]
pub fn axis_code(name: &str) -> Option<u16> {
    AXIS_NAMES
        .iter()
        .find(|(n, _)| n.eq_ignore_ascii_case(name))
        .map(|(_, c)| *c)
}

/// Why an override cannot apply to a device.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum RemapError {
    #[error("the configured axis {0} is not one the device reports")]
    MissingAxis(&'static str),
}

/// What to change of one device's reports.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Remap {
    /// `(from, to)` for x and y.
    axes: Option<[(u16, u16); 2]>,
    /// Pen bits are a finger's.
    pen_is_finger: bool,
    /// ... and stand for `BTN_TOUCH` (the device has none).
    pen_touches: bool,
}

impl Remap {
    /// The changes for `desc`, `None` when there are none. `axes` are the
    /// codes of the axes carrying x and y.
    pub fn new(
        desc: &DeviceDescription,
        axes: Option<(u16, u16)>,
        pen_is_finger: bool,
    ) -> Result<Option<Self>, RemapError> {
        let axes = match axes {
            None => None,
            Some((x, y)) => {
                for c in [x, y] {
                    if !desc.abs.contains_key(&c) {
                        let name = AXIS_NAMES
                            .iter()
                            .find(|(_, code)| *code == c)
                            .map_or("?", |(n, _)| n);
                        return Err(RemapError::MissingAxis(name));
                    }
                }
                let mt = [x, y].contains(&ABS_MT_POSITION_X) || [x, y].contains(&ABS_MT_POSITION_Y);
                let to = if mt {
                    (ABS_MT_POSITION_X, ABS_MT_POSITION_Y)
                } else {
                    (ABS_X, ABS_Y)
                };
                Some([(x, to.0), (y, to.1)])
            }
        };
        if axes.is_none() && !pen_is_finger {
            return Ok(None);
        }
        let pen_touches = pen_is_finger && !desc.has(EV_KEY, BTN_TOUCH);
        Ok(Some(Self {
            axes,
            pen_is_finger,
            pen_touches,
        }))
    }

    /// The device as it reads once changed.
    #[must_use]
    pub fn description(&self, desc: &DeviceDescription) -> DeviceDescription {
        let mut d = desc.clone();
        if d.bits.len() <= usize::from(EV_ABS) {
            d.bits.resize(usize::from(EV_ABS) + 1, BitSet::default());
        }
        if let Some(axes) = self.axes {
            let infos: Vec<_> = axes
                .iter()
                .map(|(from, _)| desc.abs.get(from).copied())
                .collect();
            // The targets' old reports, if any, are dropped (see `event`).
            for (_, to) in axes {
                d.abs.remove(&to);
            }
            for ((from, to), info) in axes.iter().zip(infos) {
                d.abs.remove(from);
                if let Some(info) = info {
                    d.abs.insert(*to, info);
                }
            }
            let abs = &mut d.bits[usize::from(EV_ABS)];
            for (from, to) in axes {
                abs.remove(from);
                abs.insert(to);
            }
        }
        if self.pen_is_finger {
            let keys = &mut d.bits[usize::from(EV_KEY)];
            for k in [BTN_TOOL_PEN, BTN_TOOL_RUBBER, BTN_STYLUS] {
                keys.remove(k);
            }
            if self.pen_touches {
                keys.insert(BTN_TOUCH);
            }
        }
        d
    }

    /// One event as it reads once changed; `None` drops it.
    #[must_use]
    pub fn event(&self, e: &RawEvent) -> Option<RawEvent> {
        let mut e = *e;
        if let (Some(axes), EV_ABS) = (self.axes, e.kind) {
            if let Some((_, to)) = axes.iter().find(|(from, _)| *from == e.code) {
                e.code = *to;
            } else if axes.iter().any(|(_, to)| *to == e.code) && e.code != ABS_MT_SLOT {
                // The axis the position moved to had reports of its own
                // (junk on such panels): they would fight the position.
                return None;
            }
        }
        if self.pen_is_finger && e.kind == EV_KEY {
            match e.code {
                BTN_TOOL_PEN | BTN_TOOL_RUBBER if self.pen_touches => e.code = BTN_TOUCH,
                BTN_TOOL_PEN | BTN_TOOL_RUBBER | BTN_STYLUS => return None,
                _ => {}
            }
        }
        Some(e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::device::AbsInfo;
    use crate::input::event::{EV_SYN, SYN_REPORT};

    /// An eGalax 0eef:0001 as it describes itself.
    fn egalax() -> DeviceDescription {
        let mut d = DeviceDescription {
            name: "eGalax Inc. USB TouchController".to_owned(),
            ..DeviceDescription::default()
        };
        d.bits = vec![BitSet::default(); usize::from(EV_ABS) + 1];
        d.bits[usize::from(EV_SYN)].insert(SYN_REPORT);
        for k in [BTN_TOUCH, BTN_TOOL_PEN] {
            d.bits[usize::from(EV_KEY)].insert(k);
        }
        for a in [0x02, 0x03] {
            d.bits[usize::from(EV_ABS)].insert(a);
            d.abs.insert(
                a,
                AbsInfo {
                    maximum: 2047,
                    ..AbsInfo::default()
                },
            );
        }
        d
    }

    #[test]
    fn a_pen_on_odd_axes_becomes_a_single_touch_finger() {
        let d = egalax();
        assert_eq!(d.protocol(), None);
        let r = Remap::new(&d, Some((0x02, 0x03)), true).unwrap().unwrap();
        let m = r.description(&d);
        assert_eq!(m.protocol(), Some(crate::input::device::Protocol::Single));
        assert!(!m.has(EV_KEY, BTN_TOOL_PEN) && m.has(EV_KEY, BTN_TOUCH));
        assert_eq!(m.position_axes().unwrap().0.maximum, 2047);
        let e = |k, c, v| RawEvent::new(5, k, c, v);
        assert_eq!(r.event(&e(EV_ABS, 0x02, 7)), Some(e(EV_ABS, ABS_X, 7)));
        assert_eq!(r.event(&e(EV_ABS, 0x03, 9)), Some(e(EV_ABS, ABS_Y, 9)));
        assert_eq!(r.event(&e(EV_KEY, BTN_TOOL_PEN, 1)), None);
        assert_eq!(
            r.event(&e(EV_KEY, BTN_TOUCH, 1)),
            Some(e(EV_KEY, BTN_TOUCH, 1))
        );
    }

    #[test]
    fn a_pen_bit_stands_for_touch_where_the_panel_has_none() {
        let mut d = egalax();
        d.bits[usize::from(EV_KEY)] = BitSet::default();
        d.bits[usize::from(EV_KEY)].insert(BTN_TOOL_PEN);
        let r = Remap::new(&d, None, true).unwrap().unwrap();
        assert!(r.description(&d).has(EV_KEY, BTN_TOUCH));
        assert_eq!(
            r.event(&RawEvent::new(0, EV_KEY, BTN_TOOL_PEN, 1)),
            Some(RawEvent::new(0, EV_KEY, BTN_TOUCH, 1))
        );
    }

    #[test]
    fn nothing_to_change_and_axes_the_device_lacks() {
        let d = egalax();
        assert_eq!(Remap::new(&d, None, false), Ok(None));
        assert_eq!(
            Remap::new(&d, Some((0x02, 0x05)), false),
            Err(RemapError::MissingAxis("ABS_RZ"))
        );
        assert_eq!(axis_code("abs_rx"), Some(0x03));
        assert_eq!(axis_code("ABS_NOPE"), None);
    }
}
