//! Picking: which body part lies under a screen point, for the current pose
//! and camera, so that a finger can grab it.

use crate::character::camera::Camera;
use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::{Skeleton, WorldPose};
use crate::screen::ScreenPoint;

/// The body parts a finger can grab, and the bone that leads to each (so
/// that a touch on the forearm grabs the hand).
const GRABBABLE: [(Role, Option<Role>); 11] = [
    (Role::Head, Some(Role::Neck)),
    (Role::LeftHand, Some(Role::LeftElbow)),
    (Role::RightHand, Some(Role::RightElbow)),
    (Role::LeftFoot, Some(Role::LeftKnee)),
    (Role::RightFoot, Some(Role::RightKnee)),
    (Role::LeftElbow, None),
    (Role::RightElbow, None),
    (Role::LeftKnee, None),
    (Role::RightKnee, None),
    (Role::Chest, Some(Role::Pelvis)),
    (Role::Pelvis, None),
];

fn segment_distance(p: ScreenPoint, a: ScreenPoint, b: ScreenPoint) -> f64 {
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    let len2 = dx * dx + dy * dy;
    let t = if len2 < 1e-12 {
        0.0
    } else {
        (((p.x - a.x) * dx + (p.y - a.y) * dy) / len2).clamp(0.0, 1.0)
    };
    p.distance(ScreenPoint::new(a.x + dx * t, a.y + dy * t))
}

/// The body part under `at`, within `radius_px` of its joint or of the
/// outer half of the bone leading to it; the nearest wins.
#[must_use]
pub fn pick(
    camera: &Camera,
    _skeleton: &Skeleton,
    roles: &RoleMap,
    world: &WorldPose,
    at: ScreenPoint,
    radius_px: f64,
) -> Option<Role> {
    let mut best: Option<(Role, f64)> = None;
    for (role, from) in GRABBABLE {
        let Some(p) = camera.project(world.positions[roles.get(role)]) else {
            continue;
        };
        let mut d = p.distance(at);
        if let Some(from) = from {
            if let Some(q) = camera.project(world.positions[roles.get(from)]) {
                let mid = ScreenPoint::new((p.x + q.x) / 2.0, (p.y + q.y) / 2.0);
                d = d.min(segment_distance(at, p, mid));
            }
        }
        if d <= radius_px && best.is_none_or(|(_, b)| d < b) {
            best = Some((role, d));
        }
    }
    best.map(|(r, _)| r)
}
