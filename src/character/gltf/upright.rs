//! A bow deeper than a figure's head allows: a chibi's head, two fifths of
//! its height, goes through the floor where a person's stops above it (a
//! studio's deep bow); a knight's cape hung from its chest goes under in
//! a lean. The library's upper body is turned back up about its pelvis by
//! the least turn that keeps the head's mesh and what the trunk carries
//! off the floor (rather than the whole figure raised off its feet); the
//! legs stay where the library puts them, and the arms turn with the
//! trunk.

use glam::{DQuat, DVec3};

use super::limbs::Carried;
use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::{Skeleton, WorldPose};

/// Halvings of the turn searched for (the most turn, to the head straight
/// above the pelvis, over 4096: under 0.03 degrees).
const STEPS: u32 = 12;

/// What turns a library's upper body back up for one figure.
#[derive(Clone, Debug)]
pub(super) struct Upright {
    /// Per library joint: above the pelvis and not a leg's (turned with
    /// the trunk).
    upper: Vec<bool>,
    /// The library's pelvis and head.
    pelvis: usize,
    head: usize,
    /// The mesh points the figure's head carries (rest pose).
    pub(super) points: Carried,
}

impl Upright {
    /// For `lib` (whose roles are `lib_roles`) and the figure's head's mesh
    /// `points`.
    pub(super) fn new(lib: &Skeleton, lib_roles: &RoleMap, points: Carried) -> Self {
        let pelvis = lib_roles.get(Role::Pelvis);
        let hips = [Role::LeftHip, Role::RightHip].map(|r| lib_roles.get(r));
        let upper = (0..lib.len())
            .map(|j| {
                j != pelvis
                    && lib.is_ancestor(pelvis, j)
                    && hips
                        .iter()
                        .all(|&h| !lib.is_ancestor(j, h) && !lib.is_ancestor(h, j))
            })
            .collect();
        Self {
            upper,
            pelvis,
            head: lib_roles.get(Role::Head),
            points,
        }
    }

    /// For a posture `lib` whose figure has its head under the floor: the
    /// posture with its upper body turned back up by the least turn that
    /// leaves `lowest` (the height of the figure's lowest head point,
    /// posed after a library posture) at the floor or above; `None` where
    /// no turn raises it (the head straight above or below the pelvis). A
    /// head that no turn brings off the floor is turned as far as it
    /// goes, straight above the pelvis.
    pub(super) fn turned(
        &self,
        lib: &WorldPose,
        lowest: impl Fn(&WorldPose) -> f64,
    ) -> Option<WorldPose> {
        let pivot = lib.positions[self.pelvis];
        let up = lib.positions[self.head] - pivot;
        let axis = up.cross(DVec3::Y);
        if axis.length() < 1e-9 * up.length().max(1e-9) {
            return None;
        }
        let axis = axis.normalize();
        let turn = |angle: f64| {
            let q = DQuat::from_axis_angle(axis, angle);
            let mut w = lib.clone();
            for (j, _) in self.upper.iter().enumerate().filter(|(_, u)| **u) {
                w.positions[j] = pivot + q * (lib.positions[j] - pivot);
                w.rotations[j] = (q * lib.rotations[j]).normalize();
            }
            w
        };
        let most = up.angle_between(DVec3::Y);
        let at_most = turn(most);
        if lowest(&at_most) < 0.0 {
            return Some(at_most);
        }
        let (mut lo, mut hi) = (0.0, most);
        for _ in 0..STEPS {
            let mid = (lo + hi) / 2.0;
            if lowest(&turn(mid)) < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Some(turn(hi))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bowed_trunk_is_turned_up_by_the_least_turn_that_clears_the_floor() {
        // A pelvis 1 m up, its chest 0.5 m ahead of it level with it and
        // its head 1 m ahead (bowed flat), a leg down from the pelvis.
        let positions = vec![
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.5),
            DVec3::new(0.0, 1.0, 1.0),
            DVec3::new(0.1, 0.5, 0.0),
        ];
        let lib = WorldPose {
            rotations: vec![DQuat::IDENTITY; 4],
            positions,
        };
        let up = Upright {
            upper: vec![false, true, true, false],
            pelvis: 0,
            head: 2,
            points: Carried::default(),
        };
        // The head's mesh hangs 1.2 m below its joint: 0.2 m under.
        let lowest = |w: &WorldPose| w.positions[2].y - 1.2;
        let turned = up.turned(&lib, lowest).expect("turned");
        // Turned until the head stands 1.2 m up: sin(a) = 0.2.
        assert!(lowest(&turned).abs() < 1e-3, "{turned:?}");
        let a = 0.2f64.asin();
        assert!(
            (turned.positions[1] - DVec3::new(0.0, 1.0 + 0.5 * a.sin(), 0.5 * a.cos())).length()
                < 1e-3
        );
        // The leg and pelvis stay; the trunk's joints turn with it.
        assert_eq!(turned.positions[3], lib.positions[3]);
        assert_eq!(turned.positions[0], lib.positions[0]);
        assert!((turned.rotations[2].to_axis_angle().1 - a).abs() < 1e-3);
        // A head that no turn lifts enough is turned upright.
        let most = up.turned(&lib, |w| w.positions[2].y - 9.0).expect("turned");
        assert!((most.positions[2] - DVec3::new(0.0, 2.0, 0.0)).length() < 1e-9);
        // A head straight below the pelvis: no turn raises it.
        let mut hanging = lib.clone();
        hanging.positions[2] = DVec3::new(0.0, 0.0, 0.0);
        assert!(up.turned(&hanging, lowest).is_none());
    }
}
