//! Time control during an action (the paper's section 5): the action's
//! generalized time (0..1) follows the time synthesised from the touches,
//! moving at most one frame's worth per frame, forward or back; where the
//! condition segment forbids stillness, time keeps moving while the finger
//! rests; when every finger lifts, time runs forward or back as the segment
//! says. Reaching 1 finishes the action, returning to 0 cancels it.
//!
//! Pure and deterministic: time comes from the caller's `dt`.

use serde::Serialize;

use crate::character::library::{ActionDef, Release};

/// What happened to an action, with the time it happened at.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "event", rename_all = "snake_case")]
pub enum ActionEvent {
    Started {
        action: String,
        time_s: f64,
        /// A walk the pelvis finger started by going out of posing's
        /// reach (told as the travelling action its drag came nearest, or
        /// `walking`): no action template started it.
        #[serde(skip_serializing_if = "std::ops::Not::not")]
        by_reach: bool,
        /// How the template recogniser decided it (none for the paper's
        /// rule, a walk by reach, or an action started otherwise).
        #[serde(skip_serializing_if = "Option::is_none")]
        decided: Option<Decided>,
    },
    /// A drag lifted having started nothing: the action it came nearest
    /// to starting, and what held it back.
    NearMiss {
        action: String,
        time_s: f64,
        /// The leading template's cost and the limit it had to be under
        /// (m).
        cost_m: f64,
        cost_limit_m: f64,
        /// Its lead over the next action, and the lead needed (m).
        margin_m: f64,
        margin_needed_m: f64,
        /// Share of the template's path the drag covered.
        coverage: f64,
        /// The threshold that held it back: `cost` or `margin`.
        held_by: &'static str,
    },
    /// Time stopped moving with a finger resting (where allowed).
    Stopped {
        action: String,
        time_s: f64,
        at: f64,
    },
    Finished {
        action: String,
        time_s: f64,
    },
    Cancelled {
        action: String,
        time_s: f64,
    },
}

/// How the template recogniser decided to start an action.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Decided {
    /// The best template's cost (m).
    pub cost_m: f64,
    /// How much more the next action cost (m; infinite: no other action
    /// matched).
    pub margin_m: f64,
    /// Share of the template's path the drag covered.
    pub coverage: f64,
}

/// How the action stands after a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    Playing,
    Finished,
    Cancelled,
}

/// The touches' say in this frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drive {
    /// The generalized time synthesised from the touches, while a finger
    /// is down; `None` when every finger has lifted.
    pub target: Option<f64>,
    /// The fingers are down but not moving on the screen.
    pub resting: bool,
}

/// One action being played.
#[derive(Clone, Debug)]
pub struct ActionTimeline {
    def: ActionDef,
    /// Length of the action at natural speed (s): one frame's worth of
    /// generalized time is `dt / duration`.
    duration: f64,
    t: f64,
    /// Direction of the last move: +1 forward, −1 back.
    direction: f64,
    moving: bool,
    status: Status,
    clock: f64,
}

impl ActionTimeline {
    /// Start `def` at generalized time `t0` (the recognised part of the
    /// trajectory) at `time_s`.
    #[must_use]
    pub fn start(
        def: ActionDef,
        duration: f64,
        t0: f64,
        time_s: f64,
        events: &mut Vec<ActionEvent>,
    ) -> Self {
        events.push(ActionEvent::Started {
            action: def.name.clone(),
            time_s,
            by_reach: false,
            decided: None,
        });
        Self {
            def,
            duration: duration.max(1e-3),
            t: t0.clamp(0.0, 1.0),
            direction: 1.0,
            moving: true,
            status: Status::Playing,
            clock: time_s,
        }
    }

    /// The current generalized time.
    #[must_use]
    pub fn time(&self) -> f64 {
        self.t
    }

    #[must_use]
    pub fn status(&self) -> Status {
        self.status
    }

    #[must_use]
    pub fn name(&self) -> &str {
        &self.def.name
    }

