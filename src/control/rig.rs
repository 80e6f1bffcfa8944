//! The camera rig: an orbit around the character that visitors turn, tilt
//! and zoom with fingers on empty space, within limits that keep the
//! character in view, easing back to its home view when the table is idle.

use glam::{DQuat, DVec3};

use crate::character::camera::Camera;
use crate::screen::ScreenPoint;

/// Limits and the home view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigLimits {
    /// Tilt above the horizontal (radians).
    pub min_pitch: f64,
    pub max_pitch: f64,
    /// Distance from the eye to the point looked at (m).
    pub min_distance: f64,
    pub max_distance: f64,
    /// Radians of turn per pixel of one-finger drag.
    pub orbit_per_px: f64,
}

impl Default for RigLimits {
    fn default() -> Self {
        Self {
            // Never overhead: from above 40° a figure reads as a head and
            // shoulders, and drags of its parts lose their height.
            min_pitch: (-2.0f64).to_radians(),
            max_pitch: 40.0f64.to_radians(),
            // The whole body (0 to 1.9 m around the look-at point at
            // 0.95 m) stays in a 40° view from 3 m; from 6 m, tilted as
            // far as it goes, a 1.7 m figure still fills a quarter of the
            // picture's height (8 m and 65° left it 80 px of 720).
            min_distance: 3.0,
            max_distance: 6.0,
            orbit_per_px: 0.006,
        }
    }
}

/// Where the camera is on its orbit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    /// Turn around the vertical (radians; 0 looks along −Z from +Z).
    pub yaw: f64,
    pub pitch: f64,
    pub distance: f64,
}

impl Orbit {
    /// The home view: from the character's front left, three quarters to
    /// the side (actions along the facing direction are more than 45° from
    /// the line of sight, so drags can start them), a little above chest
    /// height.
    pub const HOME: Orbit = Orbit {
        yaw: 1.0,
        pitch: 0.22,
        distance: 3.6,
    };
}

/// The camera rig.
#[derive(Clone, Debug, PartialEq)]
pub struct Rig {
    pub orbit: Orbit,
    pub home: Orbit,
    pub limits: RigLimits,
    /// The point looked at: above the character's floor point.
    pub target: DVec3,
    pub fov_y_deg: f64,
    /// Picture size in pixels.
    pub width: f64,
    pub height: f64,
}

/// Height of the point looked at (m).
const LOOK_HEIGHT: f64 = 0.95;

impl Rig {
    #[must_use]
    pub fn new(width: f64, height: f64) -> Self {
        // Portrait pictures need a wider view to show the whole body.
        let fov = if height > width { 55.0 } else { 40.0 };
        Self {
            orbit: Orbit::HOME,
            home: Orbit::HOME,
            limits: RigLimits::default(),
            target: DVec3::new(0.0, LOOK_HEIGHT, 0.0),
            fov_y_deg: fov,
            width,
            height,
        }
    }

    /// The camera for the current orbit.
    #[must_use]
    pub fn camera(&self) -> Camera {
        let o = &self.orbit;
        let dir = DQuat::from_rotation_y(o.yaw) * DVec3::new(0.0, o.pitch.sin(), o.pitch.cos());
        Camera {
            eye: self.target + dir * o.distance,
            target: self.target,
            fov_y_deg: self.fov_y_deg,
            width: self.width,
            height: self.height,
        }
    }

    fn clamp(&mut self) {
        let l = &self.limits;
        self.orbit.pitch = self.orbit.pitch.clamp(l.min_pitch, l.max_pitch);
        self.orbit.distance = self.orbit.distance.clamp(l.min_distance, l.max_distance);
    }

    /// One finger dragged by (`dx`, `dy`) pixels: turn and tilt.
    pub fn drag(&mut self, dx: f64, dy: f64) {
        self.orbit.yaw -= dx * self.limits.orbit_per_px;
        self.orbit.pitch += dy * self.limits.orbit_per_px;
        self.clamp();
    }

    /// Two fingers: their distance grew by `ratio` (zoom in) and their
    /// direction turned by `twist` radians (turn the view with them).
    pub fn pinch(&mut self, ratio: f64, twist: f64) {
        if ratio.is_finite() && ratio > 0.0 {
            self.orbit.distance /= ratio;
        }
        if twist.is_finite() {
            self.orbit.yaw += twist;
        }
        self.clamp();
    }

    /// Fingers on empty space moved from the first point of each pair to
    /// the second: one turns and tilts the view, two zoom and turn it.
    pub fn gesture(&mut self, moves: &[(ScreenPoint, ScreenPoint)]) {
        match moves {
            [(a, b)] => self.drag(b.x - a.x, b.y - a.y),
            [(a0, a1), (b0, b1), ..] => {
                let d0 = a0.distance(*b0);
                let d1 = a1.distance(*b1);
                let ang = |p: &ScreenPoint, q: &ScreenPoint| (q.y - p.y).atan2(q.x - p.x);
                let twist = crate::character::body::wrap(ang(a1, b1) - ang(a0, b0));
                if d0 > 10.0 {
                    self.pinch(d1 / d0, twist);
                }
            }
            [] => {}
        }
    }

    /// Ease the look-at point towards above `floor_point` and, when
    /// `go_home`, the orbit towards home; `dt` seconds passed.
    pub fn settle(&mut self, floor_point: DVec3, go_home: bool, dt: f64) {
        let k = 1.0 - (-dt / 0.6).exp();
        let goal = DVec3::new(floor_point.x, LOOK_HEIGHT, floor_point.z);
        self.target += (goal - self.target) * k;
        if go_home {
            let h = self.home;
            let o = &mut self.orbit;
            let dyaw = crate::character::body::wrap(h.yaw - o.yaw);
            o.yaw += dyaw * k;
            o.pitch += (h.pitch - o.pitch) * k;
            o.distance += (h.distance - o.distance) * k;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_keep_the_character_in_view() {
        let mut r = Rig::new(1280.0, 720.0);
        r.drag(0.0, 1e6);
        r.pinch(100.0, 0.0);
        assert_eq!(r.orbit.pitch, r.limits.max_pitch);
        assert_eq!(r.orbit.distance, r.limits.min_distance);
        let c = r.camera();
        let s = c.project(DVec3::new(0.0, 0.9, 0.0)).unwrap();
        assert!(s.x > 0.0 && s.x < 1280.0 && s.y > 0.0 && s.y < 720.0);
        r.pinch(1e-6, f64::NAN);
        assert_eq!(r.orbit.distance, r.limits.max_distance);
    }

    #[test]
    fn the_view_eases_home_when_idle() {
        let mut r = Rig::new(1280.0, 720.0);
        r.drag(300.0, -40.0);
        for _ in 0..150 {
            r.settle(DVec3::ZERO, true, 1.0 / 30.0);
        }
        assert!((r.orbit.yaw - r.home.yaw).abs() < 1e-2);
        assert!((r.orbit.pitch - r.home.pitch).abs() < 1e-2);
    }
}
