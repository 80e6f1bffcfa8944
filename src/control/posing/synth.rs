//! Posture synthesis from constraints (the paper's section 4): find the
//! latent cells whose representatives best meet the constraints (looking
//! first at blocks of cells, then at the cells of the best blocks), blend
//! those cells' samples weighted by how well each meets them (refitted to
//! meet them), blend each constrained limb on its own so that it reaches
//! its constraint from where the body put it, then let IK move each
//! constrained part onto its constraint (at most 0.2 m) and keep planted
//! feet where they are.

use glam::{DQuat, DVec3};

use super::constraint::{Constraint, Local, SynthOptions, Target, localize};
use super::fit::{mean_rotation, refit, refit_limbs};
use super::ik::apply_ik;
use super::model::{LearnedModel, PartColumns};
use super::rank::keep_best;
use super::sample::{Sample, pose_of};
use crate::character::body::{Anchor, Placement, wrap};
use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::{Pose, Skeleton, forward_kinematics};

/// The samples that meet the constraints best (at most `opts.blend`), with
/// their costs, the best first and the rest in no order: through the grid
/// (the representatives of the blocks, then of the cells of the best
/// blocks, then the samples of the best cells) or by scoring every sample.
#[must_use]
pub fn select(
    model: &LearnedModel,
    constraints: &[Constraint],
    at: &Placement,
    opts: &SynthOptions,
) -> Vec<(usize, f64)> {
    let local = localize(constraints, at);
    let index = &model.index;
    let score_run = |cols: &PartColumns,
                     run: std::ops::Range<usize>,
                     slack: f64,
                     out: &mut Vec<(usize, f64)>| {
        score(&local, at.anchor, cols, run, slack, out);
    };
    // One buffer for every stage: each stage appends its scores after the
    // kept entries of the stage before, which are then dropped.
    let mut scored = Vec::with_capacity(256);
    if opts.use_grid && !model.cells.is_empty() {
        let range = |starts: &[u32], i: usize| starts[i] as usize..starts[i + 1] as usize;
        // The cells to look at: those of the blocks whose representatives
        // meet the constraints best, or every one.
        if opts.blocks > 0 && !index.blocks.is_empty() {
            score_run(
                &index.blocks,
                0..index.blocks.len(),
                opts.block_slack,
                &mut scored,
            );
            keep_best(&mut scored, opts.blocks);
            let blocks = scored.len();
            for k in 0..blocks {
                let b = scored[k].0;
                score_run(
                    &index.cells,
                    range(&index.cells_of_block, b),
                    0.0,
                    &mut scored,
                );
            }
            scored.drain(..blocks);
        } else {
            score_run(&index.cells, 0..index.cells.len(), 0.0, &mut scored);
        }
        // The samples of the cells whose representatives meet the
        // constraints best.
        keep_best(&mut scored, opts.cells);
        let cells = scored.len();
        for k in 0..cells {
            let c = index.cell_ids[scored[k].0] as usize;
            score_run(
                &index.samples,
                range(&index.samples_of_cell, c),
                0.0,
                &mut scored,
            );
        }
        scored.drain(..cells);
    } else {
        score_run(&index.samples, 0..index.samples.len(), 0.0, &mut scored);
    }
    keep_best(&mut scored, opts.blend);
    // The mean over the caller's constraints: bounds cost nothing where
    // they are met, and do not dilute the rest.
    let count = local.iter().filter(|c| !c.target.is_bound()).count();
    let (ids, count) = (&index.samples.ids, count.max(1) as f64);
    for s in &mut scored {
        *s = (ids[s.0] as usize, s.1 / count);
    }
    // The best first (its rotations set the hemisphere the blend aligns
    // to); the order of the rest does not matter.
    if let Some(first) = (0..scored.len()).min_by_key(|&k| (scored[k].1.to_bits(), scored[k].0)) {
        scored.swap(0, first);
    }
    scored
}

