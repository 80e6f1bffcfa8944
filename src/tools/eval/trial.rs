//! What every action trial shares: the test clip's true path of the
//! dragged part, where its character stands, and the cameras looking at it
//! (used by [`super::actions`] and [`super::separation`]).

use glam::{DQuat, DVec3};

use crate::character::camera::Camera;
use crate::character::motion::Clip;
use crate::character::roles::Role;
use crate::character::skeleton::forward_kinematics;
use crate::control::posing::sample::{Anchor, Placement};

/// The camera of a trial: `angle_deg` around the character at `at`,
/// 3 m from its chest.
pub(crate) fn camera(angle_deg: f64, at: &Placement, chest_height: f64) -> Camera {
    let dir = DQuat::from_rotation_y(at.yaw + angle_deg.to_radians()) * DVec3::Z;
    let target = at.position + DVec3::Y * chest_height;
    Camera {
        eye: target + dir * 3.0,
        target,
        fov_y_deg: 45.0,
        width: 1280.0,
        height: 720.0,
    }
}

/// What a trial needs of a test clip: where its character stands, the
/// dragged part's true path, and its chest height (for the cameras).
pub(crate) struct Trial {
    pub(crate) at: Placement,
    pub(crate) path: Vec<DVec3>,
    pub(crate) chest: f64,
}

impl Trial {
    pub(crate) fn of(clip: &Clip, role: Role) -> Self {
        let at = Placement {
            anchor: Anchor::ClipStart,
            ..Placement::of(&clip.skeleton, &clip.roles, &clip.frames[0])
        };
        let path = clip
            .frames
            .iter()
            .map(|f| forward_kinematics(&clip.skeleton, f).positions[clip.roles.get(role)])
            .collect();
        let chest = forward_kinematics(&clip.skeleton, &clip.frames[0]).positions
            [clip.roles.get(Role::Chest)]
        .y;
        Self { at, path, chest }
    }
}

/// Which side the trial cameras stand on for a part: -1 for the right
/// side's parts, 1 otherwise.
pub(crate) fn side_of(role: Role) -> f64 {
    match role {
        Role::RightHand | Role::RightFoot | Role::RightElbow | Role::RightKnee => -1.0,
        _ => 1.0,
    }
}
