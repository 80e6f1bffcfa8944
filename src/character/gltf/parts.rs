//! The figure's triangles in its rest pose: skinned primitives through
//! their skin's joints and inverse bind matrices (weights that do not sum
//! to one normalised, and said), meshes hung rigidly on a joint carried by
//! it. Every count, index and number is checked before it is used.

use crate::reading::quote;
use glam::{DMat4, DVec3};

use super::read::{Budget, File, Kind};
use super::{GltfError, Part};

/// The figure's parts, positions in the file's world frame, and what was
/// fixed on the way. `joint_of[node]` is the skeleton index of a joint
/// node; `carrier(node)` the nearest joint above a node.
pub(super) fn parts(
    file: &File,
    world: &[DMat4],
    joint_of: &[usize],
    carrier: &dyn Fn(usize) -> Option<usize>,
) -> Result<(Vec<Part>, Vec<String>), GltfError> {
    let mut out = Vec::new();
    let mut warnings = Vec::new();
    let mut budget = Budget::default();
    // Decoded images by index (`None`: could not be read, said once).
    let mut textures: Vec<Option<Option<super::texture::Texture>>> =
        vec![None; file.doc.images().len()];
    let mut fixes = WeightFixes::default();
    for node in file.doc.nodes() {
        let Some(mesh) = node.mesh() else {
            continue;
        };
        // Skinned: each skin joint's matrix from the bind pose to the rest
        // pose; rigid: the node's own transform, carried by its joint.
        let (matrices, skin_joints): (Vec<DMat4>, Vec<usize>) = match node.skin() {
            Some(skin) => skin_matrices(file, &skin, world, joint_of, &mut budget)?,
            None => {
                let Some(j) = carrier(node.index()) else {
                    warnings.push(format!(
                        "mesh {} hangs on no joint: left out",
                        quote(mesh.name().unwrap_or(""))
                    ));
                    continue;
                };
                (vec![world[node.index()]], vec![joint_of[j]])
            }
        };
        for prim in mesh.primitives() {
            if prim.mode() != gltf::mesh::Mode::Triangles {
                warnings.push(format!(
                    "mesh {}: a primitive of {:?} left out (triangles only)",
                    quote(mesh.name().unwrap_or("")),
                    prim.mode()
                ));
                continue;
            }
            let what = |s: &str| format!("mesh {} {s}", quote(mesh.name().unwrap_or("")));
            let positions = positions(file, &prim, &what, &mut budget)?;
            let n = positions.len();
            let skinned = node.skin().is_some()
                && prim.get(&gltf::Semantic::Joints(0)).is_some()
                && prim.get(&gltf::Semantic::Weights(0)).is_some();
            let (joints, weights) = if skinned {
                skin_data(file, &prim, n, &what, &mut budget)?
            } else {
                (vec![[0; 4]; n], vec![[1.0, 0.0, 0.0, 0.0]; n])
            };
            let indices = indices(file, &prim, n, &what, &mut budget)?;
            // Rest-pose positions and the skeleton's joints.
            let mut part = Part {
                positions: Vec::with_capacity(n),
                joints: Vec::with_capacity(n),
                weights: Vec::with_capacity(n),
                indices: indices[..indices.len() / 3 * 3].to_vec(),
                base_colour: prim.material().pbr_metallic_roughness().base_color_factor(),
                colours: Vec::new(),
                role: None,
            };
            part.colours = colours(file, &prim, n, &mut budget, &mut textures, &mut warnings)?;
            let skin = (&matrices[..], &skin_joints[..]);
            let vertices = (&positions[..], &joints[..], &weights[..]);
            rest_vertices(file, &what, vertices, skin, &mut fixes, &mut part)?;
            out.push(part);
        }
    }
    fixes.say(&mut warnings);
    if out.is_empty() {
        return Err(file.data_error("no triangles to draw".to_owned()));
    }
    Ok((out, warnings))
}

/// A primitive's vertex positions, joints and weights.
type Vertices<'a> = (&'a [[f32; 3]], &'a [[u16; 4]], &'a [[f32; 4]]);

/// A primitive's vertices into `part` at rest, each moved by its skin
/// joints' matrices (`skin`: the matrices and the skeleton's joint of
/// each) by its weights (fixed where they need it), and carried by those
/// joints.
fn rest_vertices(
    file: &File,
    what: &dyn Fn(&str) -> String,
    (positions, joints, weights): Vertices<'_>,
    (matrices, skin_joints): (&[DMat4], &[usize]),
    fixes: &mut WeightFixes,
    part: &mut Part,
) -> Result<(), GltfError> {
    for ((p, j), w) in positions.iter().zip(joints).zip(weights) {
        let v = DVec3::new(p[0].into(), p[1].into(), p[2].into());
        let w = fixes.weights(*w);
        let mut q = DVec3::ZERO;
        let mut ours = [0u16; 4];
        for k in 0..4 {
            if w[k] == 0.0 {
                continue;
            }
            let s = j[k] as usize;
            let (Some(m), Some(&o)) = (matrices.get(s), skin_joints.get(s)) else {
                return Err(file.data_error(what(&format!(
                    "names joint {s} of a skin of {}",
                    matrices.len()
                ))));
            };
            q += m.transform_point3(v) * f64::from(w[k]);
            ours[k] = u16::try_from(o).unwrap_or(0);
        }
        part.positions.push([q.x as f32, q.y as f32, q.z as f32]);
        part.joints.push(ours);
        part.weights.push(w);
    }
    Ok(())
}

