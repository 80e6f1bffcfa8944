//! Authoring recordings: a small builder for evemu recordings of a
//! protocol-B touchscreen, used for the bundled demo recordings and for test
//! recordings of cases that no real file has (lost events, slot overflow,
//! out-of-range values).
//!
//! Gestures are described as finger paths; the builder emits what a real
//! panel's kernel driver would: `ABS_MT_SLOT` switches, tracking ids,
//! positions, `BTN_TOUCH` and `SYN_REPORT` per frame.

use crate::input::device::{AbsInfo, DeviceDescription, InputId};
use crate::input::evemu::Recording;
use crate::input::event::*;

/// A protocol-B panel description: `slots` slots, axes `0..=max`.
#[must_use]
pub fn panel(name: &str, slots: i32, max: i32) -> DeviceDescription {
    let mut d = DeviceDescription {
        name: name.to_owned(),
        id: InputId {
            bustype: 0x03,
            vendor: 0x1d6b,
            product: 0x4d54,
            version: 1,
        },
        ..DeviceDescription::default()
    };
    d.properties.insert(INPUT_PROP_DIRECT);
    for code in [SYN_REPORT, SYN_CONFIG, SYN_DROPPED] {
        d.set_bit(EV_SYN, code);
    }
    d.set_bit(EV_KEY, BTN_TOUCH);
    let axis = AbsInfo {
        maximum: max,
        resolution: 10,
        ..AbsInfo::default()
    };
    d.set_abs(ABS_X, axis);
    d.set_abs(ABS_Y, axis);
    d.set_abs(
        ABS_MT_SLOT,
        AbsInfo {
            maximum: slots - 1,
            ..AbsInfo::default()
        },
    );
    d.set_abs(ABS_MT_POSITION_X, axis);
    d.set_abs(ABS_MT_POSITION_Y, axis);
    d.set_abs(
        ABS_MT_TRACKING_ID,
        AbsInfo {
            maximum: 65535,
            ..AbsInfo::default()
        },
    );
    d
}

/// Builds a recording frame by frame.
#[derive(Clone, Debug)]
pub struct Synth {
    rec: Recording,
    time_us: i64,
    current_slot: i32,
    next_tracking_id: i32,
    /// Per slot: tracking id and position, or `None` when up.
    slots: Vec<Option<(i32, i32, i32)>>,
    touching: bool,
}

impl Synth {
    #[must_use]
    pub fn new(device: DeviceDescription) -> Self {
        let n = device.slot_count();
        Self {
            rec: Recording {
                version: (1, 3),
                device,
                events: Vec::new(),
                dropped_trailing_events: 0,
            },
            time_us: 0,
            current_slot: 0,
            next_tracking_id: 1,
            slots: vec![None; n],
            touching: false,
        }
    }

    fn ev(&mut self, kind: u16, code: u16, value: i32) {
        self.rec
            .events
            .push(RawEvent::new(self.time_us, kind, code, value));
    }

    /// Emit any event as is (for malformed cases).
    pub fn raw(&mut self, kind: u16, code: u16, value: i32) -> &mut Self {
        self.ev(kind, code, value);
        self
    }

    fn select(&mut self, slot: i32) {
        if slot != self.current_slot {
            self.ev(EV_ABS, ABS_MT_SLOT, slot);
            self.current_slot = slot;
        }
    }

    /// Put a finger down in `slot` at `(x, y)`.
    pub fn down(&mut self, slot: i32, x: i32, y: i32) -> &mut Self {
        self.select(slot);
        let id = self.next_tracking_id;
        self.next_tracking_id = (self.next_tracking_id + 1) % 65536;
        self.ev(EV_ABS, ABS_MT_TRACKING_ID, id);
        self.ev(EV_ABS, ABS_MT_POSITION_X, x);
        self.ev(EV_ABS, ABS_MT_POSITION_Y, y);
        if let Some(s) = self.slots.get_mut(slot as usize) {
            *s = Some((id, x, y));
        }
        self
    }

    /// Move the finger in `slot` (only changed axes are sent).
    pub fn to(&mut self, slot: i32, x: i32, y: i32) -> &mut Self {
        let old = self.slots.get(slot as usize).copied().flatten();
        self.select(slot);
        let (id, ox, oy) = old.unwrap_or((-1, i32::MIN, i32::MIN));
        if x != ox {
            self.ev(EV_ABS, ABS_MT_POSITION_X, x);
        }
        if y != oy {
            self.ev(EV_ABS, ABS_MT_POSITION_Y, y);
        }
        if let Some(s) = self.slots.get_mut(slot as usize) {
            *s = Some((id, x, y));
        }
        self
    }

