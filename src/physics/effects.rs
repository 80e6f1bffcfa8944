//! Physical effects (the paper's eq. 6–7): the ragdoll's motion, not its
//! posture, is added to the tracked posture. Per segment, the change of
//! its simulated rotation relative to its parent segment is accumulated
//! with attenuation,
//!
//!   Δq_i = s1 · Δq_i' + s2 · (q_sim,i − q_sim,i'),
//!
//! and added to the joint's tracked rotation in the regions (two arms, two
//! legs, the torso) that no finger holds and that do not touch the floor;
//! the same on the pelvis's position and rotation. The paper gives
//! s1 = 0.2 Δt and s2 = 0.5 Δt; read with Δt in seconds they would leave
//! nothing to see, so Δt is read in frames of 1/30 s: at 30 frames a
//! second s1 = 0.2 and s2 = 0.5, and both scale with the frame time.
//! A region's effect fades in and out over about 0.1 s when its condition
//! changes, so switching never pops.

use glam::{DQuat, DVec3};

use super::ragdoll::{Segment, SimState};
use crate::character::skeleton::rotation_difference;
use crate::character::skeleton::{Pose, Skeleton, WorldPose};
use crate::physics::body::Region;

/// The paper's reference frame time for s1 and s2 (s).
pub const REFERENCE_FRAME_S: f64 = 1.0 / 30.0;

/// Attenuation parameters of eq. 6, per frame of [`REFERENCE_FRAME_S`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Attenuation {
    pub s1: f64,
    pub s2: f64,
}

impl Default for Attenuation {
    fn default() -> Self {
        Self { s1: 0.2, s2: 0.5 }
    }
}

/// The largest effect on a joint (rad) or on the pelvis (m): what the
/// ragdoll adds stays an effect, never a posture of its own.
const MAX_ROTATION: f64 = 0.6;
const MAX_OFFSET: f64 = 0.1;

/// The effects' own acceleration is bounded (rad/s², m/s²): added to
/// tracking's bound (200 rad/s²) a joint's speed still changes by less than
/// 10 rad/s in a 1/30 s frame, so the effects never pop.
const MAX_EFFECT_ACCEL: f64 = 90.0;
const MAX_EFFECT_ACCEL_ROOT: f64 = 10.0;

/// Move `value` (changing by `rate` per frame) towards `next`, changing
/// its rate by at most `max_change`: the new value and rate.
fn bounded(value: DVec3, rate: DVec3, next: DVec3, max_change: f64) -> (DVec3, DVec3) {
    let rate = rate + (next - value - rate).clamp_length_max(max_change);
    (value + rate, rate)
}

/// Accumulated effects between frames.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Effects {
    pub attenuation: Attenuation,
    /// Last frame's simulated rotation of each segment relative to its
    /// parent (the pelvis: its world rotation) and the pelvis position.
    last: Option<(Vec<DQuat>, DVec3)>,
    /// Δq per segment (rotation vector, in its parent's rest axes), and
    /// its change over the last frame.
    delta: Vec<DVec3>,
    delta_rate: Vec<DVec3>,
    /// Δ of the pelvis position (m) and its change over the last frame;
    /// its rotation is the first segment's.
    root: DVec3,
    root_rate: DVec3,
    /// How much of each region's effect shows (0..1).
    weight: [f64; 5],
    /// How much of the pelvis's effect shows (0..1).
    root_weight: f64,
}

impl Effects {
    #[must_use]
    pub fn new(attenuation: Attenuation) -> Self {
        Self {
            attenuation,
            ..Self::default()
        }
    }

    /// Forget the ragdoll's last state (after it was put back): no
    /// velocity is read across a reset.
    pub fn forget(&mut self) {
        self.last = None;
    }

