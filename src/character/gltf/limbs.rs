//! A figure's limbs: two-bone IK on world positions, the turn that bends a
//! knee or elbow towards a pole, and the mesh points a limb's end carries
//! (what must stay off the floor).

use glam::{DQuat, DVec3};

use super::Figure;
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
pub(super) fn end_points(fig: &Figure, end: usize) -> Vec<(usize, DVec3)> {
    if fig.made_up.get(end).copied().unwrap_or(false) {
        return made_up_end_points(fig, end);
    }
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
    let all: Vec<(usize, DVec3)> = fig
        .parts
        .iter()
        .flat_map(|p| p.positions.iter().zip(&p.joints).zip(&p.weights))
        .filter_map(|((v, j), w)| {
            let k = (0..4).max_by(|&a, &b| w[a].total_cmp(&w[b])).unwrap_or(0);
            let j = usize::from(j[k]);
            ours.get(j)
                .copied()
                .unwrap_or(false)
                .then(|| (j, DVec3::new(v[0].into(), v[1].into(), v[2].into())))
        })
        .collect();
    let step = all.len().div_ceil(256).max(1);
    all.into_iter().step_by(step).collect()
}

/// A made-up end's mesh points: those its nearest real joint carries
/// that lie nearer the end than that joint's own half of the way.
fn made_up_end_points(fig: &Figure, end: usize) -> Vec<(usize, DVec3)> {
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
    let all: Vec<(usize, DVec3)> = fig
        .parts
        .iter()
        .flat_map(|p| p.positions.iter().zip(&p.joints).zip(&p.weights))
        .filter_map(|((v, j), w)| {
            let k = (0..4).max_by(|&a, &b| w[a].total_cmp(&w[b])).unwrap_or(0);
            let v = DVec3::new(v[0].into(), v[1].into(), v[2].into());
            (usize::from(j[k]) == real && (v - from).dot(along) / len2 > 0.5).then_some((real, v))
        })
        .collect();
    let step = all.len().div_ceil(256).max(1);
    all.into_iter().step_by(step).collect()
}
