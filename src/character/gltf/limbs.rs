//! A figure's limbs: two-bone IK on world positions, the turn that bends a
//! knee or elbow towards a pole, and the mesh points a limb's end carries
//! (what must stay off the floor).

use glam::{DMat4, DQuat, DVec3};

use super::{Figure, Point, carried_blended};
use crate::character::roles::Role;
use crate::character::skeleton::two_bone_turns;

/// Two-bone IK on world positions: the turns (world, about `a` and then
/// about `b`) that bend the limb `a`-`b`-`c` so that `c` reaches `goal`
/// (as near as the limb's lengths allow), in the plane it bends in.
pub(super) fn two_bone(a: DVec3, b: DVec3, c: DVec3, goal: DVec3) -> Option<(DQuat, DQuat)> {
    if !goal.is_finite() {
        return None;
    }
    let (bend_a, bend_b, swing) = two_bone_turns(a, b, c, goal)?;
    // World turn of the upper joint; the middle's own bend applies after
    // it (world frame once the upper has turned).
    let ta = swing * bend_a;
    let tb = ta * bend_b * ta.inverse();
    Some((ta, tb))
}

/// The turn about the line from `a` to `goal` that brings `middle` (a knee
/// or elbow) to the side of it where `pole` is.
pub(super) fn toward(a: DVec3, middle: DVec3, goal: DVec3, pole: DVec3) -> DQuat {
    let u = goal - a;
    if u.length() < 1e-9 {
        return DQuat::IDENTITY;
    }
    let u = u.normalize();
    let off = |p: DVec3| {
        let v = p - a;
        v - u * v.dot(u)
    };
    let (m, p) = (off(middle), off(pole));
    if m.length() < 1e-6 || p.length() < 1e-6 {
        return DQuat::IDENTITY;
    }
    DQuat::from_rotation_arc(m.normalize(), p.normalize())
}

/// The mesh points (rest pose) that a limb's `end`, the unmapped joints
/// beside it or the unmapped joints below them carry most, at most 256 of
/// them spread over it, each with that joint.
pub(super) fn end_points(fig: &Figure, end: usize) -> Vec<Point> {
    if fig.made_up.get(end).copied().unwrap_or(false) {
        return made_up_end_points(fig, end);
    }
    spread(carried_by_end(fig, end), fig.rest[end].w_axis.truncate())
}

/// The most mesh points of a hand looked at near the floor (see
/// [`near_points`]).
const NEAR_MAX: usize = 8192;

/// The mesh points a hand carries, as [`end_points`] picks them, looked
/// at when it is near the floor: every one, or where there are more than
/// [`NEAR_MAX`], [`end_points`]'s and as many more spread over them; none
/// where [`end_points`] left none out. [`end_points`] keeps the furthest
/// out in directions about 22 degrees apart: a broad shield's rim turned
/// between two of them goes lower than any (7.7 mm, a knight's in a
/// crouch).
pub(super) fn near_points(fig: &Figure, end: usize) -> Vec<Point> {
    if fig.made_up.get(end).copied().unwrap_or(false) {
        return Vec::new();
    }
    let all = carried_by_end(fig, end);
    if all.len() <= KEPT {
        return Vec::new();
    }
    if all.len() <= NEAR_MAX {
        return all;
    }
    let step = all.len().div_ceil(NEAR_MAX - KEPT);
    let mut near: Vec<Point> = all.iter().step_by(step).copied().collect();
    near.extend(spread(all, fig.rest[end].w_axis.truncate()));
    near
}

