//! From a glTF document to a [`Figure`]: the skins' joints as a skeleton
//! in the nodes' rest pose, turned upright and facing +Z from the
//! skeleton itself, scaled to metres, the mesh skinned into that pose, and
//! the roles found by name or, failing that, by where the joints stand.

use std::collections::BTreeMap;

use glam::{DMat4, DQuat, DVec3};

use super::read::File;
use super::{Figure, GltfError, Part};
use crate::character::motion::detect_scale;
use crate::character::roles::{self, Role, RoleMap};
use crate::character::skeleton::{Joint, Skeleton, forward_kinematics};

/// Every node's world transform in the default scene's rest pose (nodes in
/// no scene: from their own parents).
fn world_transforms(file: &File) -> Result<Vec<DMat4>, GltfError> {
    let n = file.doc.nodes().len();
    let mut parent = vec![None; n];
    for node in file.doc.nodes() {
        for c in node.children() {
            parent[c.index()] = Some(node.index());
        }
    }
    let local: Vec<DMat4> = file
        .doc
        .nodes()
        .map(|node| {
            let m = node.transform().matrix();
            DMat4::from_cols_array_2d(&m.map(|c| c.map(f64::from)))
        })
        .collect();
    let mut world: Vec<Option<DMat4>> = vec![None; n];
    for i in 0..n {
        // The chain up to a node already placed (or the top), placed down.
        let mut chain = vec![i];
        while let Some(p) = parent[*chain.last().unwrap_or(&i)] {
            if world[p].is_some() || chain.len() > n {
                break;
            }
            chain.push(p);
        }
        for &j in chain.iter().rev() {
            if world[j].is_none() {
                let up = parent[j].and_then(|p| world[p]).unwrap_or(DMat4::IDENTITY);
                world[j] = Some(up * local[j]);
            }
        }
    }
    let world: Vec<DMat4> = world.into_iter().map(Option::unwrap_or_default).collect();
    if let Some(bad) = (0..n).find(|&i| !world[i].is_finite()) {
        return Err(file.data_error(format!(
            "node {bad} (`{}`): its transform is not finite",
            file.doc
                .nodes()
                .nth(bad)
                .and_then(|n| n.name())
                .unwrap_or("")
        )));
    }
    Ok(world)
}

/// The rotation and translation of `m` (its scale and shear left out).
fn rigid(m: DMat4) -> DMat4 {
    let (_, r, t) = m.to_scale_rotation_translation();
    let r = if r.is_finite() { r } else { DQuat::IDENTITY };
    DMat4::from_rotation_translation(r.normalize(), t)
}

