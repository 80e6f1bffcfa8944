//! No joint snaps: the shown posture's joints may change their angular
//! velocity by at most [`MAX_ACCEL`] a second. Foot IK over a yanked body
//! can flip a knee or an ankle in one frame (a target out of reach, then
//! back in it); the change is spread over the next frames instead. The
//! library's quickest motions turn their joints at about a third of this,
//! so what the method shows is left alone.

use glam::{DQuat, DVec3};

use super::Controller;
use super::feet::rise_over_floor;
use crate::character::roles::Role;
use crate::character::skeleton::{Pose, rotation_difference};

/// The most a joint's angular velocity changes in a second (rad/s²).
const MAX_ACCEL: f64 = 240.0;

/// The posture shown last and its joints' angular velocities.
#[derive(Clone, Debug, Default)]
pub(super) struct Jerk {
    last: Option<(Pose, Vec<DVec3>)>,
}

impl Controller {
    /// Bound the shown posture's joint accelerations against the last
    /// frame's (see the module).
    pub(super) fn bound_jerks(&mut self, dt: f64) {
        if dt <= 0.0 {
            return;
        }
        let Some((last, vel)) = &mut self.jerk.last else {
            self.jerk.last = Some((
                self.output.clone(),
                vec![DVec3::ZERO; self.output.rotations.len()],
            ));
            return;
        };
        let most = MAX_ACCEL * dt;
        for (j, (q, v)) in self
            .output
            .rotations
            .iter_mut()
            .zip(vel.iter_mut())
            .enumerate()
        {
            let from = last.rotations[j];
            let mut w = rotation_difference(from, *q) / dt;
            let change = w - *v;
            let len = change.length();
            if len > most {
                w = *v + change * (most / len);
                *q = (DQuat::from_scaled_axis(w * dt) * from).normalize();
            }
            *v = w;
        }
        // The floor still holds: a foot or a hand the bound (or a finger)
        // left under it lifts the body, its joints untouched (bending the leg
        // to lift the foot undid the bound: a knee popped as a kick began).
        rise_over_floor(
            &self.ch.lib.skeleton,
            &self.ch.roles,
            &mut self.output,
            &[
                Role::LeftFoot,
                Role::RightFoot,
                Role::LeftHand,
                Role::RightHand,
            ],
        );
        if let Some((last, _)) = &mut self.jerk.last {
            last.clone_from(&self.output);
        }
    }
}
