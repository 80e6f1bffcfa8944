//! How far apart the actions a drag has to tell between are, next to how
//! far the held-out drags of one action stray from its own trajectory.
//!
//! Both are eq. 1's cost (px) of the first half of a path against an
//! action's projected trajectory, seen from the views `eval actions` uses
//! (the side, 90°, and the front-side, 45°, of the primary part). When two
//! actions led by the same part lie closer to each other than the drags of
//! one of them lie to its own trajectory, no threshold separates them from
//! that view: the drag alone does not say which was meant.

use glam::DVec3;
use serde::Serialize;

use crate::character::body::{Anchor, Placement};
use crate::character::motion::Clip;
use crate::character::roles::Role;
use crate::control::action::model::ActionModel;
use crate::control::action::trail::{StartRule, TrailPoint, match_trail};
use crate::control::action::trials::{Trial, camera, side_of};

/// What `eval actions` adds under `separation`.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Separation {
    /// For each ordered pair of actions led by the same part, from each
    /// view: the first half of `action`'s trajectory against `other`'s.
    pub pairs: Vec<PairCost>,
    /// For each tested action, from each view: its held-out drags (first
    /// half, at their own speed) against its own trajectory.
    pub own: Vec<OwnCost>,
}

/// One row of [`Separation::pairs`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PairCost {
    pub action: String,
    pub other: String,
    pub view_deg: f64,
    pub cost_px: f64,
}

/// One row of [`Separation::own`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OwnCost {
    pub action: String,
    pub view_deg: f64,
    pub drags: usize,
    pub mean_px: f64,
    pub max_px: f64,
}

fn round1(x: f64) -> f64 {
    (x * 10.0).round() / 10.0
}

/// The first half of a path (points at `dt` s apart) as a trail.
fn first_half(
    points: &[DVec3],
    dt: f64,
    cam: &crate::character::camera::Camera,
) -> Vec<TrailPoint> {
    let half = points.len() / 2 + 1;
    points[..half.min(points.len())]
        .iter()
        .enumerate()
        .filter_map(|(k, p)| {
            cam.project(*p).map(|at| TrailPoint {
                at,
                t: k as f64 * dt,
            })
        })
        .collect()
}

/// Measure the separation of `actions` and the spread of `tests`
/// (`(action name, clip)`) around their own actions.
#[must_use]
pub fn separation(
    actions: &[ActionModel],
    tests: &[(String, &Clip)],
    rule: &StartRule,
) -> Separation {
    let mut out = Separation::default();
    let cost = |trail: &[TrailPoint], traj: &[TrailPoint]| {
        if trail.len() < 2 || traj.is_empty() {
            return None;
        }
        match_trail(trail, traj, rule.h, rule.tempo).map(|m| m.cost)
    };
    let origin = Placement {
        position: DVec3::ZERO,
        yaw: 0.0,
        anchor: Anchor::ClipStart,
    };
    for a in actions {
        let chest = a
            .model
            .samples
            .first()
            .map_or(1.3, |s| s.parts[0][Role::Chest.index()].y);
        let side = side_of(a.def.primary);
        for view in [90.0 * side, 45.0 * side] {
            let cam = camera(view, &origin, chest);
            let n = a.trajectory.len().max(2) - 1;
            let trail = first_half(&a.trajectory, a.duration / n as f64, &cam);
            for b in actions {
                if b.def.name == a.def.name || b.def.primary != a.def.primary {
                    continue;
                }
                if let Some(c) = cost(&trail, &b.projected(&cam, &origin)) {
                    out.pairs.push(PairCost {
                        action: a.def.name.clone(),
                        other: b.def.name.clone(),
                        view_deg: view,
                        cost_px: round1(c),
                    });
                }
            }
        }
    }
    let mut own: std::collections::BTreeMap<(String, i64), Vec<f64>> = Default::default();
    for (name, clip) in tests {
        let Some(a) = actions.iter().find(|a| a.def.name == *name) else {
            continue;
        };
        let role = a.def.primary;
        let Trial { at, path, chest } = Trial::of(clip, role);
        let side = side_of(role);
        for view in [90.0 * side, 45.0 * side] {
            let cam = camera(view, &at, chest);
            let trail = first_half(&path, clip.frame_time, &cam);
            if let Some(c) = cost(&trail, &a.projected(&cam, &at)) {
                own.entry((name.clone(), view as i64)).or_default().push(c);
            }
        }
    }
    out.own = own
        .into_iter()
        .map(|((action, view), costs)| OwnCost {
            action,
            view_deg: view as f64,
            drags: costs.len(),
            mean_px: round1(costs.iter().sum::<f64>() / costs.len() as f64),
            max_px: round1(costs.iter().copied().fold(0.0, f64::max)),
        })
        .collect();
    out
}
