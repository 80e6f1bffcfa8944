//! Acceleration-based tracking (the paper's eq. 2–4): the output pose
//! follows the target pose through PD control on accelerations, one gain
//! `k` and damping `d` for every joint (accelerations, not torques, so one
//! pair fits all), and the same on the pelvis position. Integrated
//! semi-implicitly with the frame's real `dt`: velocity first, then
//! position. The result is continuous: a target that jumps (a switch from
//! posing to an action) is reached smoothly, without a pop.

use glam::{DQuat, DVec3};

use crate::character::skeleton::{Pose, rotation_difference};

/// Default bound on the joints' acceleration (rad/s²): above what the
/// library's quickest motions need (kicks and punches reach about
/// 100 rad/s²), low enough that a jump in the target shows as a quick
/// motion (at most 6.7 rad/s of speed change per 1/30 s frame) rather than
/// a pop. With the default gains it causes no overshoot.
pub const MAX_TRACKING_ACCEL: f64 = 200.0;

/// Default bound on the pelvis's acceleration (m/s²): a jump's take-off
/// needs about 2 g.
pub const MAX_TRACKING_ACCEL_ROOT: f64 = 40.0;

/// PD gains on accelerations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gains {
    /// Stiffness, 1/s²: acceleration per radian (or metre) of error.
    pub k: f64,
    /// Damping, 1/s: acceleration per rad/s (or m/s) of velocity.
    pub d: f64,
    /// Accelerations are bounded by this (rad/s², joints): a target that
    /// jumps far (an action starting, a posture blend that switches) is
    /// reached quickly but no joint's speed changes by more than this
    /// times the frame time.
    pub max_accel: f64,
    /// The same for the pelvis position (m/s²).
    pub max_accel_root: f64,
}

impl Gains {
    /// Critically damped gains that settle in about `settle_s` seconds.
    #[must_use]
    pub fn critical(settle_s: f64) -> Self {
        let w = 4.0 / settle_s.max(1e-3);
        Self {
            k: w * w,
            d: 2.0 * w,
            max_accel: MAX_TRACKING_ACCEL,
            max_accel_root: MAX_TRACKING_ACCEL_ROOT,
        }
    }
}

impl Default for Gains {
    fn default() -> Self {
        Self::critical(0.15)
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
            let acc = (rotation_difference(*q, *qt) * gains.k - *w * gains.d)
                .clamp_length_max(gains.max_accel);
            *w += acc * dt;
            let turn = *w * dt;
            let angle = turn.length();
            if angle > 1e-12 {
                *q = (DQuat::from_axis_angle(turn / angle, angle) * *q).normalize();
            }
        }
        let p = self.pose.translations[0];
        let acc = ((target.translations[0] - p) * gains.k - self.root_velocity * gains.d)
            .clamp_length_max(gains.max_accel_root);
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

    /// The same gains without saturation: the pure eq. 2–3.
    fn unlimited(g: Gains) -> Gains {
        Gains {
            max_accel: f64::INFINITY,
            max_accel_root: f64::INFINITY,
            ..g
        }
    }

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
            t.step(&target, unlimited(gains), dt);
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
    fn bounded_accelerations_reach_far_targets_without_a_pop() {
        // A target 2.5 rad away (an action starting far from the posture
        // shown): the speed never changes by more than max_accel · dt in a
        // frame, there is no overshoot, and it is reached within 0.5 s.
        let gains = Gains::default();
        let dt = 1.0 / 30.0;
        let mut t = AccelTracker::new(pose(0.0, 0.0));
        let target = pose(2.5, 0.3);
        let mut last_speed = 0.0;
        for frame in 0..30 {
            for _ in 0..8 {
                t.step(&target, gains, dt / 8.0);
            }
            let speed = t.angular_velocity[1].length();
            assert!(
                (speed - last_speed).abs() <= gains.max_accel * dt + 1e-9,
                "frame {frame}: speed {last_speed} -> {speed}"
            );
            last_speed = speed;
            let angle = t.pose.rotations[1].angle_between(DQuat::IDENTITY);
            assert!(angle <= 2.5 + 1e-6, "overshoot {angle}");
            if frame == 15 {
                assert!((angle - 2.5).abs() < 0.05, "reached late: {angle}");
            }
        }
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
