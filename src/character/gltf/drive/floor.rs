//! Keeping a figure's mesh off the floor: a foot or hand whose points
//! went under is turned flatter about its ankle or wrist and lifted, a
//! one-bone arm too long to hang is swung up about its shoulder, a bow
//! that would put the head under is turned back up, and what is left
//! raises the whole figure.

use glam::{DMat4, DQuat, DVec3};

use super::{Drive, LIMBS, Settled};
use crate::character::gltf::Figure;
use crate::character::roles::Role;
use crate::character::skeleton::WorldPose;

/// Turns tried, up to [`FLATTEN_MAX`], to bring a foot's sole off the
/// floor.
const FLATTEN_STEPS: u8 = 8;

/// The most a foot is turned flatter to keep its sole off the floor
/// before it is lifted (rad, about 23 degrees).
const FLATTEN_MAX: f64 = 0.4;

/// The most a hand is turned about its wrist to keep what it holds off
/// the floor before it is lifted (rad, a quarter turn: a sword hanging
/// from it held level).
const HAND_TURN_MAX: f64 = std::f64::consts::FRAC_PI_2;

/// How near the floor (m) a hand's points come before all it carries is
/// looked at (`limbs::near_points`): more than the points kept for it
/// miss by (7.7 mm, a knight's shield rim).
const NEAR_M: f64 = 0.05;

impl Drive {
    /// The figure placed by `w` for the library's posture `lib` (standing
    /// `raise` off it), each limb put on the library's end and kept off
    /// the floor (see the module).
    pub(super) fn off_the_floor(
        &self,
        fig: &Figure,
        lib: &WorldPose,
        w: &[DMat4],
        raise: DVec3,
        offsets: [DVec3; 2],
    ) -> Settled {
        let mut lift = [0.0f64; 4];
        let mut turn = [DQuat::IDENTITY; 4];
        let mut fixed = self.reach(fig, lib, w, (lift, turn), raise, offsets);
        let mut posed = self.place(fig, lib, &fixed, raise);
        // No sole under the floor: a foot whose lowest point went under is
        // first turned flatter about its ankle (a longer foot than the
        // library's, pointed as steeply, reaches lower), by at most
        // `FLATTEN_MAX`; what is left under lifts it by as much (the leg
        // bends), once more if need be. A hand under the floor (long arms
        // in a crouch, a sword it holds) is first turned about its wrist
        // by at most `HAND_TURN_MAX` as a foot is, then lifted by what is
        // left under.
        for pass in 0..3 {
            let mut under = false;
            let skin = self.skinning(&posed);
            for (k, (_, _, f)) in LIMBS.into_iter().enumerate() {
                let j = self.fig_roles.get(f);
                if self.end_clear(&skin, k) {
                    continue;
                }
                if pass > 0 && !self.one_bone[k] {
                    // Only how far it is under is wanted now.
                    let low = self.end_lowest(&skin, k);
                    if low < -1e-4 {
                        under = true;
                        lift[k] -= low;
                    }
                    continue;
                }
                let points = self.end_now(&skin, k);
                let lowest =
                    |ps: &mut dyn Iterator<Item = DVec3>| ps.min_by(|a, b| a.y.total_cmp(&b.y));
                let Some(low) = lowest(&mut points.iter().copied()) else {
                    continue;
                };
                if low.y >= -1e-4 {
                    continue;
                }
                under = true;
                let ankle = posed[j].w_axis.truncate();
                let axis = (low - ankle).cross(DVec3::Y);
                if k >= 2 && self.one_bone[k] {
                    // A one-bone arm too long to hang where the library's
                    // does (a chibi's): swung up about its shoulder by
                    // the least turn that brings its hand onto the floor.
                    let shoulder = posed[self.fig_roles.get(LIMBS[k].0)].w_axis.truncate();
                    let chest = posed[self.fig_roles.get(Role::Chest)].w_axis.truncate();
                    turn[k] = swing_clear(&points, shoulder, ankle, chest) * turn[k];
                } else if pass == 0 && axis.length() > 1e-9 {
                    // Turned towards raising the lowest point: the least
                    // turn that brings every point onto the floor, else
                    // the one that leaves the lowest highest (raising the
                    // toes lowers the heel).
                    let axis = axis.normalize();
                    let most = if k < 2 { FLATTEN_MAX } else { HAND_TURN_MAX };
                    let angle = flatter(&points, (ankle, axis), low.y, most);
                    turn[k] = DQuat::from_axis_angle(axis, angle) * turn[k];
                } else {
                    lift[k] -= low.y;
                }
            }
            if !under {
                break;
            }
            fixed = self.reach(fig, lib, w, (lift, turn), raise, offsets);
            posed = self.place(fig, lib, &fixed, raise);
        }
        // A limb too short to reach where it is lifted to (a stride longer
        // than the legs, scaled), a head no turn of the trunk lifts: the
        // whole figure rises by what is left.
        let skin = self.skinning(&posed);
        let low = (0..LIMBS.len())
            .map(|k| self.end_lowest(&skin, k))
            .chain([
                self.low.lowest_below(&skin, 0.0),
                self.upright.points.lowest_below(&skin, 0.0),
            ])
            .fold(0.0f64, f64::min);
        if low < -1e-4 {
            for m in &mut posed {
                m.w_axis.y -= low;
            }
        }
        // The lifts of feet the library stands on.
        let standing = |k: usize| if self.stands(lib, k) { lift[k] } else { 0.0 };
        Settled {
            posed,
            lift: [standing(0), standing(1)],
            rise: (-low).max(0.0),
        }
    }

