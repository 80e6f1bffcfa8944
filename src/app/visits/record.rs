//! What visitors do, as rows: the table's touch events and the characters'
//! action events made into sessions, touches (grabs and camera moves),
//! actions and near misses. Pure: times come in as seconds on the frames'
//! clock and go out as Unix milliseconds from the epoch given at the start.
//! No personal data and no trajectories: a touch keeps only the cell of a
//! coarse grid where the finger landed.

use std::collections::{BTreeMap, BTreeSet};

use crate::control::action::timeline::ActionEvent;
use crate::control::stage::{Took, TouchEvent};
use crate::input::touch::ContactId;

/// Cells across and down the picture for where fingers land.
pub const GRID: (u32, u32) = (16, 9);

/// One row of the record. Rows with the same key replace each other (a
/// session is told again as it grows, an action again when it ends).
#[derive(Clone, Debug, PartialEq)]
pub enum Row {
    /// A session: from the first touch after the table was idle to its
    /// last finger lifting (`length_s`); `ended` once the table went idle
    /// again. Keyed by its start.
    Session {
        start_ms: i64,
        length_s: f64,
        peak_fingers: u32,
        /// Characters whose parts were grabbed.
        characters: u32,
        ended: bool,
    },
    /// A finger that landed and lifted: what it took (`part` with the
    /// character, `camera`, or `nothing`), the cell it landed in and how
    /// long it stayed.
    Touch {
        session_ms: i64,
        at_ms: i64,
        took: &'static str,
        part: Option<&'static str>,
        character: Option<u32>,
        cell: (u32, u32),
        duration_s: f64,
    },
    /// An action a character started: how it was decided (the template's
    /// cost and margin; none for a walk started by reach or the paper's
    /// rule) and how it ended (`playing` until it does). Keyed by its
    /// start, character and name.
    Action {
        session_ms: i64,
        at_ms: i64,
        character: u32,
        action: String,
        by_reach: bool,
        cost_m: Option<f64>,
        margin_m: Option<f64>,
        outcome: &'static str,
        length_s: Option<f64>,
    },
    /// A drag that came nearest to an action and started nothing, and the
    /// threshold that held it back.
    NearMiss {
        session_ms: i64,
        at_ms: i64,
        character: u32,
        action: String,
        cost_m: f64,
        cost_limit_m: f64,
        margin_m: f64,
        margin_needed_m: f64,
        held_by: &'static str,
    },
}

/// A finger down now.
#[derive(Clone, Copy, Debug)]
struct Finger {
    t: f64,
    took: Took,
    cell: (u32, u32),
}

/// The session going on.
#[derive(Clone, Debug)]
struct Open {
    start: f64,
    start_ms: i64,
    /// The last time a finger lifted or went down.
    last: f64,
    peak: u32,
    characters: BTreeSet<usize>,
}

/// Actions playing: (character, name) to their start (s) and the row
/// told then.
type Playing = BTreeMap<(usize, String), (f64, Row)>;

/// The rows being made from a table's events.
#[derive(Clone, Debug)]
pub struct Visits {
    epoch_ms: f64,
    idle_after_s: f64,
    picture: (f64, f64),
    session: Option<Open>,
    fingers: BTreeMap<ContactId, Finger>,
    playing: Playing,
    /// Sessions, touches, actions started and near misses made so far.
    pub counts: Counts,
}

/// How many of each row were made.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Counts {
    pub sessions: u64,
    pub touches: u64,
    pub grabs: u64,
    pub actions: u64,
    pub near_misses: u64,
}

impl Visits {
    /// Frames' time 0 is `epoch_unix_s` (Unix seconds); a session ends
    /// after `idle_after_s` with no finger down; the picture is `width` x
    /// `height` pixels.
    #[must_use]
    pub fn new(epoch_unix_s: f64, idle_after_s: f64, width: f64, height: f64) -> Self {
        Self {
            epoch_ms: epoch_unix_s * 1e3,
            idle_after_s,
            picture: (width.max(1.0), height.max(1.0)),
            session: None,
            fingers: BTreeMap::new(),
            playing: BTreeMap::new(),
            counts: Counts::default(),
        }
    }

    fn ms(&self, t: f64) -> i64 {
        (self.epoch_ms + t * 1e3).round() as i64
    }

    fn cell(&self, x: f64, y: f64) -> (u32, u32) {
        let c = |v: f64, size: f64, n: u32| {
            ((v / size * f64::from(n)).floor() as i64).clamp(0, i64::from(n) - 1) as u32
        };
        (c(x, self.picture.0, GRID.0), c(y, self.picture.1, GRID.1))
    }

