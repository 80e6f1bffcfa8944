//! The pose a skin was bound in: each joint's bind pose from the skins'
//! inverse bind matrices, the model's place they share, and the nodes
//! moved back into it where the file stores another pose on them (an idle
//! pose), so that a figure is retargeted from the pose its mesh was made
//! in.

use glam::{DMat4, DVec3};

use super::{Joints, world_transforms};
use crate::character::gltf::GltfError;
use crate::character::gltf::read::{Budget, File, Kind};

/// Whether the file's meshes are mostly skinned: not a figure of rigid
/// meshes hung on its joints with a few skinned parts.
fn mostly_skinned(file: &File) -> bool {
    let (mut skinned, mut rigid) = (0usize, 0usize);
    for node in file.doc.nodes() {
        if let Some(mesh) = node.mesh() {
            let count: usize = mesh
                .primitives()
                .filter_map(|p| p.get(&gltf::Semantic::Positions).map(|a| a.count()))
                .sum();
            if node.skin().is_some() {
                skinned += count;
            } else {
                rigid += count;
            }
        }
    }
    rigid * 10 <= skinned
}

/// Each node's bind pose as its skin (the first that has it) binds it, in
/// the nodes' world; `None` for nodes no skin binds.
fn skin_binds(
    file: &File,
    world: &[DMat4],
    joints: &Joints,
) -> Result<Vec<Option<DMat4>>, GltfError> {
    let mut bind: Vec<Option<DMat4>> = vec![None; world.len()];
    let mut budget = Budget::default();
    for skin in file.doc.skins() {
        let Some(a) = skin.inverse_bind_matrices() else {
            continue;
        };
        file.check(&a, "inverse bind matrices", Kind::Matrices, &mut budget)?;
        let nodes: Vec<usize> = skin.joints().map(|j| j.index()).collect();
        let ibms: Vec<DMat4> = skin
            .reader(|b| file.buffer(b))
            .read_inverse_bind_matrices()
            .map(|it| {
                it.map(|m| DMat4::from_cols_array_2d(&m.map(|c| c.map(f64::from))))
                    .collect()
            })
            .unwrap_or_default();
        if ibms.len() < nodes.len()
            || ibms
                .iter()
                .any(|m| !m.is_finite() || m.determinant().abs() < 1e-12)
        {
            // Said by the parts' reader, which refuses them.
            continue;
        }
        let model = model_place(world, joints, skin.index(), &nodes, &ibms);
        for (k, &n) in nodes.iter().enumerate() {
            if bind[n].is_none() {
                bind[n] = Some(model * ibms[k].inverse());
            }
        }
    }
    Ok(bind)
}

/// The model's place for skin `skin` (its joint `nodes`, their inverse bind
/// matrices `ibms`): the skinning matrix most joints share at the nodes'
/// pose (every joint shares it where that is the bind pose); the
/// armature's own place where a joint (its root, unmoved) agrees with it,
/// else the one most joints agree on.
fn model_place(
    world: &[DMat4],
    joints: &Joints,
    skin: usize,
    nodes: &[usize],
    ibms: &[DMat4],
) -> DMat4 {
    let skinning: Vec<DMat4> = nodes
        .iter()
        .zip(ibms)
        .map(|(&n, m)| world[n] * *m)
        .collect();
    let close = |a: &DMat4, b: &DMat4| {
        a.to_cols_array()
            .iter()
            .zip(b.to_cols_array())
            .all(|(x, y)| (x - y).abs() < 1e-4 * (1.0 + x.abs().max(y.abs())))
    };
    let armature = nodes
        .iter()
        .find_map(|&n| {
            joints
                .joint_parent(n)
                .is_none()
                .then(|| joints.parent_node[n])
        })
        .map_or(DMat4::IDENTITY, |p| p.map_or(DMat4::IDENTITY, |p| world[p]));
    let model = if skinning.iter().any(|b| close(&armature, b)) {
        armature
    } else {
        skinning
            .iter()
            .take(64)
            .max_by_key(|a| skinning.iter().filter(|b| close(a, b)).count())
            .copied()
            .unwrap_or(DMat4::IDENTITY)
    };
    tracing::debug!(
        skin,
        joints = nodes.len(),
        agree = skinning.iter().filter(|b| close(&model, b)).count(),
        "joints whose skinning matrix at the nodes' pose is the model's"
    );
    model
}

/// Each node's world transform with the skinned joints in their bind
/// pose (from the skins' inverse bind matrices), where the nodes hold
/// another pose (an idle pose stored on the nodes): the nodes a joint
/// carries go with it. `None` where the nodes already stand in the bind
/// pose (within half a percent of the skeleton's size).
fn bind_pose(
    file: &File,
    world: &[DMat4],
    joints: &Joints,
) -> Result<Option<Vec<DMat4>>, GltfError> {
    // A figure built of rigid meshes hung on its joints looks as it should
    // in the nodes' pose, wherever its few skinned parts were bound.
    if !mostly_skinned(file) {
        return Ok(None);
    }
    let bind = skin_binds(file, world, joints)?;
    let places: Vec<DVec3> = joints
        .order
        .iter()
        .map(|&n| world[n].w_axis.truncate())
        .collect();
    let size = places
        .iter()
        .flat_map(|a| {
            places
                .iter()
                .step_by((places.len() / 32).max(1))
                .map(move |b| (*a - *b).length())
        })
        .fold(0.0f64, f64::max);
    let moved = joints
        .order
        .iter()
        .filter_map(|&n| bind[n].map(|b| (b.w_axis - world[n].w_axis).truncate().length()))
        .fold(0.0f64, f64::max);
    if moved.is_nan() || moved <= 0.005 * size || bind.iter().flatten().any(|m| !m.is_finite()) {
        return Ok(None);
    }
    // Every node in the bind pose: a joint as its skin binds it, a node a
    // joint carries as its joint moved.
    let mut out = world.to_vec();
    for n in 0..world.len() {
        if let Some(b) = bind[n] {
            out[n] = b;
        } else if let Some(c) = joints.carrier(n) {
            if let Some(b) = bind[c] {
                out[n] = b * world[c].inverse() * world[n];
            }
        }
    }
    Ok(Some(out))
}

/// Each node's world transform in the skin's bind pose (said in `notes`
/// where the nodes hold another), else as the nodes stand.
pub(super) fn bind_or_node_pose(
    file: &File,
    joints: &Joints,
    notes: &mut Vec<String>,
) -> Result<Vec<DMat4>, GltfError> {
    let node_pose = world_transforms(file)?;
    Ok(match bind_pose(file, &node_pose, joints)? {
        Some(bound) => {
            notes.push(
                "its nodes hold another pose than the skin's bind pose: the bind pose is used"
                    .to_owned(),
            );
            bound
        }
        None => node_pose,
    })
}
