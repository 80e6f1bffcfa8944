//! A skinned figure in the frame: its joints posed from the character's
//! posture into skinning matrices, with the parts fingers hold glowing
//! and the table's tint; its rest-pose triangles (`gltf::Geometry`) are
//! uploaded once and skinned by linear blend skinning as they are drawn
//! (see `skinned`), lit with their rest normals turned as their vertices
//! are, in the material's colour or its base colour texture's at each
//! vertex (its shadow is the capsule figure's, see `scene`).

use std::sync::Arc;

use glam::DMat4;

use super::mesh::{DrawList, JointGpu, SkinnedDraw};
use crate::character::gltf::Skin;
use crate::character::roles::Role;

/// Joints that glow when a finger holds a part: each held part's joint and
/// the unmapped joints below it (a hand's palm and fingers), down to the
/// next part.
fn glowing(skin: &Skin, held: &[Role]) -> Vec<bool> {
    let fig = &skin.figure;
    let sk = &fig.skeleton;
    let mapped: Vec<usize> = Role::ALL.iter().map(|r| fig.roles.get(*r)).collect();
    let mut glow = vec![false; sk.len()];
    for &r in held {
        glow[fig.roles.get(r)] = true;
    }
    // Parents come before children: spread down to unmapped joints.
    for j in 0..sk.len() {
        if let Some(p) = sk.joints[j].parent {
            if glow[p] && !mapped.contains(&j) {
                glow[j] = true;
            }
        }
    }
    glow
}

/// Adds the figure, its joints posed as `posed` (see `Skin::joints`), to
/// the frame; the parts in `held` glow, `tint` is blended in. A posture
/// whose joints are not finite draws nothing.
pub(crate) fn draw(
    list: &mut DrawList,
    skin: &Skin,
    posed: &[DMat4],
    held: &[Role],
    tint: Option<[f32; 3]>,
) {
    let fig = &skin.figure;
    let mut skinning = skin.drive.skinning(posed);
    if skinning.iter().any(|m| !m.is_finite()) {
        return;
    }
    // Joints the posture lacks keep their rest pose.
    skinning.resize(fig.rest.len(), DMat4::IDENTITY);
    let glow = glowing(skin, held);
    let tint = tint.map_or([-1.0, 0.0, 0.0], |t| t);
    let joints = skinning
        .iter()
        .enumerate()
        .map(|(j, m)| JointGpu {
            skin: m.as_mat4().to_cols_array_2d(),
            extra: [
                if glow.get(j).copied().unwrap_or(false) {
                    1.0
                } else {
                    0.0
                },
                tint[0],
                tint[1],
                tint[2],
            ],
        })
        .collect();
    let reach = &skin.geometry.reach;
    let spheres = (0..fig.rest.len())
        .filter(|&j| reach[j] >= 0.0)
        .map(|j| {
            // Skinning matrices are rigid: a vertex within `reach` of its
            // joint at rest is within it of the joint posed.
            let c = (skinning[j] * fig.rest[j]).w_axis.truncate().as_vec3();
            [c.x, c.y, c.z, reach[j]]
        })
        .collect();
    list.figures.push(SkinnedDraw {
        geometry: Arc::clone(&skin.geometry),
        own: fig.own,
        joints,
        spheres,
    });
}