    /// Advance by `dt` seconds.
    pub fn step(&mut self, dt: f64, drive: Drive, events: &mut Vec<ActionEvent>) -> Status {
        if self.status != Status::Playing {
            return self.status;
        }
        self.clock += dt;
        let frame = dt / self.duration;
        let segment = *self.def.segment_at(self.t);
        let delta = match drive.target {
            // A resting finger where stillness is not allowed: time keeps
            // going the way it went.
            Some(_) if drive.resting && !segment.still => self.direction * frame,
            Some(target) => (target - self.t).clamp(-frame, frame),
            None => match segment.release {
                Release::Forward => frame,
                Release::Backward => -frame,
            },
        };
        let was_moving = self.moving;
        self.moving = delta.abs() > frame * 0.25;
        if delta.abs() > 1e-12 {
            self.direction = delta.signum();
        }
        if was_moving && !self.moving {
            events.push(ActionEvent::Stopped {
                action: self.def.name.clone(),
                time_s: self.clock,
                at: self.t,
            });
        }
        self.t = (self.t + delta).clamp(0.0, 1.0);
        // Within a millionth of a frame of an end is at the end.
        if self.t >= 1.0 - frame * 1e-6 {
            self.t = 1.0;
            self.status = Status::Finished;
            events.push(ActionEvent::Finished {
                action: self.def.name.clone(),
                time_s: self.clock,
            });
        } else if self.t <= frame * 1e-6 && delta < 0.0 {
            self.t = 0.0;
            self.status = Status::Cancelled;
            events.push(ActionEvent::Cancelled {
                action: self.def.name.clone(),
                time_s: self.clock,
            });
        }
        self.status
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::character::library::Segment;
    use crate::character::roles::Role;

    /// A punch-like action: wind-up (may pause, cancels on lift), strike
    /// (keeps moving, completes on lift), recovery (may pause).
    fn punch() -> ActionDef {
        ActionDef {
            name: "punch".into(),
            clips: vec![],
            primary: Role::RightHand,
            threshold_m: None,
            segments: vec![
                Segment {
                    until: 0.3,
                    still: true,
                    release: Release::Backward,
                },
                Segment {
                    until: 0.7,
                    still: false,
                    release: Release::Forward,
                },
                Segment {
                    until: 1.0,
                    still: true,
                    release: Release::Forward,
                },
            ],
        }
    }

    const DT: f64 = 0.1; // one frame = 0.1 of generalized time at duration 1 s

    /// Step through finger states: `Some(t)` a finger asking for time `t`
    /// (resting when it asks for the same as in the previous frame),
    /// `None` no finger.
    fn run(tl: &mut ActionTimeline, drives: &[Option<f64>], ev: &mut Vec<ActionEvent>) -> Vec<f64> {
        let mut previous = None;
        drives
            .iter()
            .map(|d| {
                let resting = d.is_some() && *d == previous;
                previous = *d;
                tl.step(
                    DT,
                    Drive {
                        target: *d,
                        resting,
                    },
                    ev,
                );
                (tl.time() * 1000.0).round() / 1000.0
            })
            .collect()
    }

    #[test]
    fn time_follows_the_touch_at_most_a_frame_per_frame() {
        let mut ev = Vec::new();
        let mut tl = ActionTimeline::start(punch(), 1.0, 0.1, 0.0, &mut ev);
        // The finger jumps ahead to 0.9: time goes there a frame at a time.
        let t = run(&mut tl, &[Some(0.9); 3], &mut ev);
        assert_eq!(t, vec![0.2, 0.3, 0.4]);
        // And back when the finger goes back (the strike keeps moving, but
        // a finger asking for the past is obeyed).
        let t = run(&mut tl, &[Some(0.1), Some(0.1)], &mut ev);
        assert_eq!(t, vec![0.3, 0.2]);
    }

    #[test]
    fn stillness_is_allowed_only_where_the_segment_allows_it() {
        let mut ev = Vec::new();
        let mut tl = ActionTimeline::start(punch(), 1.0, 0.1, 0.0, &mut ev);
        // Resting in the wind-up: time stands.
        let t = run(
            &mut tl,
            &[Some(0.2), Some(0.2), Some(0.2), Some(0.2)],
            &mut ev,
        );
        assert_eq!(t, vec![0.2, 0.2, 0.2, 0.2]);
        assert!(ev.iter().any(|e| matches!(e, ActionEvent::Stopped { .. })));
        // The finger moves into the strike and rests there: time keeps
        // going forward through the strike.
        let t = run(
            &mut tl,
            &[Some(0.4), Some(0.4), Some(0.4), Some(0.4), Some(0.4)],
            &mut ev,
        );
        assert_eq!(t, vec![0.3, 0.4, 0.5, 0.6, 0.7]);
        // In the recovery it may stop again.
        let t = run(&mut tl, &[Some(0.75), Some(0.75), Some(0.75)], &mut ev);
        assert_eq!(t, vec![0.75, 0.75, 0.75]);
    }

    #[test]
    fn lifting_in_the_wind_up_cancels_and_in_the_strike_finishes() {
        let mut ev = Vec::new();
        let mut tl = ActionTimeline::start(punch(), 1.0, 0.1, 0.0, &mut ev);
        run(&mut tl, &[Some(0.2)], &mut ev);
        let t = run(&mut tl, &[None, None, None], &mut ev);
        assert_eq!(t, vec![0.1, 0.0, 0.0]);
        assert_eq!(tl.status(), Status::Cancelled);
        assert!(matches!(ev.last(), Some(ActionEvent::Cancelled { .. })));

        let mut ev = Vec::new();
        let mut tl = ActionTimeline::start(punch(), 1.0, 0.3, 5.0, &mut ev);
        run(&mut tl, &[Some(0.5), Some(0.5)], &mut ev);
        let t = run(&mut tl, &[None; 8], &mut ev);
        assert_eq!(t[..6], [0.6, 0.7, 0.8, 0.9, 1.0, 1.0]);
        assert_eq!(tl.status(), Status::Finished);
        match ev.last() {
            Some(ActionEvent::Finished { time_s, .. }) => {
                assert!((time_s - 5.7).abs() < 1e-9, "{time_s}")
            }
            other => panic!("{other:?}"),
        }
        assert!(matches!(ev[0], ActionEvent::Started { time_s, .. } if time_s == 5.0));
    }
}
