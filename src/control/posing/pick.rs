//! Picking: which body part lies under a screen point, for the current pose
//! and camera, so that a finger can grab it.

use glam::{DMat4, DVec3};

use crate::character::camera::Camera;
use crate::character::gltf::Skin;
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

/// How near a touch must fall to a skinned figure's vertex on the screen
/// to be on its surface (px), at most the pick radius.
const SURFACE_PX: f64 = 10.0;

/// The part under `at` on a glTF figure's skinned surface: of the
/// figure's vertices within a few pixels of the touch, the one nearest
/// the camera, and the grabbable part nearest it in space (its joint, or
/// the outer half of the bone leading to it). The figure is posed by
/// `joints` (see `Skin::joints`). The own body's surface is the
/// capsules' [`pick`] already follows, so it is left to that.
#[must_use]
pub fn pick_on_surface(
    camera: &Camera,
    roles: &RoleMap,
    world: &WorldPose,
    (skin, joints): (&Skin, &[DMat4]),
    at: ScreenPoint,
    radius_px: f64,
) -> Option<Role> {
    if skin.figure.own {
        return None;
    }
    let near = SURFACE_PX.min(radius_px);
    let front = skin
        .drive
        .skin(&skin.figure, joints)
        .into_iter()
        .flatten()
        .filter(|p| p.is_finite())
        .filter(|p| camera.project(*p).is_some_and(|s| s.distance(at) <= near))
        .min_by(|a, b| {
            a.distance_squared(camera.eye)
                .total_cmp(&b.distance_squared(camera.eye))
        })?;
    let to_bone = |p: DVec3, a: DVec3, b: DVec3| {
        let ab = b - a;
        let t = if ab.length_squared() > 1e-12 {
            ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        p.distance(a + ab * t)
    };
    GRABBABLE
        .iter()
        .map(|&(role, from)| {
            let p = world.positions[roles.get(role)];
            let d = match from {
                Some(f) => to_bone(front, p, (p + world.positions[roles.get(f)]) / 2.0),
                None => front.distance(p),
            };
            (role, d)
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(r, _)| r)
}

/// The part a finger at `at` grabs: [`pick`], else on `figure`'s skinned
/// surface ([`pick_on_surface`]).
#[must_use]
pub fn pick_with(
    camera: &Camera,
    skeleton: &Skeleton,
    roles: &RoleMap,
    world: &WorldPose,
    figure: Option<(&Skin, &[DMat4])>,
    at: ScreenPoint,
    radius_px: f64,
) -> Option<Role> {
    pick(camera, skeleton, roles, world, at, radius_px)
        .or_else(|| figure.and_then(|f| pick_on_surface(camera, roles, world, f, at, radius_px)))
}