    /// A bow that would put the head under the floor (the figure placed
    /// by `w`, standing `raise` off the library's): the library's posture
    /// with the trunk turned back up, the legs as they were (so `raise`
    /// holds).
    pub(super) fn turned_up(
        &self,
        fig: &Figure,
        lib: &WorldPose,
        w: &[DMat4],
        raise: DVec3,
    ) -> Option<WorldPose> {
        let head_lowest = |w: &[DMat4]| self.upright.points.lowest_below(&self.skinning(w), 0.0);
        if head_lowest(w) >= 0.0 {
            return None;
        }
        let free = vec![None; fig.rest.len()];
        self.upright
            .turned(lib, |l| head_lowest(&self.place(fig, l, &free, raise)))
    }

    /// The height of foot `k`'s lowest mesh point (0 left, 1 right) in
    /// the posture `posed` (joint transforms from [`Self::pose`]).
    #[must_use]
    pub fn foot_lowest(&self, posed: &[DMat4], k: usize) -> Option<f64> {
        self.end_now(&self.skinning(posed), k.min(1))
            .into_iter()
            .map(|p| p.y)
            .min_by(f64::total_cmp)
    }

    /// Where limb `k`'s end's mesh points are for skinning matrices
    /// `skin` (from [`Self::skinning`] of a posture, made once for all
    /// four limbs): a hand near the floor by all it carries.
    fn end_now(&self, skin: &[DMat4], k: usize) -> Vec<DVec3> {
        let kept = self.ends[k].now(skin);
        if !self.near[k].is_empty() && kept.iter().any(|p| p.y < NEAR_M) {
            return self.near[k].now(skin);
        }
        kept
    }

    /// The height of limb `k`'s end's lowest mesh point
    /// ([`Self::end_now`]), or 0 where none is under the floor.
    fn end_lowest(&self, skin: &[DMat4], k: usize) -> f64 {
        if self.near[k].is_empty() || self.ends[k].lowest_below(skin, NEAR_M) >= NEAR_M {
            self.ends[k].lowest_below(skin, 0.0)
        } else {
            self.near[k].lowest_below(skin, 0.0)
        }
    }

    /// Whether none of limb `k`'s end's mesh points ([`Self::end_now`])
    /// can be under the floor for skinning matrices `skin`.
    fn end_clear(&self, skin: &[DMat4], k: usize) -> bool {
        self.ends[k].floor_bound(skin) >= -1e-4
            && (self.near[k].is_empty() || self.near[k].floor_bound(skin) >= -1e-4)
    }
}

