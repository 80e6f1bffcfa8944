//! What an input device is: its identity, capabilities and axis ranges, and
//! what marionette makes of it (touchscreen, touchpad, pen, or nothing of
//! interest).
//!
//! A [`DeviceDescription`] comes either from a live device (ioctls) or from
//! the header of an evemu recording; everything downstream treats the two
//! alike. Classification follows udev's `input_id` builtin, because old
//! kernels (and the recordings made on them) do not set `INPUT_PROP_DIRECT`
//! on touchscreens.

use std::collections::BTreeMap;
use std::fmt;

use serde::Serialize;

use super::event::{
    ABS_CNT, ABS_MT_POSITION_X, ABS_MT_POSITION_Y, ABS_MT_SLOT, ABS_X, ABS_Y, BTN_LEFT, BTN_STYLUS,
    BTN_TOOL_FINGER, BTN_TOOL_PEN, BTN_TOUCH, EV_ABS, EV_CNT, EV_KEY, INPUT_PROP_DIRECT,
    INPUT_PROP_POINTER,
};

/// `struct input_id`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize)]
pub struct InputId {
    pub bustype: u16,
    pub vendor: u16,
    pub product: u16,
    pub version: u16,
}

impl fmt::Display for InputId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:04x}:{:04x}", self.vendor, self.product)
    }
}

/// `struct input_absinfo`: the range and current value of one axis.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct AbsInfo {
    pub value: i32,
    pub minimum: i32,
    pub maximum: i32,
    pub fuzz: i32,
    pub flat: i32,
    /// Units per millimetre (0 when the device does not say).
    pub resolution: i32,
}

impl AbsInfo {
    /// Clamp a value into `[minimum, maximum]`. Works even when the range
    /// is swapped (then nothing is in range and the value stays as it is,
    /// which calibration refuses separately).
    #[must_use]
    pub fn clamp(&self, v: i32) -> i32 {
        if self.minimum <= self.maximum {
            v.clamp(self.minimum, self.maximum)
        } else {
            v
        }
    }

    #[must_use]
    pub fn contains(&self, v: i32) -> bool {
        (self.minimum..=self.maximum).contains(&v)
    }
}

/// A variable-length bit set stored as the kernel's little-endian bytes.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct BitSet(pub Vec<u8>);

impl BitSet {
    #[must_use]
    pub fn contains(&self, bit: u16) -> bool {
        let (byte, bit) = (usize::from(bit / 8), bit % 8);
        self.0.get(byte).is_some_and(|b| b & (1 << bit) != 0)
    }

    pub fn insert(&mut self, bit: u16) {
        let byte = usize::from(bit / 8);
        if self.0.len() <= byte {
            self.0.resize(byte + 1, 0);
        }
        self.0[byte] |= 1 << (bit % 8);
    }

    pub fn remove(&mut self, bit: u16) {
        if let Some(b) = self.0.get_mut(usize::from(bit / 8)) {
            *b &= !(1 << (bit % 8));
        }
    }

    /// The set bits, ascending.
    pub fn iter(&self) -> impl Iterator<Item = u16> + '_ {
        self.0.iter().enumerate().flat_map(|(i, b)| {
            (0..8u16).filter_map(move |bit| (b & (1 << bit) != 0).then_some(i as u16 * 8 + bit))
        })
    }
}

/// Everything marionette knows about a device before its first event.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DeviceDescription {
    pub name: String,
    pub id: InputId,
    /// `INPUT_PROP_*` bits.
    pub properties: BitSet,
    /// Supported codes per event type (index = `EV_*`); entry 0 holds the
    /// `EV_SYN` codes, as evemu's `B: 00` line does. A type is supported
    /// when it has codes.
    pub bits: Vec<BitSet>,
    /// Axis ranges of the supported `EV_ABS` codes.
    pub abs: BTreeMap<u16, AbsInfo>,
    /// LED states (`L:` lines) and switch states (`S:` lines).
    pub leds: Vec<(u16, i32)>,
    pub switches: Vec<(u16, i32)>,
}

