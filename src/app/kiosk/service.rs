//! The service view: over the scene, for a technician at the table, the
//! touchscreens read, every finger's calibrated point and its trail, and
//! the vital signs (frame rate, frame time, touch-to-flip latency). On
//! with `display.service_view`, or toggled by five fingers or more held
//! down together for three seconds. Pure: touch frames and times in,
//! marks out.

use std::collections::{BTreeMap, VecDeque};

use super::vitals::Summary;
use crate::control::marks::ServiceMarks;
use crate::input::touch::{Phase, ScreenFrame};
use crate::screen::ScreenPoint;

/// Fingers held together that toggle the view...
pub const GESTURE_FINGERS: usize = 5;
/// ...for this long (s).
pub const GESTURE_S: f64 = 3.0;
/// How much of each finger's path is drawn (s).
const TRAIL_S: f64 = 1.5;

/// The service view's state.
#[derive(Clone, Debug, Default)]
pub struct ServiceView {
    pub on: bool,
    /// Since when enough fingers are down, and whether that hold has
    /// toggled the view already.
    held_since: Option<f64>,
    toggled: bool,
    /// Every finger down: its recent points, newest last.
    trails: BTreeMap<u64, VecDeque<(f64, ScreenPoint)>>,
    /// The touchscreens read, by instance: path and name.
    pub panels: BTreeMap<u32, String>,
    /// Today's visitor sessions and actions (the visits record), if kept.
    pub today: Option<(u64, u64)>,
}

impl ServiceView {
    #[must_use]
    pub fn new(on: bool) -> Self {
        Self {
            on,
            ..Self::default()
        }
    }

    /// A touch frame at `t` (its contacts' ids made unique across panels).
    /// Returns whether this frame's hold toggled the view.
    pub fn touch(&mut self, frame: &ScreenFrame, t: f64) -> bool {
        for c in &frame.contacts {
            match c.phase {
                Phase::Up | Phase::Cancel => {
                    self.trails.remove(&c.id);
                }
                _ => {
                    let trail = self.trails.entry(c.id).or_default();
                    trail.push_back((t, c.screen));
                }
            }
        }
        self.tick(t)
    }

    /// Time passes: old trail points go, and a hold is timed.
    pub fn tick(&mut self, t: f64) -> bool {
        for trail in self.trails.values_mut() {
            while trail.len() > 1 && trail.front().is_some_and(|(s, _)| t - s > TRAIL_S) {
                trail.pop_front();
            }
        }
        if self.trails.len() < GESTURE_FINGERS {
            self.held_since = None;
            self.toggled = false;
            return false;
        }
        let since = *self.held_since.get_or_insert(t);
        if !self.toggled && t - since >= GESTURE_S {
            self.toggled = true;
            self.on = !self.on;
            tracing::info!(on = self.on, "service view toggled by a five-finger hold");
            return true;
        }
        false
    }

