//! Body geometry shared by every stage: where the character stands on the
//! floor ([`Placement`], with the [`Anchor`] of what is put there), the
//! way a posture faces, and the length of its legs under names that say
//! which length.

use glam::{DQuat, DVec3};

use super::roles::{Role, RoleMap};
use super::skeleton::{Pose, Skeleton, WorldPose, forward_kinematics};

/// The facing of a posture: yaw (radians, 0 = +Z, positive turns towards
/// +X) of the direction the hips point, from the left and right hips.
#[must_use]
pub fn facing_yaw(world: &WorldPose, roles: &RoleMap) -> f64 {
    let l = world.positions[roles.get(Role::LeftHip)] - world.positions[roles.get(Role::RightHip)];
    let fwd = l.cross(DVec3::Y);
    if fwd.x.hypot(fwd.z) < 1e-9 {
        return 0.0;
    }
    fwd.x.atan2(fwd.z)
}

/// The turn about the vertical from facing +Z to the way the hips of
/// `world` face ([`facing_yaw`] as a rotation).
#[must_use]
pub fn facing(world: &WorldPose, roles: &RoleMap) -> DQuat {
    DQuat::from_rotation_y(facing_yaw(world, roles))
}

/// An angle in (−π, π].
#[must_use]
pub fn wrap(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let r = a.rem_euclid(t);
    if r > std::f64::consts::PI { r - t } else { r }
}

/// What of a sample is put at the placement.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Anchor {
    /// The start of the sample's clip (the paper: the sample's offset and
    /// turn since its clip began are added to where the character stood
    /// when posing began).
    #[default]
    ClipStart,
    /// The sample's own pelvis: it stands exactly where the placement is,
    /// facing its way (for evaluations and for holding the character in
    /// place).
    Root,
}

/// Where the character stands: its floor position and facing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    pub position: DVec3,
    pub yaw: f64,
    pub anchor: Anchor,
}

impl Placement {
    /// World position of a sample's joint placed here (`p` relative to
    /// the anchor, facing +Z: `control::posing::sample::Sample::local`).
    #[must_use]
    pub fn place(&self, p: DVec3) -> DVec3 {
        DVec3::new(self.position.x, 0.0, self.position.z) + DQuat::from_rotation_y(self.yaw) * p
    }

    /// The placement of a pose: its root's floor point and its facing.
    #[must_use]
    pub fn of(skeleton: &Skeleton, roles: &RoleMap, pose: &Pose) -> Self {
        let w = forward_kinematics(skeleton, pose);
        let r = w.positions[0];
        Self {
            position: DVec3::new(r.x, 0.0, r.z),
            yaw: facing_yaw(&w, roles),
            anchor: Anchor::Root,
        }
    }
}

impl Anchor {
    /// Index into a sample's parts, one set per anchor.
    #[must_use]
    pub fn index(self) -> usize {
        match self {
            Anchor::ClipStart => 0,
            Anchor::Root => 1,
        }
    }
}

/// Thigh plus shin along the rest skeleton's bones, the mean of both
/// legs, in the skeleton's units (how much a library is scaled onto
/// another skeleton).
#[must_use]
pub fn leg_length_mean(skeleton: &Skeleton, roles: &RoleMap) -> f64 {
    let leg = |knee: Role, foot: Role| {
        skeleton.joints[roles.get(knee)].offset.length()
            + skeleton.joints[roles.get(foot)].offset.length()
    };
    0.5 * (leg(Role::LeftKnee, Role::LeftFoot) + leg(Role::RightKnee, Role::RightFoot))
}

/// Hip to ankle along the rest skeleton's bones, the shorter leg, in the
/// skeleton's units (how far a planted foot may be from its hip).
#[must_use]
pub fn leg_length_shorter(sk: &Skeleton, roles: &RoleMap) -> f64 {
    [
        (Role::LeftKnee, Role::LeftFoot),
        (Role::RightKnee, Role::RightFoot),
    ]
    .into_iter()
    .map(|(knee, foot)| {
        sk.joints[roles.get(knee)].offset.length() + sk.joints[roles.get(foot)].offset.length()
    })
    .fold(f64::INFINITY, f64::min)
}

/// Hip to knee to ankle between the joints' places `positions`, the mean
/// of both legs (a posed figure's legs, whatever its bones' offsets).
#[must_use]
pub fn leg_length_posed(positions: &[DVec3], roles: &RoleMap) -> f64 {
    let at = |r: Role| positions[roles.get(r)];
    [
        (Role::LeftHip, Role::LeftKnee, Role::LeftFoot),
        (Role::RightHip, Role::RightKnee, Role::RightFoot),
    ]
    .iter()
    .map(|&(h, k, f)| (at(k) - at(h)).length() + (at(f) - at(k)).length())
    .sum::<f64>()
        / 2.0
}
