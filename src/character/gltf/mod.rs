//! An exhibit's own character: a skinned glTF 2.0 figure (`.glb`, or
//! `.gltf` with its buffers embedded or beside it), read whole or not at
//! all. Its skeleton is turned into marionette's conventions (Y up,
//! facing +Z, metres, feet on the floor) from the skeleton itself,
//! whatever root transforms the file carries, and its joints are given
//! the library's roles by their names, else by where they stand.

mod drive;
mod frame;
mod geometry;
pub mod humanoid;
mod limbs;
mod names;
mod parts;
mod places;
mod read;
mod rig;
mod texture;
mod upright;
mod vrm;

pub use drive::{Drive, Hold};
pub use geometry::Geometry;

/// A figure with how it follows one library.
#[derive(Clone, Debug)]
pub struct Skin {
    pub figure: Figure,
    pub drive: Drive,
    /// Its triangles as a renderer skins them (made once).
    pub geometry: std::sync::Arc<Geometry>,
}

impl Skin {
    #[must_use]
    pub fn new(figure: Figure, lib: &super::library::Library, lib_roles: &RoleMap) -> Self {
        let drive = Drive::new(&figure, lib, lib_roles);
        let geometry = std::sync::Arc::new(Geometry::new(&figure));
        Self {
            figure,
            drive,
            geometry,
        }
    }

    /// The figure made as large as the library's character (its legs as
    /// long), then driven by it: on the table fingers grab and move the
    /// library's parts, which the figure's then cover.
    #[must_use]
    pub fn life_size(figure: Figure, lib: &super::library::Library, lib_roles: &RoleMap) -> Self {
        let s = Drive::leg_ratio(&figure, &lib.skeleton, lib_roles);
        let figure = if s.is_finite() && s > 0.0 {
            figure.scaled(1.0 / s)
        } else {
            figure
        };
        Self::new(figure, lib, lib_roles)
    }

    /// The figure's vertices, part by part, posed as the library's
    /// `world` (the own body's joints are the library's, as posed).
    #[must_use]
    pub fn posed(&self, world: &super::skeleton::WorldPose) -> Vec<Vec<glam::DVec3>> {
        self.drive.skin(&self.figure, &self.joints(world))
    }

    /// The figure's joint transforms (world, metres) posed as the
    /// library's `world`, alone.
    #[must_use]
    pub fn joints(&self, world: &super::skeleton::WorldPose) -> Vec<DMat4> {
        self.joints_held(world, &mut Hold::default())
    }

    /// The figure's joint transforms posed as the library's `world`, one
    /// of a sequence of postures: its feet stay where they came down
    /// (`hold`, carried from each posture to the next; see
    /// [`Drive::pose_held`]).
    #[must_use]
    pub fn joints_held(&self, world: &super::skeleton::WorldPose, hold: &mut Hold) -> Vec<DMat4> {
        let fig = &self.figure;
        if fig.own {
            (0..fig.skeleton.len().min(world.positions.len()))
                .map(|j| DMat4::from_rotation_translation(world.rotations[j], world.positions[j]))
                .collect()
        } else {
            self.drive.pose_held(fig, world, hold)
        }
    }
}

use std::path::{Path, PathBuf};

use glam::DMat4;
use thiserror::Error;

use super::roles::RoleMap;
use super::skeleton::Skeleton;

/// The largest glTF file read (bytes): a kiosk character is a few MB.
pub const MAX_FILE_BYTES: u64 = 256 << 20;

/// The most the vertex and index data of a figure may need (bytes, as
/// read and kept: u8 indices count as the u32 they become, an accessor
/// shared by several primitives once for each), checked from the
/// accessors' counts before anything is read.
pub const MAX_DATA_BYTES: u64 = 1 << 30;

/// The most vertices a figure may have: four figures' vertices as the
/// renderer keeps them (88 bytes each) stay within the 256 MiB a GPU
/// buffer may hold.
pub const MAX_VERTICES: u64 = 400_000;

/// The most triangles a figure may have.
pub const MAX_TRIANGLES: u64 = 1_000_000;