pub(super) fn figure(
    file: &File,
    overrides: &BTreeMap<String, String>,
) -> Result<Figure, GltfError> {
    let path = file.path.clone();
    if file.doc.skins().len() == 0 {
        return Err(GltfError::NoSkin { path });
    }
    let world = world_transforms(file)?;
    let nodes: Vec<gltf::Node<'_>> = file.doc.nodes().collect();
    // The skins' joints, each once, parents first.
    let mut is_joint = vec![false; nodes.len()];
    for skin in file.doc.skins() {
        for j in skin.joints() {
            is_joint[j.index()] = true;
        }
    }
    let mut parent_node = vec![None; nodes.len()];
    for node in &nodes {
        for c in node.children() {
            parent_node[c.index()] = Some(node.index());
        }
    }
    let joint_parent = |mut n: usize| -> Option<usize> {
        let mut guard = 0;
        while let Some(p) = parent_node[n] {
            if is_joint[p] {
                return Some(p);
            }
            n = p;
            guard += 1;
            if guard > nodes.len() {
                break;
            }
        }
        None
    };
    let mut order: Vec<usize> = Vec::new();
    let mut placed = vec![false; nodes.len()];
    let mut todo: Vec<usize> = (0..nodes.len())
        .filter(|&i| is_joint[i] && joint_parent(i).is_none())
        .collect();
    while let Some(n) = todo.pop() {
        if placed[n] {
            continue;
        }
        placed[n] = true;
        order.push(n);
        for c in (0..nodes.len()).rev() {
            if is_joint[c] && !placed[c] && joint_parent(c) == Some(n) {
                todo.push(c);
            }
        }
    }
    if order.len() < 8 {
        return Err(GltfError::TooFewJoints {
            path,
            joints: order.len(),
        });
    }
    let mut index_of = vec![usize::MAX; nodes.len()];
    for (k, &n) in order.iter().enumerate() {
        index_of[n] = k;
    }
    let roots = order.iter().filter(|&&n| joint_parent(n).is_none()).count();
    // Several top joints hang under one made-up root at the first's place.
    let extra_root = usize::from(roots > 1);
    let joint_of: Vec<usize> = index_of
        .iter()
        .map(|&k| k.wrapping_add(extra_root))
        .collect();

    // Upright, facing +Z, in metres, from the skeleton and the mesh.
    let raw: Vec<DVec3> = order.iter().map(|&n| world[n].w_axis.truncate()).collect();
    let carrier = |n: usize| {
        if is_joint[n] {
            Some(n)
        } else {
            joint_parent(n)
        }
    };
    let (parts_raw, warnings) = super::parts::parts(file, &world, &joint_of, &carrier)?;
    let verts: Vec<DVec3> = parts_raw
        .iter()
        .flat_map(|p| {
            p.positions
                .iter()
                .map(|v| DVec3::new(v[0].into(), v[1].into(), v[2].into()))
        })
        .collect();
    let (turn, up_name) = upright(&raw);
    let rot = |p: DVec3| turn * p;
    let lowest = verts
        .iter()
        .chain(&raw)
        .map(|p| rot(*p).y)
        .fold(f64::INFINITY, f64::min);
    let highest = verts
        .iter()
        .chain(&raw)
        .map(|p| rot(*p).y)
        .fold(f64::NEG_INFINITY, f64::max);
    let height_units = highest - lowest;
    if !(height_units.is_finite() && height_units > 0.0) {
        return Err(file.data_error("the figure has no height".to_owned()));
    }
    let scale = detect_scale(height_units);
    let upright_joints: Vec<DVec3> = raw.iter().map(|p| rot(*p)).collect();
    let parents: Vec<Option<usize>> = order
        .iter()
        .map(|&n| joint_parent(n).map(|q| index_of[q]))
        .collect();
    let (yaw, facing_name) = facing(&upright_joints, &parents, height_units, turn);
    let turn = DQuat::from_rotation_y(yaw) * turn;
    let centre = {
        let c = order
            .first()
            .map_or(DVec3::ZERO, |&n| turn * world[n].w_axis.truncate());
        DVec3::new(c.x, lowest, c.z)
    };
    let normal = DMat4::from_scale(DVec3::splat(scale))
        * DMat4::from_translation(-centre)
        * DMat4::from_quat(turn);
    let at = |p: DVec3| normal.transform_point3(p);

    // The skeleton: rest offsets in the world axes, identity rotations.
    let mut joints = Vec::with_capacity(order.len() + extra_root);
    let mut rest = Vec::with_capacity(order.len() + extra_root);
    if extra_root == 1 {
        joints.push(Joint {
            name: "(root)".to_owned(),
            parent: None,
            offset: at(raw[0]),
            end_site: None,
        });
        rest.push(DMat4::from_translation(at(raw[0])));
    }
    for (k, &n) in order.iter().enumerate() {
        let p = at(raw[k]);
        let parent = joint_parent(n)
            .map(|q| index_of[q] + extra_root)
            .or((extra_root == 1).then_some(0));
        let offset = match parent {
            Some(q) => p - rest[q].w_axis.truncate(),
            None => p,
        };
        joints.push(Joint {
            name: nodes[n]
                .name()
                .map_or_else(|| format!("joint {n}"), str::to_owned),
            parent,
            offset,
            end_site: None,
        });
        rest.push(rigid(normal * world[n]));
    }
    let skeleton = Skeleton { joints };
    let parts: Vec<Part> = parts_raw
        .into_iter()
        .map(|mut p| {
            for v in &mut p.positions {
                let q = at(DVec3::new(v[0].into(), v[1].into(), v[2].into()));
                *v = [q.x as f32, q.y as f32, q.z as f32];
            }
            p
        })
        .collect();

    let height_m = height_units * scale;
    let (roles, roles_by) = match roles::fill(&skeleton, overrides) {
        Ok(r) => (r, "names"),
        // A joint named for a role that the skeleton lacks is the
        // configuration's mistake: said, not guessed around.
        Err(e @ (roles::RolesError::UnknownRole(_) | roles::RolesError::UnknownJoint { .. })) => {
            return Err(GltfError::Data {
                path: file.path.clone(),
                why: format!(
                    "mesh_roles: {}",
                    e.to_string().trim_start_matches("[roles] ")
                ),
            });
        }
        Err(_) => {
            let mut by =
                by_places(&skeleton, height_m).map_err(|missing| GltfError::NotHumanoid {
                    path: file.path.clone(),
                    missing,
                })?;
            // The configured joints over where joints stand (their names
            // were checked above).
            for (role, joint) in overrides {
                if let (Some(r), Some(j)) = (roles::Role::from_name(role), skeleton.find(joint)) {
                    by.0.insert(r, j);
                }
            }
            (by, "places")
        }
    };
    Ok(Figure {
        skeleton,
        rest,
        roles,
        roles_by,
        parts,
        skins: file.doc.skins().len(),
        height_m,
        scale_to_m: scale,
        facing: facing_name,
        up: up_name,
        warnings,
        own: false,
    })
}