/// How a device reports contacts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Protocol {
    /// Multitouch protocol B: slots and tracking ids.
    #[serde(rename = "B")]
    B,
    /// Multitouch protocol A: anonymous contacts separated by SYN_MT_REPORT.
    #[serde(rename = "A")]
    A,
    /// One contact on ABS_X/ABS_Y with BTN_TOUCH.
    #[serde(rename = "single")]
    Single,
}

impl fmt::Display for Protocol {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Protocol::B => "B",
            Protocol::A => "A",
            Protocol::Single => "single",
        })
    }
}

/// What marionette makes of a device.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DeviceKind {
    /// A finger touchscreen: marionette reads it.
    Touchscreen,
    /// A touchpad (indirect): its coordinates do not map to the screen.
    Touchpad,
    /// A pen or tablet tool: reported as a separate tool, never a finger.
    Pen,
    /// Keyboards, mice and everything else.
    Other,
}

impl fmt::Display for DeviceKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            DeviceKind::Touchscreen => "touchscreen",
            DeviceKind::Touchpad => "touchpad",
            DeviceKind::Pen => "pen",
            DeviceKind::Other => "other",
        })
    }
}

impl DeviceDescription {
    /// The supported codes of one event type (empty when unsupported).
    #[must_use]
    pub fn codes(&self, kind: u16) -> &BitSet {
        static EMPTY: BitSet = BitSet(Vec::new());
        self.bits.get(usize::from(kind)).unwrap_or(&EMPTY)
    }

    #[must_use]
    pub fn has(&self, kind: u16, code: u16) -> bool {
        self.codes(kind).contains(code)
    }

    #[must_use]
    pub fn has_abs(&self, code: u16) -> bool {
        self.has(EV_ABS, code) || self.abs.contains_key(&code)
    }

    #[must_use]
    pub fn has_property(&self, prop: u16) -> bool {
        self.properties.contains(prop)
    }

    /// Mark a code as supported (used by the evemu reader and by tests that
    /// build descriptions).
    pub fn set_bit(&mut self, kind: u16, code: u16) {
        if self.bits.len() < EV_CNT {
            self.bits.resize(EV_CNT, BitSet::default());
        }
        self.bits[usize::from(kind)].insert(code);
    }

    /// Add an absolute axis with its range.
    pub fn set_abs(&mut self, code: u16, info: AbsInfo) {
        if usize::from(code) < ABS_CNT {
            self.set_bit(EV_ABS, code);
            self.abs.insert(code, info);
        }
    }

    /// The multitouch protocol, or `None` for devices without any position
    /// axis.
    #[must_use]
    pub fn protocol(&self) -> Option<Protocol> {
        if self.has_abs(ABS_MT_SLOT) && self.has_abs(ABS_MT_POSITION_X) {
            Some(Protocol::B)
        } else if self.has_abs(ABS_MT_POSITION_X) {
            Some(Protocol::A)
        } else if self.has_abs(ABS_X) && self.has_abs(ABS_Y) {
            Some(Protocol::Single)
        } else {
            None
        }
    }

    /// Whether the device says its coordinates are on the screen
    /// (`INPUT_PROP_DIRECT`), or is a touchscreen by udev's rules although an
    /// old kernel did not set the property.
    #[must_use]
    pub fn is_direct(&self) -> bool {
        self.has_property(INPUT_PROP_DIRECT) || self.kind() == DeviceKind::Touchscreen
    }

    /// Classify the device as udev's `input_id` builtin does for pointing
    /// devices with absolute axes.
    #[must_use]
    pub fn kind(&self) -> DeviceKind {
        let has_xy =
            (self.has_abs(ABS_X) && self.has_abs(ABS_Y)) || self.has_abs(ABS_MT_POSITION_X);
        if !has_xy {
            return DeviceKind::Other;
        }
        let direct = self.has_property(INPUT_PROP_DIRECT);
        if self.has(EV_KEY, BTN_TOOL_PEN) || self.has(EV_KEY, BTN_STYLUS) {
            return DeviceKind::Pen;
        }
        if self.has_property(INPUT_PROP_POINTER) && !direct {
            return DeviceKind::Touchpad;
        }
        if self.has(EV_KEY, BTN_TOOL_FINGER) && !direct {
            return DeviceKind::Touchpad;
        }
        if self.has(EV_KEY, BTN_LEFT) && !direct {
            // An absolute mouse or a graphics tablet's puck.
            return DeviceKind::Other;
        }
        if self.has(EV_KEY, BTN_TOUCH) || direct {
            return DeviceKind::Touchscreen;
        }
        DeviceKind::Other
    }

