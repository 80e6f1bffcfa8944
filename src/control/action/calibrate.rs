//! Thresholds of the template recogniser chosen for one library, by
//! leave-one-clip-out on the library's own clips: each clip in turn is
//! replayed as the trials replay held-out capture (two views, three paces,
//! noise, slow posing drags; [`super::trials`]) against the templates of
//! every other clip, and the cost threshold, margin and coverage floor that
//! start the most right actions (a wrong start counted as two misses) while
//! slow drags start at most half the budget are kept: leave-one-out is
//! optimistic, so the budget is halved.
//!
//! The same drags, decided with the chosen thresholds, are what
//! `marionette library check` reports to the library's builder.

use serde::Serialize;

use super::model::ActionModel;
use super::recogniser::{
    CAPS, COVERAGE_FLOORS, DragMatch, GATES, Recogniser, SLOW_CAPS, TemplateRule, Thresholds,
};
use super::trials::{Drag, each_drag};
use crate::character::library::Library;
use crate::character::motion::Clip;
use crate::character::roles::Role;

/// Slow posing drags may start an action in at most this share of trials
/// (the calibration aims at half of it).
pub const SLOW_BUDGET: f64 = 0.02;

/// The seed of the calibration's trials (fixed: a library calibrates the
/// same way every time).
pub const SEED: u64 = 1;

const COSTS_M: [f64; 24] = [
    0.02, 0.03, 0.04, 0.05, 0.06, 0.07, 0.08, 0.09, 0.10, 0.11, 0.12, 0.13, 0.14, 0.15, 0.16, 0.17,
    0.18, 0.19, 0.20, 0.22, 0.24, 0.26, 0.28, 0.30,
];
const MARGINS_M: [f64; 6] = [0.0, 0.005, 0.01, 0.02, 0.03, 0.05];

/// What one left-out drag did with the chosen thresholds.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Outcome {
    /// The action whose clip was left out, and the clip.
    pub action: String,
    pub clip: String,
    /// The view (degrees around the character's facing) and pace.
    pub view_deg: f64,
    /// A slow posing drag (which should start nothing).
    pub slow: bool,
    /// What it started.
    pub started: Option<String>,
    /// Share of the drag's duration seen when it started.
    pub decided_at: Option<f64>,
}

/// A library's calibration: the recogniser with its thresholds, and the
/// left-out drags decided with them.
#[derive(Clone, Debug, PartialEq)]
pub struct Calibration {
    pub recogniser: Recogniser,
    pub outcomes: Vec<Outcome>,
    /// Whether any threshold kept slow drags within half the budget (else
    /// the strictest was kept).
    pub within_budget: bool,
}

/// Per point of a drag, for each coverage floor: the leading action, its
/// cost and the next action's cost.
type Trace = Vec<[(u16, f32, f32); GATES]>;

struct Recorded {
    test: usize,
    view_deg: f64,
    slow: bool,
    /// Per point: the share of the drag's duration seen.
    seen: Vec<f32>,
    trace: Trace,
}

/// A wrong start counts as this many missed ones: a visitor who meant a
/// punch and got a wave has lost more than one who got nothing.
const WRONG_WEIGHT: f64 = 2.0;

/// The first point of a recorded drag where an action starts with these
/// thresholds, and which.
fn decide(
    r: &Recorded,
    gate: usize,
    cost_m: f64,
    margin_m: f64,
    limits: &[Option<f64>],
) -> Option<(usize, usize)> {
    r.trace.iter().enumerate().find_map(|(n, row)| {
        let (a, c, next) = row[gate];
        if a == u16::MAX {
            return None;
        }
        let limit = limits[usize::from(a)].unwrap_or(cost_m);
        (f64::from(c) <= limit && f64::from(next) - f64::from(c) >= margin_m)
            .then_some((usize::from(a), n))
    })
}

/// [`decide`] for every threshold of [`COSTS_M`] at once, in one pass
/// over the drag: `out[k]` for `COSTS_M[k]`. A threshold decides at the
/// first point whose cost is under it, so as the least cost so far falls,
/// the thresholds above it are decided, highest first.
fn first_decisions(
    r: &Recorded,
    gate: usize,
    margin_m: f64,
    limits: &[Option<f64>],
    out: &mut [Option<(usize, usize)>],
) {
    out.fill(None);
    // Thresholds from `open` up are decided.
    let mut open = COSTS_M.len();
    for (n, row) in r.trace.iter().enumerate() {
        let (a, c, next) = row[gate];
        if a == u16::MAX || f64::from(next) - f64::from(c) < margin_m {
            continue;
        }
        let (a, c) = (usize::from(a), f64::from(c));
        if let Some(limit) = limits[a] {
            // An action with its own threshold starts at it, whatever the
            // library's.
            if c <= limit {
                for d in out.iter_mut().filter(|d| d.is_none()) {
                    *d = Some((a, n));
                }
                return;
            }
            continue;
        }
        while open > 0 && COSTS_M[open - 1] >= c {
            open -= 1;
            out[open] = Some((a, n));
        }
        if open == 0 {
            return;
        }
    }
}

