//! The input hub with an injected device opener: real recordings played as
//! devices that can be unplugged and plugged back, without /dev/input.

mod common;

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::io;
use std::os::fd::BorrowedFd;
use std::path::{Path, PathBuf};
use std::rc::Rc;

use marionette::app::config::Config;
use marionette::input::device::DeviceDescription;
use marionette::input::evemu::Recording;
use marionette::input::event::RawEvent;
use marionette::input::hub::{DeviceOpener, EventDevice, HubEvent, InputHub, LiveError};
use marionette::input::tracker::{KernelState, Phase};

/// A device node backed by a recording: each `read` returns the next
/// `chunk` frames; once unplugged, reads fail with `Gone`.
#[derive(Clone)]
struct Node {
    rec: Rc<Recording>,
    cursor: Rc<RefCell<usize>>,
    plugged: Rc<RefCell<bool>>,
    chunk: usize,
}

struct NodeDevice {
    node: Node,
    path: PathBuf,
}

impl EventDevice for NodeDevice {
    fn description(&self) -> &DeviceDescription {
        &self.node.rec.device
    }
    fn poll_fd(&self) -> Option<BorrowedFd<'_>> {
        None
    }
    fn read(&mut self, out: &mut Vec<RawEvent>) -> Result<(), LiveError> {
        if !*self.node.plugged.borrow() {
            return Err(LiveError::Gone(self.path.clone()));
        }
        let mut cursor = self.node.cursor.borrow_mut();
        let mut frames = 0;
        while *cursor < self.node.rec.events.len() && frames < self.node.chunk {
            let e = self.node.rec.events[*cursor];
            out.push(e);
            *cursor += 1;
            if e.is_syn_report() {
                frames += 1;
            }
        }
        Ok(())
    }
    fn kernel_state(&self) -> io::Result<KernelState> {
        Ok(KernelState::default())
    }
    fn grab(&mut self) -> io::Result<()> {
        Ok(())
    }
}

#[derive(Clone, Default)]
struct Opener {
    nodes: Rc<RefCell<BTreeMap<PathBuf, Node>>>,
}

impl DeviceOpener for Opener {
    fn scan(&self, _dir: &Path) -> io::Result<Vec<PathBuf>> {
        Ok(self
            .nodes
            .borrow()
            .iter()
            .filter(|(_, n)| *n.plugged.borrow())
            .map(|(p, _)| p.clone())
            .collect())
    }
    fn open(&self, path: &Path) -> io::Result<Box<dyn EventDevice>> {
        let node = self
            .nodes
            .borrow()
            .get(path)
            .cloned()
            .ok_or_else(|| io::Error::from(io::ErrorKind::NotFound))?;
        if !*node.plugged.borrow() {
            return Err(io::Error::from(io::ErrorKind::NotFound));
        }
        Ok(Box::new(NodeDevice {
            node,
            path: path.to_owned(),
        }))
    }
}

fn real(name: &str) -> Rc<Recording> {
    let dir = common::shared_dir().join("recordings/evemu");
    Rc::new(Recording::read_file(&dir.join(name)).unwrap())
}

fn node(rec: Rc<Recording>, chunk: usize) -> Node {
    Node {
        rec,
        cursor: Rc::default(),
        plugged: Rc::new(RefCell::new(true)),
        chunk,
    }
}

const CONFIG: &str = r#"
[display]
width = 800
height = 480

[[input.device]]
match_name = "Atmel maXTouch Touchscreen"
calibration = [-1.0, 0.0, 1.0, 0.0, 1.0, 0.0]
"#;

#[test]
fn touchscreens_are_read_and_other_devices_skipped() {
    let opener = Opener::default();
    opener.nodes.borrow_mut().insert(
        "/dev/input/event3".into(),
        node(real("atmel-maxtouch.1-finger-drag-up-down.evemu"), 1000),
    );
    opener.nodes.borrow_mut().insert(
        "/dev/input/event4".into(),
        node(real("evemu-data.bcm5974-touchpad.evemu"), 1000),
    );
    opener.nodes.borrow_mut().insert(
        "/dev/input/event5".into(),
        node(real("dell-canvas-pen.evemu"), 1000),
    );
    let config = Config::parse(CONFIG, Path::new("test.toml")).unwrap();
    let mut hub = InputHub::new(opener, config.input.clone(), config.display.picture());
    let mut out = Vec::new();
    hub.dispatch(0, &mut out);
    assert_eq!(hub.device_count(), 1, "only the touchscreen is opened");
    let touches: Vec<_> = out
        .iter()
        .filter_map(|e| match e {
            HubEvent::Touch { frame, .. } => Some(&frame.contacts),
            _ => None,
        })
        .flatten()
        .collect();
    assert!(!touches.is_empty());
    // The configured matrix mirrors x: raw x near 0 lands near the right edge.
    for c in &touches {
        let expected_x = (1.0 - f64::from(c.raw.x) / 799.0) * 800.0;
        assert!((c.screen.x - expected_x).abs() < 1e-6, "{c:?}");
        assert!((0.0..=800.0).contains(&c.screen.x) && (0.0..=480.0).contains(&c.screen.y));
    }
}

