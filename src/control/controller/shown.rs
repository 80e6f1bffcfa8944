//! The shown part: the posture tracking control shows (the paper's
//! section 6), following the target by bounded accelerations, its world
//! pose, and the bound on its joint accelerations once corrected.

use glam::DVec3;

use super::MAX_SUBSTEP;
use super::jerk::Jerk;
use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::{Pose, Skeleton, WorldPose, forward_kinematics};
use crate::control::tracking::accel::{AccelTracker, Gains};

/// The posture shown, the tracker that moves it and its world pose.
#[derive(Clone)]
pub(super) struct Shown {
    tracker: AccelTracker,
    /// The tracked posture with its corrections: what is shown.
    output: Pose,
    /// Its world pose, as of the last [`Self::show`].
    world: WorldPose,
    /// Its last joint velocities, bounding their change.
    jerk: Jerk,
}

impl Shown {
    /// At rest in `pose`, whose world pose is `world`.
    pub fn new(pose: Pose, world: WorldPose) -> Self {
        Self {
            tracker: AccelTracker::new(pose.clone()),
            output: pose,
            world,
            jerk: Jerk::default(),
        }
    }

    /// Tracking control: the shown posture follows `target` by bounded
    /// accelerations settling in about `settle_s`, in sub-steps short
    /// enough to stay stable; with `settle_s` 0 it is the target.
    pub fn track(&mut self, target: &Pose, settle_s: f64, dt: f64) {
        if settle_s > 0.0 {
            let gains = Gains::critical(settle_s);
            let steps = (dt / MAX_SUBSTEP).ceil().max(1.0) as usize;
            for _ in 0..steps {
                self.tracker.step(target, gains, dt / steps as f64);
            }
        } else {
            self.tracker = AccelTracker::new(target.clone());
        }
        self.output = self.tracker.pose.clone();
    }

    /// The posture shown.
    pub fn pose(&self) -> &Pose {
        &self.output
    }

    /// The posture shown, to correct.
    pub fn pose_mut(&mut self) -> &mut Pose {
        &mut self.output
    }

    /// The world pose last shown.
    pub fn world(&self) -> &WorldPose {
        &self.world
    }

    /// The world pose last shown, the posture to correct and the tracker
    /// (the feet hold the tracker where they stand).
    pub fn for_correction(&mut self) -> (&WorldPose, &mut Pose, &mut AccelTracker) {
        (&self.world, &mut self.output, &mut self.tracker)
    }

    /// The bound on the shown posture's joint accelerations
    /// ([`Jerk::bound`]): the parts fingers `held` and the feet
    /// `standing` (left, right) are kept.
    pub fn bound(
        &mut self,
        skeleton: &Skeleton,
        roles: &RoleMap,
        held: &[Role],
        standing: [bool; 2],
        dt: f64,
    ) {
        self.jerk
            .bound(skeleton, roles, &mut self.output, held, standing, dt);
    }

    /// The corrected posture is shown: its world pose.
    pub fn show(&mut self, skeleton: &Skeleton) {
        self.world = forward_kinematics(skeleton, &self.output);
    }

    /// The body moved by `by` at once (a shove).
    pub fn shove(&mut self, by: DVec3) {
        self.output.translations[0] += by;
        for p in &mut self.world.positions {
            *p += by;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::testbody;
    use super::*;

    #[test]
    fn the_shown_posture_follows_its_target_and_settles_on_it() {
        let (sk, _) = testbody::body();
        let rest = testbody::standing(&sk);
        let mut s = Shown::new(rest.clone(), testbody::world(&sk, &rest));
        let target = testbody::moved(&rest, DVec3::new(0.3, 0.0, 0.0));
        // One frame: on its way, not there (accelerations are bounded).
        s.track(&target, 0.12, 1.0 / 60.0);
        let x = s.pose().translations[0].x - rest.translations[0].x;
        assert!(x > 0.0 && x < 0.15, "{x}");
        // A second later: settled, without overshooting on the way.
        let mut most = 0.0f64;
        for _ in 0..60 {
            s.track(&target, 0.12, 1.0 / 60.0);
            most = most.max(s.pose().translations[0].x - rest.translations[0].x);
        }
        let x = s.pose().translations[0].x - rest.translations[0].x;
        assert!((x - 0.3).abs() < 1e-3, "{x}");
        assert!(most < 0.3 + 0.01, "overshot to {most}");
        // Tracking off: the target at once.
        s.track(&rest, 0.0, 1.0 / 60.0);
        assert_eq!(s.pose(), &rest);
        // Shown, then shoved: the world pose moves with the posture.
        s.show(&sk);
        let before = s.world().positions[0];
        s.shove(DVec3::new(0.0, 0.0, 0.2));
        assert_eq!(s.world().positions[0], before + DVec3::new(0.0, 0.0, 0.2));
        s.show(&sk);
        assert!((s.world().positions[0] - (before + DVec3::new(0.0, 0.0, 0.2))).length() < 1e-12);
    }
}