    fn session_row(&self, ended: bool) -> Option<Row> {
        let s = self.session.as_ref()?;
        Some(Row::Session {
            start_ms: s.start_ms,
            length_s: (s.last - s.start).max(0.0),
            peak_fingers: s.peak,
            characters: s.characters.len() as u32,
            ended,
        })
    }

    /// A touch event from the table.
    pub fn touched(&mut self, e: &TouchEvent, out: &mut Vec<Row>) {
        match *e {
            TouchEvent::Down { id, t, at, took } => {
                if self.session.is_none() {
                    self.session = Some(Open {
                        start: t,
                        start_ms: self.ms(t),
                        last: t,
                        peak: 0,
                        characters: BTreeSet::new(),
                    });
                    self.counts.sessions += 1;
                }
                let cell = self.cell(at.x, at.y);
                self.fingers.insert(id, Finger { t, took, cell });
                let down = self.fingers.len() as u32;
                if let Some(s) = self.session.as_mut() {
                    s.last = t;
                    s.peak = s.peak.max(down);
                    if let Took::Part { character, .. } = took {
                        s.characters.insert(character);
                    }
                }
                out.extend(self.session_row(false));
            }
            TouchEvent::Up { id, t } => {
                let Some(f) = self.fingers.remove(&id) else {
                    return;
                };
                let Some(s) = self.session.as_mut() else {
                    return;
                };
                s.last = t;
                let session_ms = s.start_ms;
                let (took, part, character) = match f.took {
                    Took::Part { character, role } => {
                        self.counts.grabs += 1;
                        ("part", Some(role.name()), Some(character as u32))
                    }
                    Took::Camera => ("camera", None, None),
                    Took::Nothing => ("nothing", None, None),
                };
                self.counts.touches += 1;
                out.push(Row::Touch {
                    session_ms,
                    at_ms: self.ms(f.t),
                    took,
                    part,
                    character,
                    cell: f.cell,
                    duration_s: (t - f.t).max(0.0),
                });
                out.extend(self.session_row(false));
            }
        }
    }

    /// An action event of character `k`.
    pub fn action(&mut self, k: usize, e: &ActionEvent, out: &mut Vec<Row>) {
        let Some(session_ms) = self.session.as_ref().map(|s| s.start_ms) else {
            // An action with nobody at the table (a walk ending after the
            // session did) belongs to no session.
            if let ActionEvent::Finished { action, .. } | ActionEvent::Cancelled { action, .. } = e
            {
                self.playing.remove(&(k, action.clone()));
            }
            return;
        };
        match e {
            ActionEvent::Started {
                action,
                time_s,
                by_reach,
                decided,
            } => {
                let row = Row::Action {
                    session_ms,
                    at_ms: self.ms(*time_s),
                    character: k as u32,
                    action: action.clone(),
                    by_reach: *by_reach,
                    cost_m: decided.map(|d| d.cost_m),
                    margin_m: decided.map(|d| d.margin_m).filter(|m| m.is_finite()),
                    outcome: "playing",
                    length_s: None,
                };
                self.playing
                    .insert((k, action.clone()), (*time_s, row.clone()));
                self.counts.actions += 1;
                out.push(row);
            }
            ActionEvent::Finished { action, time_s }
            | ActionEvent::Cancelled { action, time_s } => {
                // The start's row told again with how it ended.
                let Some((t0, mut row)) = self.playing.remove(&(k, action.clone())) else {
                    return;
                };
                if let Row::Action {
                    outcome, length_s, ..
                } = &mut row
                {
                    *outcome = if matches!(e, ActionEvent::Finished { .. }) {
                        "finished"
                    } else {
                        "cancelled"
                    };
                    *length_s = Some((time_s - t0).max(0.0));
                }
                out.push(row);
            }
            ActionEvent::NearMiss {
                action,
                time_s,
                cost_m,
                cost_limit_m,
                margin_m,
                margin_needed_m,
                held_by,
                ..
            } => {
                self.counts.near_misses += 1;
                out.push(Row::NearMiss {
                    session_ms,
                    at_ms: self.ms(*time_s),
                    character: k as u32,
                    action: action.clone(),
                    cost_m: *cost_m,
                    cost_limit_m: *cost_limit_m,
                    margin_m: if margin_m.is_finite() {
                        *margin_m
                    } else {
                        -1.0
                    },
                    margin_needed_m: *margin_needed_m,
                    held_by,
                });
            }
            ActionEvent::Stopped { .. } => {}
        }
    }

