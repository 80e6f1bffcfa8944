//! marionette's own skeleton and the inverse kinematics that turns authored
//! targets (pelvis, hands, feet) into joint rotations.
//!
//! The skeleton is 1.70 m tall to the top of the head, in a T-pose at rest,
//! facing +Z with its left on +X (Y up, right-handed, metres). Joint names
//! follow the CMU/MotionBuilder convention so that any tool reads them.

use glam::{DMat3, DQuat, DVec3};

use crate::character::skeleton::{Joint, Skeleton};

/// Joint indices of the rig.
pub mod j {
    pub const HIPS: usize = 0;
    pub const SPINE: usize = 1;
    pub const CHEST: usize = 2;
    pub const NECK: usize = 3;
    pub const HEAD: usize = 4;
    pub const L_CLAVICLE: usize = 5;
    pub const L_ARM: usize = 6;
    pub const L_FOREARM: usize = 7;
    pub const L_HAND: usize = 8;
    pub const R_CLAVICLE: usize = 9;
    pub const R_ARM: usize = 10;
    pub const R_FOREARM: usize = 11;
    pub const R_HAND: usize = 12;
    pub const L_THIGH: usize = 13;
    pub const L_SHIN: usize = 14;
    pub const L_FOOT: usize = 15;
    pub const L_TOE: usize = 16;
    pub const R_THIGH: usize = 17;
    pub const R_SHIN: usize = 18;
    pub const R_FOOT: usize = 19;
    pub const R_TOE: usize = 20;
}

/// Upper arm, forearm, thigh and shin lengths (m).
pub const UPPER_ARM: f64 = 0.28;
pub const FOREARM: f64 = 0.25;
pub const THIGH: f64 = 0.42;
pub const SHIN: f64 = 0.40;
/// Height of the ankle joint above the floor when the foot is flat (m).
pub const ANKLE_HEIGHT: f64 = 0.08;

/// The rig's skeleton.
#[must_use]
pub fn skeleton() -> Skeleton {
    let v = DVec3::new;
    let joint = |name: &str, parent: Option<usize>, offset: DVec3, end: Option<DVec3>| Joint {
        name: name.to_owned(),
        parent,
        offset,
        end_site: end,
    };
    let mut joints = vec![
        joint("Hips", None, v(0.0, 0.0, 0.0), None),
        joint("Spine", Some(j::HIPS), v(0.0, 0.10, 0.0), None),
        joint("Spine1", Some(j::SPINE), v(0.0, 0.17, 0.0), None),
        joint("Neck", Some(j::CHEST), v(0.0, 0.20, 0.0), None),
        joint(
            "Head",
            Some(j::NECK),
            v(0.0, 0.10, 0.0),
            Some(v(0.0, 0.18, 0.0)),
        ),
    ];
    for (side, prefix) in [(1.0, "Left"), (-1.0, "Right")] {
        let base = joints.len();
        joints.push(joint(
            &format!("{prefix}Shoulder"),
            Some(j::CHEST),
            v(0.02 * side, 0.15, 0.0),
            None,
        ));
        joints.push(joint(
            &format!("{prefix}Arm"),
            Some(base),
            v(0.16 * side, 0.0, 0.0),
            None,
        ));
        joints.push(joint(
            &format!("{prefix}ForeArm"),
            Some(base + 1),
            v(UPPER_ARM * side, 0.0, 0.0),
            None,
        ));
        joints.push(joint(
            &format!("{prefix}Hand"),
            Some(base + 2),
            v(FOREARM * side, 0.0, 0.0),
            Some(v(0.17 * side, 0.0, 0.0)),
        ));
    }
    for (side, prefix) in [(1.0, "Left"), (-1.0, "Right")] {
        let base = joints.len();
        joints.push(joint(
            &format!("{prefix}UpLeg"),
            Some(j::HIPS),
            v(0.09 * side, -0.05, 0.0),
            None,
        ));
        joints.push(joint(
            &format!("{prefix}Leg"),
            Some(base),
            v(0.0, -THIGH, 0.0),
            None,
        ));
        joints.push(joint(
            &format!("{prefix}Foot"),
            Some(base + 1),
            v(0.0, -SHIN, 0.0),
            None,
        ));
        joints.push(joint(
            &format!("{prefix}ToeBase"),
            Some(base + 2),
            v(0.0, -0.06, 0.13),
            Some(v(0.0, 0.0, 0.06)),
        ));
    }
    Skeleton { joints }
}

