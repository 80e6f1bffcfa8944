//! From a glTF document to a [`Figure`]: the skins' joints as a skeleton
//! in the nodes' rest pose, turned upright and facing +Z from the
//! skeleton itself, scaled to metres, the mesh skinned into that pose, and
//! the roles found by name or, failing that, by where the joints stand.

use std::collections::BTreeMap;

use glam::{DMat4, DQuat, DVec3};

use super::read::{Budget, File, Kind};
use super::{Figure, GltfError, Part, frame, humanoid, places};
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

/// Each node's world transform in the skin's bind pose (said in `notes`
/// where the nodes hold another), else as the nodes stand.
fn bind_or_node_pose(
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

/// The turn that stands the figure up facing +Z, and what said which way
/// is up and which way it faces: its body's frame (its sides swapped where
/// its names put them the other way round), else its joints' spread.
fn body_turn(
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

/// How far the figure reaches along the file's axis turned up by `turn`.
fn extent_along_y(verts: &[DVec3], raw: &[DVec3], turn: DQuat) -> f64 {
    let (lo, hi) = verts
        .iter()
        .chain(raw)
        .map(|p| (turn * *p).y)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), y| {
            (l.min(y), h.max(y))
        });
    hi - lo
}

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
