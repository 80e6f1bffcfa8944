//! The turn that stands a figure up facing +Z: its body's frame (see
//! `frame`), else, where its names do not say, its joints' spread (up
//! along its longest axis, feet where the joints spread widest, facing as
//! its toes or its mesh say).

use std::collections::BTreeMap;

use glam::{DQuat, DVec3};

use crate::character::gltf::{Part, frame, humanoid};
use crate::character::roles::Role;

/// The turn that stands the figure up facing +Z, and what said which way
/// is up and which way it faces: its body's frame (its sides swapped where
/// its names put them the other way round), else its joints' spread.
pub(super) fn body_turn(
    found: &mut BTreeMap<Role, (usize, humanoid::Evidence)>,
    (names, parents, places): (&[String], &[Option<usize>], &[DVec3]),
    parts_raw: &[Part],
    (raw, verts): (&[DVec3], &[DVec3]),
    notes: &mut Vec<String>,
) -> (DQuat, String, String) {
    match frame::body_frame(found, places, parents, parts_raw, names) {
        Some(b) => {
            if b.crossed {
                notes.push("its joints' names put left and right the other way round from where its toes point: their sides are swapped".to_owned());
                frame::swap_sides(found);
            }
            (b.turn, b.up, b.facing)
        }
        None => {
            let (turn, up_name) = upright(raw);
            let upright_joints: Vec<DVec3> = places.iter().map(|p| turn * *p).collect();
            let height_units = extent_along_y(verts, raw, turn);
            let (yaw, facing_name) = facing(&upright_joints, parents, height_units, turn);
            (DQuat::from_rotation_y(yaw) * turn, up_name, facing_name)
        }
    }
}

/// How far the figure reaches along the file's axis turned up by `turn`.
pub(super) fn extent_along_y(verts: &[DVec3], raw: &[DVec3], turn: DQuat) -> f64 {
    let (lo, hi) = verts
        .iter()
        .chain(raw)
        .map(|p| (turn * *p).y)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), y| {
            (l.min(y), h.max(y))
        });
    hi - lo
}

/// The turn that stands the figure up where its names do not say up: the
/// file's Y unless the skeleton is less than half as long along it as
/// along its longest axis (then that axis is the body's); its feet are at
/// the end where the joints spread widest across it (two feet apart,
/// against one head).
fn upright(joints: &[DVec3]) -> (DQuat, String) {
    let pts = joints;
    let axes = [DVec3::X, DVec3::Y, DVec3::Z];
    let extent = |a: DVec3| {
        let (lo, hi) = joints
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
                (l.min(p.dot(a)), h.max(p.dot(a)))
            });
        (hi - lo, lo, hi)
    };
    let (k, longest) = axes
        .iter()
        .enumerate()
        .map(|(k, a)| (k, extent(*a).0))
        .fold((1, f64::NEG_INFINITY), |best, (k, e)| {
            if e > best.1 + 1e-9 { (k, e) } else { best }
        });
    // glTF's up (+Y) unless the figure clearly lies along another axis: a
    // T-pose's arm span, fingers and all, can outreach its height, never
    // twice it.
    let k = if extent(DVec3::Y).0 >= 0.5 * longest {
        1
    } else {
        k
    };
    let axis = axes[k];
    let (len, lo, hi) = extent(axis);
    // The spread across the axis of the points within 8% of each end.
    let spread = |near: f64| {
        let band: Vec<DVec3> = pts
            .iter()
            .filter(|p| (p.dot(axis) - near).abs() < 0.08 * len)
            .map(|p| *p - axis * p.dot(axis))
            .collect();
        let mut widest: f64 = 0.0;
        for a in &band {
            for b in band.iter().step_by((band.len() / 64).max(1)) {
                widest = widest.max((*a - *b).length());
            }
        }
        widest
    };
    // Ties (within 1% of the height) keep the file's own sense of up.
    let (bottom, top) = (spread(lo), spread(hi));
    let up = if (bottom - top).abs() < 0.01 * len {
        if axis == DVec3::Y { DVec3::Y } else { axis }
    } else if bottom > top {
        axis
    } else {
        -axis
    };
    let name = format!(
        "{}{}",
        if up.dot(axis) > 0.0 { "+" } else { "-" },
        ["X", "Y", "Z"][k]
    );
    (DQuat::from_rotation_arc(up, DVec3::Y), name)
}

/// The turn about Y that faces the upright figure +Z: where its toes
/// point (a low joint from a low parent that is not the skeleton's root,
/// as a toe from its ankle), else as the file has it (glTF faces +Z).
/// Also names the file's axis the figure faced.
fn facing(joints: &[DVec3], parents: &[Option<usize>], h: f64, up: DQuat) -> (f64, String) {
    let mut votes = DVec3::ZERO;
    let lowest = joints.iter().map(|q| q.y).fold(f64::INFINITY, f64::min);
    // The two lowest joints (the toes, where the feet have them), each
    // from its parent, when that is low too and not the root (a rig whose
    // feet hang from its root says nothing of where they point).
    let mut order: Vec<usize> = (0..joints.len()).collect();
    order.sort_by(|&a, &b| joints[a].y.total_cmp(&joints[b].y));
    for &j in order.iter().take(2) {
        let Some(p) = parents[j] else { continue };
        if parents[p].is_none() {
            continue;
        }
        let (a, b) = (joints[p], joints[j]);
        if b.y - lowest < 0.1 * h && a.y - lowest < 0.15 * h {
            let d = (b - a).with_y(0.0);
            if d.length() > 0.01 * h {
                votes += d.normalize();
            }
        }
    }
    let yaw = if votes.length() > 0.5 {
        // Turn `votes` onto +Z.
        -votes.x.atan2(votes.z)
    } else {
        0.0
    };
    let was = (DQuat::from_rotation_y(yaw) * up).inverse() * DVec3::Z;
    let k = (0..3)
        .max_by(|&a, &b| was[a].abs().total_cmp(&was[b].abs()))
        .unwrap_or(2);
    let name = format!(
        "{}{}",
        if was[k] >= 0.0 { "+" } else { "-" },
        ["X", "Y", "Z"][k]
    );
    (yaw, name)
}