/// The mesh points that a limb's `end`, the unmapped joints beside it or
/// the unmapped joints below them carry most, each with that joint.
fn carried_by_end(fig: &Figure, end: usize) -> Vec<Point> {
    let mapped: Vec<usize> = Role::ALL.iter().map(|r| fig.roles.get(*r)).collect();
    let mut ours = vec![false; fig.skeleton.len()];
    ours[end] = true;
    // And the unmapped joints beside it (RobotExpressive's hand is one of
    // three palms on the forearm, with the thumb).
    if let Some(parent) = fig.skeleton.joints[end].parent {
        for (j, joint) in fig.skeleton.joints.iter().enumerate() {
            if joint.parent == Some(parent) && !mapped.contains(&j) {
                ours[j] = true;
            }
        }
    }
    for j in 0..fig.skeleton.len() {
        if let Some(p) = fig.skeleton.joints[j].parent {
            if ours[p] && !mapped.contains(&j) {
                ours[j] = true;
            }
        }
    }
    carried_blended(&fig.parts)
        .filter(|p| ours.get(p.joint).copied().unwrap_or(false))
        .collect()
}

/// How many points [`spread`] keeps at most.
const KEPT: usize = 418;

/// At most 256 of `all` spread over them, the 64 furthest from `from`
/// (the tip of a sword in a hand, a toe cap) and the furthest out in each
/// of 98 directions (what goes lowest however the part turns), whatever
/// the spread left out.
fn spread(mut all: Vec<Point>, from: DVec3) -> Vec<Point> {
    if all.len() <= KEPT {
        return all;
    }
    let mut out: Vec<Point> = Vec::with_capacity(KEPT);
    for x in -2..=2i32 {
        for y in -2..=2i32 {
            for z in -2..=2i32 {
                if x.abs().max(y.abs()).max(z.abs()) < 2 {
                    continue;
                }
                let d = DVec3::new(f64::from(x), f64::from(y), f64::from(z));
                if let Some(p) = all
                    .iter()
                    .max_by(|a, b| a.at.dot(d).total_cmp(&b.at.dot(d)))
                {
                    out.push(*p);
                }
            }
        }
    }
    all.sort_by(|a, b| (b.at - from).length().total_cmp(&(a.at - from).length()));
    let rest = all.split_off(64);
    let step = rest.len().div_ceil(256).max(1);
    out.extend(all);
    out.extend(rest.into_iter().step_by(step));
    out
}

/// A foot's points and the points of its shin below the knee at rest (a
/// shin's mesh that reaches past the ankle, a trouser cuff, a robot's
/// shin plate that a low kick or a lunge brings to the floor: 29.7 mm
/// into it when only the shin below half the ankle's height was kept
/// off).
pub(super) fn foot_points(fig: &Figure, foot: usize, shin: usize) -> Vec<Point> {
    let mut points = end_points(fig, foot);
    let ankle = fig.rest[foot].w_axis.truncate();
    let knee = fig.rest[shin].w_axis.y;
    if shin != foot && !fig.made_up.get(shin).copied().unwrap_or(false) {
        let low: Vec<Point> = carried_blended(&fig.parts)
            .filter(|p| p.joint == shin && p.at.y < knee)
            .collect();
        points.extend(spread(low, ankle));
    }
    points
}

/// A made-up end's mesh points: those its nearest real joint carries
/// that lie nearer the end than that joint's own half of the way.
fn made_up_end_points(fig: &Figure, end: usize) -> Vec<Point> {
    let mut real = end;
    while fig.made_up.get(real).copied().unwrap_or(false) {
        match fig.skeleton.joints[real].parent {
            Some(p) => real = p,
            None => return Vec::new(),
        }
    }
    let (from, to) = (
        fig.rest[real].w_axis.truncate(),
        fig.rest[end].w_axis.truncate(),
    );
    let along = to - from;
    let len2 = along.length_squared().max(1e-12);
    let all: Vec<Point> = carried_blended(&fig.parts)
        .filter(|p| p.joint == real && (p.at - from).dot(along) / len2 > 0.5)
        .collect();
    let step = all.len().div_ceil(256).max(1);
    all.into_iter().step_by(step).collect()
}

