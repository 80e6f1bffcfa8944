//! The library's locomotion frames, ready for matching: each frame's
//! posture with its facing removed, how its root moves to the next frame
//! (in its own facing frame), and the features a walk is matched on: where
//! its root goes over the next second and which way it faces 0.6 s on,
//! where its feet are and how they and the root move (in the manner of
//! motion matching).

use glam::{DQuat, DVec3};

use crate::character::body::{facing_yaw, wrap};
use crate::character::library::Library;
use crate::character::motion::Clip;
use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::{WorldPose, forward_kinematics};

/// Seconds ahead at which the root's future places are matched.
pub(crate) const FUTURE_S: [f64; 3] = [0.3, 0.6, 0.9];

/// How many numbers describe a frame for matching.
pub(crate) const FEATURES: usize = 20;

/// Seconds ahead at which the frame's facing is matched...
pub(crate) const FACING_S: f64 = 0.6;
/// ...by the features from this one on: the sine and cosine of its turn
/// from the facing now (the last two).
pub(crate) const FACING: usize = 18;

/// A clip that travels less than this (m, root over the floor) is not
/// locomotion: it is said so at load and left out.
pub const MIN_TRAVEL_M: f64 = 0.5;

/// A foot within this height of its lowest in the clip (m)...
const CONTACT_M: f64 = 0.02;
/// ...and slower than this (m/s) stands on the floor.
const CONTACT_SPEED: f64 = 0.3;

/// One frame of a locomotion clip.
#[derive(Clone, Debug)]
pub struct GaitFrame {
    /// Index of the clip in [`Gait::clips`].
    pub clip: usize,
    /// Local rotations; the root's with its facing removed.
    pub rotations: Vec<DQuat>,
    /// The root's height (m).
    pub root_y: f64,
    /// The root's move to the next frame: x and z in this frame's facing
    /// frame (m), and the turn (radians, positive towards +X).
    pub step: DVec3,
    pub turn: f64,
    /// Whether each foot (left, right) stands on the floor here: low and
    /// nearly still.
    pub contacts: [bool; 2],
    /// How soon a foot leaves the floor from here in its clip (s; 0 where
    /// one is off it, infinite where none leaves it again).
    pub lift_in_s: f64,
    /// What a walk is matched on (see the module).
    pub features: [f64; FEATURES],
}

/// A locomotion clip's place among the frames.
#[derive(Clone, Debug)]
pub struct GaitClip {
    pub name: String,
    /// Its frames are `first..first + len` of [`Gait::frames`].
    pub first: usize,
    pub len: usize,
    pub frame_time: f64,
    /// Its steadiest speed over the floor (m/s): the median of its frames'.
    pub speed: f64,
}

/// Every locomotion frame of a library.
#[derive(Clone, Debug, Default)]
pub struct Gait {
    pub frames: Vec<GaitFrame>,
    pub clips: Vec<GaitClip>,
}