    /// What to draw, when on.
    #[must_use]
    pub fn marks(&self, vitals: &Summary, output: &str, size: (u32, u32)) -> Option<ServiceMarks> {
        if !self.on {
            return None;
        }
        let mut lines = vec![format!(
            "SERVICE VIEW   {output} {}x{}   (5 fingers held 3 s: off)",
            size.0, size.1
        )];
        if self.panels.is_empty() {
            lines.push("touchscreens: none read; see marionette list-devices".to_owned());
        } else {
            lines.extend(self.panels.values().map(|p| format!("touchscreen: {p}")));
        }
        lines.push(match self.today {
            Some((sessions, actions)) => {
                format!("today: {sessions} visitor sessions, {actions} actions started")
            }
            None => "today: no visits record (kiosk.visits)".to_owned(),
        });
        lines.push(format!(
            "{:.1} fps   frame {:.1} / {:.1} ms   touch to flip {:.0} / {:.0} ms   (p50 / p99)",
            vitals.fps,
            vitals.frame_ms_p50,
            vitals.frame_ms_p99,
            vitals.latency_ms_p50,
            vitals.latency_ms_p99
        ));
        for trail in self.trails.values() {
            if let Some((_, p)) = trail.back() {
                lines.push(format!("finger at {:.0}, {:.0}", p.x, p.y));
            }
        }
        Some(ServiceMarks {
            lines,
            trails: self
                .trails
                .values()
                .map(|t| t.iter().map(|(_, p)| *p).collect())
                .collect(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::calibration::RawPoint;
    use crate::input::touch::{ScreenContact, Tool};

    fn frame(t: f64, fingers: &[(u64, Phase, f64)]) -> ScreenFrame {
        ScreenFrame {
            t,
            contacts: fingers
                .iter()
                .map(|&(id, phase, x)| ScreenContact {
                    id,
                    phase,
                    tool: Tool::Finger,
                    raw: RawPoint { x: 0, y: 0 },
                    screen: ScreenPoint::new(x, 100.0),
                })
                .collect(),
        }
    }

    #[test]
    fn five_fingers_held_three_seconds_toggle_it_once() {
        let mut v = ServiceView::new(false);
        let down: Vec<_> = (1..=5)
            .map(|id| (id, Phase::Down, 10.0 * id as f64))
            .collect();
        assert!(!v.touch(&frame(0.0, &down), 0.0));
        assert!(!v.tick(2.9));
        assert!(v.tick(3.0));
        assert!(v.on);
        // Held on: no second toggle.
        assert!(!v.tick(9.0));
        assert!(v.on);
        // One lifts, all go down again and hold: off.
        assert!(!v.touch(&frame(9.5, &[(5, Phase::Up, 50.0)]), 9.5));
        v.touch(&frame(10.0, &[(6, Phase::Down, 60.0)]), 10.0);
        assert!(v.tick(13.0));
        assert!(!v.on);
    }

    #[test]
    fn four_fingers_or_a_short_hold_do_nothing() {
        let mut v = ServiceView::new(true);
        let four: Vec<_> = (1..=4).map(|id| (id, Phase::Down, 0.0)).collect();
        v.touch(&frame(0.0, &four), 0.0);
        assert!(!v.tick(10.0));
        let five: Vec<_> = (1..=5).map(|id| (id, Phase::Down, 0.0)).collect();
        let mut w = ServiceView::new(true);
        w.touch(&frame(0.0, &five), 0.0);
        w.touch(&frame(2.0, &[(1, Phase::Up, 0.0)]), 2.0);
        assert!(!w.tick(5.0));
        assert!(v.on && w.on);
    }

    #[test]
    fn it_shows_panels_fingers_trails_and_figures() {
        let mut v = ServiceView::new(true);
        v.panels
            .insert(1, "/dev/input/event5 \"ILITEK Multi-Touch\"".to_owned());
        v.touch(&frame(0.0, &[(1, Phase::Down, 100.0)]), 0.0);
        for k in 1..=30 {
            let t = f64::from(k) * 0.1;
            v.touch(&frame(t, &[(1, Phase::Move, 100.0 + 10.0 * t)]), t);
        }
        let s = Summary {
            fps: 59.9,
            frame_ms_p50: 2.5,
            frame_ms_p99: 7.0,
            latency_ms_p50: 22.0,
            latency_ms_p99: 41.0,
            ..Summary::default()
        };
        let m = v.marks(&s, "Virtual-1", (1280, 720)).unwrap();
        let text = m.lines.join("\n");
        assert!(text.contains("ILITEK"), "{text}");
        assert!(text.contains("59.9 fps"), "{text}");
        assert!(text.contains("touch to flip 22 / 41 ms"), "{text}");
        assert!(text.contains("finger at 130, 100"), "{text}");
        assert!(text.contains("today: no visits record"), "{text}");
        v.today = Some((14, 37));
        let today = v
            .marks(&s, "Virtual-1", (1280, 720))
            .unwrap()
            .lines
            .join("\n");
        assert!(
            today.contains("today: 14 visitor sessions, 37 actions started"),
            "{today}"
        );
        // The last 1.5 s of the path.
        assert_eq!(m.trails.len(), 1);
        assert!(
            (14..=17).contains(&m.trails[0].len()),
            "{}",
            m.trails[0].len()
        );
        v.on = false;
        assert!(v.marks(&s, "Virtual-1", (1280, 720)).is_none());
    }
}