/// The farthest a vertex may lie from its mesh's origin, in the file's
/// units (a figure in millimetres is a few thousand across).
const MAX_COORDINATE: f32 = 1e6;

/// A primitive's vertex positions, checked: every one finite (`what`
/// names the mesh in errors).
fn positions(
    file: &File,
    prim: &gltf::Primitive<'_>,
    what: &dyn Fn(&str) -> String,
    budget: &mut Budget,
) -> Result<Vec<[f32; 3]>, GltfError> {
    let reader = prim.reader(|b| file.buffer(b));
    let pos = prim
        .get(&gltf::Semantic::Positions)
        .ok_or_else(|| file.data_error(what("has no positions")))?;
    file.check(&pos, &what("positions"), Kind::Points, budget)?;
    let positions: Vec<[f32; 3]> = reader
        .read_positions()
        .ok_or_else(|| file.data_error(what("positions unreadable")))?
        .collect();
    if positions.iter().flatten().any(|x| !x.is_finite()) {
        return Err(file.data_error(what("has positions that are not finite")));
    }
    if let Some(far) = positions
        .iter()
        .flatten()
        .find(|x| x.abs() > MAX_COORDINATE)
    {
        return Err(file.data_error(what(&format!(
            "has a vertex {far:e} units from its origin: past the {MAX_COORDINATE:e} (a kilometre in millimetres) a figure's vertices may lie"
        ))));
    }
    Ok(positions)
}

/// A primitive's vertex indices (its `n` vertices in order where it has
/// none), checked: none past its vertices.
fn indices(
    file: &File,
    prim: &gltf::Primitive<'_>,
    n: usize,
    what: &dyn Fn(&str) -> String,
    budget: &mut Budget,
) -> Result<Vec<u32>, GltfError> {
    let reader = prim.reader(|b| file.buffer(b));
    let indices: Vec<u32> = match prim.indices() {
        Some(a) => {
            file.check(&a, &what("indices"), Kind::Indices, budget)?;
            reader
                .read_indices()
                .ok_or_else(|| file.data_error(what("indices unreadable")))?
                .into_u32()
                .collect()
        }
        None => (0..n as u32).collect(),
    };
    if let Some(bad) = indices.iter().find(|&&i| i as usize >= n) {
        return Err(file.data_error(what(&format!("has index {bad}, past its {n} vertices"))));
    }
    Ok(indices)
}

/// What was fixed in the skin weights: vertices with none, vertices
/// whose weights did not sum to one, and the sum farthest from it.
#[derive(Default)]
struct WeightFixes {
    unweighted: usize,
    renormalised: usize,
    worst_sum: Option<f64>,
}

impl WeightFixes {
    /// A vertex's weights, usable: no negative or not-finite weight, a
    /// vertex with none carried by its first joint, the rest summing to
    /// one.
    fn weights(&mut self, w: [f32; 4]) -> [f32; 4] {
        let w = w.map(|x| if x.is_finite() { x.max(0.0) } else { 0.0 });
        let sum: f32 = w.iter().sum();
        if sum <= 1e-6 {
            self.unweighted += 1;
            return [1.0, 0.0, 0.0, 0.0];
        }
        if (sum - 1.0).abs() > 1e-3 {
            self.renormalised += 1;
            let worst = self.worst_sum.unwrap_or(1.0);
            if (f64::from(sum) - 1.0).abs() > (worst - 1.0).abs() {
                self.worst_sum = Some(f64::from(sum));
            }
            return w.map(|x| x / sum);
        }
        w
    }

    /// What was fixed, in `warnings`.
    fn say(&self, warnings: &mut Vec<String>) {
        if self.renormalised > 0 {
            warnings.push(format!(
                "{} vertices' skin weights did not sum to 1 (up to {:.3}): normalised",
                self.renormalised,
                self.worst_sum.unwrap_or(1.0)
            ));
        }
        if self.unweighted > 0 {
            warnings.push(format!(
                "{} vertices had no skin weight: carried by their first joint",
                self.unweighted
            ));
        }
    }
}