/// The summed distance to the targets of each entry of `cols[run]` (less
/// `slack` times the entry's spread, where it has one), constraint by
/// constraint down the columns, appended to `out` with the entry's
/// position in `cols` (sums rank as the means do; only the kept ones are
/// divided).
fn score(
    local: &[Local],
    anchor: Anchor,
    cols: &PartColumns,
    run: std::ops::Range<usize>,
    slack: f64,
    out: &mut Vec<(usize, f64)>,
) {
    let from = out.len();
    out.extend(run.clone().map(|k| (k, 0.0)));
    let sums = &mut out[from..];
    for c in local {
        let col = &cols.column(anchor, c.role)[run.clone()];
        let spread = cols.spread(anchor, c.role);
        if slack > 0.0 && !spread.is_empty() {
            let spread = &spread[run.clone()];
            match c.target {
                Target::Point(q) => {
                    for ((s, p), r) in sums.iter_mut().zip(col).zip(spread) {
                        s.1 += ((*p - q).length() - slack * r).max(0.0);
                    }
                }
                Target::Ray(ray) => {
                    for ((s, p), r) in sums.iter_mut().zip(col).zip(spread) {
                        s.1 += (ray.distance(*p) - slack * r).max(0.0);
                    }
                }
                Target::Within { at, radius } => {
                    for ((s, p), r) in sums.iter_mut().zip(col).zip(spread) {
                        s.1 += ((*p - at).length() - radius - slack * r).max(0.0);
                    }
                }
            }
            continue;
        }
        match c.target {
            Target::Point(q) => {
                for (s, p) in sums.iter_mut().zip(col) {
                    s.1 += (*p - q).length();
                }
            }
            Target::Ray(r) => {
                for (s, p) in sums.iter_mut().zip(col) {
                    s.1 += r.distance(*p);
                }
            }
            Target::Within { at, radius } => {
                for (s, p) in sums.iter_mut().zip(col) {
                    s.1 += ((*p - at).length() - radius).max(0.0);
                }
            }
        }
    }
}

/// The samples to blend and their weights (summing to one), best first:
/// the best samples weighted by the inverse square of their cost, then, if
/// `opts.fit`, refitted to meet the constraints.
#[must_use]
pub fn choose(
    model: &LearnedModel,
    constraints: &[Constraint],
    at: &Placement,
    opts: &SynthOptions,
) -> Vec<(usize, f64)> {
    let eps = 0.01;
    let mut weights: Vec<(usize, f64)> = select(model, constraints, at, opts)
        .into_iter()
        .map(|(i, c)| (i, 1.0 / (c + eps).powi(2)))
        .collect();
    let total: f64 = weights.iter().map(|w| w.1).sum();
    for w in &mut weights {
        w.1 /= total;
    }
    if opts.fit > 0.0 && weights.len() > 1 {
        refit(model, constraints, at, &mut weights, opts.fit);
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
    let mut offset = DVec3::ZERO;
    let (mut s, mut c) = (0.0, 0.0);
    for &(i, w) in weights {
        let sample = &model.samples[i];
        offset += sample.root_offset * w;
        s += sample.yaw.sin() * w;
        c += sample.yaw.cos() * w;
    }
    let blended = Sample {
        rotations: (0..first.rotations.len())
            .map(|j| mean_rotation(model, weights, j))
            .collect(),
        root_offset: offset,
        yaw: wrap(s.atan2(c)),
        ..first.clone()
    };
    pose_of(skeleton, &blended, at)
}

/// How far a sample may put a planted foot from where it stands before
/// the search counts it against the sample (m): IK brings a foot this far
/// back without the leg stretching out of its pose.
pub const PLANTED_SLACK_M: f64 = 0.1;

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
    // Planted feet bound the search: a sample that puts a free foot more
    // than a step from where it stands would have IK drag the leg back to
    // it (a library's walks and runs carry the pelvis metres from where
    // their clip began; the legs would trail, stretched, behind it).
    let mut search = constraints.to_vec();
    if let Some(feet) = planted {
        for (role, at) in [Role::LeftFoot, Role::RightFoot].into_iter().zip(feet) {
            if constraints.iter().all(|c| c.role != role) {
                search.push(Constraint {
                    role,
                    target: Target::Within {
                        at,
                        radius: PLANTED_SLACK_M,
                    },
                });
            }
        }
    }
    let weights = choose(model, &search, at, opts);
    let mut pose = blend(skeleton, model, &weights, at);
    if opts.limb_fit > 0.0 {
        refit_limbs(
            skeleton,
            roles,
            model,
            constraints,
            &mut pose,
            &weights,
            opts,
        );
    }
    if opts.ik {
        // The hands keep the way the blend turned them: IK moves a hand by
        // bending its arm, and letting it turn along would twist the wrist
        // (on held-out clips keeping the turn lowers MPJPE by 0.18 cm with
        // 5 targets, by 0.08 cm with 5 touches).
        let hands: Vec<usize> = constraints
            .iter()
            .filter(|c| matches!(c.role, Role::RightHand | Role::LeftHand))
            .map(|c| roles.get(c.role))
            .collect();
        let before = forward_kinematics(skeleton, &pose);
        apply_ik(
            skeleton,
            roles,
            &mut pose,
            constraints,
            planted,
            opts.max_ik_m,
        );
        if !hands.is_empty() {
            let after = forward_kinematics(skeleton, &pose);
            for j in hands {
                let parent = skeleton.joints[j]
                    .parent
                    .map_or(DQuat::IDENTITY, |p| after.rotations[p]);
                pose.rotations[j] = (parent.inverse() * before.rotations[j]).normalize();
            }
        }
    }
    pose
}
