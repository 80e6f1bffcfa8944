//! A skinned figure in the frame: posed from the character's posture,
//! skinned on the CPU (linear blend skinning, every vertex each frame),
//! lit with smooth normals, in its material's colour or its base colour
//! texture's at each vertex (the table's tint blended in), the parts fingers hold glowing (its shadow is the capsule
//! figure's, see `scene`).

use glam::DVec3;

use super::mesh::{DrawList, Vertex3};
use crate::character::gltf::Skin;
use crate::character::roles::Role;
use crate::character::skeleton::WorldPose;

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

/// Adds the figure, posed as the library's `world`, to the frame's body
/// and shadow meshes; the parts in `held` glow, `tint` is blended in (into
/// the own body's clothes by `clothes`, as the capsule figure's are).
pub(crate) fn draw(
    list: &mut DrawList,
    skin: &Skin,
    world: &WorldPose,
    held: &[Role],
    tint: Option<[f32; 3]>,
    clothes: fn([f32; 3], [f32; 3]) -> [f32; 3],
) {
    let fig = &skin.figure;
    let posed = skin.posed(world);
    let glow = glowing(skin, held);
    for (part, points) in fig.parts.iter().zip(&posed) {
        if points.iter().any(|p| !p.is_finite()) {
            continue;
        }
        // Smooth normals: each vertex's triangles, weighted by their area.
        let mut normals = vec![DVec3::ZERO; points.len()];
        for t in part.indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| i as usize);
            let n = (points[b] - points[a]).cross(points[c] - points[a]);
            for i in [a, b, c] {
                normals[i] += n;
            }
        }
        // The vertex's own colour (its texture's) or the part's, with the
        // table's tint.
        let colour = |i: usize| -> [f32; 3] {
            let c = part.colours.get(i).unwrap_or(&part.base_colour);
            let rgb = [c[0], c[1], c[2]];
            match tint {
                Some(t) if fig.own => clothes(rgb, t),
                Some(t) => [
                    0.5 * rgb[0] + 0.5 * t[0],
                    0.5 * rgb[1] + 0.5 * t[1],
                    0.5 * rgb[2] + 0.5 * t[2],
                ],
                None => rgb,
            }
        };
        let f = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32];
        {
            let mesh = &mut list.body;
            let base = mesh.base();
            mesh.vertices.extend(
                points
                    .iter()
                    .zip(&normals)
                    .zip(&part.joints)
                    .zip(&part.weights)
                    .enumerate()
                    .map(|(i, (((p, n), j), w))| {
                        // The joint that carries the vertex most.
                        let k = (0..4).max_by(|&a, &b| w[a].total_cmp(&w[b])).unwrap_or(0);
                        let lit = match part.role {
                            Some(r) => held.contains(&r),
                            None => glow.get(usize::from(j[k])).copied().unwrap_or(false),
                        };
                        let c = colour(i);
                        Vertex3 {
                            pos: f(*p),
                            normal: f(n.normalize_or_zero()),
                            color: [c[0], c[1], c[2], if lit { 1.0 } else { 0.0 }],
                        }
                    }),
            );
            mesh.indices.extend(part.indices.iter().map(|i| base + i));
        }
    }
}
