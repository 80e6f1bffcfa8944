//! A pinhole camera: world points to screen pixels and screen pixels to
//! half-lines (the paper's touch constraints). Pure; the renderer and the
//! controllers share it.

use glam::DVec3;

use crate::screen::ScreenPoint;

/// A half-line from `origin` along the unit vector `dir`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HalfLine {
    pub origin: DVec3,
    pub dir: DVec3,
}

impl HalfLine {
    /// The point of the half-line nearest to `p`.
    #[must_use]
    pub fn closest(&self, p: DVec3) -> DVec3 {
        self.origin + self.dir * (p - self.origin).dot(self.dir).max(0.0)
    }

    /// Distance from `p` to the half-line.
    #[must_use]
    pub fn distance(&self, p: DVec3) -> f64 {
        (p - self.closest(p)).length()
    }
}

/// A perspective camera looking from `eye` at `target`, Y up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: DVec3,
    pub target: DVec3,
    /// Vertical field of view in degrees.
    pub fov_y_deg: f64,
    /// Viewport in pixels.
    pub width: f64,
    pub height: f64,
}

impl Camera {
    fn basis(&self) -> (DVec3, DVec3, DVec3) {
        let forward = (self.target - self.eye).normalize();
        let right = forward.cross(DVec3::Y).try_normalize().unwrap_or(DVec3::X);
        let up = right.cross(forward);
        (right, up, forward)
    }

    fn tan_half(&self) -> (f64, f64) {
        let t = (self.fov_y_deg.to_radians() / 2.0).tan();
        (t * self.width / self.height, t)
    }

    /// Screen position of a world point; `None` behind the camera.
    #[must_use]
    pub fn project(&self, p: DVec3) -> Option<ScreenPoint> {
        let (right, up, forward) = self.basis();
        let v = p - self.eye;
        let z = v.dot(forward);
        if z <= 1e-9 {
            return None;
        }
        let (tx, ty) = self.tan_half();
        let nx = v.dot(right) / (z * tx);
        let ny = v.dot(up) / (z * ty);
        Some(ScreenPoint::new(
            (nx + 1.0) / 2.0 * self.width,
            (1.0 - ny) / 2.0 * self.height,
        ))
    }

    /// The half-line from the eye through a screen point.
    #[must_use]
    pub fn ray(&self, s: ScreenPoint) -> HalfLine {
        let (right, up, forward) = self.basis();
        let (tx, ty) = self.tan_half();
        let nx = s.x / self.width * 2.0 - 1.0;
        let ny = 1.0 - s.y / self.height * 2.0;
        HalfLine {
            origin: self.eye,
            dir: (forward + right * nx * tx + up * ny * ty).normalize(),
        }
    }

    /// The unit vector from the eye towards the target.
    #[must_use]
    pub fn eye_vector(&self) -> DVec3 {
        (self.target - self.eye).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rays_pass_through_the_points_they_come_from() {
        let cam = Camera {
            eye: DVec3::new(3.0, 1.4, 1.0),
            target: DVec3::new(0.0, 1.0, 0.0),
            fov_y_deg: 45.0,
            width: 1280.0,
            height: 720.0,
        };
        for p in [DVec3::new(0.2, 1.5, 0.3), DVec3::new(-0.3, 0.1, -0.2)] {
            let s = cam.project(p).unwrap();
            assert!(cam.ray(s).distance(p) < 1e-9);
        }
        let c = cam.project(cam.target).unwrap();
        assert!((c.x - 640.0).abs() < 1e-9 && (c.y - 360.0).abs() < 1e-9);
        assert!(
            cam.project(DVec3::new(6.0, 1.4, 2.0)).is_none(),
            "behind the eye"
        );
    }
}
