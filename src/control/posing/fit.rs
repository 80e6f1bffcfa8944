//! Blend weights fitted to meet the constraints: least squares across the
//! constraints' rays, a ridge towards the cost weights, no negative
//! weights (solved through the constraints' few columns), and each
//! constrained limb refitted on its own.

use glam::{DQuat, DVec3};

use super::constraint::{Constraint, SynthOptions, Target, localize};
use super::limbs::{self, limb_index};
use super::model::LearnedModel;
use super::rank::smallest;
use crate::character::body::Placement;
use crate::character::roles::RoleMap;
use crate::character::skeleton::{Pose, Skeleton, forward_kinematics};

/// Refit blend weights so that the blend of the samples' constrained parts
/// meets the constraints: least squares on the parts' positions (a ray
/// counts only the offset across it), pulled towards the given weights by
/// `ridge`, the weights summing to one and none negative (a negative one is
/// dropped and the rest refitted).
pub(crate) fn refit(
    model: &LearnedModel,
    constraints: &[Constraint],
    at: &Placement,
    weights: &mut [(usize, f64)],
    ridge: f64,
) {
    let local = localize(constraints, at);
    let cols: Vec<Vec<DVec3>> = local
        .iter()
        .map(|c| {
            weights
                .iter()
                .map(|(i, _)| across(c.target, model.samples[*i].part(at.anchor, c.role)))
                .collect()
        })
        .collect();
    let prior: Vec<f64> = weights.iter().map(|w| w.1).collect();
    fit_weights(weights, &prior, &cols, ridge);
}

/// The offset of `p` from a target that a fit should remove: all of it from
/// a point, the part across the line from a half-line.
pub(crate) fn across(target: Target, p: DVec3) -> DVec3 {
    match target {
        Target::Point(q) => p - q,
        Target::Ray(r) => {
            let v = p - r.origin;
            v - r.dir * v.dot(r.dir)
        }
        Target::Within { at, radius } => {
            let v = p - at;
            v - v.clamp_length_max(radius)
        }
    }
}

/// Weights (summing to one, none negative) whose blend of each
/// constraint's offsets (`cols[constraint][sample]`) is least, pulled
/// towards `prior` by `ridge` (> 0); a negative weight is dropped and the
/// rest refitted. Leaves `weights` as they are if the system is singular.
///
/// The system is `ridge I + A A'` (A: a row of offsets per sample), solved
/// through the few columns of A (Woodbury), not the many samples.
pub(crate) fn fit_weights(
    weights: &mut [(usize, f64)],
    prior: &[f64],
    cols: &[Vec<DVec3>],
    ridge: f64,
) {
    let k = weights.len();
    let d = 3 * cols.len();
    if ridge <= 0.0 || k == 0 {
        return;
    }
    let mut a = vec![0.0; k * d];
    for (c, col) in cols.iter().enumerate() {
        for (row, v) in a.chunks_exact_mut(d).zip(col) {
            row[3 * c..3 * c + 3].copy_from_slice(&v.to_array());
        }
    }
    let g: Vec<f64> = prior.iter().map(|w| ridge * w).collect();
    // Minimise w'Mw/2 - g'w subject to sum(w) = 1: w = M^-1 (g + mu 1).
    let mut active: Vec<usize> = (0..k).collect();
    while !active.is_empty() {
        let mut inner = normal_matrix(&a, d, &active, ridge);
        if !cholesky(&mut inner, d) {
            return;
        }
        // M^-1 b = (b - A (ridge I + A'A)^-1 A'b) / ridge.
        let solve = |b: Vec<f64>| -> Vec<f64> {
            let mut atb = vec![0.0; d];
            for (&s, bs) in active.iter().zip(&b) {
                for (t, x) in atb.iter_mut().zip(&a[s * d..(s + 1) * d]) {
                    *t += x * bs;
                }
            }
            let z = cholesky_solve(&inner, atb, d);
            active
                .iter()
                .zip(&b)
                .map(|(&s, bs)| {
                    let az: f64 = a[s * d..(s + 1) * d]
                        .iter()
                        .zip(&z)
                        .map(|(x, y)| x * y)
                        .sum();
                    (bs - az) / ridge
                })
                .collect()
        };
        let x = solve(active.iter().map(|&s| g[s]).collect());
        let y = solve(vec![1.0; active.len()]);
        let mu = (1.0 - x.iter().sum::<f64>()) / y.iter().sum::<f64>();
        let w: Vec<f64> = x.iter().zip(&y).map(|(a, b)| a + mu * b).collect();
        if w.iter().all(|v| *v >= 0.0) {
            for entry in weights.iter_mut() {
                entry.1 = 0.0;
            }
            for (&s, v) in active.iter().zip(w) {
                weights[s].1 = v;
            }
            return;
        }
        active = active
            .iter()
            .zip(&w)
            .filter(|(_, v)| **v >= 0.0)
            .map(|(s, _)| *s)
            .collect();
    }
}