    /// Number of slots of a protocol B device (`ABS_MT_SLOT` maximum + 1).
    #[must_use]
    pub fn slot_count(&self) -> usize {
        self.abs.get(&ABS_MT_SLOT).map_or(1, |a| {
            usize::try_from(a.maximum.saturating_add(1))
                .unwrap_or(1)
                .max(1)
        })
    }

    /// The axis that carries positions for this device's protocol.
    #[must_use]
    pub fn position_axes(&self) -> Option<(AbsInfo, AbsInfo)> {
        let (x, y) = match self.protocol()? {
            Protocol::A | Protocol::B => (ABS_MT_POSITION_X, ABS_MT_POSITION_Y),
            Protocol::Single => (ABS_X, ABS_Y),
        };
        Some((*self.abs.get(&x)?, *self.abs.get(&y)?))
    }
}

/// A short label for a device in logs: name (escaped and cut, as any
/// name a device gives itself) and vendor:product.
#[must_use]
pub fn device_label(name: &str, id: InputId) -> String {
    format!("\"{}\" ({id})", crate::reading::quote_bare(name))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::event::*;

    fn screen(direct: bool) -> DeviceDescription {
        let mut d = DeviceDescription::default();
        let r = AbsInfo {
            maximum: 4095,
            ..AbsInfo::default()
        };
        d.set_abs(ABS_X, r);
        d.set_abs(ABS_Y, r);
        d.set_abs(ABS_MT_SLOT, AbsInfo { maximum: 9, ..r });
        d.set_abs(ABS_MT_POSITION_X, r);
        d.set_abs(ABS_MT_POSITION_Y, r);
        d.set_abs(
            ABS_MT_TRACKING_ID,
            AbsInfo {
                maximum: 65535,
                ..r
            },
        );
        d.set_bit(EV_KEY, BTN_TOUCH);
        if direct {
            d.properties.insert(INPUT_PROP_DIRECT);
        }
        d
    }

    #[test]
    fn touchscreen_without_direct_property_is_still_a_touchscreen() {
        let d = screen(false);
        assert_eq!(d.kind(), DeviceKind::Touchscreen);
        assert!(d.is_direct());
        assert_eq!(d.protocol(), Some(Protocol::B));
        assert_eq!(d.slot_count(), 10);
    }

    #[test]
    fn finger_tool_without_direct_is_a_touchpad() {
        let mut d = screen(false);
        d.set_bit(EV_KEY, BTN_TOOL_FINGER);
        assert_eq!(d.kind(), DeviceKind::Touchpad);
        d.properties.insert(INPUT_PROP_DIRECT);
        assert_eq!(d.kind(), DeviceKind::Touchscreen);
    }

    #[test]
    fn pointer_property_makes_a_touchpad_and_pens_are_pens() {
        let mut d = screen(false);
        d.properties.insert(INPUT_PROP_POINTER);
        assert_eq!(d.kind(), DeviceKind::Touchpad);
        let mut p = screen(true);
        p.set_bit(EV_KEY, BTN_TOOL_PEN);
        assert_eq!(p.kind(), DeviceKind::Pen);
    }

    #[test]
    fn bitset_iterates_set_bits() {
        let mut b = BitSet::default();
        for bit in [0, 7, 8, 330] {
            b.insert(bit);
        }
        assert_eq!(b.iter().collect::<Vec<_>>(), vec![0, 7, 8, 330]);
        assert!(!b.contains(331));
    }
}
