//! A skinned figure in the frame: its rest-pose triangles uploaded once
//! ([`Geometry`]), skinned every frame by linear blend skinning from the
//! joints' skinning matrices (in the vertex shader, the matrices in a
//! storage buffer; on a CPU renderer by [`skin_on_cpu`], see
//! `skinned`), lit with its rest normals turned as its vertices are, in its
//! material's colour or its base colour texture's at each vertex (the
//! table's tint blended in), the parts fingers hold glowing (its shadow is
//! the capsule figure's, see `scene`).

use std::sync::Arc;

use bytemuck::{Pod, Zeroable};
use glam::{DMat4, Mat4, Vec3};

use super::mesh::{DrawList, Vertex3};
use crate::character::gltf::{Geometry, Skin};
use crate::character::roles::Role;
use crate::character::skeleton::WorldPose;

/// A skinned vertex as the shader reads it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SkinVertex {
    /// Rest pose (m).
    pub pos: [f32; 3],
    pub normal: [f32; 3],
    /// Linear RGB untinted...
    pub plain: [f32; 3],
    /// ...and tinted: `rgb + a * tint`.
    pub tinted: [f32; 4],
    pub joints: [u32; 4],
    pub weights: [f32; 4],
    /// The joint whose glow it shows.
    pub glow: u32,
}

/// One joint of a figure as the shader reads it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct JointGpu {
    /// Rest pose to posed (columns).
    pub skin: [[f32; 4]; 4],
    /// x: 1 where the joint glows; yzw: the figure's tint (its first
    /// joint's; y < 0: none).
    pub extra: [f32; 4],
}

/// A figure to draw this frame.
#[derive(Clone, Debug)]
pub struct SkinnedDraw {
    /// The triangles, shared with the figure (the renderer keeps them on
    /// the GPU while the figure is drawn).
    pub geometry: Arc<Geometry>,
    /// The own body (its clothes tinted as the capsule figure's are).
    pub own: bool,
    pub joints: Vec<JointGpu>,
    /// Balls (centre, radius; m) holding every posed vertex: the damage a
    /// frame can do.
    pub spheres: Vec<[f32; 4]>,
}

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

/// The vertices of `g` as uploaded: the own body's clothes take the tint
/// as the capsule figure's do (`scene::tinted`, linear in the tint), any
/// other figure is blended half and half with it.
#[must_use]
pub fn vertices(g: &Geometry, own: bool) -> Vec<SkinVertex> {
    (0..g.positions.len())
        .map(|i| {
            let rgb = g.colours[i];
            let (c0, k) = if own {
                let c0 = super::scene::tinted(rgb, [0.0; 3]);
                (c0, super::scene::tinted(rgb, [1.0; 3])[0] - c0[0])
            } else {
                (rgb.map(|c| 0.5 * c), 0.5)
            };
            SkinVertex {
                pos: g.positions[i],
                normal: g.normals[i],
                plain: rgb,
                tinted: [c0[0], c0[1], c0[2], k],
                joints: g.joints[i].map(u32::from),
                weights: g.weights[i],
                glow: u32::from(g.glow_joint[i]),
            }
        })
        .collect()
}

/// Adds the figure, posed as the library's `world`, to the frame; the
/// parts in `held` glow, `tint` is blended in. A posture whose joints are
/// not finite draws nothing.
pub(crate) fn draw(
    list: &mut DrawList,
    skin: &Skin,
    world: &WorldPose,
    held: &[Role],
    tint: Option<[f32; 3]>,
) {
    let fig = &skin.figure;
    let posed = skin.joints(world);
    let mut skinning = skin.drive.skinning(&posed);
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

/// What `vs_skinned` does, on the CPU: `vertices` skinned by `joints`
/// (their tint and glow) into lit vertices appended to `out`.
pub fn skin_on_cpu(vertices: &[SkinVertex], joints: &[JointGpu], out: &mut Vec<Vertex3>) {
    let Some(first) = joints.first() else {
        return;
    };
    let mats: Vec<Mat4> = joints
        .iter()
        .map(|j| Mat4::from_cols_array_2d(&j.skin))
        .collect();
    let tint = first.extra;
    let joint = |k: u32| mats.get(k as usize).copied().unwrap_or(Mat4::IDENTITY);
    out.extend(vertices.iter().map(|v| {
        let w = v.weights;
        let m = joint(v.joints[0]) * w[0]
            + joint(v.joints[1]) * w[1]
            + joint(v.joints[2]) * w[2]
            + joint(v.joints[3]) * w[3];
        let rgb = if tint[1] >= 0.0 {
            [0, 1, 2].map(|c| v.tinted[c] + v.tinted[3] * tint[c + 1])
        } else {
            v.plain
        };
        let glow = joints.get(v.glow as usize).map_or(0.0, |j| j.extra[0]);
        Vertex3 {
            pos: m.transform_point3(Vec3::from(v.pos)).to_array(),
            normal: m
                .transform_vector3(Vec3::from(v.normal))
                .normalize_or_zero()
                .to_array(),
            color: [rgb[0], rgb[1], rgb[2], glow],
        }
    }));
}
