//! No joint snaps: the shown posture's joints may change their angular
//! velocity by at most [`MAX_SHOWN_ACCEL`] a second. Foot IK over a yanked body
//! can flip a knee or an ankle in one frame (a target out of reach, then
//! back in it); the change is spread over the next frames instead. The
//! library's quickest motions turn their joints at about a third of this,
//! so what the method shows is left alone.
//!
//! The feet keep what the feet passes gave them as far as the bound
//! allows: the legs' joints turn back towards putting each foot where it
//! was (CCD, each turn kept within the bound), and a planted foot still
//! off its place (a leg held back under a lunging body) moves the body
//! back over it, its joints untouched. Before, the bound alone dragged
//! planted feet up to 234 mm in a frame under abuse.

use glam::{DQuat, DVec3};

use super::Controller;
use super::feet::rise_over_floor;
use crate::character::roles::Role;
use crate::character::skeleton::{Pose, forward_kinematics, rotation_difference};
use crate::control::posing::ik::{ccd_within, chain};

/// The most a shown joint's angular velocity changes in a second
/// (rad/s²): the bound on the posture on the screen, above tracking's own
/// ([`crate::control::tracking::accel::MAX_TRACKING_ACCEL`]).
const MAX_SHOWN_ACCEL: f64 = 240.0;

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
        let Some((mut last, mut vel)) = self.jerk.last.take() else {
            self.jerk.last = Some((
                self.output.clone(),
                vec![DVec3::ZERO; self.output.rotations.len()],
            ));
            return;
        };
        let most = MAX_SHOWN_ACCEL * dt;
        let sk = &self.ch.lib.skeleton;
        let before = forward_kinematics(sk, &self.output);
        let (from, old) = (&last.rotations, &vel);
        // Joint j's local rotation `q`, its angular velocity's change kept
        // within the bound.
        let bounded = |j: usize, q: DQuat| -> DQuat {
            let w = rotation_difference(from[j], q) / dt;
            let change = w - old[j];
            let len = change.length();
            if len > most {
                let w = old[j] + change * (most / len);
                (DQuat::from_scaled_axis(w * dt) * from[j]).normalize()
            } else {
                q
            }
        };
        for (j, q) in self.output.rotations.iter_mut().enumerate() {
            *q = bounded(j, *q);
        }
        // The feet go back where the feet passes put them as far as the
        // bound lets their legs turn...
        let held = self.held();
        let after = forward_kinematics(sk, &self.output);
        let goals: Vec<(usize, Vec<usize>, DVec3)> = [Role::LeftFoot, Role::RightFoot]
            .into_iter()
            .filter(|r| !held.contains(r))
            .filter_map(|r| {
                let j = self.ch.roles.get(r);
                let moved = (before.positions[j] - after.positions[j]).length() > 5e-4;
                moved.then(|| (j, chain(sk, &self.ch.roles, r), before.positions[j]))
            })
            .collect();
        if !goals.is_empty() {
            ccd_within(sk, &mut self.output, &goals, 8, bounded);
        }
        for (j, v) in vel.iter_mut().enumerate() {
            *v = rotation_difference(last.rotations[j], self.output.rotations[j]) / dt;
        }
        // ...and a planted foot they could not bring back (its leg held
        // back under a lunging body) stays where it stands: the body moves
        // back over it, its joints untouched. Not for a foot the sweep lifts
        // (it moves over the floor; moving the body for it slid the foot
        // that had just begun a step).
        let after = forward_kinematics(sk, &self.output);
        let mut shift = DVec3::ZERO;
        let mut n = 0.0;
        for (k, role) in [Role::LeftFoot, Role::RightFoot].into_iter().enumerate() {
            if self.feet[k].anchor.is_none() || held.contains(&role) || self.swept[k] > 0.0 {
                continue;
            }
            let j = self.ch.roles.get(role);
            shift += (before.positions[j] - after.positions[j]).with_y(0.0);
            n += 1.0;
        }
        if n > 0.0 {
            self.output.translations[0] += shift / n;
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
        last.clone_from(&self.output);
        self.jerk.last = Some((last, vel));
    }
}
