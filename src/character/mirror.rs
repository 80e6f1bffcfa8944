//! Mirrored copies of clips: the motion as the performer's mirror image
//! would do it, left and right swapped, so that an action taught with one
//! hand is also known with the other.
//!
//! Rigs differ in how their bones' local frames sit: in some the left and
//! right offsets mirror across local x (a CMU conversion), in others the
//! right side's bones point the other way along x (the Bandai share's). So
//! the mirror of each joint's local frame is found from the skeleton
//! itself: the reflection that best takes its partner's children's offsets
//! to its own children's. The world is mirrored across x = 0. A joint's
//! rotation becomes its partner's seen between its parent's mirror and its
//! own; the root's between the world's and its own.

use glam::{DMat3, DQuat, DVec3};

use super::motion::Clip;
use super::skeleton::{Pose, Skeleton};

/// Why a clip has no mirror image.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MirrorError {
    #[error(
        "the skeleton has no left and right joints to swap (joint names with Left/Right, _L/_R, L_/R_ or .L/.R)"
    )]
    NoPairs,
    #[error(
        "the skeleton is not left-right symmetric: its offsets match their partners' only within {0:.0}% across any axis"
    )]
    Asymmetric(f64),
}

/// Name swaps that turn a left joint's name into its partner's, and back.
const SWAPS: [(&str, &str); 8] = [
    ("Left", "Right"),
    ("left", "right"),
    ("LEFT", "RIGHT"),
    ("_L", "_R"),
    ("L_", "R_"),
    (".L", ".R"),
    ("_l", "_r"),
    ("l_", "r_"),
];

/// The partner of every joint (itself for joints on the middle line).
#[must_use]
pub fn partners(skeleton: &Skeleton) -> Vec<usize> {
    let index = |name: &str| skeleton.joints.iter().position(|j| j.name == name);
    skeleton
        .joints
        .iter()
        .enumerate()
        .map(|(i, j)| {
            // A leading L or R before a capital (CMU's LHipJoint, RThumb).
            let initial = match j.name.as_bytes() {
                [b'L', c, ..] if c.is_ascii_uppercase() => Some(format!("R{}", &j.name[1..])),
                [b'R', c, ..] if c.is_ascii_uppercase() => Some(format!("L{}", &j.name[1..])),
                _ => None,
            };
            SWAPS
                .iter()
                .flat_map(|(a, b)| [(a, b), (b, a)])
                .filter(|(from, _)| j.name.contains(*from))
                .map(|(from, to)| j.name.replacen(*from, to, 1))
                .chain(initial)
                .find_map(|n| index(&n))
                .filter(|&p| p != i)
                .unwrap_or(i)
        })
        .collect()
}

/// The improper sign-diagonal reflections a joint's local frame can be
/// mirrored by.
const REFLECTIONS: [DVec3; 4] = [
    DVec3::new(-1.0, 1.0, 1.0),
    DVec3::new(1.0, -1.0, 1.0),
    DVec3::new(1.0, 1.0, -1.0),
    DVec3::new(-1.0, -1.0, -1.0),
];

/// The world's mirror: across x = 0.
const WORLD: DVec3 = DVec3::new(-1.0, 1.0, 1.0);

/// At most this many frames tell apart reflections the offsets cannot.
const MOTION_SAMPLES: usize = 200;

