//! The stance a posture is left in when the fingers lift: a foot a finger
//! raised comes down to the floor, and a body lifted off both feet comes
//! down onto them, so that the character never stays balanced on one leg
//! (or on air) with nobody holding it.

use glam::DVec3;

use super::Feet;
use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::{Pose, Skeleton, forward_kinematics};
use crate::control::posing::ik::plant_feet;

/// A foot whose ankle is this much higher than standing (m) is off the
/// floor.
const RAISED_M: f64 = 0.06;

/// Widest stance a foot is put down in (m between the ankles, on the
/// floor); a foot raised farther from the other comes down this far from
/// it, in the same direction.
const WIDEST_STANCE_M: f64 = 0.5;

impl Feet {
    /// Put the raised feet of the target posture `target` down (the
    /// fingers have lifted).
    pub(in crate::control::controller) fn settle_stance(
        &self,
        sk: &Skeleton,
        roles: &RoleMap,
        target: &mut Pose,
    ) {
        let feet = [Role::LeftFoot, Role::RightFoot];
        let w = forward_kinematics(sk, target);
        let ankles = feet.map(|r| w.positions[roles.get(r)]);
        let up = ankles.map(|a| a.y > self.ankle_rest + RAISED_M);
        if !up[0] && !up[1] {
            return;
        }
        // Off both feet: the body comes down until the lower one stands.
        if up[0] && up[1] {
            let drop = ankles[0].y.min(ankles[1].y) - self.ankle_rest;
            target.translations[0].y -= drop;
        }
        let w = forward_kinematics(sk, target);
        let ankles = feet.map(|r| w.positions[roles.get(r)]);
        let floor = |p: DVec3| p.with_y(self.ankle_rest);
        let hips = [Role::LeftHip, Role::RightHip].map(|r| w.positions[roles.get(r)]);
        let mut goals = [None; 2];
        for k in 0..2 {
            let other = floor(ankles[1 - k]);
            goals[k] = Some(if up[k] {
                let apart = (floor(ankles[k]) - other).clamp_length_max(WIDEST_STANCE_M);
                // Within the leg's reach: no nearer the hip than the
                // floor under it allows.
                let under = floor(hips[k]);
                let room = (self.leg_length * 0.97).powi(2) - (hips[k].y - self.ankle_rest).powi(2);
                under + (other + apart - under).clamp_length_max(room.max(0.0).sqrt())
            } else {
                ankles[k]
            });
        }
        // A leg that cannot reach the floor (the hip hitched up as the
        // foot was raised) brings the body down by what it lacks.
        for _ in 0..3 {
            plant_feet(sk, roles, target, goals);
            let w = forward_kinematics(sk, target);
            let short = (0..2)
                .filter_map(|k| goals[k].map(|g| w.positions[roles.get(feet[k])].y - g.y))
                .fold(0.0f64, f64::max);
            if short < 0.002 {
                break;
            }
            target.translations[0].y -= short;
        }
        tracing::debug!(
            left = up[0],
            right = up[1],
            "the fingers lifted with a foot off the floor: it is put down"
        );
    }
}