    /// Eq. 6 for one frame of `dt` seconds.
    pub fn update(&mut self, segments: &[Segment], states: &[SimState], dt: f64) {
        let frames = (dt / REFERENCE_FRAME_S).max(0.0);
        let (s1, s2) = (
            (self.attenuation.s1 * frames).clamp(0.0, 0.95),
            self.attenuation.s2 * frames,
        );
        let relative: Vec<DQuat> = segments
            .iter()
            .zip(states)
            .map(|(s, st)| match s.parent() {
                Some(p) => (states[p].rotation.inverse() * st.rotation).normalize(),
                None => st.rotation,
            })
            .collect();
        let root_pos = states.first().map_or(DVec3::ZERO, |s| s.position);
        self.delta.resize(segments.len(), DVec3::ZERO);
        self.delta_rate.resize(segments.len(), DVec3::ZERO);
        if let Some((last, last_root)) = &self.last {
            let dt2 = dt * dt;
            for k in 0..segments.len() {
                // In the parent's axes (rest-relative) for children, world
                // axes for the pelvis.
                let change = rotation_difference(last[k], relative[k]);
                let next = (self.delta[k] * s1 + change * s2).clamp_length_max(MAX_ROTATION);
                (self.delta[k], self.delta_rate[k]) = bounded(
                    self.delta[k],
                    self.delta_rate[k],
                    next,
                    MAX_EFFECT_ACCEL * dt2,
                );
            }
            let next = (self.root * s1 + (root_pos - *last_root) * s2).clamp_length_max(MAX_OFFSET);
            (self.root, self.root_rate) =
                bounded(self.root, self.root_rate, next, MAX_EFFECT_ACCEL_ROOT * dt2);
        }
        if relative.iter().all(|q| q.is_finite()) && root_pos.is_finite() {
            self.last = Some((relative, root_pos));
        } else {
            self.last = None;
            self.delta.fill(DVec3::ZERO);
            self.delta_rate.fill(DVec3::ZERO);
            self.root = DVec3::ZERO;
            self.root_rate = DVec3::ZERO;
        }
    }

    /// Move each region's (and the pelvis's) weight towards showing its
    /// effect or not, over about 0.1 s.
    pub fn set_active(&mut self, regions: [bool; 5], root: bool, dt: f64) {
        let rate = 1.0 - (-dt.max(0.0) / 0.1).exp();
        for (w, on) in self.weight.iter_mut().zip(regions) {
            *w += (f64::from(u8::from(on)) - *w) * rate;
        }
        self.root_weight += (f64::from(u8::from(root)) - self.root_weight) * rate;
    }

    /// Eq. 7: add the effects to `pose` (the tracked posture; `w` its
    /// world transforms).
    pub fn apply(&self, skeleton: &Skeleton, segments: &[Segment], pose: &mut Pose, w: &WorldPose) {
        if self.delta.len() != segments.len() {
            return;
        }
        for (k, s) in segments.iter().enumerate() {
            let (weight, world) = match s.parent() {
                // Δq is in the parent segment's rest axes: into world axes
                // with the parent's posture.
                Some(p) => (
                    self.weight[s.region().index()],
                    segments[p].rotation_in(w) * self.delta[k],
                ),
                // The pelvis: world axes already.
                None => (self.root_weight, self.delta[k]),
            };
            if weight < 1e-3 {
                continue;
            }
            // Into the axes of the joint's skeleton parent, in which its
            // rotation is given.
            let j = s.joint();
            let parent_rot = skeleton.joints[j]
                .parent
                .map_or(DQuat::IDENTITY, |q| w.rotations[q]);
            let local = parent_rot.inverse() * world * weight;
            pose.rotations[j] = (quat_from_vector(local) * pose.rotations[j]).normalize();
        }
        if self.root_weight > 1e-3 && !pose.translations.is_empty() {
            pose.translations[0] += self.root * self.root_weight;
        }
    }
}

/// The rotation of a rotation vector (axis × angle).
#[must_use]
pub fn quat_from_vector(v: DVec3) -> DQuat {
    let angle = v.length();
    if angle < 1e-12 {
        DQuat::IDENTITY
    } else {
        DQuat::from_axis_angle(v / angle, angle)
    }
}

/// Which regions are free for effects: not held by a finger, not touching
/// the floor.
#[must_use]
pub fn free_regions(held: &[Region], touching: &[Region]) -> [bool; 5] {
    Region::ALL.map(|r| !held.contains(&r) && !touching.contains(&r))
}
