//! Property tests: random event streams and random text never panic; once
//! every slot is lifted, no contact is left down. Longer runs:
//! `PROPTEST_CASES=20000 cargo test --release --test properties`.

use std::path::Path;

use proptest::prelude::*;

use marionette::input::device::AbsInfo;
use marionette::input::evemu::Recording;
use marionette::input::event::*;
use marionette::input::tracker::{ContactTracker, ResyncSource, TouchFrame};
use marionette::tools::synth::panel;

/// An event that a buggy or hostile device might send to a touchscreen.
fn any_event() -> impl Strategy<Value = (u16, u16, i32)> {
    prop_oneof![
        4 => (Just(EV_ABS), prop_oneof![Just(ABS_MT_SLOT), Just(ABS_MT_TRACKING_ID), Just(ABS_MT_POSITION_X), Just(ABS_MT_POSITION_Y), Just(ABS_MT_TOOL_TYPE), Just(ABS_MT_TOUCH_MAJOR), Just(ABS_X), Just(ABS_Y)], prop_oneof![-3i32..12, -100i32..5000, any::<i32>()]),
        1 => (Just(EV_KEY), prop_oneof![Just(BTN_TOUCH), Just(BTN_TOOL_PEN), Just(BTN_TOOL_FINGER)], 0i32..2),
        2 => (Just(EV_SYN), Just(SYN_REPORT), Just(0)),
        1 => (Just(EV_SYN), prop_oneof![Just(SYN_MT_REPORT), Just(SYN_DROPPED)], Just(0)),
    ]
}

fn devices() -> Vec<marionette::input::device::DeviceDescription> {
    let b = panel("B", 4, 4095);
    let mut a = b.clone();
    a.abs.remove(&ABS_MT_SLOT);
    a.bits[usize::from(EV_ABS)] = Default::default();
    for (code, info) in b.abs.iter().filter(|(c, _)| **c != ABS_MT_SLOT) {
        a.set_abs(*code, *info);
    }
    let mut single = marionette::input::device::DeviceDescription::default();
    single.set_abs(
        ABS_X,
        AbsInfo {
            maximum: 1000,
            ..AbsInfo::default()
        },
    );
    single.set_abs(
        ABS_Y,
        AbsInfo {
            maximum: 1000,
            ..AbsInfo::default()
        },
    );
    single.set_bit(EV_KEY, BTN_TOUCH);
    vec![b, a, single]
}

/// Lift everything the way each protocol lifts: -1 on every slot, an empty
/// protocol-A frame, BTN_TOUCH 0.
fn lift_all(slots: i32) -> Vec<(u16, u16, i32)> {
    let mut v = Vec::new();
    for s in 0..slots {
        v.push((EV_ABS, ABS_MT_SLOT, s));
        v.push((EV_ABS, ABS_MT_TRACKING_ID, -1));
    }
    v.push((EV_SYN, SYN_MT_REPORT, 0));
    v.push((EV_KEY, BTN_TOUCH, 0));
    v.push((EV_SYN, SYN_REPORT, 0));
    v
}

proptest! {
    #[test]
    fn random_streams_never_panic_and_lifting_everything_leaves_nothing_down(
        events in prop::collection::vec(any_event(), 0..400),
        which in 0usize..3,
    ) {
        let device = &devices()[which];
        let mut t = ContactTracker::new(device, ResyncSource::Reconcile, 1).unwrap();
        let mut frames: Vec<TouchFrame> = Vec::new();
        let mut time = 0;
        for (kind, code, value) in events.iter().copied().chain(lift_all(4)) {
            time += 1000;
            t.push(&RawEvent::new(time, kind, code, value), &mut frames);
        }
        prop_assert_eq!(t.active_count(), 0);
        for f in &frames {
            for c in &f.contacts {
                prop_assert!((0..=4095).contains(&c.raw.x) && (0..=4095).contains(&c.raw.y));
            }
        }
        // Every contact that went down ended exactly once.
        let mut open = std::collections::HashSet::new();
        for c in frames.iter().flat_map(|f| &f.contacts) {
            if c.phase == marionette::input::tracker::Phase::Down {
                prop_assert!(open.insert(c.id));
            } else if !c.phase.is_down() {
                prop_assert!(open.remove(&c.id));
            } else {
                prop_assert!(open.contains(&c.id));
            }
        }
        prop_assert!(open.is_empty());
    }

    #[test]
    fn random_text_never_panics_the_parser(text in "(#[^\n]*\n|[NIPBALSE]: [-0-9a-f. ]{0,40}\n|E: [0-9]{1,3}\\.[0-9]{6} 000[0-3] 00[0-3][0-9a-f] -?[0-9]{1,12}\n){0,60}") {
        let _ = Recording::parse(&text, Path::new("random"));
    }

    #[test]
    fn random_bytes_never_panic_the_parser(bytes in prop::collection::vec(any::<u8>(), 0..2000)) {
        let _ = Recording::parse(&String::from_utf8_lossy(&bytes), Path::new("random"));
    }
}
