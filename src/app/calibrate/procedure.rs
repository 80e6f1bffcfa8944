//! The calibration procedure as a state machine, apart from the display
//! and the devices: which touchscreen to calibrate, then one steady touch
//! per target. It is fed the hub's events and the time (seconds on any
//! clock) and says what to show next, so every path through it (a finger
//! that slides, lifts at once, never comes, a second panel, a stop) is
//! tested without a screen or a panel.

use std::path::PathBuf;

use crate::input::calibration::RawPoint;
use crate::input::hub::HubEvent;
use crate::input::touch::Phase;

/// Targets as fractions of the picture: four near the corners, then the
/// check point in the middle.
pub const TARGETS: [(f64, f64); 5] = [(0.1, 0.1), (0.9, 0.1), (0.9, 0.9), (0.1, 0.9), (0.5, 0.5)];

/// A touch is taken from the samples of its last `STEADY_S` seconds before
/// the finger lifts, when they all lie within `STEADY_SPREAD` of the
/// panel's range of their median.
const STEADY_S: f64 = 0.25;
const STEADY_SPREAD: f64 = 0.01;

/// With no device named, the only touchscreen is taken once it has been
/// alone this long (s): a second one may still be announced.
const ALONE_S: f64 = 2.0;
/// Looking for the touchscreen gives up after this long (s).
const FIND_TIMEOUT_S: f64 = 10.0;

/// What to ask the visitor when a touch was not steady.
pub const HOLD_STILL: &str = "hold the finger still on the target a moment, then lift it";

/// The steady position of one touch: its samples (time in seconds, raw
/// point) from going down to lifting, the last at the lift (a finger that
/// holds still sends no events: each sample stands until the next);
/// `None` if the finger did not hold still for the last `STEADY_S`.
#[must_use]
pub fn steady_touch(samples: &[(f64, RawPoint)], range: (f64, f64)) -> Option<RawPoint> {
    let (end, _) = *samples.last()?;
    // The sample in force when the window opens, and those after it.
    let from = samples.iter().rposition(|(t, _)| *t <= end - STEADY_S)?;
    let tail: Vec<RawPoint> = samples[from..].iter().map(|(_, p)| *p).collect();
    let median = |mut v: Vec<i32>| {
        v.sort_unstable();
        v[v.len() / 2]
    };
    let m = RawPoint {
        x: median(tail.iter().map(|p| p.x).collect()),
        y: median(tail.iter().map(|p| p.y).collect()),
    };
    let steady = tail.iter().all(|p| {
        f64::from((p.x - m.x).abs()) <= range.0 * STEADY_SPREAD
            && f64::from((p.y - m.y).abs()) <= range.1 * STEADY_SPREAD
    });
    steady.then_some(m)
}

/// A touchscreen the hub announced.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Found {
    pub device: u32,
    pub path: PathBuf,
    pub name: String,
}

/// Finding the touchscreen to calibrate.
#[derive(Clone, Debug)]
pub struct FindDevice {
    wanted: Option<String>,
    started: f64,
    seen: Vec<Found>,
}

/// Where finding the touchscreen stands.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Finding {
    Waiting,
    Found(Found),
    /// Given up: what to tell the operator.
    Failed(String),
}

impl FindDevice {
    /// Look for the touchscreen named `wanted` (or the only one) from `t`.
    #[must_use]
    pub fn new(wanted: Option<String>, t: f64) -> Self {
        Self {
            wanted,
            started: t,
            seen: Vec::new(),
        }
    }

