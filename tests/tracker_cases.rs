//! The tracker on recordings the project writes for cases that no real file
//! has: lost events, slot overflow, out-of-range values, repeated tracking
//! ids, palms and pens. The recordings live in tests/data (regenerate with
//! `MARIONETTE_REGENERATE=1`); each test parses the file on disk.

mod common;

use std::path::PathBuf;

use marionette::input::evemu::Recording;
use marionette::input::event::*;
use marionette::input::tracker::{
    ContactTracker, KernelState, Phase, ResyncSource, SlotState, TouchFrame, track_events,
};
use marionette::tools::synth::{Synth, panel};

const DT: i64 = 10_000;

/// Write (when regenerating) and read back a test recording.
fn fixture(name: &str, synth: &Synth) -> Recording {
    let path: PathBuf = common::data_dir().join(name);
    let text = synth.to_text();
    if std::env::var_os("MARIONETTE_REGENERATE").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, &text).unwrap();
    }
    let on_disk = std::fs::read_to_string(&path).unwrap_or_else(|e| {
        panic!(
            "{}: {e}; regenerate with MARIONETTE_REGENERATE=1",
            path.display()
        )
    });
    assert_eq!(
        on_disk,
        text,
        "{} is stale; regenerate with MARIONETTE_REGENERATE=1",
        path.display()
    );
    Recording::read_file(&path).unwrap()
}

fn down_after(frames: &[TouchFrame]) -> usize {
    frames.last().map_or(0, |f| {
        f.contacts.iter().filter(|c| c.phase.is_down()).count()
    })
}

#[test]
fn syn_dropped_mid_gesture_leaves_no_contact_stuck() {
    // Two fingers down and moving; events are lost while finger 1 lifts
    // (its -1 never arrives); finger 0 goes on moving afterwards.
    let mut s = Synth::new(panel("dropped panel", 10, 4095));
    s.down(0, 1000, 1000).down(1, 3000, 3000).frame(DT);
    s.glide(&[(0, 1200, 1000), (1, 3100, 3000)], 5, DT);
    s.dropped().to(0, 1250, 1010).frame(DT); // the rest of that frame is lost
    s.forget(1);
    s.glide(&[(0, 1500, 1100)], 5, DT);
    s.up(0).frame(DT);
    let rec = fixture("syn-dropped-mid-gesture.evemu", &s);
    let (frames, stats) = track_events(&rec.device, &rec.events).unwrap();
    assert_eq!(stats.dropped, 1);
    let drop_frame = frames
        .iter()
        .find(|f| f.contacts.iter().any(|c| c.phase == Phase::Cancel))
        .expect("contacts are cancelled at the drop");
    assert_eq!(
        drop_frame
            .contacts
            .iter()
            .filter(|c| c.phase == Phase::Cancel)
            .count(),
        2
    );
    // Finger 0 comes back as a new contact as soon as it reports again...
    let resumed = frames
        .iter()
        .skip_while(|f| f.time_us <= drop_frame.time_us)
        .flat_map(|f| &f.contacts)
        .find(|c| c.phase == Phase::Down)
        .expect("the finger that stayed down is reported again");
    assert!(resumed.raw.x > 1250);
    // ...and nothing is down at the end: finger 1's lost lift is not stuck.
    assert_eq!(down_after(&frames), 0);
}

#[test]
fn live_resync_uses_the_kernel_state() {
    let mut s = Synth::new(panel("live panel", 4, 4095));
    s.down(0, 100, 100).down(1, 200, 200).frame(DT);
    s.dropped().frame(DT);
    let rec = s.finish();
    let mut t = ContactTracker::new(&rec.device, ResyncSource::Kernel, 7).unwrap();
    let mut frames = Vec::new();
    for e in &rec.events {
        t.push(e, &mut frames);
    }
    assert!(t.needs_resync());
    // The kernel says: slot 0 still down (moved), slot 1 lifted, slot 2 new.
    let state = KernelState {
        current_slot: 2,
        slots: vec![
            SlotState {
                tracking_id: 1,
                x: 150,
                y: 100,
                tool_type: 0,
            },
            SlotState {
                tracking_id: -1,
                ..SlotState::default()
            },
            SlotState {
                tracking_id: 9,
                x: 900,
                y: 900,
                tool_type: 0,
            },
            SlotState {
                tracking_id: -1,
                ..SlotState::default()
            },
        ],
        ..KernelState::default()
    };
    t.resync(&state, 99, &mut frames);
    assert!(!t.needs_resync());
    let f = frames.last().unwrap();
    let phases: Vec<Phase> = f.contacts.iter().map(|c| c.phase).collect();
    assert!(phases.contains(&Phase::Up), "{phases:?}");
    assert!(phases.contains(&Phase::Move), "{phases:?}");
    assert!(phases.contains(&Phase::Down), "{phases:?}");
    assert_eq!(t.active_count(), 2);
    assert!(
        f.contacts.iter().all(|c| c.id >> 32 == 7),
        "ids carry the device instance"
    );
}

