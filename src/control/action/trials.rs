//! The trials a recogniser is judged by, shared by `eval actions` (held-out
//! capture), `library check` and the calibration of the template
//! recogniser (the library's own clips, each left out in turn).
//!
//! For each test clip the dragged part's true path is projected from a side
//! camera and from a 45° front-side camera (both on the part's side of the
//! body) and replayed as a finger trail at ×0.7, ×1 and ×1.5 of its speed
//! with 2 px of noise, one point per frame. After each, a slow posing drag
//! of the same part (as long, in a random direction, at under a third of
//! the speed) must start nothing. Deterministic for a seed.

use glam::{DQuat, DVec3};

use super::trail::TrailPoint;
use crate::character::body::{Anchor, Placement};
use crate::character::camera::Camera;
use crate::character::motion::Clip;
use crate::character::roles::Role;
use crate::character::skeleton::forward_kinematics;
use crate::screen::ScreenPoint;

/// The camera of a trial: `angle_deg` around the character at `at`,
/// 3 m from its chest.
pub fn camera(angle_deg: f64, at: &Placement, chest_height: f64) -> Camera {
    let dir = DQuat::from_rotation_y(at.yaw + angle_deg.to_radians()) * DVec3::Z;
    let target = at.position + DVec3::Y * chest_height;
    Camera {
        eye: target + dir * 3.0,
        target,
        fov_y_deg: 45.0,
        width: 1280.0,
        height: 720.0,
    }
}

/// What a trial needs of a test clip: where its character stands, the
/// dragged part's true path, and its chest height (for the cameras).
pub struct Trial {
    pub at: Placement,
    pub path: Vec<DVec3>,
    pub chest: f64,
}

impl Trial {
    pub fn of(clip: &Clip, role: Role) -> Self {
        let at = Placement {
            anchor: Anchor::ClipStart,
            ..Placement::of(&clip.skeleton, &clip.roles, &clip.frames[0])
        };
        let path = clip
            .frames
            .iter()
            .map(|f| forward_kinematics(&clip.skeleton, f).positions[clip.roles.get(role)])
            .collect();
        let chest = forward_kinematics(&clip.skeleton, &clip.frames[0]).positions
            [clip.roles.get(Role::Chest)]
        .y;
        Self { at, path, chest }
    }
}

/// Which side the trial cameras stand on for a part: -1 for the right
/// side's parts, 1 otherwise.
pub fn side_of(role: Role) -> f64 {
    match role {
        Role::RightHand | Role::RightFoot | Role::RightElbow | Role::RightKnee => -1.0,
        _ => 1.0,
    }
}

/// The two trial views of a part: degrees around the character's facing.
#[must_use]
pub fn views(role: Role) -> [f64; 2] {
    let side = side_of(role);
    [90.0 * side, 45.0 * side]
}

/// The paces a drag is replayed at (times the clip's own speed).
pub const PACES: [f64; 3] = [0.7, 1.0, 1.5];

/// One drag of a trial: the dragged part, the finger's trail on the screen
/// of `camera` (which looks at the clip's character from `angle_deg`
/// around it, at placement `at`), which test it comes from, and whether it
/// is a slow posing drag (that should start nothing).
pub struct Drag<'a> {
    pub role: Role,
    pub trail: &'a [TrailPoint],
    pub camera: &'a Camera,
    pub at: &'a Placement,
    pub angle_deg: f64,
    /// Index into the tests given to [`each_drag`].
    pub test: usize,
    pub slow: bool,
}

/// A small deterministic generator (64-bit LCG, high bits): the noise
/// here, the random paths of `eval walk`.
pub(crate) struct Lcg(pub(crate) u64);

impl Lcg {
    /// The next number in 0..1.
    pub(crate) fn unit(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    /// The next number in `a..b`.
    pub(crate) fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.unit()
    }
    fn noise(&mut self, px: f64) -> f64 {
        (self.unit() * 2.0 - 1.0) * px
    }
}

/// Call `f` with every drag of the trials of `tests` (`(action, dragged
/// part, clip)`): for each clip, view and pace, the true drag then a slow
/// one.
pub fn each_drag(tests: &[(Role, &Clip)], seed: u64, f: &mut dyn FnMut(&Drag<'_>)) {
    let mut rng = Lcg(seed ^ 0x9e37_79b9_7f4a_7c15);
    for (test, &(role, clip)) in tests.iter().enumerate() {
        let Trial { at, path, chest } = Trial::of(clip, role);
        // The cameras stand on the side of the primary part, as a visitor
        // looking at the punching arm would.
        for angle in views(role) {
            let cam = camera(angle, &at, chest);
            for speed in PACES {
                let trail: Vec<TrailPoint> = path
                    .iter()
                    .enumerate()
                    .filter_map(|(k, p)| {
                        cam.project(*p).map(|s| TrailPoint {
                            at: ScreenPoint::new(s.x + rng.noise(2.0), s.y + rng.noise(2.0)),
                            t: k as f64 * clip.frame_time / speed,
                        })
                    })
                    .collect();
                let drag = Drag {
                    role,
                    trail: &trail,
                    camera: &cam,
                    at: &at,
                    angle_deg: angle,
                    test,
                    slow: false,
                };
                f(&drag);
                // A slow posing drag of the same part: as long, in a random
                // direction, at under a third of the speed. (The length of
                // the true path: the noise is not the action's movement.)
                let truth: Vec<ScreenPoint> = path.iter().filter_map(|p| cam.project(*p)).collect();
                let len: f64 = truth.windows(2).map(|w| w[0].distance(w[1])).sum();
                let dir = rng.unit() * std::f64::consts::TAU;
                let duration = trail.last().map_or(1.0, |p| p.t) * (3.0 + rng.unit() * 2.0);
                let start = trail
                    .first()
                    .map_or(ScreenPoint::new(640.0, 360.0), |p| p.at);
                let steps = (duration / clip.frame_time).ceil().max(2.0) as usize;
                let slow: Vec<TrailPoint> = (0..=steps)
                    .map(|k| {
                        let s = k as f64 / steps as f64;
                        let wobble = (s * std::f64::consts::PI * 2.0).sin() * 0.15 * len;
                        TrailPoint {
                            at: ScreenPoint::new(
                                start.x + dir.cos() * len * s - dir.sin() * wobble + rng.noise(2.0),
                                start.y + dir.sin() * len * s + dir.cos() * wobble + rng.noise(2.0),
                            ),
                            t: s * duration,
                        }
                    })
                    .collect();
                f(&Drag {
                    trail: &slow,
                    slow: true,
                    ..drag
                });
            }
        }
    }
}
