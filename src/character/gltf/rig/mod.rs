//! From a glTF document to a [`Figure`]: the skins' joints as a skeleton
//! in the nodes' rest pose, turned upright and facing +Z from the
//! skeleton itself, scaled to metres, the mesh skinned into that pose, and
//! the roles found by name or, failing that, by where the joints stand.

use std::collections::BTreeMap;

use glam::{DMat4, DQuat, DVec3};

use super::read::File;
mod bind;
mod stance;

use self::bind::bind_or_node_pose;
use self::stance::{body_turn, extent_along_y};
use super::{Figure, GltfError, Part, humanoid, places};
use crate::character::motion::detect_scale;
use crate::character::roles::{self, Role};
use crate::character::skeleton::{Joint, Skeleton};

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
            "node {bad} ({}): its transform is not finite",
            crate::reading::quote(
                file.doc
                    .nodes()
                    .nth(bad)
                    .and_then(|n| n.name())
                    .unwrap_or("")
            )
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

/// The skins' joints, each once, parents first: node indices, and each
/// joint node's joint parent (the nearest joint above it).
struct Joints {
    order: Vec<usize>,
    is_joint: Vec<bool>,
    parent_node: Vec<Option<usize>>,
    /// Per node: its skeleton index (the made-up root counted), or
    /// `usize::MAX` for a node that is no joint.
    joint_of: Vec<usize>,
    index_of: Vec<usize>,
    extra_root: usize,
}

impl Joints {
    /// The skins' joints in order; refused past [`MAX_JOINTS`].
    fn new(file: &File) -> Result<Self, GltfError> {
        let this = Self::ordered(file);
        if this.order.len() > MAX_JOINTS {
            return Err(file.data_error(format!(
                "its skins have {} joints, over the {MAX_JOINTS} marionette reads (a humanoid rig has tens to a few hundred)",
                this.order.len()
            )));
        }
        Ok(this)
    }

    fn ordered(file: &File) -> Self {
        let n = file.doc.nodes().len();
        let mut is_joint = vec![false; n];
        for skin in file.doc.skins() {
            for j in skin.joints() {
                is_joint[j.index()] = true;
            }
        }
        let mut parent_node = vec![None; n];
        for node in file.doc.nodes() {
            for c in node.children() {
                parent_node[c.index()] = Some(node.index());
            }
        }
        let mut this = Self {
            order: Vec::new(),
            is_joint,
            parent_node,
            joint_of: Vec::new(),
            index_of: vec![usize::MAX; n],
            extra_root: 0,
        };
        // Each node's joint parent, once, from the top down (a long chain
        // of nodes is walked once, not once for each node in it); then
        // children lists, so that ordering them is linear in the joints.
        let jp = this.joint_parents();
        let mut kids: Vec<Vec<usize>> = vec![Vec::new(); n];
        for c in (0..n).rev() {
            if let (true, Some(p)) = (this.is_joint[c], jp[c]) {
                kids[p].push(c);
            }
        }
        let mut placed = vec![false; n];
        let mut todo: Vec<usize> = (0..n)
            .filter(|&i| this.is_joint[i] && jp[i].is_none())
            .collect();
        while let Some(j) = todo.pop() {
            if placed[j] {
                continue;
            }
            placed[j] = true;
            this.order.push(j);
            todo.extend(kids[j].iter().copied().filter(|&c| !placed[c]));
        }
        for (k, &j) in this.order.iter().enumerate() {
            this.index_of[j] = k;
        }
        let roots = this.order.iter().filter(|&&j| jp[j].is_none()).count();
        // Several top joints hang under one made-up root at the first's place.
        this.extra_root = usize::from(roots > 1);
        this.joint_of = this
            .index_of
            .iter()
            .map(|&k| k.wrapping_add(this.extra_root))
            .collect();
        this
    }

    /// Every node's nearest joint above it, each node visited once (from
    /// the nodes at the top down; a node in a cycle, which the glTF reader
    /// refuses, has none).
    fn joint_parents(&self) -> Vec<Option<usize>> {
        let n = self.parent_node.len();
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
        for (c, p) in self.parent_node.iter().enumerate() {
            if let Some(p) = *p {
                children[p].push(c);
            }
        }
        let mut jp = vec![None; n];
        let mut todo: Vec<usize> = (0..n).filter(|&i| self.parent_node[i].is_none()).collect();
        while let Some(p) = todo.pop() {
            for &c in &children[p] {
                jp[c] = if self.is_joint[p] { Some(p) } else { jp[p] };
                todo.push(c);
            }
        }
        jp
    }

    /// The nearest joint above node `n`.
    fn joint_parent(&self, mut n: usize) -> Option<usize> {
        let mut guard = 0;
        while let Some(p) = self.parent_node[n] {
            if self.is_joint[p] {
                return Some(p);
            }
            n = p;
            guard += 1;
            if guard > self.parent_node.len() {
                break;
            }
        }
        None
    }

