//! `marionette eval actions`: how reliably drags start the right action.
//!
//! For each test clip `<action>_*.bvh` (clips not in the library), the
//! primary part's true path is projected from a side camera and from a 45°
//! front-side camera (both on the primary part's side of the body) and
//! replayed as a finger trail at ×0.7, ×1 and ×1.5 of its speed with 2 px
//! of noise, one point per frame, until an action
//! starts. Slow posing drags (paths of each primary part at under a third
//! of the action's speed, in random directions) must start nothing.

use std::collections::BTreeMap;

use serde::Serialize;

use super::trial::{Trial, camera, side_of};
use crate::character::camera::Camera;
use crate::character::motion::Clip;
use crate::character::roles::Role;
use crate::control::action::model::{ActionModel, recognize};
use crate::control::action::trail::{StartRule, TrailPoint};
use crate::control::posing::sample::Placement;
use crate::screen::ScreenPoint;

/// What `eval actions` prints.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ActionEval {
    pub trials: usize,
    pub correct: f64,
    pub wrong_action: f64,
    pub missed: f64,
    pub false_trigger_slow: f64,
    /// Mean fraction of the true trajectory seen when the action started
    /// (by time: the last point the recogniser had, over the drag's
    /// duration).
    pub decided_at: f64,
    /// The same figures for each action tested, in name order.
    pub actions: Vec<ActionRow>,
    /// For each action tested, how many of its drags started each action
    /// (`"none"`: nothing started).
    pub confusion: BTreeMap<String, BTreeMap<String, usize>>,
    /// How far apart the actions are from the trial views, next to how far
    /// the held-out drags stray from their own action (`eval actions` adds
    /// it; see [`super::separation`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub separation: Option<super::separation::Separation>,
}

/// One action's row of [`ActionEval`].
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ActionRow {
    pub action: String,
    pub trials: usize,
    pub correct: f64,
    pub wrong_action: f64,
    pub missed: f64,
    pub false_trigger_slow: f64,
    pub decided_at: f64,
}

/// Counts behind a row.
#[derive(Default)]
struct Tally {
    trials: usize,
    correct: usize,
    wrong: usize,
    missed: usize,
    slow_trials: usize,
    slow_triggers: usize,
    decided: Vec<f64>,
}

impl Tally {
    fn row(&self, action: String) -> ActionRow {
        let frac = |a: usize, b: usize| {
            if b == 0 {
                0.0
            } else {
                (a as f64 / b as f64 * 1000.0).round() / 1000.0
            }
        };
        ActionRow {
            action,
            trials: self.trials,
            correct: frac(self.correct, self.trials),
            wrong_action: frac(self.wrong, self.trials),
            missed: frac(self.missed, self.trials),
            false_trigger_slow: frac(self.slow_triggers, self.slow_trials),
            decided_at: if self.decided.is_empty() {
                0.0
            } else {
                (self.decided.iter().sum::<f64>() / self.decided.len() as f64 * 1000.0).round()
                    / 1000.0
            },
        }
    }
}

/// A small deterministic generator for the noise.
struct Lcg(u64);

impl Lcg {
    fn unit(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn noise(&mut self, px: f64) -> f64 {
        (self.unit() * 2.0 - 1.0) * px
    }
}

/// Feed a trail point by point; the first recognition decides.
fn first_recognition(
    actions: &[ActionModel],
    role: Role,
    trail: &[TrailPoint],
    cam: &Camera,
    at: &Placement,
    rule: &StartRule,
) -> Option<(usize, usize)> {
    (2..=trail.len())
        .find_map(|n| recognize(actions, role, &trail[..n], cam, at, rule).map(|r| (r.action, n)))
}

/// The fraction of a trail's duration that its first `n` points span.
fn seen_fraction(trail: &[TrailPoint], n: usize) -> f64 {
    match (
        trail.first(),
        trail.last(),
        n.checked_sub(1).and_then(|i| trail.get(i)),
    ) {
        (Some(a), Some(b), Some(c)) if b.t > a.t => ((c.t - a.t) / (b.t - a.t)).clamp(0.0, 1.0),
        _ => 1.0,
    }
}

/// One drag to judge: the dragged part, the finger's trail on the screen
/// of `camera` (which looks at the clip's character from `angle_deg`
/// around it, at placement `at`).
pub struct Drag<'a> {
    pub role: Role,
    pub trail: &'a [TrailPoint],
    pub camera: &'a Camera,
    pub at: &'a Placement,
    pub angle_deg: f64,
}

/// Run the evaluation on the action models alone: each trail is fed point
/// by point to [`recognize`]. `tests` are `(action name, clip)`.
#[must_use]
pub fn eval_actions(
    actions: &[ActionModel],
    tests: &[(String, &Clip)],
    rule: &StartRule,
    seed: u64,
) -> ActionEval {
    let mut judge = |d: &Drag<'_>| {
        first_recognition(actions, d.role, d.trail, d.camera, d.at, rule)
            .map(|(a, n)| (actions[a].def.name.clone(), n))
    };
    eval_with(&with_primary(actions, tests), seed, &mut judge)
}