/// The turn that stands the figure up: the axis along which the skeleton
/// is longest is the body's; its feet are at the end where the joints
/// spread widest across it (two feet apart, against one head).
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
    let (k, _) = axes
        .iter()
        .enumerate()
        .map(|(k, a)| (k, extent(*a).0))
        .fold((1, f64::NEG_INFINITY), |best, (k, e)| {
            if e > best.1 + 1e-9 { (k, e) } else { best }
        });
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

/// Roles from where the joints stand in the upright figure (`h` tall,
/// facing +Z, its left at +X): each side's lowest joint and the low ones
/// above it are the foot, the joint above them (or beside, for a rig whose
/// feet hang from its root) the knee and its parent the hip; the chains
/// that leave the trunk sideways high up are the arms, the first long bone
/// along them the upper arm; the highest joint on the middle line the head.
/// What is missing is named.
fn by_places(skeleton: &Skeleton, h: f64) -> Result<RoleMap, String> {
    let p: Vec<DVec3> = forward_kinematics(skeleton, &skeleton.rest_pose()).positions;
    let n = skeleton.len();
    let floor = p.iter().map(|q| q.y).fold(f64::INFINITY, f64::min);
    let y = |j: usize| p[j].y - floor;
    let parent = |j: usize| skeleton.joints[j].parent;
    let middle = |j: usize| p[j].x.abs() < 0.03 * h;
    let mut size = vec![1usize; n];
    for j in (0..n).rev() {
        if let Some(q) = parent(j) {
            size[q] += size[j];
        }
    }
    for (joint, at) in skeleton.joints.iter().zip(&p) {
        tracing::debug!(
            joint = %joint.name,
            x = at.x / h,
            y = (at.y - floor) / h,
            z = at.z / h,
            "where a joint stands (shares of the height)"
        );
    }
    let mut map = BTreeMap::new();
    if let Some(head) = (0..n)
        .filter(|&j| middle(j))
        .max_by(|&a, &b| y(a).total_cmp(&y(b)))
    {
        map.insert(Role::Head, head);
    }
    for (sign, [foot_r, knee_r, hip_r, hand_r, elbow_r, shoulder_r]) in [
        (
            1.0,
            [
                Role::LeftFoot,
                Role::LeftKnee,
                Role::LeftHip,
                Role::LeftHand,
                Role::LeftElbow,
                Role::LeftShoulder,
            ],
        ),
        (
            -1.0,
            [
                Role::RightFoot,
                Role::RightKnee,
                Role::RightHip,
                Role::RightHand,
                Role::RightElbow,
                Role::RightShoulder,
            ],
        ),
    ] {
        let side = |j: usize| p[j].x * sign > 0.03 * h;
        // The arm: the largest chain leaving the trunk sideways, high.
        let arm_root = (0..n)
            .filter(|&j| side(j) && y(j) > 0.5 * h && parent(j).is_some_and(|q| !side(q)))
            .max_by_key(|&j| size[j]);
        let in_arm = |j: usize| arm_root.is_some_and(|a| skeleton.is_ancestor(a, j));
        // The foot: up from the side's lowest joint while still low.
        let lowest = (0..n)
            .filter(|&j| side(j) && !in_arm(j))
            .min_by(|&a, &b| y(a).total_cmp(&y(b)))
            .filter(|&j| y(j) < 0.12 * h);
        let foot = lowest.map(|mut j| {
            while let Some(q) = parent(j).filter(|&q| side(q) && y(q) < 0.12 * h) {
                j = q;
            }
            j
        });
        let knee_band = |j: usize| side(j) && !in_arm(j) && (0.12 * h..0.45 * h).contains(&y(j));
        let knee = foot.and_then(|f| {
            parent(f).filter(|&q| knee_band(q)).or_else(|| {
                // Feet that hang from the root: the knee-high joint nearest
                // above the foot that hangs from a hip-high one.
                (0..n)
                    .filter(|&j| knee_band(j) && parent(j).is_some_and(|q| side(q) && y(q) > y(j)))
                    .min_by(|&a, &b| {
                        let d = |j: usize| (p[j] - p[f]).with_y(0.0).length();
                        d(a).total_cmp(&d(b))
                    })
            })
        });
        let hip = knee.and_then(parent).filter(|&q| parent(q).is_some());
        let (mut hand, mut elbow, mut shoulder) = (None, None, None);
        if let Some(root) = arm_root {
            let mut chain = vec![root];
            loop {
                let last = *chain.last().unwrap_or(&root);
                let kids: Vec<usize> = skeleton.children(last).collect();
                if kids.len() != 1 {
                    break;
                }
                chain.push(kids[0]);
            }
            if let Some(i) = (0..chain.len().saturating_sub(1))
                .find(|&i| (p[chain[i + 1]] - p[chain[i]]).length() >= 0.1 * h)
            {
                shoulder = Some(chain[i]);
                elbow = Some(chain[i + 1]);
                hand = chain.get(i + 2).copied().or_else(|| {
                    // The forearm ends in several fingers or palms: the
                    // one nearest their middle.
                    let kids: Vec<usize> = skeleton.children(chain[i + 1]).collect();
                    let mid = kids.iter().map(|&k| p[k]).sum::<DVec3>() / kids.len().max(1) as f64;
                    kids.into_iter()
                        .min_by(|&a, &b| (p[a] - mid).length().total_cmp(&(p[b] - mid).length()))
                });
            }
        }
        for (role, j) in [
            (foot_r, foot),
            (knee_r, knee),
            (hip_r, hip),
            (hand_r, hand),
            (elbow_r, elbow),
            (shoulder_r, shoulder),
        ] {
            if let Some(j) = j {
                map.insert(role, j);
            }
        }
    }
    roles::complete(skeleton, map).map_err(|e| match e {
        roles::RolesError::Missing(m) => m.iter().map(|r| r.name()).collect::<Vec<_>>().join(", "),
        e => e.to_string(),
    })
}
