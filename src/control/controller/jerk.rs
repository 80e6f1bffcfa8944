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

use super::feet::rise_over_floor;
use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::{
    Pose, Skeleton, WorldPose, forward_kinematics, rotation_difference,
};
use crate::control::posing::ik::{ccd_within, chain};

/// The most a shown joint's angular velocity changes in a second
/// (rad/s²): the bound on the posture on the screen, above tracking's own
/// ([`crate::control::tracking::accel::MAX_TRACKING_ACCEL`]).
const MAX_SHOWN_ACCEL: f64 = 240.0;

/// The bound on the shown posture's joint accelerations: the posture
/// shown last and its joints' angular velocities.
#[derive(Clone, Debug, Default)]
pub(super) struct Jerk {
    last: Option<(Pose, Vec<DVec3>)>,
}

impl Jerk {
    /// Bound the joint accelerations of `output`, the posture to show,
    /// against the last frame's (see the module); `held` are the parts
    /// fingers hold and `standing[k]` says whether foot `k` (left, right)
    /// stands planted where it is to stay.
    pub(super) fn bound(
        &mut self,
        sk: &Skeleton,
        roles: &RoleMap,
        output: &mut Pose,
        held: &[Role],
        standing: [bool; 2],
        dt: f64,
    ) {
        if dt <= 0.0 {
            return;
        }
        let Some((mut last, mut vel)) = self.last.take() else {
            self.last = Some((output.clone(), vec![DVec3::ZERO; output.rotations.len()]));
            return;
        };
        let most = MAX_SHOWN_ACCEL * dt;
        let before = forward_kinematics(sk, output);
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
        for (j, q) in output.rotations.iter_mut().enumerate() {
            *q = bounded(j, *q);
        }
        // The feet go back where the feet passes put them as far as the
        // bound lets their legs turn...
        let goals = moved_feet(sk, roles, &before, output, held);
        if !goals.is_empty() {
            ccd_within(sk, output, &goals, 8, bounded);
        }
        for (j, v) in vel.iter_mut().enumerate() {
            *v = rotation_difference(last.rotations[j], output.rotations[j]) / dt;
        }
        // ...and a planted foot they could not bring back (its leg held
        // back under a lunging body) stays where it stands.
        back_over_standing(sk, roles, &before, output, held, standing);
        // The floor still holds: a foot or a hand the bound (or a finger)
        // left under it lifts the body, its joints untouched (bending the leg
        // to lift the foot undid the bound: a knee popped as a kick began).
        rise_over_floor(
            sk,
            roles,
            output,
            &[
                Role::LeftFoot,
                Role::RightFoot,
                Role::LeftHand,
                Role::RightHand,
            ],
        );
        last.clone_from(output);
        self.last = Some((last, vel));
    }
}

/// The feet no finger `held` that `output` has moved from where they are
/// in `before`: each joint with its leg's chain and where it was.
fn moved_feet(
    sk: &Skeleton,
    roles: &RoleMap,
    before: &WorldPose,
    output: &Pose,
    held: &[Role],
) -> Vec<(usize, Vec<usize>, DVec3)> {
    let after = forward_kinematics(sk, output);
    [Role::LeftFoot, Role::RightFoot]
        .into_iter()
        .filter(|r| !held.contains(r))
        .filter_map(|r| {
            let j = roles.get(r);
            let moved = (before.positions[j] - after.positions[j]).length() > 5e-4;
            moved.then(|| (j, chain(sk, roles, r), before.positions[j]))
        })
        .collect()
}

/// The body of `output` moved back over the planted feet (`standing`,
/// left and right; not `held`) that stood elsewhere in `before`, its joints
/// untouched. Not for a foot the sweep lifts (it moves over the floor;
/// moving the body for it slid the foot that had just begun a step).
fn back_over_standing(
    sk: &Skeleton,
    roles: &RoleMap,
    before: &WorldPose,
    output: &mut Pose,
    held: &[Role],
    standing: [bool; 2],
) {
    let after = forward_kinematics(sk, output);
    let mut shift = DVec3::ZERO;
    let mut n = 0.0;
    for (k, role) in [Role::LeftFoot, Role::RightFoot].into_iter().enumerate() {
        if !standing[k] || held.contains(&role) {
            continue;
        }
        let j = roles.get(role);
        shift += (before.positions[j] - after.positions[j]).with_y(0.0);
        n += 1.0;
    }
    if n > 0.0 {
        output.translations[0] += shift / n;
    }
}

#[cfg(test)]
mod tests {
    use glam::DQuat;

    use super::super::testbody::{body, crouched};
    use super::{Jerk, MAX_SHOWN_ACCEL};
    use crate::character::roles::Role;
    use crate::character::skeleton::rotation_difference;

    const DT: f64 = 1.0 / 30.0;

    #[test]
    fn a_joint_that_would_snap_is_spread_over_the_next_frames() {
        let (sk, roles) = body();
        let still = crouched(&sk, &roles, 0.05);
        let mut jerk = Jerk::default();
        let mut shown = still.clone();
        jerk.bound(&sk, &roles, &mut shown, &[], [true; 2], DT);
        jerk.bound(&sk, &roles, &mut shown, &[], [true; 2], DT);
        // The left elbow asked to turn a radian in one frame (30 rad/s).
        let elbow = roles.get(Role::LeftElbow);
        let mut snapped = still.clone();
        snapped.rotations[elbow] = DQuat::from_rotation_y(1.0) * still.rotations[elbow];
        let mut out = snapped.clone();
        jerk.bound(&sk, &roles, &mut out, &[], [true; 2], DT);
        let turned = rotation_difference(still.rotations[elbow], out.rotations[elbow]).length();
        let most = MAX_SHOWN_ACCEL * DT * DT;
        assert!(
            turned <= most + 1e-9,
            "turned {turned:.4} rad in a frame, at most {most:.4}"
        );
        assert!(turned > 0.5 * most, "it turns on, {turned:.4} rad");
        // Kept on, it gets there.
        for _ in 0..30 {
            out = snapped.clone();
            jerk.bound(&sk, &roles, &mut out, &[], [true; 2], DT);
        }
        let left = rotation_difference(snapped.rotations[elbow], out.rotations[elbow]).length();
        assert!(left < 0.01, "{left:.4} rad short after a second");
    }

    #[test]
    fn what_the_library_moves_is_left_alone() {
        let (sk, roles) = body();
        let still = crouched(&sk, &roles, 0.05);
        let mut jerk = Jerk::default();
        let mut shown = still.clone();
        jerk.bound(&sk, &roles, &mut shown, &[], [true; 2], DT);
        // A head turning at 3 rad/s from rest: 3 rad/s of change in a
        // frame, under the bound's 8.
        let head = roles.get(Role::Head);
        let mut turning = still.clone();
        turning.rotations[head] = DQuat::from_rotation_y(0.1) * still.rotations[head];
        let mut out = turning.clone();
        jerk.bound(&sk, &roles, &mut out, &[], [true; 2], DT);
        assert_eq!(out.rotations, turning.rotations);
    }
}
