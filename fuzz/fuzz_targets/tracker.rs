//! Any event stream through the tracker, on each protocol: no panic, every
//! position inside the axis range, and no contact left down after every
//! slot is lifted.
#![no_main]

use libfuzzer_sys::fuzz_target;
use marionette::input::device::{AbsInfo, DeviceDescription};
use marionette::input::event::*;
use marionette::tools::synth::panel;
use marionette::input::tracker::{ContactTracker, ResyncSource};

fn device(which: u8) -> DeviceDescription {
    let b = panel("B", 8, 4095);
    match which % 3 {
        0 => b,
        1 => {
            let mut a = DeviceDescription::default();
            for (code, info) in b.abs.iter().filter(|(c, _)| **c != ABS_MT_SLOT) {
                a.set_abs(*code, *info);
            }
            a.set_bit(EV_KEY, BTN_TOUCH);
            a
        }
        _ => {
            let mut s = DeviceDescription::default();
            let r = AbsInfo { maximum: 4095, ..AbsInfo::default() };
            s.set_abs(ABS_X, r);
            s.set_abs(ABS_Y, r);
            s.set_bit(EV_KEY, BTN_TOUCH);
            s
        }
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((&which, rest)) = data.split_first() else { return };
    let mut t = ContactTracker::new(&device(which), ResyncSource::Reconcile, 1).unwrap();
    let mut frames = Vec::new();
    let kinds = [EV_SYN, EV_KEY, EV_ABS];
    for (i, c) in rest.chunks_exact(7).enumerate() {
        let kind = kinds[usize::from(c[0]) % 3];
        let code = u16::from_le_bytes([c[1], c[2] & 0x03]);
        let value = i32::from_le_bytes([c[3], c[4], c[5], c[6]]);
        t.push(&RawEvent::new(i as i64 * 1000, kind, code, value), &mut frames);
    }
    let end = rest.len() as i64 * 1000;
    for s in 0..8 {
        t.push(&RawEvent::new(end, EV_ABS, ABS_MT_SLOT, s), &mut frames);
        t.push(&RawEvent::new(end, EV_ABS, ABS_MT_TRACKING_ID, -1), &mut frames);
    }
    t.push(&RawEvent::new(end, EV_SYN, SYN_MT_REPORT, 0), &mut frames);
    t.push(&RawEvent::new(end, EV_KEY, BTN_TOUCH, 0), &mut frames);
    t.push(&RawEvent::new(end, EV_SYN, SYN_REPORT, 0), &mut frames);
    assert_eq!(t.active_count(), 0);
    for c in frames.iter().flat_map(|f| &f.contacts) {
        assert!((0..=4095).contains(&c.raw.x) && (0..=4095).contains(&c.raw.y));
    }
});