#[test]
fn a_pen_on_odd_axes_is_opened_as_a_touchscreen_with_its_overrides() {
    let with = |config: &str| {
        let opener = Opener::default();
        opener.nodes.borrow_mut().insert(
            "/dev/input/event6".into(),
            node(Rc::new(common::egalax_like()), 1000),
        );
        let config = Config::parse(config, Path::new("test.toml")).unwrap();
        let mut hub = InputHub::new(opener, config.input.clone(), config.display.picture());
        let mut out = Vec::new();
        hub.dispatch(0, &mut out);
        let fingers = out
            .iter()
            .filter_map(|e| match e {
                HubEvent::Touch { frame, .. } => Some(&frame.contacts),
                _ => None,
            })
            .flatten()
            .filter(|c| c.tool == marionette::input::touch::Tool::Finger)
            .count();
        (hub.device_count(), fingers)
    };
    // As it announces itself: a pen without positions, not opened.
    assert_eq!(with(""), (0, 0));
    let (devices, fingers) = with(
        "[[input.device]]\nmatch_usb = \"0eef:0001\"\naxes = { x = \"ABS_Z\", y = \"ABS_RX\" }\ntool = \"finger\"\n",
    );
    assert_eq!(devices, 1);
    assert!(fingers > 20, "{fingers} finger contacts");
}

#[test]
fn unplug_cancels_contacts_and_replug_restores_calibration() {
    let opener = Opener::default();
    let rec = real("atmel-maxtouch.1-finger-drag-up-down.evemu");
    let panel = node(rec, 10);
    opener
        .nodes
        .borrow_mut()
        .insert("/dev/input/event7".into(), panel.clone());
    let config = Config::parse(CONFIG, Path::new("test.toml")).unwrap();
    let mut hub = InputHub::new(
        opener.clone(),
        config.input.clone(),
        config.display.picture(),
    );
    let mut out = Vec::new();
    hub.dispatch(0, &mut out);
    hub.dispatch(10_000, &mut out);
    let down_before: usize = match out.iter().rev().find_map(|e| match e {
        HubEvent::Touch { frame, .. } => Some(&frame.contacts),
        _ => None,
    }) {
        Some(c) => c.iter().filter(|c| c.phase.is_down()).count(),
        None => 0,
    };
    assert_eq!(down_before, 1, "a finger is down mid-drag");

    // Unplug: the finger is cancelled and the device removed, no panic.
    *panel.plugged.borrow_mut() = false;
    out.clear();
    hub.dispatch(20_000, &mut out);
    assert!(
        matches!(out.last(), Some(HubEvent::Removed { .. })),
        "{out:?}"
    );
    let cancelled = out.iter().any(|e| matches!(e, HubEvent::Touch { frame, .. } if frame.contacts.iter().any(|c| c.phase == Phase::Cancel)));
    assert!(cancelled, "the finger that was down is cancelled: {out:?}");
    assert_eq!(hub.device_count(), 0);
    hub.dispatch(30_000, &mut out);

    // Plugged back (under another node name, as USB does): picked up at the
    // next rescan, calibration applied again.
    let rec2 = real("atmel-maxtouch.1-finger-drag-up-down.evemu");
    opener
        .nodes
        .borrow_mut()
        .insert("/dev/input/event9".into(), node(rec2, 1000));
    out.clear();
    hub.dispatch(500_000, &mut out);
    assert_eq!(hub.device_count(), 0, "not before the rescan interval");
    hub.dispatch(1_100_000, &mut out);
    assert_eq!(hub.device_count(), 1);
    assert!(
        matches!(&out[0], HubEvent::Added { path, .. } if path == Path::new("/dev/input/event9"))
    );
    let c = out
        .iter()
        .find_map(|e| match e {
            HubEvent::Touch { frame, .. } => frame.contacts.first().copied(),
            _ => None,
        })
        .unwrap();
    let expected_x = (1.0 - f64::from(c.raw.x) / 799.0) * 800.0;
    assert!(
        (c.screen.x - expected_x).abs() < 1e-6,
        "calibration re-applied"
    );
}

