//! Sample postures: frames of the library's clips, each with what the
//! method needs precomputed: its joint rotations, its root placement
//! relative to the start of its clip, its joint positions when that start is
//! at the origin facing +Z, and its positions aligned by pelvis position and
//! facing for the posture distance (Kovar et al.).

use glam::{DQuat, DVec3};

use super::limbs;
use crate::character::body::{Anchor, Placement, facing_yaw, wrap};
use crate::character::motion::Clip;
use crate::character::roles::Role;
use crate::character::skeleton::{Pose, Skeleton, forward_kinematics};

/// A sample posture.
#[derive(Clone, Debug, PartialEq)]
pub struct Sample {
    /// Which clip (index into the model's clip list) and frame.
    pub clip: usize,
    pub frame: usize,
    /// Generalized time of the frame in its clip, 0..1.
    pub time: f64,
    /// Local rotations of every joint; the root's has its facing removed.
    pub rotations: Vec<DQuat>,
    /// Root offset from the clip's start: x and z in the start's facing
    /// frame, y the root's height.
    pub root_offset: DVec3,
    /// Facing relative to the clip's start (radians).
    pub yaw: f64,
    /// Joint positions with the clip's start at the origin facing +Z.
    pub placed: Vec<DVec3>,
    /// Joint positions relative to the pelvis's floor point, facing +Z.
    pub aligned: Vec<DVec3>,
    /// The positions of the role joints (in [`Role::ALL`] order) for each
    /// anchor ([`Anchor::ClipStart`], [`Anchor::Root`]), kept inline so
    /// that the search reads one sample's parts from one place.
    pub parts: [[DVec3; Role::ALL.len()]; 2],
    /// Each limb's reach (`limbs::reach`, in `limbs::LIMBS` order).
    pub reach: [DVec3; 5],
}

/// Samples from frames `frames` of a clip.
#[must_use]
pub fn samples_of(
    clip_index: usize,
    clip: &Clip,
    frames: impl Iterator<Item = usize>,
) -> Vec<Sample> {
    let sk = &clip.skeleton;
    let roles = &clip.roles;
    let w0 = forward_kinematics(sk, &clip.frames[0]);
    let yaw0 = facing_yaw(&w0, roles);
    let root0 = w0.positions[0];
    let last = clip.frames.len().saturating_sub(1).max(1) as f64;
    let chains = limbs::LIMBS.map(|r| limbs::chain(sk, roles, r));
    frames
        .filter(|&k| k < clip.frames.len())
        .map(|k| {
            let pose = &clip.frames[k];
            let w = forward_kinematics(sk, pose);
            let yaw = facing_yaw(&w, roles);
            let unyaw = DQuat::from_rotation_y(-yaw);
            let root = w.positions[0];
            let floor = DVec3::new(root.x, 0.0, root.z);
            let d = DQuat::from_rotation_y(-yaw0) * (root - root0);
            let mut rotations = pose.rotations.clone();
            rotations[0] = (unyaw * w.rotations[0]).normalize();
            let rel = DQuat::from_rotation_y(-yaw0);
            let start = DVec3::new(root0.x, 0.0, root0.z);
            let placed: Vec<DVec3> = w.positions.iter().map(|p| rel * (*p - start)).collect();
            let aligned: Vec<DVec3> = w.positions.iter().map(|p| unyaw * (*p - floor)).collect();
            let parts = [&placed, &aligned].map(|ps| Role::ALL.map(|r| ps[roles.get(r)]));
            let reach = chains.each_ref().map(|c| {
                c.as_ref()
                    .map_or(DVec3::ZERO, |c| limbs::reach(sk, c, &pose.rotations))
            });
            Sample {
                clip: clip_index,
                frame: k,
                time: k as f64 / last,
                rotations,
                root_offset: DVec3::new(d.x, root.y, d.z),
                yaw: wrap(yaw - yaw0),
                placed,
                aligned,
                parts,
                reach,
            }
        })
        .collect()
}

/// The posture distance: mean distance between corresponding joints after
/// aligning pelvis position and facing.
#[must_use]
pub fn distance(a: &Sample, b: &Sample) -> f64 {
    a.aligned
        .iter()
        .zip(&b.aligned)
        .map(|(p, q)| (*p - *q).length())
        .sum::<f64>()
        / a.aligned.len().max(1) as f64
}

impl Sample {
    /// A role joint's position relative to the anchor, facing +Z.
    #[must_use]
    pub fn part(&self, anchor: Anchor, role: Role) -> DVec3 {
        self.parts[anchor.index()][role.index()]
    }

    /// Joint positions relative to the anchor, facing +Z.
    #[must_use]
    pub fn local(&self, anchor: Anchor) -> &[DVec3] {
        match anchor {
            Anchor::ClipStart => &self.placed,
            Anchor::Root => &self.aligned,
        }
    }
}

/// The pose of a sample placed at `at`: root translation and rotation from
/// the placement, other joints' rotations and translations from the sample
/// (translations from the skeleton's rest offsets).
#[must_use]
pub fn pose_of(skeleton: &Skeleton, sample: &Sample, at: &Placement) -> Pose {
    let mut pose = skeleton.rest_pose();
    pose.rotations.clone_from(&sample.rotations);
    let (off, yaw) = match at.anchor {
        Anchor::ClipStart => (
            DVec3::new(sample.root_offset.x, 0.0, sample.root_offset.z),
            sample.yaw,
        ),
        Anchor::Root => (DVec3::ZERO, 0.0),
    };
    pose.translations[0] = at.place(off) + DVec3::Y * sample.root_offset.y;
    pose.rotations[0] = (DQuat::from_rotation_y(at.yaw + yaw) * sample.rotations[0]).normalize();
    pose
}