    /// Take the hub's events at `t` and say where the search stands.
    pub fn step(&mut self, t: f64, events: impl IntoIterator<Item = HubEvent>) -> Finding {
        for e in events {
            if let HubEvent::Added { device, path, name } = e {
                self.seen.push(Found { device, path, name });
            }
        }
        let found = match &self.wanted {
            Some(n) => self.seen.iter().find(|d| d.name == *n).cloned(),
            None if self.seen.len() == 1 && t - self.started > ALONE_S => {
                self.seen.first().cloned()
            }
            None => None,
        };
        if let Some(d) = found {
            return Finding::Found(d);
        }
        if t - self.started <= FIND_TIMEOUT_S {
            return Finding::Waiting;
        }
        let names: Vec<&str> = self.seen.iter().map(|d| d.name.as_str()).collect();
        Finding::Failed(match (&self.wanted, names.len()) {
            (Some(n), _) => format!(
                "no touchscreen named \"{n}\" (found: {}); see `marionette list-devices`",
                if names.is_empty() {
                    "none".to_owned()
                } else {
                    names.join(", ")
                }
            ),
            (None, 0) => {
                "no touchscreen found: plug one in (see `marionette list-devices`)".to_owned()
            }
            (None, _) => format!(
                "several touchscreens: choose one with --device NAME ({})",
                names.join(", ")
            ),
        })
    }
}

/// One steady touch per target, from one device's first finger.
#[derive(Clone, Debug)]
pub struct Touches {
    device: u32,
    /// The panel's axis ranges, for what "steady" means.
    range: (f64, f64),
    targets: usize,
    timeout_s: f64,
    taken: Vec<RawPoint>,
    samples: Vec<(f64, RawPoint)>,
    /// When the current target was shown.
    shown_at: f64,
    hint: Option<&'static str>,
}

/// Where the touches stand after a step.
#[derive(Clone, Debug, PartialEq)]
pub enum Collecting {
    /// Show target `target` (0-based) with the hint, if any; a new target
    /// or a hint that changed.
    Show {
        target: usize,
        hint: Option<&'static str>,
    },
    /// Nothing new.
    Waiting,
    /// No finger came to target `target` (0-based) in time.
    TimedOut { target: usize },
    /// Every target has its touch.
    Done(Vec<RawPoint>),
}

impl Touches {
    /// Collect `targets` touches from `device`, each within `timeout_s` of
    /// its target being shown; the first target is shown at `t`.
    #[must_use]
    pub fn new(device: u32, range: (f64, f64), targets: usize, timeout_s: f64, t: f64) -> Self {
        Self {
            device,
            range,
            targets,
            timeout_s,
            taken: Vec::new(),
            samples: Vec::new(),
            shown_at: t,
            hint: None,
        }
    }

    /// The target to show first.
    #[must_use]
    pub fn first(&self) -> Collecting {
        Collecting::Show {
            target: 0,
            hint: None,
        }
    }