/// The thresholds that start the most drags of `recorded` as their own
/// action (`which` says each test's action and template), the fewest as
/// another and earliest, with slow drags' starts within budget; whether
/// they are.
fn search(
    recorded: &[Recorded],
    which: &[(usize, usize)],
    limits: &[Option<f64>],
) -> (bool, Thresholds) {
    let true_drags = recorded.iter().filter(|r| !r.slow).count().max(1) as f64;
    let slow_drags = recorded.iter().filter(|r| r.slow).count().max(1) as f64;
    // (within budget, score, earlier decisions, fewer slow starts) and the
    // thresholds that give it.
    let mut best: Option<((bool, f64, f64, f64), Thresholds)> = None;
    let mut decisions = vec![None; COSTS_M.len()];
    for gate in 0..GATES {
        let (coverage, max_slow) = (COVERAGE_FLOORS[gate / CAPS], SLOW_CAPS[gate % CAPS]);
        for margin_m in MARGINS_M {
            // For every cost threshold at once: per threshold, the counts.
            let mut correct = [0usize; COSTS_M.len()];
            let mut wrong = [0usize; COSTS_M.len()];
            let mut slow = [0usize; COSTS_M.len()];
            let mut decided = [0.0f64; COSTS_M.len()];
            for r in recorded {
                first_decisions(r, gate, margin_m, limits, &mut decisions);
                for (k, d) in decisions.iter().enumerate() {
                    match (r.slow, d) {
                        (true, Some(_)) => slow[k] += 1,
                        (false, Some((a, n))) if *a == which[r.test].0 => {
                            correct[k] += 1;
                            decided[k] += f64::from(r.seen[*n]);
                        }
                        (false, Some(_)) => wrong[k] += 1,
                        _ => {}
                    }
                }
            }
            for (k, cost_m) in COSTS_M.iter().enumerate() {
                let slow_share = slow[k] as f64 / slow_drags;
                let key = (
                    slow_share <= SLOW_BUDGET / 2.0,
                    (correct[k] as f64 - WRONG_WEIGHT * wrong[k] as f64) / true_drags,
                    -(decided[k] / correct[k].max(1) as f64),
                    -slow_share,
                );
                let better = best
                    .as_ref()
                    .is_none_or(|(b, _)| key.partial_cmp(b).is_some_and(std::cmp::Ordering::is_gt));
                if better {
                    best = Some((
                        key,
                        Thresholds {
                            cost_m: *cost_m,
                            margin_m,
                            coverage,
                            max_slow,
                        },
                    ));
                }
            }
        }
    }
    best.map_or((true, Thresholds::default()), |(k, t)| (k.0, t))
}

impl Recorded {
    /// Drag `d` fed point by point to its match `m`: each point's lead
    /// under every gate, and how much of the drag was seen by then.
    fn of(mut m: DragMatch, d: &Drag<'_>) -> Self {
        let (t0, t1) = (
            d.trail.first().map_or(0.0, |p| p.t),
            d.trail.last().map_or(0.0, |p| p.t),
        );
        let mut trace = Trace::with_capacity(d.trail.len());
        let mut seen = Vec::with_capacity(d.trail.len());
        for p in d.trail {
            m.push(*p);
            let mut row = [(u16::MAX, f32::INFINITY, f32::INFINITY); GATES];
            for (k, r) in row.iter_mut().enumerate() {
                if let Some((a, c, n)) = m.lead(k) {
                    *r = (a as u16, c as f32, n as f32);
                }
            }
            trace.push(row);
            seen.push(if t1 > t0 {
                ((p.t - t0) / (t1 - t0)) as f32
            } else {
                1.0
            });
        }
        Self {
            test: d.test,
            view_deg: d.angle_deg,
            slow: d.slow,
            seen,
            trace,
        }
    }
}

/// The drags calibration leaves out in turn, one per template whose clip
/// the library holds: which (action, template) each is, and the dragged
/// part and clip, in the same order.
pub type LeftOut<'l> = (Vec<(usize, usize)>, Vec<(Role, &'l Clip)>);

/// The drags calibration leaves out in turn (see [`LeftOut`]).
#[must_use]
pub fn left_out_tests<'l>(lib: &'l Library, actions: &[ActionModel]) -> LeftOut<'l> {
    let mut which = Vec::new();
    let mut tests = Vec::new();
    for (ai, a) in actions.iter().enumerate() {
        for (ci, t) in a.templates.iter().enumerate() {
            if let Some(clip) = lib.clips.get(&t.clip) {
                which.push((ai, ci));
                tests.push((a.def.primary, clip));
            }
        }
    }
    (which, tests)
}

/// Choose the thresholds of `actions` (the library's models) by
/// leave-one-clip-out.
#[must_use]
pub fn calibrate(lib: &Library, actions: &[ActionModel], rule: TemplateRule) -> Calibration {
    let recogniser = Recogniser {
        rule,
        thresholds: Thresholds::default(),
    };
    let (which, tests) = left_out_tests(lib, actions);
    let mut recorded = Vec::new();
    each_drag(&tests, SEED, &mut |d| {
        let m = DragMatch::new(
            &recogniser,
            actions,
            d.role,
            d.camera,
            d.at,
            Some(which[d.test]),
        );
        recorded.push(Recorded::of(m, d));
    });
    let limits: Vec<Option<f64>> = actions.iter().map(|a| a.def.threshold_m).collect();
    let (within_budget, thresholds) = search(&recorded, &which, &limits);
    let floor = super::recogniser::gate_of(&thresholds);
    let outcomes = recorded
        .iter()
        .map(|r| {
            let (ai, ci) = which[r.test];
            let d = decide(r, floor, thresholds.cost_m, thresholds.margin_m, &limits);
            Outcome {
                action: actions[ai].def.name.clone(),
                clip: actions[ai].templates[ci].clip.clone(),
                view_deg: r.view_deg,
                slow: r.slow,
                started: d.map(|(a, _)| actions[a].def.name.clone()),
                decided_at: d.map(|(_, n)| f64::from(r.seen[n])),
            }
        })
        .collect();
    Calibration {
        recogniser: Recogniser { rule, thresholds },
        outcomes,
        within_budget,
    }
}