    /// Lift the finger in `slot`.
    pub fn up(&mut self, slot: i32) -> &mut Self {
        self.select(slot);
        self.ev(EV_ABS, ABS_MT_TRACKING_ID, -1);
        if let Some(s) = self.slots.get_mut(slot as usize) {
            *s = None;
        }
        self
    }

    /// Close the frame: `BTN_TOUCH` and single-touch axes as a kernel
    /// driver emulates them, then `SYN_REPORT`; advance the clock.
    pub fn frame(&mut self, dt_us: i64) -> &mut Self {
        let first = self.slots.iter().flatten().next().copied();
        let touching = first.is_some();
        if touching != self.touching {
            self.ev(EV_KEY, BTN_TOUCH, i32::from(touching));
            self.touching = touching;
        }
        if let Some((_, x, y)) = first {
            self.ev(EV_ABS, ABS_X, x);
            self.ev(EV_ABS, ABS_Y, y);
        }
        self.ev(EV_SYN, SYN_REPORT, 0);
        self.time_us += dt_us;
        self
    }

    /// The kernel's buffer overflowed: `SYN_DROPPED`, then the events the
    /// client still sees up to the next `SYN_REPORT`.
    pub fn dropped(&mut self) -> &mut Self {
        self.ev(EV_SYN, SYN_DROPPED, 0);
        self
    }

    /// Forget the builder's idea of a slot (its events were lost).
    pub fn forget(&mut self, slot: i32) -> &mut Self {
        if let Some(s) = self.slots.get_mut(slot as usize) {
            *s = None;
        }
        self
    }

    /// Move every listed finger along straight lines from their current
    /// positions to the targets in `frames` frames of `dt_us`, easing in and
    /// out.
    pub fn glide(&mut self, targets: &[(i32, i32, i32)], frames: u32, dt_us: i64) -> &mut Self {
        let starts: Vec<(i32, i32, i32)> = targets
            .iter()
            .map(|(s, _, _)| {
                let (_, x, y) = self
                    .slots
                    .get(*s as usize)
                    .copied()
                    .flatten()
                    .unwrap_or((0, 0, 0));
                (*s, x, y)
            })
            .collect();
        for k in 1..=frames {
            let t = f64::from(k) / f64::from(frames);
            let e = t * t * (3.0 - 2.0 * t);
            for ((s, x0, y0), (_, x1, y1)) in starts.iter().zip(targets) {
                let x = f64::from(*x0) + (f64::from(*x1) - f64::from(*x0)) * e;
                let y = f64::from(*y0) + (f64::from(*y1) - f64::from(*y0)) * e;
                self.to(*s, x.round() as i32, y.round() as i32);
            }
            self.frame(dt_us);
        }
        self
    }

    #[must_use]
    pub fn finish(&self) -> Recording {
        self.rec.clone()
    }

    /// The recording as evemu text.
    #[must_use]
    pub fn to_text(&self) -> String {
        let mut out = Vec::new();
        self.rec
            .write(&mut out)
            .expect("writing to memory cannot fail");
        String::from_utf8(out).expect("the writer writes UTF-8")
    }
}

/// The bundled demo recording: one finger poses, two fingers pose, quick
/// drags, a held finger while another moves, a pinch.
#[must_use]
pub fn demo_two_hands() -> Synth {
    const DT: i64 = 16_667;
    let mut s = Synth::new(panel("marionette demo panel", 10, 4095));
    s.frame(DT); // an idle first frame
    // One finger drags slowly (posing with one hand).
    s.down(0, 2300, 1500).frame(DT);
    s.glide(&[(0, 2600, 1100)], 45, DT)
        .glide(&[(0, 2500, 1700)], 40, DT);
    s.up(0).frame(DT);
    for _ in 0..20 {
        s.frame(DT);
    }
    // Two fingers pose both hands.
    s.down(0, 1700, 1600).down(1, 2400, 1600).frame(DT);
    s.glide(&[(0, 1500, 1000), (1, 2600, 1000)], 50, DT);
    s.up(0).up(1).frame(DT);
    // A quick drag forward (an action-like stroke), twice.
    for (x0, x1) in [(2200, 3000), (1900, 1100)] {
        s.down(0, x0, 1400).frame(DT);
        s.glide(&[(0, x1, 1350)], 12, DT);
        s.up(0).frame(DT);
        for _ in 0..15 {
            s.frame(DT);
        }
    }
    // One finger holds a part while another moves.
    s.down(2, 2050, 3300).frame(DT);
    s.down(3, 2300, 1500).frame(DT);
    s.glide(&[(3, 2700, 900)], 40, DT);
    s.up(3).frame(DT).up(2).frame(DT);
    // A two-finger pinch on empty space (camera zoom).
    s.down(0, 600, 2000).down(1, 1000, 2000).frame(DT);
    s.glide(&[(0, 300, 2000), (1, 1300, 2000)], 40, DT);
    s.up(0).up(1).frame(DT);
    s
}