/// `ridge I + A'A` over the `active` rows of `a` (each `d` long), row by
/// row (`d` x `d`).
fn normal_matrix(a: &[f64], d: usize, active: &[usize], ridge: f64) -> Vec<f64> {
    let mut inner = vec![0.0; d * d];
    for &s in active {
        let row = &a[s * d..(s + 1) * d];
        for i in 0..d {
            for j in 0..=i {
                inner[i * d + j] += row[i] * row[j];
            }
        }
    }
    for i in 0..d {
        inner[i * d + i] += ridge;
        for j in 0..i {
            inner[j * d + i] = inner[i * d + j];
        }
    }
    inner
}

/// Blend each constrained limb on its own (the joints from its base down;
/// the head's limb is the spine, done first since the arms hang from it):
/// the body's samples and the `opts.limb_extra` samples whose limbs reach
/// the constraint best (found through the reach grid, or by measuring
/// every sample), hung from where the body's blend puts the limb's base,
/// weighted to reach the constraint, pulled towards the body's weights by
/// `opts.limb_fit` (a sample the body does not use pulls towards none).
pub fn refit_limbs(
    skeleton: &Skeleton,
    roles: &RoleMap,
    model: &LearnedModel,
    constraints: &[Constraint],
    pose: &mut Pose,
    weights: &[(usize, f64)],
    opts: &SynthOptions,
) {
    let (ridge, extra) = (opts.limb_fit, opts.limb_extra);
    // The spine first: the arms hang from it.
    let mut order: Vec<&Constraint> = constraints.iter().collect();
    order.sort_by_key(|c| limb_index(c.role));
    for c in order {
        let (Some(limb), Some(chain)) = (limb_index(c.role), limbs::chain(skeleton, roles, c.role))
        else {
            continue;
        };
        let w = forward_kinematics(skeleton, pose);
        let base = chain[0];
        // The constraint in the frame the limb's reach is measured in.
        let unturn = skeleton.joints[base]
            .parent
            .map_or(DQuat::IDENTITY, |p| w.rotations[p])
            .inverse();
        let origin = w.positions[base];
        let target = c.target.moved(-origin, unturn);
        let reach = &model.index.reach[limb];
        let miss = |i: usize| across(target, reach[i]);
        let mut own = weights.to_vec();
        if extra > 0 {
            let nearest = if opts.use_grid {
                model.index.reach_grids[limb].nearest(extra + weights.len(), |r| across(target, r))
            } else {
                let scored = reach
                    .iter()
                    .enumerate()
                    .map(|(i, r)| (i, across(target, *r).length_squared()));
                smallest(scored, extra + weights.len())
            };
            let others = nearest
                .into_iter()
                .filter(|(i, _)| weights.iter().all(|w| w.0 != *i))
                .take(extra);
            own.extend(others.map(|(i, _)| (i, 0.0)));
        }
        let prior: Vec<f64> = own.iter().map(|w| w.1).collect();
        let col: Vec<DVec3> = own.iter().map(|(i, _)| miss(*i)).collect();
        fit_weights(&mut own, &prior, &[col], ridge);
        own.retain(|w| w.1 > 0.0);
        if own.is_empty() {
            continue;
        }
        own.sort_by(|a, b| b.1.total_cmp(&a.1));
        for j in base..skeleton.len() {
            if limbs::hangs_from(skeleton, j, base) {
                pose.rotations[j] = mean_rotation(model, &own, j);
            }
        }
    }
}

