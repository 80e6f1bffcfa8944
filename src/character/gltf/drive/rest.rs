//! How a figure's rest pose stands against the library's: the library's
//! standing postures and planted feet, which library joint each figure
//! joint turns with and hangs from, in what order, and how much wider the
//! figure's hips are.

use glam::{DQuat, DVec3};

use super::{CHAIN, Follow};
use crate::character::body::facing;
use crate::character::gltf::Figure;
use crate::character::library::Library;
use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::{WorldPose, forward_kinematics};

/// Every fifth posture of the library's clips (world), and how high its
/// ankles stand: the lower one's median over them (a rest pose may stand
/// otherwise).
pub(super) fn standing(library: &Library, lib_roles: &RoleMap) -> (Vec<WorldPose>, f64) {
    let lib = &library.skeleton;
    let feet = [Role::LeftFoot, Role::RightFoot].map(|r| lib_roles.get(r));
    let standing: Vec<WorldPose> = library
        .clips
        .values()
        .flat_map(|c| c.frames.iter().step_by(5))
        .map(|p| forward_kinematics(lib, p))
        .filter(|w| w.positions.iter().all(|p| p.is_finite()))
        .collect();
    let mut lows: Vec<f64> = standing
        .iter()
        .map(|w| w.positions[feet[0]].y.min(w.positions[feet[1]].y))
        .collect();
    lows.sort_by(f64::total_cmp);
    let stand = lows.get(lows.len() / 2).copied().unwrap_or(0.08);
    (standing, stand)
}

/// How a planted foot lies, facing +Z: each foot's turn where it stands
/// within 1 cm of `stand`, the body's facing taken out, averaged. A
/// figure's rest foot lies flat; the library's rest pose need not (a
/// studio's T-pose may point the toes).
pub(super) fn planted_feet(
    standing: &[WorldPose],
    stand: f64,
    lib_roles: &RoleMap,
) -> [Option<DQuat>; 2] {
    [Role::LeftFoot, Role::RightFoot].map(|r| {
        let f = lib_roles.get(r);
        let mut sum = glam::DVec4::ZERO;
        for w in standing {
            if (w.positions[f].y - stand).abs() > 0.01 {
                continue;
            }
            let q = facing(w, lib_roles).inverse() * w.rotations[f];
            let v = glam::DVec4::from(q);
            sum += if v.dot(sum) < 0.0 { -v } else { v };
        }
        (sum.length() > 1e-9).then(|| DQuat::from_vec4(sum.normalize()))
    })
}

/// Per figure joint, the library joint it turns with and the turn from
/// that joint's to the figure's rest (see `Drive::follow`), and the joint
/// it hangs from (see `Drive::hang`).
pub(super) fn follow_and_hang(
    fig: &Figure,
    rest_lib: &WorldPose,
    lib_roles: &RoleMap,
    planted: &[Option<DQuat>; 2],
) -> (Vec<Follow>, Vec<Option<usize>>) {
    let fpos: Vec<DVec3> = fig.rest.iter().map(|m| m.w_axis.truncate()).collect();
    let mut follow = vec![None; fig.rest.len()];
    let mut hang: Vec<Option<usize>> = fig.skeleton.joints.iter().map(|j| j.parent).collect();
    let dir = |p: &[DVec3], roles: &RoleMap, a: Role, b: Role| p[roles.get(b)] - p[roles.get(a)];
    // Rest alignment per role, an end role taking its limb's.
    let mut align = std::collections::BTreeMap::new();
    for (role, to, _) in CHAIN {
        if let Some(to) = to {
            let (f, l) = (
                dir(&fpos, &fig.roles, role, to),
                dir(&rest_lib.positions, lib_roles, role, to),
            );
            let c = if f.length() > 1e-9 && l.length() > 1e-9 {
                DQuat::from_rotation_arc(f.normalize(), l.normalize())
            } else {
                DQuat::IDENTITY
            };
            align.insert(role, c);
        }
    }
    for (role, _, up) in CHAIN {
        let c = align
            .get(&role)
            .or_else(|| up.and_then(|u| align.get(&u)))
            .copied()
            .unwrap_or(DQuat::IDENTITY);
        let m = fig.roles.get(role);
        let l = lib_roles.get(role);
        // A made-up joint goes where the joint above it takes it.
        if fig.made_up.get(m).copied().unwrap_or(false) {
            continue;
        }
        // From the library's rest, the bone laid along it; a foot from
        // how the library's planted foot lies.
        let from = match role {
            Role::LeftFoot => planted[0].map(|q| q.inverse()),
            Role::RightFoot => planted[1].map(|q| q.inverse()),
            _ => None,
        };
        follow[m] = Some((
            l,
            from.unwrap_or_else(|| rest_lib.rotations[l].inverse() * c),
        ));
        // Hung elsewhere by the rig: hang it on its limb.
        if let Some(up) = up {
            let u = fig.roles.get(up);
            if u != m && !fig.skeleton.is_ancestor(u, m) && !fig.skeleton.is_ancestor(m, u) {
                hang[m] = Some(u);
            }
        }
    }
    (follow, hang)
}

/// The figure's joints, each after the one it hangs from; anything left in
/// a loop of hangings keeps its own parent.
pub(super) fn hang_order(fig: &Figure, hang: &mut [Option<usize>]) -> Vec<usize> {
    let n = hang.len();
    let mut order = Vec::with_capacity(n);
    let mut done = vec![false; n];
    let mut stack: Vec<usize> = (0..n).filter(|&j| hang[j].is_none()).collect();
    stack.reverse();
    while let Some(j) = stack.pop() {
        if done[j] {
            continue;
        }
        done[j] = true;
        order.push(j);
        for c in (0..n).rev() {
            if hang[c] == Some(j) && !done[c] {
                stack.push(c);
            }
        }
    }
    for j in 0..n {
        if !done[j] {
            hang[j] = fig.skeleton.joints[j].parent;
            order.push(j);
        }
    }
    order
}

/// A hip's place under the pelvis along the floor, the figure's (from its
/// rest) less the library's scaled (from its clips facing +Z: its rest
/// pose need not stand; the Bandai hips sit 9 cm apart in height there).
/// Across and forward: a figure whose hips sit behind its pelvis joint
/// (a robot's, 7 cm) stands with its feet under its hips, not
/// under the joint.
pub(super) fn hip_wide(
    hip: Role,
    (fpos, fig_roles): (&[DVec3], &RoleMap),
    (standing, rest_lib, lib_roles): (&[WorldPose], &WorldPose, &RoleMap),
    scale: f64,
) -> DVec3 {
    let (mut sum, mut n) = (DVec3::ZERO, 0.0);
    for w in standing {
        sum += facing(w, lib_roles).inverse()
            * (w.positions[lib_roles.get(hip)] - w.positions[lib_roles.get(Role::Pelvis)]);
        n += 1.0;
    }
    let lib_under = if n > 0.0 {
        sum / n
    } else {
        rest_lib.positions[lib_roles.get(hip)] - rest_lib.positions[lib_roles.get(Role::Pelvis)]
    };
    let d = fpos[fig_roles.get(hip)] - fpos[fig_roles.get(Role::Pelvis)] - lib_under * scale;
    DVec3::new(d.x, 0.0, d.z)
}