/// What is wrong with a glTF file; nothing of it is kept.
#[derive(Debug, Error)]
pub enum GltfError {
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {bytes} bytes, over the {max} bytes a character file may have")]
    TooBig { path: PathBuf, bytes: u64, max: u64 },
    #[error("{path}: not a glTF 2.0 file ({why})")]
    NotGltf { path: PathBuf, why: String },
    #[error("{path}: {why}")]
    Buffer { path: PathBuf, why: String },
    #[error("{path}: {why}")]
    Data { path: PathBuf, why: String },
    #[error("{path}: no skin: a character needs a skeleton (a glTF skin with its joints)")]
    NoSkin { path: PathBuf },
    #[error(
        "{path}: its skeleton has {joints} joint(s): a character needs at least a pelvis, a head, two arms and two legs (a bone each)"
    )]
    TooFewJoints { path: PathBuf, joints: usize },
    #[error(
        "{path}: not a humanoid skeleton: no joint found for {missing} (neither by name, by the hierarchy nor by where it stands); found: {found}. Name the joints under [character.mesh_roles] (e.g. pelvis = \"Hips\"); `RUST_LOG=debug marionette inspect` shows where each joint stands"
    )]
    NotHumanoid {
        path: PathBuf,
        missing: String,
        found: String,
    },
}

/// One drawable part: a primitive's triangles, skinned (joint indices into
/// [`Figure::skeleton`] and weights per vertex) or carried rigidly by one
/// joint.
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    /// Positions in the figure's rest pose (normalised frame, metres).
    pub positions: Vec<[f32; 3]>,
    pub joints: Vec<[u16; 4]>,
    pub weights: Vec<[f32; 4]>,
    pub indices: Vec<u32>,
    /// The material's base colour factor (linear RGBA).
    pub base_colour: [f32; 4],
    /// Each vertex's colour (linear RGBA): the base colour texture at its
    /// texture coordinates times the factor; empty: the factor alone.
    pub colours: Vec<[f32; 4]>,
    /// The body part it shows, where it is one (the project's own body):
    /// it glows whole while a finger holds that part.
    pub role: Option<super::roles::Role>,
}

impl Part {
    /// Its vertices' positions, in double precision.
    pub(crate) fn points(&self) -> impl Iterator<Item = glam::DVec3> + '_ {
        self.positions
            .iter()
            .map(|v| glam::DVec3::new(v[0].into(), v[1].into(), v[2].into()))
    }
}

/// Every vertex of `parts` (rest pose) with the joint that carries it
/// most.
pub(crate) fn carried(parts: &[Part]) -> impl Iterator<Item = (usize, glam::DVec3)> + '_ {
    carried_blended(parts).map(|p| (p.joint, p.at))
}

/// A mesh point as it is skinned: where it is at rest, the joint that
/// carries it most, and its joints and weights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Point {
    pub joint: usize,
    pub at: glam::DVec3,
    pub joints: [u16; 4],
    pub weights: [f32; 4],
}

impl Point {
    /// Where it is for skinning matrices `skin` (rest to posed).
    #[must_use]
    pub fn now(&self, skin: &[DMat4]) -> glam::DVec3 {
        let mut sum = glam::DVec3::ZERO;
        for (j, w) in self.joints.iter().zip(self.weights) {
            if w > 0.0 {
                let at = skin
                    .get(usize::from(*j))
                    .map_or(self.at, |m| m.transform_point3(self.at));
                sum += at * f64::from(w);
            }
        }
        sum
    }
}

/// Every vertex of `parts` as a [`Point`].
pub(crate) fn carried_blended(parts: &[Part]) -> impl Iterator<Item = Point> + '_ {
    parts
        .iter()
        .flat_map(|p| p.positions.iter().zip(p.joints.iter().zip(&p.weights)))
        .map(|(v, (j, w))| {
            let k = (0..4).max_by(|&a, &b| w[a].total_cmp(&w[b])).unwrap_or(0);
            Point {
                joint: usize::from(j[k]),
                at: glam::DVec3::new(v[0].into(), v[1].into(), v[2].into()),
                joints: *j,
                weights: *w,
            }
        })
}