#[test]
fn devices_that_fail_to_open_are_retried() {
    let opener = Opener::default();
    let config = Config::parse(CONFIG, Path::new("test.toml")).unwrap();
    let mut hub = InputHub::new(
        opener.clone(),
        config.input.clone(),
        config.display.picture(),
    );
    let mut out = Vec::new();
    hub.dispatch(0, &mut out);
    assert_eq!(hub.device_count(), 0);
    opener.nodes.borrow_mut().insert(
        "/dev/input/event1".into(),
        node(real("quanta-optical.touch-on-left.evemu"), 1000),
    );
    hub.rescan(5, &mut out);
    assert_eq!(hub.device_count(), 1);
}

#[test]
fn two_panels_number_their_fingers_apart() {
    // Two panels of one make, each touched by one finger: each numbers it
    // from its own first slot; the hub hands out ids that differ (the
    // panel in the high bits), so a stage holding both never mixes them.
    let opener = Opener::default();
    for path in ["/dev/input/event3", "/dev/input/event6"] {
        opener.nodes.borrow_mut().insert(
            path.into(),
            node(real("atmel-maxtouch.1-finger-drag-up-down.evemu"), 1000),
        );
    }
    let config = Config::parse(CONFIG, Path::new("test.toml")).unwrap();
    let mut hub = InputHub::new(opener, config.input.clone(), config.display.picture());
    let mut out = Vec::new();
    hub.dispatch(0, &mut out);
    assert_eq!(hub.device_count(), 2);
    let mut ids: BTreeMap<u32, std::collections::BTreeSet<u64>> = BTreeMap::new();
    for e in &out {
        if let HubEvent::Touch { device, frame } = e {
            for c in &frame.contacts {
                assert_eq!(c.id >> 32, u64::from(*device), "{c:?}");
                ids.entry(*device).or_default().insert(c.id);
            }
        }
    }
    assert_eq!(ids.len(), 2, "{ids:?}");
    let sets: Vec<_> = ids.values().collect();
    assert!(sets[0].is_disjoint(sets[1]), "{ids:?}");
}

#[test]
fn frames_come_out_in_seconds_since_the_callers_start() {
    // The hub hands out finished frames: their time is the recording's
    // event stamps counted from the epoch the caller gives, so the kiosk
    // feeds them on without converting anything.
    let rec = real("atmel-maxtouch.1-finger-drag-up-down.evemu");
    let config = Config::parse(CONFIG, Path::new("test.toml")).unwrap();
    let times = |epoch_us: i64| -> Vec<f64> {
        let opener = Opener::default();
        opener
            .nodes
            .borrow_mut()
            .insert("/dev/input/event3".into(), node(rec.clone(), 1000));
        let mut hub =
            InputHub::new(opener, config.input.clone(), config.display.picture()).since(epoch_us);
        let mut out = Vec::new();
        hub.dispatch(0, &mut out);
        out.iter()
            .filter_map(|e| match e {
                HubEvent::Touch { frame, .. } => Some(frame.t),
                _ => None,
            })
            .collect()
    };
    let first_us = rec.events[0].time_us;
    let from_first = times(first_us);
    let later = times(first_us + 2_500_000);
    assert!(from_first.len() > 10, "{} frames", from_first.len());
    assert!(
        from_first[0] >= 0.0 && from_first[0] < 0.1,
        "{}",
        from_first[0]
    );
    assert!(from_first.windows(2).all(|w| w[0] <= w[1]));
    assert_eq!(from_first.len(), later.len());
    for (a, b) in from_first.iter().zip(&later) {
        assert!((a - b - 2.5).abs() < 1e-9, "{a} {b}");
    }
    // `watch` prints the frame flat, as its operators read it.
    let line = serde_json::to_value(HubEvent::Touch {
        device: 1,
        frame: marionette::input::touch::ScreenFrame {
            t: 0.5,
            contacts: Vec::new(),
        },
    })
    .unwrap();
    assert_eq!(
        line,
        serde_json::json!({"event": "touch", "device": 1, "t": 0.5, "contacts": []})
    );
}
