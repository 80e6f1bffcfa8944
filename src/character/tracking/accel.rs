//! Acceleration-based tracking (the paper's eq. 2–4): the output pose
//! follows the target pose through PD control on accelerations, one gain
//! `k` and damping `d` for every joint (accelerations, not torques, so one
//! pair fits all), and the same on the pelvis position. Integrated
//! semi-implicitly with the frame's real `dt`: velocity first, then
//! position. The result is continuous: a target that jumps (a switch from
//! posing to an action) is reached smoothly, without a pop.

use glam::{DQuat, DVec3};

use crate::character::skeleton::Pose;

/// PD gains on accelerations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gains {
    /// Stiffness, 1/s²: acceleration per radian (or metre) of error.
    pub k: f64,
    /// Damping, 1/s: acceleration per rad/s (or m/s) of velocity.
    pub d: f64,
}

impl Gains {
    /// Critically damped gains that settle in about `settle_s` seconds.
    #[must_use]
    pub fn critical(settle_s: f64) -> Self {
        let w = 4.0 / settle_s.max(1e-3);
        Self {
            k: w * w,
            d: 2.0 * w,
        }
    }
}

impl Default for Gains {
    fn default() -> Self {
        Self::critical(0.15)
    }
}

/// The rotation from `from` to `to` as a rotation vector (axis × angle),
/// the shorter way round: the paper's "difference between two rotations".
#[must_use]
pub fn rotation_difference(from: DQuat, to: DQuat) -> DVec3 {
    let mut q = to * from.inverse();
    if q.w < 0.0 {
        q = -q;
    }
    let (axis, angle) = q.normalize().to_axis_angle();
    if angle.abs() < 1e-12 {
        DVec3::ZERO
    } else {
        axis * angle
    }
}

/// The tracked character: current pose and velocities.
#[derive(Clone, Debug, PartialEq)]
pub struct AccelTracker {
    pub pose: Pose,
    /// Angular velocity of each joint (rad/s, rotation vector in the
    /// parent's frame).
    pub angular_velocity: Vec<DVec3>,
    /// Velocity of the pelvis (root) position (m/s).
    pub root_velocity: DVec3,
}

impl AccelTracker {
    /// Start at rest in `pose`.
    #[must_use]
    pub fn new(pose: Pose) -> Self {
        let n = pose.rotations.len();
        Self {
            pose,
            angular_velocity: vec![DVec3::ZERO; n],
            root_velocity: DVec3::ZERO,
        }
    }

    /// One step of `dt` seconds towards `target` (eq. 2–4).
    pub fn step(&mut self, target: &Pose, gains: Gains, dt: f64) -> &Pose {
        if !(dt.is_finite() && dt > 0.0) {
            return &self.pose;
        }
        for ((q, w), qt) in self
            .pose
            .rotations
            .iter_mut()
            .zip(&mut self.angular_velocity)
            .zip(&target.rotations)
        {
            let acc = rotation_difference(*q, *qt) * gains.k - *w * gains.d;
            *w += acc * dt;
            let turn = *w * dt;
            let angle = turn.length();
            if angle > 1e-12 {
                *q = (DQuat::from_axis_angle(turn / angle, angle) * *q).normalize();
            }
        }
        let p = self.pose.translations[0];
        let acc = (target.translations[0] - p) * gains.k - self.root_velocity * gains.d;
        self.root_velocity += acc * dt;
        self.pose.translations[0] = p + self.root_velocity * dt;
        // Other joints' translations follow the target (bone offsets).
        for (t, tt) in self
            .pose
            .translations
            .iter_mut()
            .zip(&target.translations)
            .skip(1)
        {
            *t = *tt;
        }
        &self.pose
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(angle: f64, x: f64) -> Pose {
        Pose {
            translations: vec![DVec3::new(x, 0.9, 0.0), DVec3::Y * 0.5],
            rotations: vec![DQuat::IDENTITY, DQuat::from_rotation_z(angle)],
        }
    }

    #[test]
    fn reaches_a_target_without_overshoot() {
        let mut t = AccelTracker::new(pose(0.0, 0.0));
        let target = pose(1.2, 0.5);
        let mut last_angle = 0.0;
        for _ in 0..120 {
            t.step(&target, Gains::default(), 1.0 / 60.0);
            let angle = t.pose.rotations[1].angle_between(DQuat::IDENTITY);
            assert!(angle <= 1.2 + 1e-6, "no overshoot: {angle}");
            assert!(angle >= last_angle - 1e-9, "monotone approach");
            last_angle = angle;
        }
        assert!((last_angle - 1.2).abs() < 1e-3, "{last_angle}");
        assert!((t.pose.translations[0].x - 0.5).abs() < 1e-3);
    }

    #[test]
    fn a_jumping_target_gives_continuous_motion() {
        // The paper's use: a switch of controller moves the target at once;
        // the output's velocity changes by at most k·error·dt per frame.
        let gains = Gains::default();
        let dt = 1.0 / 60.0;
        let mut t = AccelTracker::new(pose(0.0, 0.0));
        let mut speeds = Vec::new();
        for frame in 0..90 {
            let target = if frame < 30 {
                pose(0.0, 0.0)
            } else {
                pose(1.0, 0.0)
            };
            t.step(&target, gains, dt);
            speeds.push(t.angular_velocity[1].length());
        }
        let max_jump = speeds
            .windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .fold(0.0, f64::max);
        assert!(
            max_jump <= gains.k * 1.0 * dt + 1e-9,
            "speed jumped {max_jump} rad/s in one frame"
        );
        assert!(speeds.iter().all(|s| s.is_finite()));
    }

    #[test]
    fn takes_the_short_way_round_and_ignores_bad_dt() {
        let d = rotation_difference(DQuat::from_rotation_y(3.0), DQuat::from_rotation_y(-3.0));
        assert!(
            (d.length() - (std::f64::consts::TAU - 6.0)).abs() < 1e-9,
            "{d:?}"
        );
        let mut t = AccelTracker::new(pose(0.3, 0.0));
        let before = t.pose.clone();
        t.step(&pose(1.0, 1.0), Gains::default(), f64::NAN);
        t.step(&pose(1.0, 1.0), Gains::default(), 0.0);
        assert_eq!(t.pose, before);
    }
}
