//! A foot that moves fast over the floor is swinging: it is lifted clear
//! of the floor (as a walker's swinging toes clear it) rather than swept
//! along it. Whatever moved it (a step landing, the body lunging under a
//! free foot, tracking catching up), a foot low and fast is lifted by as
//! much as its lowest point lacks of [`CLEARANCE_M`], in proportion to
//! its speed between [`SLOW_M_S`] and [`SWING_M_S`], and set down again
//! over [`SET_DOWN_S`] once it slows; where a straight leg cannot lift a
//! swinging foot that far, the body rises by what it lacks, and again
//! where the bound on joint accelerations brought a swinging or stepping
//! foot back down, or left a planted foot that sweeps the floor lower than
//! the sweep asks. Feet held by a finger are the finger's.

use glam::DVec3;

use super::{Feet, FeetStep};
use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::{
    Pose, Skeleton, WorldPose, foot_points, forward_kinematics, sole,
};
use crate::control::posing::ik::plant_feet;

/// Up to this speed over the floor (m/s) a foot stays on it (a planted
/// foot of the library's walks slides at under half of it)...
const SLOW_M_S: f64 = 0.15;
/// ...from this speed on it is clear of it.
const SWING_M_S: f64 = 0.27;
/// How far above the floor a swinging foot's lowest point goes (m).
pub(super) const CLEARANCE_M: f64 = 0.022;
/// Only points this near the floor count for the speed (m).
const NEAR_M: f64 = 0.06;
/// How long a foot that slowed takes to come down (s).
const SET_DOWN_S: f64 = 0.1;

impl Feet {
    /// Lift the feet of `output` that sweep the floor (see the module),
    /// against the posture shown last frame.
    pub(super) fn clear_swept(&mut self, s: &FeetStep, output: &mut Pose) {
        let (sk, roles, dt, held) = (s.skeleton, s.roles, s.dt, s.held);
        if dt <= 0.0 {
            return;
        }
        let now = forward_kinematics(sk, output);
        let mut lifts = [0.0; 2];
        for (k, role) in [Role::LeftFoot, Role::RightFoot].into_iter().enumerate() {
            if held.contains(&role) {
                self.swept[k] = 0.0;
                continue;
            }
            let j = roles.get(role);
            let speed = foot_points(sk, s.shown_last, j)
                .zip(foot_points(sk, &now, j))
                .filter(|(a, b)| a.y.min(b.y) < NEAR_M)
                .map(|(a, b)| (b - a).with_y(0.0).length() / dt)
                .fold(0.0, f64::max);
            let want = ((speed - SLOW_M_S) / (SWING_M_S - SLOW_M_S)).clamp(0.0, 1.0);
            self.swept[k] = want.max(self.swept[k] - dt / SET_DOWN_S);
            lifts[k] = CLEARANCE_M * self.swept[k];
        }
        self.lift_feet(sk, roles, output, lifts, now);
        // What the bound on joint accelerations must not take back: a
        // foot off the floor that carries nothing, or that sweeps it, stays
        // clear of it.
        let w = forward_kinematics(sk, output);
        for (k, role) in [Role::LeftFoot, Role::RightFoot].into_iter().enumerate() {
            let y = sole(sk, &w, roles.get(role)).y;
            let lifted = self.holds[k].anchor.is_none() || self.swept[k] > 0.0;
            // As high as the sweep asks (a planted leg may not have lifted
            // it that far), or as the foot swings or steps.
            let want = y.max(CLEARANCE_M * self.swept[k]).min(CLEARANCE_M);
            self.clear[k] = (lifted && !held.contains(&role) && y > 0.0).then_some(want);
        }
    }

    /// A swinging or stepping foot that the bound on joint accelerations
    /// brought back down towards the floor (its leg may not bend that fast)
    /// is held clear of it as [`Self::clear_swept`] left it: the body
    /// rises by what the foot lacks, its joints untouched.
    pub(in crate::control::controller) fn keep_clear(
        &self,
        sk: &Skeleton,
        roles: &RoleMap,
        output: &mut Pose,
    ) {
        let w = forward_kinematics(sk, output);
        let short = [Role::LeftFoot, Role::RightFoot]
            .into_iter()
            .enumerate()
            .filter_map(|(k, role)| {
                let want = self.clear[k]?;
                Some(want - sole(sk, &w, roles.get(role)).y)
            })
            .fold(0.0, f64::max);
        if short > 1e-4 {
            output.translations[0].y += short;
        }
    }

    /// Lift each foot until its lowest point is `lifts[k]` above the
    /// floor (no lower than it is), keeping its turn; `w` is the shown
    /// posture's world pose.
    fn lift_feet(
        &self,
        sk: &Skeleton,
        roles: &RoleMap,
        output: &mut Pose,
        lifts: [f64; 2],
        mut w: WorldPose,
    ) {
        // The leg's IK turns the foot with the leg: a few passes lift its
        // lowest point as far as asked.
        for _ in 0..3 {
            let mut goals = [None; 2];
            for (k, role) in [Role::LeftFoot, Role::RightFoot].into_iter().enumerate() {
                let j = roles.get(role);
                let lowest = sole(sk, &w, j).y;
                if lifts[k] - lowest > 1e-4 {
                    goals[k] = Some(w.positions[j] + DVec3::Y * (lifts[k] - lowest));
                }
            }
            if goals.iter().all(Option::is_none) {
                break;
            }
            plant_feet(sk, roles, output, goals);
            // The foot keeps its turn: lifted, not tipped by the leg.
            let lifted = forward_kinematics(sk, output);
            for (k, role) in [Role::LeftFoot, Role::RightFoot].into_iter().enumerate() {
                let j = roles.get(role);
                if let (Some(_), Some(p)) = (goals[k], sk.joints[j].parent) {
                    output.rotations[j] =
                        (lifted.rotations[p].inverse() * w.rotations[j]).normalize();
                }
            }
            w = forward_kinematics(sk, output);
        }
        // A straight leg cannot lift its swinging foot clear: the body rises
        // by what it lacks (as a runner's does), the feet that stand
        // planted again.
        let short = (0..2)
            .filter(|&k| lifts[k] > 0.0 && self.holds[k].anchor.is_none())
            .map(|k| lifts[k] - sole(sk, &w, roles.get([Role::LeftFoot, Role::RightFoot][k])).y)
            .fold(0.0, f64::max);
        if short > 1e-3 {
            let stand: [Option<DVec3>; 2] =
                std::array::from_fn(|k| self.holds[k].anchor.filter(|_| lifts[k] == 0.0));
            output.translations[0].y += short;
            if stand.iter().any(Option::is_some) {
                plant_feet(sk, roles, output, stand);
            }
        }
    }
}