    /// The joint that carries node `n`: itself, or the nearest above.
    fn carrier(&self, n: usize) -> Option<usize> {
        if self.is_joint[n] {
            Some(n)
        } else {
            self.joint_parent(n)
        }
    }
}

pub(super) fn figure(
    file: &File,
    overrides: &BTreeMap<String, String>,
) -> Result<Figure, GltfError> {
    let path = file.path.clone();
    if file.doc.skins().len() == 0 {
        return Err(GltfError::NoSkin { path });
    }
    let joints = Joints::new(file)?;
    let mut notes = Vec::new();
    let world = bind_or_node_pose(file, &joints, &mut notes)?;
    if joints.order.len() < MIN_JOINTS {
        return Err(GltfError::TooFewJoints {
            path,
            joints: joints.order.len(),
        });
    }
    let order = &joints.order;
    let raw: Vec<DVec3> = order.iter().map(|&n| world[n].w_axis.truncate()).collect();
    let (parts_raw, warnings) =
        super::parts::parts(file, &world, &joints.joint_of, &|n| joints.carrier(n))?;
    let (names, parents, places) = joint_table(file, &joints, &raw);
    let mut found = given_roles(file, &names, &joints, overrides)?;
    {
        let rig = humanoid::Rig::new(&names, &parents, &places);
        humanoid::limbs_by_names(&rig, &mut found);
        humanoid::trunk(&rig, &mut found);
    }
    let verts: Vec<DVec3> = parts_raw.iter().flat_map(Part::points).collect();
    let (turn, up_name, facing_name) = body_turn(
        &mut found,
        (&names, &parents, &places),
        &parts_raw,
        (&raw, &verts),
        &mut notes,
    );
    let root_at = order.first().map(|&n| world[n].w_axis.truncate());
    let (normal, height_units, scale) = standing(file, turn, root_at, &verts, &raw)?;

    let extra_root = joints.extra_root;
    let (mut skeleton, mut rest) = rest_skeleton(&names, &parents, &places, &normal, |k| {
        (k >= extra_root).then(|| world[order[k - extra_root]])
    });
    let parts = placed(parts_raw, &normal);
    let height_m = height_units * scale;
    let mut made_up = vec![false; skeleton.len()];
    let roles = places::settle(
        file,
        places::Body {
            skeleton: &mut skeleton,
            rest: &mut rest,
            made_up: &mut made_up,
        },
        &parts,
        height_m,
        found,
        &mut notes,
    )?;
    let roles_by = summary(&roles.1);
    let mut warnings = warnings;
    warnings.extend(notes);
    Ok(Figure {
        skeleton,
        rest,
        roles: roles.0,
        evidence: roles.1,
        roles_by,
        parts,
        skins: file.doc.skins().len(),
        height_m,
        scale_to_m: scale,
        facing: facing_name,
        up: up_name,
        warnings,
        own: false,
        made_up,
        credit: file.extensions.as_ref().and_then(humanoid::vrm_credit),
    })
}

/// The transform that stands the figure (turned by `turn`) in metres on
/// the floor, its root joint (at `root_at`) over the origin; with its
/// height in the file's units and the scale to metres.
fn standing(
    file: &File,
    turn: DQuat,
    root_at: Option<DVec3>,
    verts: &[DVec3],
    raw: &[DVec3],
) -> Result<(DMat4, f64, f64), GltfError> {
    let height_units = extent_along_y(verts, raw, turn);
    if !(height_units.is_finite() && height_units > 0.0) {
        return Err(file.data_error("the figure has no height".to_owned()));
    }
    let lowest = verts
        .iter()
        .chain(raw)
        .map(|p| (turn * *p).y)
        .fold(f64::INFINITY, f64::min);
    let scale = detect_scale(height_units);
    let centre = {
        let c = root_at.map_or(DVec3::ZERO, |p| turn * p);
        DVec3::new(c.x, lowest, c.z)
    };
    let normal = DMat4::from_scale(DVec3::splat(scale))
        * DMat4::from_translation(-centre)
        * DMat4::from_quat(turn);
    Ok((normal, height_units, scale))
}

/// The parts with their points moved through `normal`.
fn placed(parts: Vec<Part>, normal: &DMat4) -> Vec<Part> {
    parts
        .into_iter()
        .map(|mut p| {
            for v in &mut p.positions {
                let q = normal.transform_point3(DVec3::new(v[0].into(), v[1].into(), v[2].into()));
                *v = [q.x as f32, q.y as f32, q.z as f32];
            }
            p
        })
        .collect()
}

