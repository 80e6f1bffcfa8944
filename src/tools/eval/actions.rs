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

use crate::character::body::Placement;
use crate::character::camera::Camera;
use crate::character::motion::Clip;
use crate::character::roles::Role;
use crate::control::action::model::{ActionModel, recognize};
use crate::control::action::recogniser::{DragMatch, Explained, Held, Recogniser, Thresholds};
use crate::control::action::trail::{StartRule, TrailPoint};
pub use crate::control::action::trials::Drag;
use crate::control::action::trials::each_drag;

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
    /// The same figures for each trial view (`"action"` names it: `90°`
    /// from the side, `45°` front-side).
    pub views: Vec<ActionRow>,
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
#[must_use]
pub fn seen_fraction(trail: &[TrailPoint], n: usize) -> f64 {
    match (
        trail.first(),
        trail.last(),
        n.checked_sub(1).and_then(|i| trail.get(i)),
    ) {
        (Some(a), Some(b), Some(c)) if b.t > a.t => ((c.t - a.t) / (b.t - a.t)).clamp(0.0, 1.0),
        _ => 1.0,
    }
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

/// Run the evaluation on the template recogniser alone: each trail is fed
/// point by point to a [`DragMatch`].
#[must_use]
pub fn eval_templates(
    actions: &[ActionModel],
    recogniser: &Recogniser,
    tests: &[(String, &Clip)],
    seed: u64,
) -> ActionEval {
    let mut judge = |d: &Drag<'_>| {
        let mut m = DragMatch::new(recogniser, actions, d.role, d.camera, d.at, None);
        d.trail.iter().enumerate().find_map(|(k, p)| {
            m.push(*p);
            m.decide(actions, &recogniser.thresholds)
                .map(|r| (actions[r.action].def.name.clone(), k + 1))
        })
    };
    eval_with(&with_primary(actions, tests), seed, &mut judge)
}

/// One drag of `eval actions --explain`: the test file's action and
/// name, the view, whether it was a slow posing drag, what it started, and
/// each of its points explained up to the one that started it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TrialExplained {
    pub action: String,
    pub file: String,
    pub view_deg: f64,
    pub slow: bool,
    pub started: Option<String>,
    pub points: Vec<PointExplained>,
}

/// A drag point explained, at `t` seconds from the drag's first.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PointExplained {
    pub t: f64,
    #[serde(flatten)]
    pub at: Explained,
}

/// Feed `trail` to `m` point by point, each point explained, until an
/// action starts: the points explained, and what started after how many
/// points.
pub fn explain_drag(
    mut m: DragMatch,
    actions: &[ActionModel],
    thresholds: &Thresholds,
    trail: &[TrailPoint],
) -> (Vec<PointExplained>, Option<(String, usize)>) {
    let t0 = trail.first().map_or(0.0, |p| p.t);
    let mut points = Vec::new();
    let started = trail.iter().enumerate().find_map(|(k, p)| {
        m.push(*p);
        let at = m.explain(actions, thresholds);
        let starts = at.held == Held::Starts;
        points.push(PointExplained {
            t: ((p.t - t0) * 1000.0).round() / 1000.0,
            at,
        });
        let decided = m.decide(actions, thresholds);
        debug_assert_eq!(starts, decided.is_some(), "explained as decided");
        decided.map(|r| (actions[r.action].def.name.clone(), k + 1))
    });
    (points, started)
}

/// [`eval_templates`], each drag explained point by point into `trials`
/// (`files` names each test).
#[must_use]
pub fn eval_templates_explained(
    actions: &[ActionModel],
    recogniser: &Recogniser,
    tests: &[(String, &Clip)],
    files: &[String],
    seed: u64,
    trials: &mut Vec<TrialExplained>,
) -> ActionEval {
    let known: Vec<usize> = (0..tests.len())
        .filter(|&i| actions.iter().any(|a| a.def.name == tests[i].0))
        .collect();
    let tests_known: Vec<(String, &Clip)> = known.iter().map(|&i| tests[i].clone()).collect();
    let mut judge = |d: &Drag<'_>| {
        let m = DragMatch::new(recogniser, actions, d.role, d.camera, d.at, None);
        let (points, started) = explain_drag(m, actions, &recogniser.thresholds, d.trail);
        let test = known[d.test];
        trials.push(TrialExplained {
            action: tests[test].0.clone(),
            file: files.get(test).cloned().unwrap_or_default(),
            view_deg: d.angle_deg,
            slow: d.slow,
            started: started.as_ref().map(|(a, _)| a.clone()),
            points,
        });
        started
    };
    eval_with(&with_primary(actions, &tests_known), seed, &mut judge)
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
    let mut all = Tally::default();
    let mut rows: BTreeMap<String, Tally> = BTreeMap::new();
    let mut views: BTreeMap<i64, Tally> = BTreeMap::new();
    let mut confusion: BTreeMap<String, BTreeMap<String, usize>> = BTreeMap::new();
    let drags: Vec<(Role, &Clip)> = tests.iter().map(|(_, r, c)| (*r, *c)).collect();
    each_drag(&drags, seed, &mut |d| {
        let name = &tests[d.test].0;
        let started = judge(d);
        let row = rows.entry(name.clone()).or_default();
        // Both sides' views count as one: 90° and 45° from the part's side.
        let view = views.entry(d.angle_deg.abs().round() as i64).or_default();
        if d.slow {
            for t in [&mut all, &mut *row, &mut *view] {
                t.slow_trials += 1;
                t.slow_triggers += usize::from(started.is_some());
            }
            return;
        }
        *confusion
            .entry(name.clone())
            .or_default()
            .entry(
                started
                    .as_ref()
                    .map_or_else(|| "none".to_owned(), |(a, _)| a.clone()),
            )
            .or_default() += 1;
        for t in [&mut all, &mut *row, &mut *view] {
            t.trials += 1;
            match &started {
                Some((a, n)) if a == name => {
                    t.correct += 1;
                    t.decided.push(seen_fraction(d.trail, *n));
                }
                Some(_) => t.wrong += 1,
                None => t.missed += 1,
            }
        }
    });
    let total = all.row(String::new());
    ActionEval {
        trials: total.trials,
        correct: total.correct,
        wrong_action: total.wrong_action,
        missed: total.missed,
        false_trigger_slow: total.false_trigger_slow,
        decided_at: total.decided_at,
        actions: rows.into_iter().map(|(name, t)| t.row(name)).collect(),
        views: views
            .into_iter()
            .map(|(deg, t)| t.row(format!("{deg}°")))
            .collect(),
        confusion,
        separation: None,
    }
}
