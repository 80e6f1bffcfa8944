//! Posture synthesis from constraints (the paper's section 4): find the
//! latent cells whose representatives best meet the constraints (looking
//! first at blocks of cells, then at the cells of the best blocks), blend
//! those cells' samples weighted by how well each meets them, then let CCD IK
//! move each constrained part onto its constraint (at most 0.2 m) and keep
//! planted feet where they are.

use glam::{DQuat, DVec3};

use super::model::LearnedModel;
use super::sample::{Placement, Sample, pose_of, wrap};
use crate::character::camera::HalfLine;
use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::{Pose, Skeleton, forward_kinematics};

/// Where a constrained body part should be.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Target {
    /// On the half-line from the camera through a touch.
    Ray(HalfLine),
    /// At a 3-D point (tests and other interfaces).
    Point(DVec3),
}

impl Target {
    /// Distance of `p` to the target.
    #[must_use]
    pub fn distance(&self, p: DVec3) -> f64 {
        match self {
            Target::Ray(r) => r.distance(p),
            Target::Point(q) => (p - *q).length(),
        }
    }

    /// The point of the target nearest to `p`.
    #[must_use]
    pub fn nearest(&self, p: DVec3) -> DVec3 {
        match self {
            Target::Ray(r) => r.closest(p),
            Target::Point(q) => *q,
        }
    }
}

/// A body part bound to a target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Constraint {
    pub role: Role,
    pub target: Target,
}

/// How to synthesise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SynthOptions {
    /// Find the region through the grid (the paper) or score every sample.
    pub use_grid: bool,
    /// Look into this many of the best cells.
    pub cells: usize,
    /// Search the cells of this many of the best blocks only (0: score
    /// every cell's representative).
    pub blocks: usize,
    /// Blend at most this many samples.
    pub blend: usize,
    /// Apply CCD IK after blending.
    pub ik: bool,
    /// Furthest IK may move a constrained part (m).
    pub max_ik_m: f64,
}

impl Default for SynthOptions {
    fn default() -> Self {
        Self {
            use_grid: true,
            cells: 20,
            blocks: 8,
            blend: 12,
            ik: true,
            max_ik_m: 0.2,
        }
    }
}

/// Mean distance of a sample's constrained parts to their targets, placed
/// at `at`.
#[must_use]
pub fn cost(sample: &Sample, roles: &RoleMap, constraints: &[Constraint], at: &Placement) -> f64 {
    if constraints.is_empty() {
        return 0.0;
    }
    constraints
        .iter()
        .map(|c| {
            c.target
                .distance(at.place(sample.local(at.anchor)[roles.get(c.role)]))
        })
        .sum::<f64>()
        / constraints.len() as f64
}

/// The indices of the `k` (at least one) lowest-scored items, in no order.
fn best(items: impl Iterator<Item = (usize, f64)>, k: usize) -> impl Iterator<Item = usize> {
    let mut items: Vec<(usize, f64)> = items.collect();
    let keep = k.clamp(1, items.len().max(1)).min(items.len());
    if keep > 0 {
        items.select_nth_unstable_by(keep - 1, |a, b| a.1.total_cmp(&b.1));
    }
    items.truncate(keep);
    items.into_iter().map(|(i, _)| i)
}