impl Gait {
    /// The locomotion clips of `lib` (its `[locomotion]` section) made
    /// ready; a clip that does not travel is left out with a warning.
    #[must_use]
    pub fn build(lib: &Library, roles: &RoleMap) -> Self {
        let mut gait = Self::default();
        for name in &lib.locomotion {
            let Some(clip) = lib.clips.get(name) else {
                continue;
            };
            if clip.frames.len() < 2 {
                tracing::warn!(clip = %name, "a locomotion clip of one frame cannot walk: left out");
                continue;
            }
            let worlds: Vec<_> = clip
                .frames
                .iter()
                .map(|p| forward_kinematics(&clip.skeleton, p))
                .collect();
            let root: Vec<DVec3> = worlds.iter().map(|w| w.positions[0].with_y(0.0)).collect();
            let travel = root.windows(2).map(|w| (w[1] - w[0]).length()).sum::<f64>();
            let reach = root
                .iter()
                .map(|p| (*p - root[0]).length())
                .fold(0.0, f64::max);
            if reach < MIN_TRAVEL_M {
                tracing::warn!(
                    clip = %name,
                    travel_m = travel,
                    farthest_m = reach,
                    "a locomotion clip whose root comes no farther than {MIN_TRAVEL_M} m from where it starts does not travel: left out (list it under [posing] or an action instead)"
                );
                continue;
            }
            let yaw: Vec<f64> = worlds.iter().map(|w| facing_yaw(w, roles)).collect();
            let dt = clip.frame_time;
            let n = clip.frames.len();
            let feet = [Role::LeftFoot, Role::RightFoot].map(|r| roles.get(r));
            let index = gait.clips.len();
            let first = gait.frames.len();
            let mut speeds = Vec::with_capacity(n);
            let lowest = feet.map(|j| {
                worlds
                    .iter()
                    .map(|w| w.positions[j].y)
                    .fold(f64::INFINITY, f64::min)
            });
            for k in 0..n {
                let unyaw = DQuat::from_rotation_y(-yaw[k]);
                let next = (k + 1).min(n - 1);
                let step = unyaw * (root[next] - root[k]);
                speeds.push(step.length() / dt);
                let mut features = features(&worlds, &root, feet, k, dt, unyaw);
                // Where the frame faces `FACING_S` on, from its facing now.
                let later = ((k as f64 + FACING_S / dt).round() as usize).min(n - 1);
                let turned = wrap(yaw[later] - yaw[k]);
                features[FACING] = turned.sin();
                features[FACING + 1] = turned.cos();
                let mut rotations = clip.frames[k].rotations.clone();
                rotations[0] = (unyaw * worlds[k].rotations[0]).normalize();
                let contacts = [0, 1].map(|i| {
                    let (p, q) = (
                        worlds[k].positions[feet[i]],
                        worlds[next].positions[feet[i]],
                    );
                    p.y <= lowest[i] + CONTACT_M
                        && (q - p).with_y(0.0).length() / dt < CONTACT_SPEED
                });
                gait.frames.push(GaitFrame {
                    clip: index,
                    rotations,
                    root_y: worlds[k].positions[0].y,
                    step: step.with_y(0.0),
                    turn: wrap(yaw[next] - yaw[k]),
                    contacts,
                    lift_in_s: f64::INFINITY,
                    features,
                });
            }
            let mut lift_in = f64::INFINITY;
            for f in gait.frames[first..].iter_mut().rev() {
                lift_in = if f.contacts.iter().all(|c| *c) {
                    lift_in + dt
                } else {
                    0.0
                };
                f.lift_in_s = lift_in;
            }
            speeds.sort_by(f64::total_cmp);
            let speed = speeds[speeds.len() / 2];
            tracing::debug!(clip = %name, frames = n, travel_m = travel, speed_m_s = speed, "locomotion clip");
            gait.clips.push(GaitClip {
                name: name.clone(),
                first,
                len: n,
                frame_time: dt,
                speed,
            });
        }
        gait
    }