/// For every joint, the reflection that takes its partner's local frame to
/// its own (`A_j` with `off_c = A_j off_{m(c)}` for its children `c`, or
/// its End Site), and the share of offset length left unmatched over the
/// whole skeleton. Rigs mirror their right side differently (across local
/// x, or with the bones pointing the other way along x): each joint's is
/// measured. Offsets along one axis (a bone along its x) or none (a hand's
/// End Site at the joint) leave the roll about the bone open: reflections
/// that differ by half a turn about it match alike, though a foot so
/// mirrored stands on its instep. Among those, the one under which the
/// partner's turns in `frames` look most like the joint's own is taken.
fn frame_mirrors(skeleton: &Skeleton, partner: &[usize], frames: &[Pose]) -> (Vec<DVec3>, f64) {
    let n = skeleton.len();
    let mut mirrors = vec![REFLECTIONS[0]; n];
    let (mut miss, mut total) = (0.0, 0.0);
    for j in 0..n {
        let pairs: Vec<(DVec3, DVec3)> = (0..n)
            .filter(|&c| skeleton.joints[c].parent == Some(j))
            .map(|c| {
                (
                    skeleton.joints[c].offset,
                    skeleton.joints[partner[c]].offset,
                )
            })
            .chain(
                skeleton.joints[j]
                    .end_site
                    .zip(skeleton.joints[partner[j]].end_site),
            )
            .collect();
        let inherited = skeleton.joints[j]
            .parent
            .map_or(REFLECTIONS[0], |p| mirrors[p]);
        if pairs.is_empty() {
            mirrors[j] = inherited;
            continue;
        }
        let cost = |m: DVec3| {
            pairs
                .iter()
                .map(|(a, b)| (*a - m * *b).length())
                .sum::<f64>()
        };
        // The parent's first, so that ties keep a chain's frames alike...
        let candidates: Vec<DVec3> = std::iter::once(inherited).chain(REFLECTIONS).collect();
        let least = candidates
            .iter()
            .map(|m| cost(*m))
            .fold(f64::INFINITY, f64::min);
        let scale = pairs.iter().map(|(a, _)| a.length()).sum::<f64>();
        let tied: Vec<DVec3> = candidates
            .into_iter()
            .filter(|m| cost(*m) <= least + 1e-6 * (1.0 + scale))
            .collect();
        // ...unless the motion tells them apart.
        let outer = skeleton.joints[j].parent.map_or(WORLD, |p| mirrors[p]);
        let unlike = |m: DVec3| -> f64 {
            frames
                .iter()
                .step_by((frames.len() / MOTION_SAMPLES).max(1))
                .map(|f| {
                    let mirrored = between(outer, f.rotations[partner[j]], m);
                    mirrored.angle_between(f.rotations[j])
                })
                .sum()
        };
        let best = tied
            .iter()
            .copied()
            .min_by(|a, b| unlike(*a).total_cmp(&unlike(*b)))
            .unwrap_or(inherited);
        mirrors[j] = best;
        miss += cost(best);
        total += pairs.iter().map(|(a, _)| a.length()).sum::<f64>();
    }
    (mirrors, miss / total.max(1e-12))
}

/// `R` seen between two mirrors: `A R B` for diagonal sign matrices whose
/// determinants agree, a rotation again.
fn between(a: DVec3, q: DQuat, b: DVec3) -> DQuat {
    let r = DMat3::from_diagonal(a) * DMat3::from_quat(q) * DMat3::from_diagonal(b);
    DQuat::from_mat3(&r).normalize()
}

impl Clip {
    /// This clip's mirror image (left and right swapped, the world mirrored
    /// across x = 0), named by the caller.
    pub fn mirrored(&self) -> Result<Clip, MirrorError> {
        let sk = &self.skeleton;
        let partner = partners(sk);
        if partner.iter().enumerate().all(|(i, &p)| i == p) {
            return Err(MirrorError::NoPairs);
        }
        let (a, miss) = frame_mirrors(sk, &partner, &self.frames);
        if miss > 0.05 {
            return Err(MirrorError::Asymmetric(miss * 100.0));
        }
        let mut out = self.clone();
        for (f, src) in out.frames.iter_mut().zip(&self.frames) {
            for j in 0..sk.len() {
                let p = partner[j];
                match sk.joints[j].parent {
                    None => {
                        f.rotations[j] = between(WORLD, src.rotations[p], a[j]);
                        f.translations[j] = WORLD * src.translations[p];
                    }
                    Some(parent) => {
                        f.rotations[j] = between(a[parent], src.rotations[p], a[j]);
                        f.translations[j] = if self.translates.get(p).copied().unwrap_or(false) {
                            a[parent] * src.translations[p]
                        } else {
                            sk.joints[j].offset
                        };
                    }
                }
            }
        }
        // The roles stay: the joint named LeftHand now does what the right
        // hand did, mirrored.
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::character::skeleton::Joint;

    #[test]
    fn partners_are_found_by_name_in_the_usual_spellings() {
        let sk = Skeleton {
            joints: [
                "Hips",
                "LeftUpLeg",
                "RightUpLeg",
                "Hand_L",
                "Hand_R",
                "Spine",
                "l_toe",
                "r_toe",
                "LHipJoint",
                "RHipJoint",
                "LowerBack",
            ]
            .iter()
            .enumerate()
            .map(|(i, n)| Joint {
                name: (*n).to_owned(),
                parent: (i > 0).then_some(0),
                offset: DVec3::X,
                end_site: None,
            })
            .collect(),
        };
        assert_eq!(partners(&sk), vec![0, 2, 1, 4, 3, 5, 7, 6, 9, 8, 10]);
    }

    #[test]
    fn a_rotation_between_mirrors_is_the_reflected_rotation() {
        let q = DQuat::from_rotation_y(0.4) * DQuat::from_rotation_x(0.3);
        for (a, b) in [
            (REFLECTIONS[0], REFLECTIONS[0]),
            (REFLECTIONS[1], REFLECTIONS[3]),
        ] {
            let m = DMat3::from_diagonal(a) * DMat3::from_quat(q) * DMat3::from_diagonal(b);
            let r = DMat3::from_quat(between(a, q, b));
            assert!(m.abs_diff_eq(r, 1e-12), "{m} {r}");
        }
    }
}