/// The mesh points below a quarter of the figure's height at rest that
/// its legs do not carry (a cape, a skirt, a tail, a weapon on the back),
/// at most 256 spread over them, each with its joint.
pub(super) fn low_points(fig: &Figure) -> Vec<Point> {
    let n = fig.skeleton.len();
    let mut leg = vec![false; n];
    for r in [
        Role::LeftHip,
        Role::RightHip,
        Role::LeftFoot,
        Role::RightFoot,
    ] {
        leg[fig.roles.get(r)] = true;
    }
    for j in 0..n {
        if let Some(p) = fig.skeleton.joints[j].parent {
            if leg[p] {
                leg[j] = true;
            }
        }
    }
    let floor = 0.25 * fig.height_m;
    let all: Vec<Point> = carried_blended(&fig.parts)
        .filter(|p| p.at.y < floor && !leg.get(p.joint).copied().unwrap_or(true))
        .collect();
    spread(all, DVec3::new(0.0, floor, 0.0))
}

/// Mesh points the figure keeps off the floor, with what bounds how low
/// they can go. Skinning moves a point as a blend of its joints'
/// transforms, so it is no lower than the lowest of its joints' spheres
/// (per joint carrying any of the points: a rest point, their mean, and
/// how far the farthest is from it): a set whose spheres are all above
/// the floor is not skinned point by point (a hanging hand, a head held
/// up), nor is a run of points near each other at rest whose spheres
/// are above the lowest point found.
#[derive(Clone, Debug, Default)]
pub(super) struct Carried {
    pub(super) points: Vec<Point>,
    spheres: Vec<Sphere>,
    /// Runs of the points near each other at rest: their indices and
    /// spheres.
    runs: Vec<(Vec<u32>, Vec<Sphere>)>,
}

/// A joint, a rest point and a radius (see [`Carried`]).
type Sphere = (usize, DVec3, f64);

/// How many points a run of [`Carried`] holds.
const RUN: usize = 48;

/// The spheres bounding `points` (see [`Carried`]).
fn spheres<'a>(points: impl Iterator<Item = &'a Point> + Clone) -> Vec<Sphere> {
    let carrying = |p: &'a Point| {
        (0..4)
            .filter(|&k| p.weights[k] > 0.0)
            .map(move |k| (usize::from(p.joints[k]), p.at))
    };
    let mut sums: Vec<(usize, DVec3, usize)> = Vec::new();
    for (j, at) in points.clone().flat_map(carrying) {
        match sums.iter_mut().find(|s| s.0 == j) {
            Some(s) => {
                s.1 += at;
                s.2 += 1;
            }
            None => sums.push((j, at, 1)),
        }
    }
    let mut out: Vec<Sphere> = sums
        .into_iter()
        .map(|(j, sum, n)| (j, sum / n as f64, 0.0))
        .collect();
    for (j, at) in points.flat_map(carrying) {
        if let Some(s) = out.iter_mut().find(|s| s.0 == j) {
            s.2 = s.2.max((at - s.1).length());
        }
    }
    out
}

/// The lowest height the spheres' points can have for skinning matrices
/// `skin` (rest to posed; a joint past them stays at rest).
fn bound(spheres: &[Sphere], skin: &[DMat4]) -> f64 {
    spheres
        .iter()
        .map(|&(j, c, r)| match skin.get(j) {
            Some(m) => {
                let stretch = m
                    .x_axis
                    .truncate()
                    .length()
                    .max(m.y_axis.truncate().length())
                    .max(m.z_axis.truncate().length());
                m.transform_point3(c).y - r * stretch
            }
            None => c.y - r,
        })
        .fold(f64::INFINITY, f64::min)
}