/// A skin's joints: each one's matrix from the bind pose to the rest
/// pose (its node's `world` matrix times its inverse bind matrix, checked),
/// and its skeleton index (`joint_of`).
fn skin_matrices(
    file: &File,
    skin: &gltf::Skin<'_>,
    world: &[DMat4],
    joint_of: &[usize],
    budget: &mut Budget,
) -> Result<(Vec<DMat4>, Vec<usize>), GltfError> {
    let joints: Vec<gltf::Node<'_>> = skin.joints().collect();
    let ibms: Vec<DMat4> = match skin.inverse_bind_matrices() {
        Some(a) => {
            file.check(&a, "inverse bind matrices", Kind::Matrices, budget)?;
            if a.count() < joints.len() {
                return Err(file.data_error(format!(
                    "skin {}: {} inverse bind matrices for {} joints",
                    skin.index(),
                    a.count(),
                    joints.len()
                )));
            }
            skin.reader(|b| file.buffer(b))
                .read_inverse_bind_matrices()
                .ok_or_else(|| file.data_error("unreadable inverse bind matrices".to_owned()))?
                .map(|m| DMat4::from_cols_array_2d(&m.map(|c| c.map(f64::from))))
                .collect()
        }
        None => vec![DMat4::IDENTITY; joints.len()],
    };
    for (k, m) in ibms.iter().enumerate().take(joints.len()) {
        if !m.is_finite() || m.determinant().abs() < 1e-12 {
            return Err(file.data_error(format!(
                "skin {}: the inverse bind matrix of joint {k} is {}",
                skin.index(),
                if m.is_finite() {
                    "singular"
                } else {
                    "not finite"
                }
            )));
        }
    }
    Ok((
        joints
            .iter()
            .zip(&ibms)
            .map(|(j, ibm)| world[j.index()] * *ibm)
            .collect(),
        joints.iter().map(|j| joint_of[j.index()]).collect(),
    ))
}

/// Each vertex's four joints and their weights.
type SkinData = (Vec<[u16; 4]>, Vec<[f32; 4]>);

/// A skinned primitive's joints and weights, one of each for each of its
/// `n` vertices, checked (`what` names the mesh in errors).
fn skin_data(
    file: &File,
    prim: &gltf::Primitive<'_>,
    n: usize,
    what: &dyn Fn(&str) -> String,
    budget: &mut Budget,
) -> Result<SkinData, GltfError> {
    let reader = prim.reader(|b| file.buffer(b));
    for (sem, kind) in [
        (gltf::Semantic::Joints(0), Kind::Joints),
        (gltf::Semantic::Weights(0), Kind::Weights),
    ] {
        let a = prim
            .get(&sem)
            .ok_or_else(|| file.data_error(what("lacks skin data")))?;
        file.check(&a, &what("skin data"), kind, budget)?;
        if a.count() != n {
            return Err(file.data_error(what("has skin data for another vertex count")));
        }
    }
    let j: Vec<[u16; 4]> = reader
        .read_joints(0)
        .ok_or_else(|| file.data_error(what("joints unreadable")))?
        .into_u16()
        .collect();
    let w: Vec<[f32; 4]> = reader
        .read_weights(0)
        .ok_or_else(|| file.data_error(what("weights unreadable")))?
        .into_f32()
        .collect();
    Ok((j, w))
}

/// Each vertex's colour from the primitive's base colour texture (times
/// the factor), where it has one and the texture coordinates it names;
/// empty otherwise, or where the image cannot be read (said once in
/// `warnings`).
fn colours(
    file: &File,
    prim: &gltf::Primitive<'_>,
    n: usize,
    budget: &mut Budget,
    textures: &mut [Option<Option<super::texture::Texture>>],
    warnings: &mut Vec<String>,
) -> Result<Vec<[f32; 4]>, GltfError> {
    let pbr = prim.material().pbr_metallic_roughness();
    let Some(info) = pbr.base_color_texture() else {
        return Ok(Vec::new());
    };
    let set = info.tex_coord();
    let Some(a) = prim.get(&gltf::Semantic::TexCoords(set)) else {
        return Ok(Vec::new());
    };
    file.check(&a, "texture coordinates", Kind::Uvs, budget)?;
    if a.count() != n {
        return Err(file.data_error(format!(
            "texture coordinates (accessor {}) for {} vertices of {n}",
            a.index(),
            a.count()
        )));
    }
    let image = info.texture().source().index();
    let Some(first) = textures.get(image).map(Option::is_none) else {
        return Ok(Vec::new());
    };
    if first {
        // What the textures decoded so far leave of the figure's texels.
        let used: u64 = textures
            .iter()
            .flatten()
            .flatten()
            .map(|t| t.texels())
            .sum();
        let left = super::texture::MAX_FIGURE_TEXELS.saturating_sub(used);
        textures[image] = Some(
            match super::texture::load(file, image, left.min(super::texture::MAX_TEXELS)) {
                Ok(t) => Some(t),
                Err(why) => {
                    warnings.push(format!(
                    "image {image} (a base colour texture) cannot be read: {why}; its material's base colour is used"
                ));
                    None
                }
            },
        );
    }
    let Some(Some(texture)) = &textures[image] else {
        return Ok(Vec::new());
    };
    let uvs: Vec<[f32; 2]> = prim
        .reader(|b| file.buffer(b))
        .read_tex_coords(set)
        .ok_or_else(|| file.data_error("texture coordinates unreadable".to_owned()))?
        .into_f32()
        .collect();
    let factor = pbr.base_color_factor();
    Ok(uvs
        .iter()
        .map(|uv| {
            let uv = uv.map(|x| if x.is_finite() { x } else { 0.0 });
            let t = texture.sample(uv);
            [
                t[0] * factor[0],
                t[1] * factor[1],
                t[2] * factor[2],
                t[3] * factor[3],
            ]
        })
        .collect())
}