/// The samples to blend and their weights, best first.
#[must_use]
pub fn choose(
    model: &LearnedModel,
    roles: &RoleMap,
    constraints: &[Constraint],
    at: &Placement,
    opts: &SynthOptions,
) -> Vec<(usize, f64)> {
    let candidates: Vec<usize> = if opts.use_grid && !model.cells.is_empty() {
        let score = |representative: u32| {
            cost(
                &model.samples[representative as usize],
                roles,
                constraints,
                at,
            )
        };
        // The cells to look at: every one, or those of the blocks whose
        // representatives meet the constraints best.
        let looked: Vec<usize> = if opts.blocks > 0 && !model.blocks.is_empty() {
            let blocks =
                (0..model.blocks.len()).map(|i| (i, score(model.blocks[i].representative)));
            best(blocks, opts.blocks)
                .flat_map(|i| model.blocks[i].cells.iter().map(|&c| c as usize))
                .collect()
        } else {
            (0..model.cells.len()).collect()
        };
        // The cells whose representatives meet the constraints best.
        let cells = looked
            .into_iter()
            .map(|i| (i, score(model.cells[i].representative)));
        best(cells, opts.cells)
            .flat_map(|i| model.cells[i].members.iter().map(|&m| m as usize))
            .collect()
    } else {
        (0..model.samples.len()).collect()
    };
    let mut scored: Vec<(usize, f64)> = candidates
        .into_iter()
        .map(|i| (i, cost(&model.samples[i], roles, constraints, at)))
        .collect();
    let blend = opts.blend.clamp(1, scored.len().max(1));
    if scored.len() > blend {
        scored.select_nth_unstable_by(blend - 1, |a, b| a.1.total_cmp(&b.1));
        scored.truncate(blend);
    }
    scored.sort_by(|a, b| a.1.total_cmp(&b.1));
    let eps = 0.01;
    let mut weights: Vec<(usize, f64)> = scored
        .iter()
        .map(|(i, c)| (*i, 1.0 / (c + eps).powi(2)))
        .collect();
    let total: f64 = weights.iter().map(|w| w.1).sum();
    for w in &mut weights {
        w.1 /= total;
    }
    weights
}

/// Blend samples with weights into one pose placed at `at`: joint rotations
/// by hemisphere-aligned weighted quaternion sums, the root's offset and
/// facing relative to its clip's start by weighted averages.
#[must_use]
pub fn blend(
    skeleton: &Skeleton,
    model: &LearnedModel,
    weights: &[(usize, f64)],
    at: &Placement,
) -> Pose {
    let first = &model.samples[weights[0].0];
    let n = first.rotations.len();
    let mut rot = vec![DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0); n];
    let mut offset = DVec3::ZERO;
    let (mut s, mut c) = (0.0, 0.0);
    for &(i, w) in weights {
        let sample = &model.samples[i];
        for ((r, q), reference) in rot.iter_mut().zip(&sample.rotations).zip(&first.rotations) {
            // Same hemisphere as the best sample, so opposite signs of one
            // rotation do not cancel.
            let q = if q.dot(*reference) < 0.0 { -*q } else { *q };
            *r += q * w;
        }
        offset += sample.root_offset * w;
        s += sample.yaw.sin() * w;
        c += sample.yaw.cos() * w;
    }
    let blended = Sample {
        rotations: rot
            .iter()
            .map(|q| {
                if q.length() > 1e-12 {
                    q.normalize()
                } else {
                    DQuat::IDENTITY
                }
            })
            .collect(),
        root_offset: offset,
        yaw: wrap(s.atan2(c)),
        ..first.clone()
    };
    pose_of(skeleton, &blended, at)
}

/// The joints CCD turns to move a body part: the limb's own joints (elbow
/// and shoulder for a hand, knee and hip for a foot, neck and chest for the
/// head), never twist or helper bones.
fn chain(skeleton: &Skeleton, roles: &RoleMap, role: Role) -> Vec<usize> {
    let r = |roles_: &[Role]| roles_.iter().map(|x| roles.get(*x)).collect::<Vec<_>>();
    // The joint between the shoulder and the chest (a clavicle), if any.
    let clavicle = |shoulder: Role| {
        let p = skeleton.joints[roles.get(shoulder)].parent;
        p.filter(|&p| p != roles.get(Role::Chest))
            .into_iter()
            .collect::<Vec<_>>()
    };
    match role {
        Role::LeftHand => [
            r(&[Role::LeftElbow, Role::LeftShoulder]),
            clavicle(Role::LeftShoulder),
        ]
        .concat(),
        Role::RightHand => [
            r(&[Role::RightElbow, Role::RightShoulder]),
            clavicle(Role::RightShoulder),
        ]
        .concat(),
        Role::LeftFoot => r(&[Role::LeftKnee, Role::LeftHip]),
        Role::RightFoot => r(&[Role::RightKnee, Role::RightHip]),
        Role::LeftElbow => r(&[Role::LeftShoulder]),
        Role::RightElbow => r(&[Role::RightShoulder]),
        Role::LeftKnee => r(&[Role::LeftHip]),
        Role::RightKnee => r(&[Role::RightHip]),
        Role::Head => r(&[Role::Neck, Role::Chest]),
        Role::Neck => r(&[Role::Chest]),
        _ => Vec::new(),
    }
}