/// Weighted mean of the samples' local rotations of joint `j`, each turned
/// into the hemisphere of the first sample's (so that opposite signs of one
/// rotation do not cancel).
pub(crate) fn mean_rotation(model: &LearnedModel, weights: &[(usize, f64)], j: usize) -> DQuat {
    let reference = model.samples[weights[0].0].rotations[j];
    let mut sum = DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0);
    for &(i, w) in weights {
        let q = model.samples[i].rotations[j];
        sum += if q.dot(reference) < 0.0 { -q } else { q } * w;
    }
    if sum.length() > 1e-12 {
        sum.normalize()
    } else {
        DQuat::IDENTITY
    }
}

/// Cholesky factorisation in place of a symmetric positive definite `n x n`
/// matrix (its lower triangle becomes L); false when it is not positive
/// definite.
pub(crate) fn cholesky(a: &mut [f64], n: usize) -> bool {
    for j in 0..n {
        let mut d = a[j * n + j];
        for p in 0..j {
            d -= a[j * n + p] * a[j * n + p];
        }
        if d <= 0.0 {
            return false;
        }
        let d = d.sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut s = a[i * n + j];
            for p in 0..j {
                s -= a[i * n + p] * a[j * n + p];
            }
            a[i * n + j] = s / d;
        }
    }
    true
}

/// Solve `L L' x = b` with `l` from [`cholesky`].
pub(crate) fn cholesky_solve(l: &[f64], mut b: Vec<f64>, n: usize) -> Vec<f64> {
    for i in 0..n {
        for p in 0..i {
            b[i] -= l[i * n + p] * b[p];
        }
        b[i] /= l[i * n + i];
    }
    for i in (0..n).rev() {
        for p in i + 1..n {
            b[i] -= l[p * n + i] * b[p];
        }
        b[i] /= l[i * n + i];
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fitted(offsets: &[f64], prior: &[f64], ridge: f64) -> Vec<f64> {
        let mut weights: Vec<(usize, f64)> = prior.iter().copied().enumerate().collect();
        let cols = vec![offsets.iter().map(|x| DVec3::new(*x, 0.0, 0.0)).collect()];
        fit_weights(&mut weights, prior, &cols, ridge);
        weights.iter().map(|w| w.1).collect()
    }

    #[test]
    fn fitted_weights_meet_a_reachable_constraint_and_sum_to_one() {
        // Samples 1 m past the target and 3 m short of it: 3/4 and 1/4
        // meet it; a small ridge barely moves that.
        let w = fitted(&[1.0, -3.0], &[0.5, 0.5], 1e-6);
        assert!(
            (w[0] - 0.75).abs() < 1e-4 && (w[1] - 0.25).abs() < 1e-4,
            "{w:?}"
        );
        // A large ridge keeps the prior.
        let w = fitted(&[1.0, -3.0], &[0.5, 0.5], 1e6);
        assert!((w[0] - 0.5).abs() < 1e-4, "{w:?}");
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn fitted_weights_drop_samples_that_would_need_a_negative_weight() {
        // Every sample overshoots: the nearest takes all the weight rather
        // than the others going negative.
        let w = fitted(&[1.0, 2.0, 5.0], &[0.2, 0.5, 0.3], 1e-6);
        assert_eq!(w[1], 0.0, "{w:?}");
        assert_eq!(w[2], 0.0, "{w:?}");
        assert!((w[0] - 1.0).abs() < 1e-12, "{w:?}");
    }
}