    /// Whether the library can walk.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.clips.is_empty()
    }

    /// The fastest of the clips' steady speeds (m/s).
    #[must_use]
    pub fn top_speed(&self) -> f64 {
        self.clips.iter().map(|c| c.speed).fold(0.0, f64::max)
    }

    /// The slowest of the clips' steady speeds (m/s).
    #[must_use]
    pub fn low_speed(&self) -> f64 {
        self.clips
            .iter()
            .map(|c| c.speed)
            .fold(f64::INFINITY, f64::min)
    }

    /// The frame whose features are nearest `query` (weights per feature),
    /// with its cost; a clip's last frame (nothing follows it) is passed
    /// over.
    #[must_use]
    pub fn best(&self, query: &[f64; FEATURES], weights: &[f64; FEATURES]) -> Option<(usize, f64)> {
        self.best_left(query, weights, 0.0, f64::INFINITY)
    }

    /// [`Self::best`] among the frames with at least `room_s` seconds of
    /// their clip after them (a walk that starts does not start in a
    /// clip's stop) from which a foot leaves the floor within `lift_s`
    /// (nor in the stand a clip begins with); with none such, among those
    /// with room; with none, among them all.
    #[must_use]
    pub fn best_with_room(
        &self,
        query: &[f64; FEATURES],
        weights: &[f64; FEATURES],
        (room_s, lift_s): (f64, f64),
    ) -> Option<(usize, f64)> {
        self.best_left(query, weights, room_s, lift_s)
            .or_else(|| self.best_left(query, weights, room_s, f64::INFINITY))
            .or_else(|| self.best(query, weights))
    }

    fn best_left(
        &self,
        query: &[f64; FEATURES],
        weights: &[f64; FEATURES],
        room_s: f64,
        lift_s: f64,
    ) -> Option<(usize, f64)> {
        let mut best: Option<(usize, f64)> = None;
        for (i, f) in self.frames.iter().enumerate() {
            let c = &self.clips[f.clip];
            let left = (c.first + c.len).saturating_sub(i + 1);
            if left == 0 || (left as f64) * c.frame_time < room_s || f.lift_in_s > lift_s {
                continue;
            }
            let cost = cost(&f.features, query, weights);
            if best.is_none_or(|(_, b)| cost < b) {
                best = Some((i, cost));
            }
        }
        best
    }
}

/// Frame `k`'s features, in the frame's own facing (`unyaw` turns the
/// world into it): where the root goes over the next [`FUTURE_S`], where
/// the feet (joints `feet`) are and how far they moved over the last
/// 0.1 s, and how far the root moved over the last 0.3 s.
fn features(
    worlds: &[WorldPose],
    root: &[DVec3],
    feet: [usize; 2],
    k: usize,
    dt: f64,
    unyaw: DQuat,
) -> [f64; FEATURES] {
    let n = worlds.len();
    let at = |k: f64| -> usize { (k.round() as usize).min(n - 1) };
    let local = |p: DVec3| unyaw * (p - root[k]);
    let mut features = [0.0; FEATURES];
    for (i, s) in FUTURE_S.iter().enumerate() {
        let f = local(root[at(k as f64 + s / dt)]);
        features[2 * i] = f.x;
        features[2 * i + 1] = f.z;
    }
    // Feet: where they are, and how far they moved over the
    // last 0.1 s; the root: how far it moved over the last 0.3 s.
    let back = at((k as f64 - 0.1 / dt).max(0.0));
    for (i, j) in feet.iter().enumerate() {
        let p = local(worlds[k].positions[*j]);
        features[6 + 3 * i..9 + 3 * i].copy_from_slice(&[p.x, p.y, p.z]);
        let d = unyaw * (worlds[k].positions[*j] - worlds[back].positions[*j]);
        features[12 + 2 * i] = d.x;
        features[13 + 2 * i] = d.z;
    }
    let d = unyaw * (root[k] - root[at((k as f64 - 0.3 / dt).max(0.0))]);
    features[16] = d.x;
    features[17] = d.z;
    features
}

/// How far a clip's root comes from where it starts, over the floor (m).
#[must_use]
pub fn travel_m(clip: &Clip) -> f64 {
    let root = |p: &crate::character::skeleton::Pose| p.translations[0].with_y(0.0);
    let Some(first) = clip.frames.first().map(root) else {
        return 0.0;
    };
    clip.frames
        .iter()
        .map(|p| (root(p) - first).length())
        .fold(0.0, f64::max)
}

/// The weighted squared distance of two feature vectors.
#[must_use]
pub fn cost(a: &[f64; FEATURES], b: &[f64; FEATURES], w: &[f64; FEATURES]) -> f64 {
    a.iter()
        .zip(b)
        .zip(w)
        .map(|((x, y), w)| w * (x - y) * (x - y))
        .sum()
}