/// A skinned figure ready to be driven.
#[derive(Clone, Debug)]
pub struct Figure {
    /// The file's joints as a skeleton (rest offsets in metres, Y up,
    /// facing +Z, the feet's lowest vertex on the floor).
    pub skeleton: Skeleton,
    /// Each joint's rest transform (normalised frame): skinning matrices
    /// are `world(pose) * rest.inverse()`.
    pub rest: Vec<DMat4>,
    /// The roles found, each with its evidence, and in a word where most
    /// came from.
    pub roles: RoleMap,
    pub evidence: std::collections::BTreeMap<super::roles::Role, humanoid::Evidence>,
    pub roles_by: &'static str,
    pub parts: Vec<Part>,
    pub skins: usize,
    /// Floor to the top of the rest-pose mesh (m).
    pub height_m: f64,
    /// Metres per file unit, as detected from the mesh's height.
    pub scale_to_m: f64,
    /// The way the figure faced in the file (`+Z`, `-Y`, ...) and which
    /// way was up.
    pub facing: String,
    pub up: String,
    /// Things that were fixed while reading (weights that did not sum to
    /// one, ...).
    pub warnings: Vec<String>,
    /// The project's own body (`render::body`): its parts are the capsule
    /// figure's clothes, tinted as those are.
    pub own: bool,
    /// Joints made up where the rig has none (a hand at the end of a
    /// forearm, the middle and end of a one-bone limb): no vertex hangs
    /// on them; they go where the joint above them takes them.
    pub made_up: Vec<bool>,
    /// A VRM's title, authors and licence.
    pub credit: Option<humanoid::Credit>,
}

impl Figure {
    /// Vertices over every part.
    #[must_use]
    pub fn vertices(&self) -> usize {
        self.parts.iter().map(|p| p.positions.len()).sum()
    }

    /// Triangles over every part.
    #[must_use]
    pub fn triangles(&self) -> usize {
        self.parts.iter().map(|p| p.indices.len() / 3).sum()
    }

    /// The figure made `s` times as large (about the floor under its
    /// origin).
    #[must_use]
    pub fn scaled(mut self, s: f64) -> Self {
        for j in &mut self.skeleton.joints {
            j.offset *= s;
        }
        for m in &mut self.rest {
            m.w_axis.x *= s;
            m.w_axis.y *= s;
            m.w_axis.z *= s;
        }
        for p in &mut self.parts {
            for v in &mut p.positions {
                *v = v.map(|x| (f64::from(x) * s) as f32);
            }
        }
        self.height_m *= s;
        self.scale_to_m *= s;
        self
    }

    /// Joints no role names (fingers, tails, accessories, IK helpers).
    #[must_use]
    pub fn unmapped(&self) -> Vec<String> {
        let mapped: Vec<usize> = super::roles::Role::ALL
            .iter()
            .map(|r| self.roles.get(*r))
            .collect();
        (0..self.skeleton.len())
            .filter(|j| !mapped.contains(j))
            .map(|j| self.skeleton.joints[j].name.clone())
            .collect()
    }
}

/// Read a figure from `path`; `overrides` name joints for roles (role →
/// joint name), as a library's `[roles]` table does.
pub fn load(
    path: &Path,
    overrides: &std::collections::BTreeMap<String, String>,
) -> Result<Figure, GltfError> {
    let file = read::File::open(path)?;
    rig::figure(&file, overrides)
}

/// [`load`] of a file's bytes already read (`path` names it in errors,
/// and its folder holds any buffer files it names).
pub fn load_bytes(
    path: &Path,
    bytes: &[u8],
    overrides: &std::collections::BTreeMap<String, String>,
) -> Result<Figure, GltfError> {
    if bytes.len() as u64 > MAX_FILE_BYTES {
        return Err(GltfError::TooBig {
            path: path.to_owned(),
            bytes: bytes.len() as u64,
            max: MAX_FILE_BYTES,
        });
    }
    let file = read::File::parse(path, bytes)?;
    rig::figure(&file, overrides)
}