/// The tests whose action is in `actions`, with its primary part.
#[must_use]
pub fn with_primary<'c>(
    actions: &[ActionModel],
    tests: &[(String, &'c Clip)],
) -> Vec<(String, Role, &'c Clip)> {
    tests
        .iter()
        .filter_map(|(name, clip)| {
            let a = actions.iter().find(|a| a.def.name == *name)?;
            Some((name.clone(), a.def.primary, *clip))
        })
        .collect()
}

/// Run the evaluation with `judge`, which says which action a drag
/// started (by name) and after how many of its points, if any.
pub fn eval_with(
    tests: &[(String, Role, &Clip)],
    seed: u64,
    judge: &mut dyn FnMut(&Drag<'_>) -> Option<(String, usize)>,
) -> ActionEval {
    let mut rng = Lcg(seed ^ 0x9e37_79b9_7f4a_7c15);
    let mut all = Tally::default();
    let mut rows: BTreeMap<String, Tally> = BTreeMap::new();
    let mut confusion: BTreeMap<String, BTreeMap<String, usize>> = BTreeMap::new();
    for &(ref name, role, clip) in tests {
        let row = rows.entry(name.clone()).or_default();
        let confused = confusion.entry(name.clone()).or_default();
        let Trial { at, path, chest } = Trial::of(clip, role);
        // The cameras stand on the side of the primary part, as a visitor
        // looking at the punching arm would: the far side's actions can be
        // along the line of sight, which the start rule excludes by design.
        let side = side_of(role);
        for angle in [90.0 * side, 45.0 * side] {
            let cam = camera(angle, &at, chest);
            for speed in [0.7, 1.0, 1.5] {
                let trail: Vec<TrailPoint> = path
                    .iter()
                    .enumerate()
                    .filter_map(|(k, p)| {
                        cam.project(*p).map(|s| TrailPoint {
                            at: ScreenPoint::new(s.x + rng.noise(2.0), s.y + rng.noise(2.0)),
                            t: k as f64 * clip.frame_time / speed,
                        })
                    })
                    .collect();
                all.trials += 1;
                row.trials += 1;
                let drag = Drag {
                    role,
                    trail: &trail,
                    camera: &cam,
                    at: &at,
                    angle_deg: angle,
                };
                let started = judge(&drag);
                *confused
                    .entry(
                        started
                            .as_ref()
                            .map_or_else(|| "none".to_owned(), |(a, _)| a.clone()),
                    )
                    .or_default() += 1;
                for t in [&mut all, &mut *row] {
                    match &started {
                        Some((a, n)) if a == name => {
                            t.correct += 1;
                            t.decided.push(seen_fraction(&trail, *n));
                        }
                        Some(_) => t.wrong += 1,
                        None => t.missed += 1,
                    }
                }
                // A slow posing drag of the same part: as long, in a random
                // direction, at under a third of the speed.
                // (The length of the true path: the noise is not the
                // action's movement.)
                let truth: Vec<ScreenPoint> = path.iter().filter_map(|p| cam.project(*p)).collect();
                let len: f64 = truth.windows(2).map(|w| w[0].distance(w[1])).sum();
                let dir = rng.unit() * std::f64::consts::TAU;
                let duration = trail.last().map_or(1.0, |p| p.t) * (3.0 + rng.unit() * 2.0);
                let start = trail
                    .first()
                    .map_or(ScreenPoint::new(640.0, 360.0), |p| p.at);
                let steps = (duration / clip.frame_time).ceil().max(2.0) as usize;
                let slow: Vec<TrailPoint> = (0..=steps)
                    .map(|k| {
                        let s = k as f64 / steps as f64;
                        let wobble = (s * std::f64::consts::PI * 2.0).sin() * 0.15 * len;
                        TrailPoint {
                            at: ScreenPoint::new(
                                start.x + dir.cos() * len * s - dir.sin() * wobble + rng.noise(2.0),
                                start.y + dir.sin() * len * s + dir.cos() * wobble + rng.noise(2.0),
                            ),
                            t: s * duration,
                        }
                    })
                    .collect();
                let drag = Drag {
                    trail: &slow,
                    ..drag
                };
                let triggered = judge(&drag).is_some();
                for t in [&mut all, &mut *row] {
                    t.slow_trials += 1;
                    t.slow_triggers += usize::from(triggered);
                }
            }
        }
    }
    let total = all.row(String::new());
    ActionEval {
        trials: total.trials,
        correct: total.correct,
        wrong_action: total.wrong_action,
        missed: total.missed,
        false_trigger_slow: total.false_trigger_slow,
        decided_at: total.decided_at,
        actions: rows.into_iter().map(|(name, t)| t.row(name)).collect(),
        confusion,
        separation: None,
    }
}