/// The joints as the roles see them: names, parents, places (the made-up
/// root first where there is one); `raw` holds the joints' places in
/// `joints.order`.
fn joint_table(
    file: &File,
    joints: &Joints,
    raw: &[DVec3],
) -> (Vec<String>, Vec<Option<usize>>, Vec<DVec3>) {
    let (order, extra_root) = (&joints.order, joints.extra_root);
    let nodes: Vec<gltf::Node<'_>> = file.doc.nodes().collect();
    let mut names = Vec::with_capacity(order.len() + extra_root);
    let mut parents = Vec::with_capacity(order.len() + extra_root);
    let mut places = Vec::with_capacity(order.len() + extra_root);
    if extra_root == 1 {
        names.push("(root)".to_owned());
        parents.push(None);
        places.push(raw[0]);
    }
    for (k, &n) in order.iter().enumerate() {
        names.push(
            nodes[n]
                .name()
                .map_or_else(|| format!("joint {n}"), str::to_owned),
        );
        parents.push(
            joints
                .joint_parent(n)
                .map(|q| joints.index_of[q] + extra_root)
                .or((extra_root == 1).then_some(0)),
        );
        places.push(raw[k]);
    }
    (names, parents, places)
}

/// The skeleton at rest through `normal`: offsets in the world axes,
/// identity rotations; each joint's rest transform its node's (`node(k)`,
/// made rigid) or, for a made-up joint, its place.
fn rest_skeleton(
    names: &[String],
    parents: &[Option<usize>],
    places: &[DVec3],
    normal: &DMat4,
    node: impl Fn(usize) -> Option<DMat4>,
) -> (Skeleton, Vec<DMat4>) {
    let mut skel_joints = Vec::with_capacity(names.len());
    let mut rest: Vec<DMat4> = Vec::with_capacity(names.len());
    for (k, name) in names.iter().enumerate() {
        let p = normal.transform_point3(places[k]);
        let offset = match parents[k] {
            Some(q) => p - rest[q].w_axis.truncate(),
            None => p,
        };
        skel_joints.push(Joint {
            name: name.clone(),
            parent: parents[k],
            offset,
            end_site: None,
        });
        rest.push(match node(k) {
            Some(m) => rigid(*normal * m),
            None => DMat4::from_translation(p),
        });
    }
    (
        Skeleton {
            joints: skel_joints,
        },
        rest,
    )
}

/// The fewest joints a character can have: a pelvis, a head, and two
/// arms and two legs of a bone each.
pub const MIN_JOINTS: usize = 6;

/// The most joints a figure's skins may have together (as BVH's
/// [`crate::character::bvh::MAX_JOINTS`]).
pub const MAX_JOINTS: usize = crate::character::bvh::MAX_JOINTS;

/// The roles the file (VRM's humanoid map) and the configuration name,
/// with their evidence; a configured role or joint that does not exist
/// is refused.
fn given_roles(
    file: &File,
    names: &[String],
    joints: &Joints,
    overrides: &BTreeMap<String, String>,
) -> Result<humanoid::Found, GltfError> {
    let mut found = humanoid::Found::new();
    for (role, joint) in overrides {
        let bad = |e: roles::RolesError| GltfError::Data {
            path: file.path.clone(),
            why: format!(
                "mesh_roles: {}",
                e.to_string().trim_start_matches("[roles] ")
            ),
        };
        let r = Role::from_name(role)
            .ok_or_else(|| bad(roles::RolesError::UnknownRole(role.clone())))?;
        let j = names.iter().position(|n| n == joint).ok_or_else(|| {
            bad(roles::RolesError::UnknownJoint {
                role: r,
                joint: joint.clone(),
            })
        })?;
        let given: BTreeMap<Role, usize> = found.iter().map(|(r, (j, _))| (*r, *j)).collect();
        roles::shared(&given, r, j, joint).map_err(bad)?;
        found.insert(r, (j, humanoid::Evidence::Configuration));
    }
    if let Some(ext) = &file.extensions {
        let bones = humanoid::vrm_bones(ext);
        let joint = |bone: &str| {
            bones
                .get(bone)
                .and_then(|&n| joints.joint_of.get(n).copied())
                .filter(|&j| j < names.len())
        };
        for (bone, role) in humanoid::VRM_BONES {
            // The chest is where the arms branch: the upper chest, else
            // the chest.
            let j = match bone {
                "upperChest" => joint(bone).or_else(|| joint("chest")),
                _ => joint(bone),
            };
            if let Some(j) = j {
                found.entry(role).or_insert((j, humanoid::Evidence::File));
            }
        }
    }
    Ok(found)
}

/// One word for where the roles came from, as before per-role evidence
/// (`names` where every role came from names or the hierarchy).
fn summary(evidence: &BTreeMap<Role, humanoid::Evidence>) -> &'static str {
    use humanoid::Evidence as E;
    let any = |e: E| evidence.values().any(|&x| x == e);
    if any(E::File) {
        "file"
    } else if any(E::Place) {
        "places"
    } else if any(E::MadeUp) {
        "names, made up ends"
    } else {
        "names"
    }
}
