//! The attract loop: a recording the idle kiosk performs until someone
//! touches, its fingers kept apart from real ones and lifted when a real
//! touch arrives.

use std::collections::BTreeSet;

use crate::input::calibration::RawPoint;
use crate::input::touch::{Phase, ScreenContact, ScreenFrame, Tool};
use crate::screen::ScreenPoint;

/// Contacts from the attract recording are kept apart from real ones.
pub(super) const ATTRACT_ID: u64 = 1 << 48;

/// The attract recording playing in a loop.
pub(super) struct Attract {
    frames: Vec<ScreenFrame>,
    /// Controller time at which the recording's time 0 plays.
    start: f64,
    next: usize,
    down: BTreeSet<u64>,
}

impl Attract {
    /// `frames` played from controller time `start` on.
    pub(super) fn new(frames: Vec<ScreenFrame>, start: f64) -> Self {
        Self {
            frames,
            start,
            next: 0,
            down: BTreeSet::new(),
        }
    }

    /// Frames due by `t`, shifted to controller time; the recording starts
    /// over a second after it ends.
    pub(super) fn due(&mut self, t: f64, out: &mut Vec<ScreenFrame>) {
        while let Some(f) = self.frames.get(self.next) {
            if self.start + f.t > t {
                return;
            }
            let mut f = f.clone();
            f.t += self.start;
            for c in &mut f.contacts {
                c.id += ATTRACT_ID;
                if c.phase.is_down() {
                    self.down.insert(c.id);
                } else {
                    self.down.remove(&c.id);
                }
            }
            out.push(f);
            self.next += 1;
        }
        let end = self.frames.last().map_or(0.0, |f| f.t);
        if t > self.start + end + 1.0 {
            self.start = t;
            self.next = 0;
        }
    }

    /// A frame that lifts what the recording still holds.
    pub(super) fn lift(&mut self, t: f64) -> Option<ScreenFrame> {
        if self.down.is_empty() {
            return None;
        }
        let contacts = std::mem::take(&mut self.down)
            .into_iter()
            .map(|id| ScreenContact {
                id,
                phase: Phase::Cancel,
                tool: Tool::Finger,
                raw: RawPoint { x: 0, y: 0 },
                screen: ScreenPoint::new(0.0, 0.0),
            })
            .collect();
        Some(ScreenFrame { t, contacts })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::calibration::RawPoint;
    use crate::input::touch::Tool;
    use crate::screen::ScreenPoint;

    fn frame(t: f64, id: u64, phase: Phase) -> ScreenFrame {
        ScreenFrame {
            t,
            contacts: vec![ScreenContact {
                id,
                phase,
                tool: Tool::Finger,
                raw: RawPoint { x: 0, y: 0 },
                screen: ScreenPoint::new(10.0, 20.0),
            }],
        }
    }

    #[test]
    fn attract_plays_in_a_loop_and_lets_go_when_touched() {
        let mut a = Attract {
            frames: vec![
                frame(0.0, 1, Phase::Down),
                frame(0.5, 1, Phase::Move),
                frame(1.0, 1, Phase::Up),
            ],
            start: 10.0,
            next: 0,
            down: BTreeSet::new(),
        };
        let mut out = Vec::new();
        a.due(9.9, &mut out);
        assert!(out.is_empty(), "nothing before its start");
        a.due(10.6, &mut out);
        assert_eq!(out.len(), 2);
        assert!((out[1].t - 10.5).abs() < 1e-9, "shifted to the loop's time");
        assert_eq!(
            out[0].contacts[0].id,
            1 + ATTRACT_ID,
            "kept apart from real ids"
        );
        // A touch now: the recording's finger is cancelled.
        let lift = a.lift(10.7).unwrap();
        assert_eq!(lift.contacts[0].phase, Phase::Cancel);
        assert!(a.lift(10.8).is_none());
        // Played to its end, it starts over a second later.
        out.clear();
        a.due(11.1, &mut out);
        a.due(12.2, &mut out);
        assert_eq!(a.next, 0);
        assert!((a.start - 12.2).abs() < 1e-9);
        out.clear();
        a.due(12.2, &mut out);
        assert_eq!(out[0].contacts[0].phase, Phase::Down);
    }
}