    /// The time is `t`: a session with no finger down for `idle_after_s`
    /// ends.
    pub fn tick(&mut self, t: f64, out: &mut Vec<Row>) {
        let idle = self
            .session
            .as_ref()
            .is_some_and(|s| self.fingers.is_empty() && t - s.last >= self.idle_after_s);
        if idle {
            self.end(out);
        }
    }

    /// The session going on ends now (the table idle, or the program
    /// stopping); fingers still down are told as touches lasting until
    /// then.
    pub fn end(&mut self, out: &mut Vec<Row>) {
        if let Some(s) = &self.session {
            let last = s.last;
            let ids: Vec<ContactId> = self.fingers.keys().copied().collect();
            for id in ids {
                self.touched(&TouchEvent::Up { id, t: last }, out);
            }
        }
        out.extend(self.session_row(true));
        self.session = None;
        self.playing.clear();
    }

    /// Whether a session is going on.
    #[must_use]
    pub fn in_session(&self) -> bool {
        self.session.is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::character::roles::Role;
    use crate::control::action::timeline::Decided;
    use crate::screen::ScreenPoint;

    fn down(id: ContactId, t: f64, x: f64, took: Took) -> TouchEvent {
        TouchEvent::Down {
            id,
            t,
            at: ScreenPoint::new(x, 10.0),
            took,
        }
    }

    #[test]
    fn a_session_runs_from_the_first_touch_to_the_idle_table() {
        let mut v = Visits::new(1_000.0, 45.0, 1600.0, 900.0);
        let mut rows = Vec::new();
        let hand = Took::Part {
            character: 0,
            role: Role::LeftHand,
        };
        v.touched(&down(1, 2.0, 50.0, hand), &mut rows);
        v.touched(&down(2, 2.5, 1599.0, Took::Camera), &mut rows);
        v.action(
            0,
            &ActionEvent::Started {
                action: "wave".into(),
                time_s: 3.0,
                by_reach: false,
                decided: Some(Decided {
                    cost_m: 0.01,
                    margin_m: 0.03,
                    coverage: 0.5,
                }),
            },
            &mut rows,
        );
        v.touched(&TouchEvent::Up { id: 1, t: 4.0 }, &mut rows);
        v.touched(&TouchEvent::Up { id: 2, t: 5.0 }, &mut rows);
        v.action(
            0,
            &ActionEvent::Finished {
                action: "wave".into(),
                time_s: 6.0,
            },
            &mut rows,
        );
        v.tick(49.9, &mut rows);
        assert!(v.in_session(), "not idle for 45 s yet");
        v.tick(50.0, &mut rows);
        assert!(!v.in_session());
        assert_eq!(
            rows.last(),
            Some(&Row::Session {
                start_ms: 1_002_000,
                length_s: 3.0,
                peak_fingers: 2,
                characters: 1,
                ended: true,
            })
        );
        let touches: Vec<_> = rows
            .iter()
            .filter_map(|r| match r {
                Row::Touch {
                    took,
                    part,
                    cell,
                    duration_s,
                    ..
                } => Some((*took, *part, *cell, *duration_s)),
                _ => None,
            })
            .collect();
        assert_eq!(
            touches,
            vec![
                ("part", Some("left_hand"), (0, 0), 2.0),
                ("camera", None, (15, 0), 2.5)
            ]
        );
        let ended = rows.iter().rev().find_map(|r| match r {
            Row::Action {
                outcome,
                length_s,
                cost_m,
                ..
            } => Some((*outcome, *length_s, *cost_m)),
            _ => None,
        });
        assert_eq!(ended, Some(("finished", Some(3.0), Some(0.01))));
        assert_eq!(
            v.counts,
            Counts {
                sessions: 1,
                touches: 2,
                grabs: 1,
                actions: 1,
                near_misses: 0
            }
        );
    }

    #[test]
    fn a_touch_after_the_idle_time_is_a_new_session_and_fingers_down_at_the_end_are_told() {
        let mut v = Visits::new(0.0, 10.0, 100.0, 100.0);
        let mut rows = Vec::new();
        v.touched(&down(1, 0.0, 5.0, Took::Camera), &mut rows);
        v.touched(&TouchEvent::Up { id: 1, t: 1.0 }, &mut rows);
        v.tick(11.0, &mut rows);
        v.touched(&down(2, 20.0, 5.0, Took::Nothing), &mut rows);
        v.end(&mut rows);
        assert_eq!(v.counts.sessions, 2);
        assert_eq!(v.counts.touches, 2);
        let ends: Vec<i64> = rows
            .iter()
            .filter_map(|r| match r {
                Row::Session {
                    start_ms,
                    ended: true,
                    ..
                } => Some(*start_ms),
                _ => None,
            })
            .collect();
        assert_eq!(ends, vec![0, 20_000]);
    }
}