#[test]
fn slots_beyond_the_maximum_are_ignored_not_fatal() {
    let mut s = Synth::new(panel("two-slot panel", 2, 4095));
    s.down(0, 500, 500).frame(DT);
    // Slot 5 on a 2-slot device: a kernel bug; its events are ignored.
    s.raw(EV_ABS, ABS_MT_SLOT, 5)
        .raw(EV_ABS, ABS_MT_TRACKING_ID, 77)
        .raw(EV_ABS, ABS_MT_POSITION_X, 9)
        .frame(DT);
    s.raw(EV_ABS, ABS_MT_SLOT, -3)
        .raw(EV_ABS, ABS_MT_POSITION_X, 9)
        .frame(DT);
    s.raw(EV_ABS, ABS_MT_SLOT, 0)
        .raw(EV_ABS, ABS_MT_POSITION_X, 600)
        .frame(DT);
    s.raw(EV_ABS, ABS_MT_TRACKING_ID, -1).frame(DT);
    let rec = fixture("slot-overflow.evemu", &s);
    let (frames, stats) = track_events(&rec.device, &rec.events).unwrap();
    assert_eq!(stats.bad_slots, 2);
    assert_eq!(stats.finger_sequences, 1);
    assert_eq!(stats.max_fingers, 1);
    let moved = frames
        .iter()
        .flat_map(|f| &f.contacts)
        .find(|c| c.phase == Phase::Move)
        .unwrap();
    assert_eq!(
        moved.raw.x, 600,
        "slot 0 is selected again and keeps working"
    );
    assert_eq!(down_after(&frames), 0);
}

#[test]
fn out_of_range_values_are_clamped() {
    let mut s = Synth::new(panel("noisy panel", 4, 1000));
    s.down(0, 500, 500).frame(DT);
    s.to(0, 1500, -20).frame(DT);
    s.to(0, i32::MAX, i32::MIN).frame(DT);
    s.up(0).frame(DT);
    let rec = fixture("out-of-range.evemu", &s);
    let (frames, stats) = track_events(&rec.device, &rec.events).unwrap();
    assert_eq!(stats.clamped, 4);
    for c in frames.iter().flat_map(|f| &f.contacts) {
        assert!(
            (0..=1000).contains(&c.raw.x) && (0..=1000).contains(&c.raw.y),
            "{c:?}"
        );
    }
    let moved: Vec<_> = frames
        .iter()
        .flat_map(|f| &f.contacts)
        .filter(|c| c.phase == Phase::Move)
        .collect();
    assert_eq!((moved[0].raw.x, moved[0].raw.y), (1000, 0));
}

#[test]
fn repeated_and_replaced_tracking_ids() {
    let mut s = Synth::new(panel("id panel", 4, 4095));
    s.raw(EV_ABS, ABS_MT_TRACKING_ID, 5)
        .raw(EV_ABS, ABS_MT_POSITION_X, 10)
        .raw(EV_ABS, ABS_MT_POSITION_Y, 10)
        .frame(DT);
    // The same id again: nothing new.
    s.raw(EV_ABS, ABS_MT_TRACKING_ID, 5).frame(DT);
    // A different id without a lift: the old touch ends, a new one begins.
    s.raw(EV_ABS, ABS_MT_TRACKING_ID, 6)
        .raw(EV_ABS, ABS_MT_POSITION_X, 20)
        .frame(DT);
    // A lift of a slot that has no touch: counted, harmless.
    s.raw(EV_ABS, ABS_MT_SLOT, 1)
        .raw(EV_ABS, ABS_MT_TRACKING_ID, -1)
        .frame(DT);
    s.raw(EV_ABS, ABS_MT_SLOT, 0)
        .raw(EV_ABS, ABS_MT_TRACKING_ID, -1)
        .frame(DT);
    let rec = fixture("tracking-ids.evemu", &s);
    let (frames, stats) = track_events(&rec.device, &rec.events).unwrap();
    assert_eq!(stats.repeated_ids, 1);
    assert_eq!(stats.finger_sequences, 2);
    assert_eq!(stats.spurious_lifts, 1);
    let replace = &frames[1];
    let phases: Vec<Phase> = replace.contacts.iter().map(|c| c.phase).collect();
    assert_eq!(phases, vec![Phase::Up, Phase::Down]);
    assert_eq!(down_after(&frames), 0);
}