/// A rotation from pitch (about +X: forward bend), yaw (about +Y: turn to
/// the left) and roll (about −Z: lean to the left), in degrees, applied yaw
/// first.
#[must_use]
pub fn body_rotation(pitch: f64, yaw: f64, roll: f64) -> DQuat {
    DQuat::from_rotation_y(yaw.to_radians())
        * DQuat::from_rotation_x(pitch.to_radians())
        * DQuat::from_rotation_z(-roll.to_radians())
}

/// The rotation that takes the rest frame (bone along `rest_dir`, bending
/// towards `rest_bend`) to the frame of a bone along `dir` bending towards
/// `bend`. Both pairs must be non-parallel.
fn align(rest_dir: DVec3, rest_bend: DVec3, dir: DVec3, bend: DVec3) -> DQuat {
    let frame = |d: DVec3, b: DVec3| {
        let d = d.normalize();
        let b = (b - d * b.dot(d)).normalize();
        DMat3::from_cols(d, b, d.cross(b))
    };
    DQuat::from_mat3(&(frame(dir, bend) * frame(rest_dir, rest_bend).transpose())).normalize()
}

/// A solved two-bone limb: the world rotations of its upper and lower bones.
#[derive(Clone, Copy, Debug)]
pub struct Limb {
    pub upper: DQuat,
    pub lower: DQuat,
    /// Where the end effector really is (the target, or as close as the
    /// limb reaches).
    pub end: DVec3,
}

/// Two-bone IK: a limb rooted at `root` with bone lengths `a` and `b`
/// reaching for `target`, its middle joint bulging towards `pole`. The rest
/// pose has the limb along `rest_dir` bulging towards `rest_bend`.
#[must_use]
pub fn two_bone(
    root: DVec3,
    a: f64,
    b: f64,
    target: DVec3,
    pole: DVec3,
    rest_dir: DVec3,
    rest_bend: DVec3,
) -> Limb {
    let to = target - root;
    let dist = to.length().clamp((a - b).abs() + 1e-6, a + b - 1e-6);
    let dir = if to.length() > 1e-9 {
        to / to.length()
    } else {
        rest_dir
    };
    let end = root + dir * dist;
    // The bulge direction, perpendicular to the root→end line.
    let mut bulge = pole - dir * pole.dot(dir);
    if bulge.length() < 1e-9 {
        bulge = rest_bend - dir * rest_bend.dot(dir);
    }
    let bulge = bulge.normalize();
    // Law of cosines: the middle joint's distance along and off the line.
    let along = (a * a - b * b + dist * dist) / (2.0 * dist);
    let off = (a * a - along * along).max(0.0).sqrt();
    let mid = root + dir * along + bulge * off;
    let upper = align(rest_dir, rest_bend, mid - root, bulge);
    let lower_dir = end - mid;
    let lower = align(rest_dir, rest_bend, lower_dir, bulge);
    Limb { upper, lower, end }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::character::skeleton::forward_kinematics;

    #[test]
    fn rig_stands_1_68_m_to_the_head_joint_and_has_every_role() {
        let s = skeleton();
        let roles = crate::character::roles::fill(&s, &Default::default()).unwrap();
        let mut pose = s.rest_pose();
        pose.translations[j::HIPS] = DVec3::new(0.0, 0.95, 0.0);
        let h = crate::character::motion::standing_height(&s, &roles, &pose);
        assert!((h - 1.68).abs() < 1e-9, "{h}");
    }

    #[test]
    fn two_bone_reaches_reachable_targets_with_the_pole_respected() {
        let root = DVec3::new(0.0, 0.9, 0.0);
        let target = DVec3::new(0.05, 0.2, 0.25);
        let limb = two_bone(root, THIGH, SHIN, target, DVec3::Z, DVec3::NEG_Y, DVec3::Z);
        let mid = root + limb.upper * DVec3::new(0.0, -THIGH, 0.0);
        let end = mid + limb.lower * DVec3::new(0.0, -SHIN, 0.0);
        assert!((end - target).length() < 1e-9);
        assert!((mid - root).z > 0.0, "the knee bulges forward");
        // Through a real skeleton's FK too.
        let s = skeleton();
        let mut pose = s.rest_pose();
        pose.translations[j::HIPS] = root - s.joints[j::L_THIGH].offset;
        pose.rotations[j::L_THIGH] = limb.upper;
        pose.rotations[j::L_SHIN] = limb.upper.inverse() * limb.lower;
        let w = forward_kinematics(&s, &pose);
        assert!((w.positions[j::L_FOOT] - target).length() < 1e-9);
    }
}