    /// Take the hub's events at `t`.
    pub fn step(&mut self, t: f64, events: impl IntoIterator<Item = HubEvent>) -> Collecting {
        for e in events {
            let HubEvent::Touch { device, frame } = e else {
                continue;
            };
            if device != self.device {
                continue;
            }
            // The first finger only.
            let Some(c) = frame.contacts.first() else {
                continue;
            };
            let at = frame.t;
            if c.phase.is_down() {
                self.samples.push((at, c.raw));
                continue;
            }
            if self.samples.is_empty() {
                continue;
            }
            if c.phase != Phase::Up {
                // Cancelled (a palm, lost events): that touch is void.
                self.samples.clear();
                continue;
            }
            let last = self.samples[self.samples.len() - 1].1;
            self.samples.push((at, last));
            let lifted = std::mem::take(&mut self.samples);
            match steady_touch(&lifted, self.range) {
                Some(p) => {
                    self.taken.push(p);
                    self.hint = None;
                }
                None => self.hint = Some(HOLD_STILL),
            }
            self.shown_at = t;
            if self.taken.len() == self.targets {
                return Collecting::Done(self.taken.clone());
            }
            // The rest of this batch came with the touch just judged.
            return Collecting::Show {
                target: self.taken.len(),
                hint: self.hint,
            };
        }
        if self.samples.is_empty() && t - self.shown_at > self.timeout_s {
            return Collecting::TimedOut {
                target: self.taken.len(),
            };
        }
        Collecting::Waiting
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::touch::{ScreenContact, ScreenFrame, Tool};
    use crate::screen::ScreenPoint;

    fn touch(device: u32, t: f64, phase: Phase, x: i32, y: i32) -> HubEvent {
        HubEvent::Touch {
            device,
            frame: ScreenFrame {
                t,
                contacts: vec![ScreenContact {
                    id: 1,
                    phase,
                    tool: Tool::Finger,
                    raw: RawPoint { x, y },
                    screen: ScreenPoint::new(0.0, 0.0),
                }],
            },
        }
    }

    fn added(device: u32, name: &str) -> HubEvent {
        HubEvent::Added {
            device,
            path: PathBuf::from(format!("/dev/input/event{device}")),
            name: name.to_owned(),
        }
    }

    /// A finger that holds still at (x, y) from `t` for `hold` seconds.
    fn press(device: u32, t: f64, hold: f64, x: i32, y: i32) -> Vec<HubEvent> {
        vec![
            touch(device, t, Phase::Down, x, y),
            touch(device, t + hold, Phase::Up, x, y),
        ]
    }

    #[test]
    fn a_steady_touch_per_target_in_order() {
        let mut c = Touches::new(3, (4095.0, 4095.0), 2, 60.0, 0.0);
        assert_eq!(c.step(0.5, Vec::new()), Collecting::Waiting);
        assert_eq!(
            c.step(1.5, press(3, 1.0, 0.5, 400, 400)),
            Collecting::Show {
                target: 1,
                hint: None
            }
        );
        assert_eq!(
            c.step(3.0, press(3, 2.0, 0.5, 3700, 3700)),
            Collecting::Done(vec![RawPoint::new(400, 400), RawPoint::new(3700, 3700)])
        );
    }

    #[test]
    fn a_finger_lifted_at_once_or_sliding_is_asked_again() {
        let mut c = Touches::new(3, (4095.0, 4095.0), 1, 60.0, 0.0);
        // A tap: too short to be steady.
        assert_eq!(
            c.step(1.1, press(3, 1.0, 0.05, 400, 400)),
            Collecting::Show {
                target: 0,
                hint: Some(HOLD_STILL)
            }
        );
        // A slide across the last quarter second.
        let mut slide = vec![touch(3, 2.0, Phase::Down, 400, 400)];
        slide.push(touch(3, 2.4, Phase::Move, 900, 400));
        slide.push(touch(3, 2.5, Phase::Up, 900, 400));
        assert_eq!(
            c.step(2.6, slide),
            Collecting::Show {
                target: 0,
                hint: Some(HOLD_STILL)
            }
        );
        // Then a good one.
        assert_eq!(
            c.step(4.0, press(3, 3.0, 0.6, 410, 390)),
            Collecting::Done(vec![RawPoint::new(410, 390)])
        );
    }

    #[test]
    fn other_panels_and_cancelled_touches_are_ignored() {
        let mut c = Touches::new(3, (4095.0, 4095.0), 1, 60.0, 0.0);
        assert_eq!(c.step(1.6, press(4, 1.0, 0.5, 10, 10)), Collecting::Waiting);
        let cancelled = vec![
            touch(3, 2.0, Phase::Down, 10, 10),
            touch(3, 2.6, Phase::Cancel, 10, 10),
        ];
        assert_eq!(c.step(2.7, cancelled), Collecting::Waiting);
        assert_eq!(
            c.step(4.0, press(3, 3.0, 0.5, 20, 20)),
            Collecting::Done(vec![RawPoint::new(20, 20)])
        );
    }

    #[test]
    fn no_touch_in_time_gives_up_but_a_finger_down_keeps_it_waiting() {
        let mut c = Touches::new(3, (4095.0, 4095.0), 2, 30.0, 0.0);
        assert_eq!(c.step(29.0, Vec::new()), Collecting::Waiting);
        // A finger resting on the panel past the timeout: still waiting.
        assert_eq!(
            c.step(29.5, vec![touch(3, 29.5, Phase::Down, 5, 5)]),
            Collecting::Waiting
        );
        assert_eq!(c.step(45.0, Vec::new()), Collecting::Waiting);
        assert_eq!(
            c.step(46.0, vec![touch(3, 46.0, Phase::Up, 5, 5)]),
            Collecting::Show {
                target: 1,
                hint: None
            }
        );
        // The timeout counts again from the new target.
        assert_eq!(c.step(75.0, Vec::new()), Collecting::Waiting);
        assert_eq!(c.step(76.5, Vec::new()), Collecting::TimedOut { target: 1 });
    }

    #[test]
    fn the_named_panel_is_found_or_the_only_one_after_two_seconds() {
        let mut f = FindDevice::new(Some("eGalax".into()), 0.0);
        assert_eq!(f.step(0.1, vec![added(1, "other")]), Finding::Waiting);
        let Finding::Found(d) = f.step(0.2, vec![added(2, "eGalax")]) else {
            panic!("the named panel was not found");
        };
        assert_eq!(d.device, 2);
        let mut f = FindDevice::new(None, 0.0);
        assert_eq!(f.step(0.5, vec![added(1, "only")]), Finding::Waiting);
        assert!(matches!(f.step(2.1, Vec::new()), Finding::Found(d) if d.name == "only"));
    }

    #[test]
    fn the_search_gives_up_saying_what_it_saw() {
        let mut f = FindDevice::new(None, 0.0);
        f.step(0.1, vec![added(1, "a"), added(2, "b")]);
        assert_eq!(f.step(9.0, Vec::new()), Finding::Waiting);
        let Finding::Failed(why) = f.step(10.5, Vec::new()) else {
            panic!("did not give up");
        };
        assert!(why.contains("--device") && why.contains("a, b"), "{why}");
        let mut f = FindDevice::new(Some("x".into()), 0.0);
        let Finding::Failed(why) = f.step(11.0, Vec::new()) else {
            panic!("did not give up");
        };
        assert!(why.contains("\"x\"") && why.contains("none"), "{why}");
        let mut f = FindDevice::new(None, 0.0);
        let Finding::Failed(why) = f.step(11.0, Vec::new()) else {
            panic!("did not give up");
        };
        assert!(why.contains("plug one in"), "{why}");
    }

    fn at(t: f64, x: i32, y: i32) -> (f64, RawPoint) {
        (t, RawPoint { x, y })
    }

    #[test]
    fn only_steady_touches_count() {
        let range = (4095.0, 4095.0);
        // Slides onto the target, then holds still with a little jitter.
        let mut s: Vec<_> = (0..10)
            .map(|k| at(f64::from(k) * 0.01, 100 + k * 40, 200))
            .collect();
        s.extend((0..30).map(|k| at(0.1 + f64::from(k) * 0.01, 500 + (k % 3) - 1, 300 + (k % 2))));
        let p = steady_touch(&s, range).unwrap();
        assert!((p.x - 500).abs() <= 1 && (p.y - 300).abs() <= 1, "{p:?}");
        // A tap: too short.
        let tap: Vec<_> = (0..5).map(|k| at(f64::from(k) * 0.01, 500, 300)).collect();
        assert_eq!(steady_touch(&tap, range), None);
        // A finger that holds perfectly still sends nothing until it lifts.
        let still = [at(0.0, 700, 800), at(0.6, 700, 800)];
        assert_eq!(
            steady_touch(&still, range),
            Some(RawPoint { x: 700, y: 800 })
        );
        // Still sliding when lifted.
        let slide: Vec<_> = (0..40)
            .map(|k| at(f64::from(k) * 0.01, 100 + k * 20, 300))
            .collect();
        assert_eq!(steady_touch(&slide, range), None);
    }
}