#[test]
fn palms_are_cancelled_and_pens_are_not_fingers() {
    let mut d = panel("pen and palm panel", 4, 4095);
    d.set_abs(
        ABS_MT_TOOL_TYPE,
        marionette::input::device::AbsInfo {
            maximum: 2,
            ..Default::default()
        },
    );
    let mut s = Synth::new(d);
    s.down(0, 100, 100).frame(DT);
    s.raw(EV_ABS, ABS_MT_TOOL_TYPE, MT_TOOL_PALM).frame(DT);
    s.raw(EV_ABS, ABS_MT_SLOT, 1)
        .raw(EV_ABS, ABS_MT_TOOL_TYPE, MT_TOOL_PEN);
    s.raw(EV_ABS, ABS_MT_TRACKING_ID, 40)
        .raw(EV_ABS, ABS_MT_POSITION_X, 300)
        .frame(DT);
    s.raw(EV_ABS, ABS_MT_TRACKING_ID, -1)
        .raw(EV_ABS, ABS_MT_SLOT, 0)
        .raw(EV_ABS, ABS_MT_TRACKING_ID, -1)
        .frame(DT);
    let rec = fixture("palm-and-pen.evemu", &s);
    let (frames, stats) = track_events(&rec.device, &rec.events).unwrap();
    assert_eq!(stats.cancelled, 1);
    assert_eq!(stats.pen_sequences, 1);
    assert_eq!(stats.finger_sequences, 1);
    let pen = frames
        .iter()
        .flat_map(|f| &f.contacts)
        .find(|c| c.phase == Phase::Down && c.raw.x == 300)
        .unwrap();
    assert_eq!(pen.tool, marionette::input::tracker::Tool::Pen);
    assert_eq!(down_after(&frames), 0);
}

#[test]
fn real_pen_recording_reports_pens_only() {
    let dir = common::shared_dir().join("recordings/evemu");
    for f in ["dell-canvas-pen.evemu", "wacom-cintiq13hd-touch-pen.evemu"] {
        let rec = Recording::read_file(&dir.join(f)).unwrap();
        let (frames, stats) = track_events(&rec.device, &rec.events).unwrap();
        assert_eq!(stats.finger_sequences, 0, "{f}");
        assert!(stats.pen_sequences > 0, "{f}: the pen touched the screen");
        assert!(
            frames
                .iter()
                .flat_map(|fr| &fr.contacts)
                .all(|c| c.tool == marionette::input::tracker::Tool::Pen)
        );
    }
}

#[test]
fn protocol_a_contacts_are_matched_by_proximity() {
    let dir = common::shared_dir().join("recordings/evemu");
    let rec =
        Recording::read_file(&dir.join("ntrig-multitouch.2-fingers-touch-release.evemu")).unwrap();
    let (frames, stats) = track_events(&rec.device, &rec.events).unwrap();
    assert_eq!(stats.max_fingers, 2);
    // Contacts keep their ids while they move: every contact's successive
    // positions are close (no swaps between the two fingers).
    let mut last: std::collections::HashMap<u64, (i32, i32)> = Default::default();
    for c in frames.iter().flat_map(|f| &f.contacts) {
        if let Some((x, y)) = last.insert(c.id, (c.raw.x, c.raw.y)) {
            let jump = f64::from(c.raw.x - x).hypot(f64::from(c.raw.y - y));
            assert!(jump < 800.0, "contact {} jumped {jump} units", c.id);
        }
    }
    assert_eq!(down_after(&frames), 0);
}