/// Runs of at most [`RUN`] of `points` (those in `order`), near each
/// other at rest: halved across the widest side of their box, again and
/// again.
fn split(points: &[Point], order: &mut [u32], runs: &mut Vec<(Vec<u32>, Vec<Sphere>)>) {
    if order.len() <= RUN {
        if !order.is_empty() {
            runs.push((
                order.to_vec(),
                spheres(order.iter().map(|&i| &points[i as usize])),
            ));
        }
        return;
    }
    let at = |i: u32| points[i as usize].at;
    let (lo, hi) = order.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), &i| (lo.min(at(i)), hi.max(at(i))),
    );
    let size = hi - lo;
    let axis = if size.x >= size.y && size.x >= size.z {
        0
    } else if size.y >= size.z {
        1
    } else {
        2
    };
    let half = order.len() / 2;
    order.select_nth_unstable_by(half, |&a, &b| at(a)[axis].total_cmp(&at(b)[axis]));
    let (a, b) = order.split_at_mut(half);
    split(points, a, runs);
    split(points, b, runs);
}

impl Carried {
    pub(super) fn new(points: Vec<Point>) -> Self {
        let mut order: Vec<u32> = (0..points.len() as u32).collect();
        let mut runs = Vec::new();
        split(&points, &mut order, &mut runs);
        Self {
            spheres: spheres(points.iter()),
            points,
            runs,
        }
    }

    pub(super) fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// A height none of the points is under, for skinning matrices
    /// `skin` (rest to posed).
    pub(super) fn floor_bound(&self, skin: &[DMat4]) -> f64 {
        bound(&self.spheres, skin)
    }

    /// Where the points are for skinning matrices `skin`.
    pub(super) fn now(&self, skin: &[DMat4]) -> Vec<DVec3> {
        self.points.iter().map(|p| p.now(skin)).collect()
    }

    /// The height of the lowest point for skinning matrices `skin`, or
    /// `ceiling` where none is lower.
    pub(super) fn lowest_below(&self, skin: &[DMat4], ceiling: f64) -> f64 {
        let mut best = ceiling;
        if self.floor_bound(skin) >= best {
            return best;
        }
        for (run, spheres) in &self.runs {
            if bound(spheres, skin) >= best {
                continue;
            }
            for &i in run {
                best = best.min(self.points[i as usize].now(skin).y);
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points blended over up to three of five joints, posed by turns,
    /// moves and scales: the bound is never above a point, and the
    /// lowest found by runs is the lowest of them all.
    #[test]
    fn the_floor_bound_holds_and_the_lowest_is_found_past_the_runs() {
        let mut seed = 0x2545_f491_u64;
        let mut next = move || {
            seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let points: Vec<Point> = (0..500)
            .map(|_| {
                let joints = [0, 1, 2, 3].map(|_| (next() * 5.0) as u16);
                let w = [next(), next(), next(), 0.0];
                let sum: f64 = w.iter().sum();
                Point {
                    joint: usize::from(joints[0]),
                    at: DVec3::new(next() - 0.5, next() * 1.5, next() - 0.5),
                    joints,
                    weights: w.map(|x| (x / sum) as f32),
                }
            })
            .collect();
        let carried = Carried::new(points.clone());
        for _ in 0..50 {
            let skin: Vec<DMat4> = (0..5)
                .map(|_| {
                    DMat4::from_scale_rotation_translation(
                        DVec3::splat(0.5 + next()),
                        DQuat::from_euler(glam::EulerRot::XYZ, next() * 6.0, next() * 6.0, next()),
                        DVec3::new(next() - 0.5, next() - 0.7, next() - 0.5),
                    )
                })
                .collect();
            let all: Vec<f64> = points.iter().map(|p| p.now(&skin).y).collect();
            let lowest = all.iter().copied().fold(f64::INFINITY, f64::min);
            assert!(carried.floor_bound(&skin) <= lowest + 1e-12);
            assert_eq!(carried.lowest_below(&skin, f64::INFINITY), lowest);
            assert_eq!(carried.lowest_below(&skin, 0.0), lowest.min(0.0));
        }
    }
}