/// Foot IK: keep each foot given a position there, turning only knee and
/// hip (the feet that carry the body stay put when the pelvis moves).
pub fn plant_feet(skeleton: &Skeleton, roles: &RoleMap, pose: &mut Pose, at: [Option<DVec3>; 2]) {
    let goals: Vec<(usize, Vec<usize>, DVec3)> =
        [(Role::LeftFoot, at[0]), (Role::RightFoot, at[1])]
            .into_iter()
            .filter_map(|(r, p)| p.map(|p| (roles.get(r), chain(skeleton, roles, r), p)))
            .collect();
    if !goals.is_empty() {
        ccd(skeleton, pose, &goals, 12);
    }
}

/// CCD IK: move each effector towards its goal, turning the joints of its
/// chain, nearest first. Turning a chain joint moves neither its ancestors
/// nor their rotations, so one forward-kinematics pass per goal and sweep
/// suffices; sweeps stop once every goal is within 0.1 mm.
pub fn ccd(
    skeleton: &Skeleton,
    pose: &mut Pose,
    goals: &[(usize, Vec<usize>, DVec3)],
    sweeps: usize,
) {
    for _ in 0..sweeps {
        let mut worst = 0.0f64;
        for (effector, chain, goal) in goals {
            let w = forward_kinematics(skeleton, pose);
            let mut end = w.positions[*effector];
            worst = worst.max((end - *goal).length());
            for &j in chain {
                let pivot = w.positions[j];
                let (a, b) = (end - pivot, *goal - pivot);
                if a.length() < 1e-9 || b.length() < 1e-9 {
                    continue;
                }
                let turn = DQuat::from_rotation_arc(a.normalize(), b.normalize());
                let parent_rot = skeleton.joints[j]
                    .parent
                    .map_or(DQuat::IDENTITY, |p| w.rotations[p]);
                // This joint's world rotation now, after the turns of the
                // joints below it (which do not change it).
                let current = parent_rot * pose.rotations[j];
                pose.rotations[j] = (parent_rot.inverse() * (turn * current)).normalize();
                end = pivot + turn * a;
            }
        }
        if worst < 1e-4 {
            break;
        }
    }
}

/// Synthesise a posture meeting `constraints`, the character standing at
/// `at`. `planted` gives positions the feet must keep (when unconstrained).
#[must_use]
pub fn synthesize(
    skeleton: &Skeleton,
    roles: &RoleMap,
    model: &LearnedModel,
    constraints: &[Constraint],
    at: &Placement,
    planted: Option<[DVec3; 2]>,
    opts: &SynthOptions,
) -> Pose {
    let weights = choose(model, roles, constraints, at, opts);
    let mut pose = blend(skeleton, model, &weights, at);
    if opts.ik {
        apply_ik(
            skeleton,
            roles,
            &mut pose,
            constraints,
            planted,
            opts.max_ik_m,
        );
    }
    pose
}

/// CCD IK onto the constraints (each part moved at most `max_move`) and
/// onto planted foot positions.
pub fn apply_ik(
    skeleton: &Skeleton,
    roles: &RoleMap,
    pose: &mut Pose,
    constraints: &[Constraint],
    planted: Option<[DVec3; 2]>,
    max_move: f64,
) {
    let w = forward_kinematics(skeleton, pose);
    let mut goals = Vec::new();
    for c in constraints {
        if c.role == Role::Pelvis {
            continue;
        }
        let e = roles.get(c.role);
        let from = w.positions[e];
        let to = c.target.nearest(from);
        let step = to - from;
        let goal = if step.length() > max_move {
            from + step * (max_move / step.length())
        } else {
            to
        };
        goals.push((e, chain(skeleton, roles, c.role), goal));
    }
    if let Some(feet) = planted {
        for (role, at) in [(Role::LeftFoot, feet[0]), (Role::RightFoot, feet[1])] {
            if constraints.iter().all(|c| c.role != role) {
                goals.push((roles.get(role), chain(skeleton, roles, role), at));
            }
        }
    }
    if !goals.is_empty() {
        ccd(skeleton, pose, &goals, 30);
    }
}