/// How far to turn a foot's or hand's `points` about its `ankle` and
/// `axis` (up to `most`, in [`FLATTEN_STEPS`]) to raise the lowest, now
/// at `low_y`: the least turn that brings every point onto the floor,
/// else the one that leaves the lowest highest (raising the toes lowers
/// the heel).
fn flatter(points: &[DVec3], (ankle, axis): (DVec3, DVec3), low_y: f64, most: f64) -> f64 {
    let low_after = |angle: f64| {
        // Only the height is wanted: the turn's row that gives it.
        let up = glam::DMat3::from_quat(DQuat::from_axis_angle(axis, angle)).row(1);
        points
            .iter()
            .map(|p| ankle.y + up.dot(*p - ankle))
            .min_by(f64::total_cmp)
            .unwrap_or(f64::NEG_INFINITY)
    };
    let mut best = (0.0, low_y);
    for step in 1..=FLATTEN_STEPS {
        let angle = most * f64::from(step) / f64::from(FLATTEN_STEPS);
        let y = low_after(angle);
        if y > best.1 + 1e-6 {
            best = (angle, y);
        }
        if y >= 0.0 {
            break;
        }
    }
    best.0
}

/// The least turn about `shoulder` that brings every point of `points`
/// (a one-bone arm's hand, posed) onto the floor: the arm swung up
/// towards where it reaches along the floor, or out from the chest where
/// it hangs straight down; at most to the horizontal.
fn swing_clear(points: &[DVec3], shoulder: DVec3, hand: DVec3, chest: DVec3) -> DQuat {
    let arm = hand - shoulder;
    let along = arm.with_y(0.0);
    let out = if along.length() > 0.2 * arm.length() {
        along
    } else {
        (shoulder - chest).with_y(0.0)
    };
    let axis = arm.cross(out);
    if arm.length() < 1e-9 || axis.length() < 1e-9 {
        return DQuat::IDENTITY;
    }
    let axis = axis.normalize();
    let lowest = |angle: f64| {
        let q = DQuat::from_axis_angle(axis, angle);
        points
            .iter()
            .map(|p| (shoulder + q * (*p - shoulder)).y)
            .fold(f64::INFINITY, f64::min)
    };
    let most = arm.angle_between(out);
    if lowest(most) < 0.0 {
        return DQuat::from_axis_angle(axis, most);
    }
    let (mut lo, mut hi) = (0.0, most);
    for _ in 0..24 {
        let mid = (lo + hi) / 2.0;
        if lowest(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    DQuat::from_axis_angle(axis, hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_long_arm_is_swung_out_by_the_least_turn_that_clears_the_floor() {
        // A shoulder 0.6 m up, an arm hanging 0.9 m straight down: its
        // hand 0.3 m under the floor, the chest to its right.
        let shoulder = DVec3::new(0.2, 0.6, 0.0);
        let hand = DVec3::new(0.2, -0.3, 0.0);
        let points = [hand, hand + DVec3::new(0.0, -0.05, 0.0)];
        let q = swing_clear(&points, shoulder, hand, DVec3::new(0.0, 0.6, 0.0));
        let moved: Vec<DVec3> = points
            .iter()
            .map(|p| shoulder + q * (*p - shoulder))
            .collect();
        let low = moved.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
        assert!(low.abs() < 1e-6, "{moved:?}");
        // Out to the side, away from the chest; the least turn: the
        // arm's 0.95 m reach meets the floor at acos(0.6 / 0.95).
        assert!(moved[0].x > 0.2, "{moved:?}");
        let angle = q.to_axis_angle().1;
        assert!((angle - (0.6f64 / 0.95).acos()).abs() < 1e-4, "{angle}");
        // An arm already clear is not turned.
        let up = [DVec3::new(0.2, 0.1, 0.0)];
        let q = swing_clear(&up, shoulder, up[0], DVec3::new(0.0, 0.6, 0.0));
        assert!(q.to_axis_angle().1.abs() < 1e-6);
    }
}
