//! A made-up body for the controller parts' unit tests: a humanoid of
//! 1.7 m, Y up, facing +Z, its left towards +X, standing straight with its
//! ankles 5 cm and its toes' tips on the floor, and postures made from it.

use std::collections::BTreeMap;

use glam::{DQuat, DVec3};

use crate::character::roles::{Role, RoleMap, fill};
use crate::character::skeleton::{Joint, Pose, Skeleton, WorldPose, forward_kinematics};
use crate::control::posing::ik::plant_feet;

/// The skeleton and its roles.
pub(super) fn body() -> (Skeleton, RoleMap) {
    let mut joints: Vec<Joint> = Vec::new();
    let mut add = |name: &str, parent: Option<usize>, offset: [f64; 3], end: Option<[f64; 3]>| {
        joints.push(Joint {
            name: name.to_owned(),
            parent,
            offset: DVec3::from_array(offset),
            end_site: end.map(DVec3::from_array),
        });
        joints.len() - 1
    };
    let hips = add("Hips", None, [0.0, 0.95, 0.0], None);
    for (side, x) in [("Left", 1.0), ("Right", -1.0)] {
        let up = add(
            &format!("{side}UpLeg"),
            Some(hips),
            [0.1 * x, -0.05, 0.0],
            None,
        );
        let leg = add(&format!("{side}Leg"), Some(up), [0.0, -0.43, 0.0], None);
        let foot = add(&format!("{side}Foot"), Some(leg), [0.0, -0.42, 0.0], None);
        add(
            &format!("{side}ToeBase"),
            Some(foot),
            [0.0, -0.04, 0.12],
            Some([0.0, -0.01, 0.05]),
        );
    }
    let spine = add("Spine", Some(hips), [0.0, 0.12, 0.0], None);
    let chest = add("Chest", Some(spine), [0.0, 0.2, 0.0], None);
    let neck = add("Neck", Some(chest), [0.0, 0.2, 0.0], None);
    add("Head", Some(neck), [0.0, 0.1, 0.0], Some([0.0, 0.18, 0.0]));
    for (side, x) in [("Left", 1.0), ("Right", -1.0)] {
        let sh = add(
            &format!("{side}Shoulder"),
            Some(chest),
            [0.05 * x, 0.15, 0.0],
            None,
        );
        let arm = add(&format!("{side}Arm"), Some(sh), [0.12 * x, 0.0, 0.0], None);
        let fore = add(
            &format!("{side}ForeArm"),
            Some(arm),
            [0.28 * x, 0.0, 0.0],
            None,
        );
        add(
            &format!("{side}Hand"),
            Some(fore),
            [0.25 * x, 0.0, 0.0],
            Some([0.08 * x, 0.0, 0.0]),
        );
    }
    let skeleton = Skeleton { joints };
    let roles = fill(&skeleton, &BTreeMap::new()).expect("the made-up body has every role");
    (skeleton, roles)
}

/// Standing straight.
pub(super) fn standing(sk: &Skeleton) -> Pose {
    sk.rest_pose()
}

/// Standing with the pelvis `drop` metres lower, the knees bent forward
/// so that the feet stay flat where they stood.
pub(super) fn crouched(sk: &Skeleton, roles: &RoleMap, drop: f64) -> Pose {
    let mut pose = standing(sk);
    let w = forward_kinematics(sk, &pose);
    let feet = [Role::LeftFoot, Role::RightFoot].map(|r| Some(w.positions[roles.get(r)]));
    // Thigh and shin turn by about the same angle (0.43 and 0.42 m).
    let bend = (1.0 - drop / 0.85).clamp(-1.0, 1.0).acos();
    for (hip, knee, foot) in [
        (Role::LeftHip, Role::LeftKnee, Role::LeftFoot),
        (Role::RightHip, Role::RightKnee, Role::RightFoot),
    ] {
        pose.rotations[roles.get(hip)] = DQuat::from_rotation_x(-bend);
        pose.rotations[roles.get(knee)] = DQuat::from_rotation_x(2.0 * bend);
        pose.rotations[roles.get(foot)] = DQuat::from_rotation_x(-bend);
    }
    pose.translations[0].y -= drop;
    // The small rest of the way, the legs no longer straight.
    for _ in 0..4 {
        plant_feet(sk, roles, &mut pose, feet);
    }
    pose
}

/// `pose` moved by `by` as a whole.
pub(super) fn moved(pose: &Pose, by: DVec3) -> Pose {
    let mut p = pose.clone();
    p.translations[0] += by;
    p
}

/// `pose` with the foot of `role` put at `at` by its leg.
pub(super) fn foot_at(sk: &Skeleton, roles: &RoleMap, pose: &Pose, role: Role, at: DVec3) -> Pose {
    let mut p = pose.clone();
    let goals = match role {
        Role::LeftFoot => [Some(at), None],
        _ => [None, Some(at)],
    };
    for _ in 0..4 {
        plant_feet(sk, roles, &mut p, goals);
    }
    p
}

/// Where the joint of `role` is in `pose`.
pub(super) fn at(sk: &Skeleton, roles: &RoleMap, pose: &Pose, role: Role) -> DVec3 {
    forward_kinematics(sk, pose).positions[roles.get(role)]
}

/// The world pose of `pose`.
pub(super) fn world(sk: &Skeleton, pose: &Pose) -> WorldPose {
    forward_kinematics(sk, pose)
}
