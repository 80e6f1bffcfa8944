//! Two actions at once, the paper's future work ("waving a hand while
//! walking"): an action of the arms or head is played on the upper body
//! while the legs go on with what they do (a walk, an action led by the
//! legs). The body is split into regions once per skeleton: the legs and
//! pelvis stay the base's; the spine turns from the base's posture at the
//! pelvis to the layered action's at the chest along a smooth ramp,
//! measured in each posture's own facing frame, so the chest (and what hangs
//! from it) stands to the body as the layered action has it; the arms and
//! head the action moves take its joint rotations, the others keep the
//! base's.

use glam::DQuat;

use crate::character::body::facing_yaw;
use crate::character::library::{ActionDef, Library};
use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::{Pose, Skeleton, forward_kinematics};

/// A hand that moves less than this (m, its farthest from where it
/// starts, relative to the chest) in every clip of an action is not the
/// action's: that arm keeps the base's motion (it swings with the walk).
const ARM_MOVES_M: f64 = 0.12;

/// Which region of the body a joint belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Region {
    /// The pelvis, the legs and anything hung below the spine.
    Lower,
    /// Between the pelvis and the chest (the chest included).
    Spine,
    /// Above the chest, carrying more than one of the arms and the head.
    Trunk,
    LeftArm,
    RightArm,
    Head,
}

/// The regions of one skeleton.
#[derive(Clone, Debug)]
pub struct Regions {
    /// The joints from the pelvis (not included) to the chest, in order.
    spine: Vec<usize>,
    region: Vec<Region>,
}

/// Which of the upper regions a layered action takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Mask {
    pub left_arm: bool,
    pub right_arm: bool,
}

const LEFT: u8 = 1;
const RIGHT: u8 = 2;
const HEAD: u8 = 4;

fn bit(role: Role) -> u8 {
    match role {
        Role::LeftShoulder | Role::LeftElbow | Role::LeftHand => LEFT,
        Role::RightShoulder | Role::RightElbow | Role::RightHand => RIGHT,
        Role::Neck | Role::Head => HEAD,
        _ => 0,
    }
}

impl Regions {
    /// The regions of `skeleton`; `None` where the chest does not hang
    /// below the pelvis (no spine to blend along).
    #[must_use]
    pub fn new(skeleton: &Skeleton, roles: &RoleMap) -> Option<Self> {
        let pelvis = roles.get(Role::Pelvis);
        let chest = roles.get(Role::Chest);
        let mut spine = Vec::new();
        let mut j = chest;
        while j != pelvis {
            spine.push(j);
            j = skeleton.joints.get(j)?.parent?;
        }
        if spine.is_empty() {
            return None;
        }
        spine.reverse();
        // Which of the arms and the head each joint carries.
        let n = skeleton.len();
        let mut carries = vec![0u8; n];
        for role in Role::ALL {
            carries[roles.get(role)] |= bit(role);
        }
        for i in (1..n).rev() {
            if let Some(p) = skeleton.joints[i].parent {
                carries[p] |= carries[i];
            }
        }
        let mut region = vec![Region::Lower; n];
        for &s in &spine {
            region[s] = Region::Spine;
        }
        for i in 0..n {
            let Some(p) = skeleton.joints[i].parent else {
                continue;
            };
            let above = p == chest || !matches!(region[p], Region::Lower | Region::Spine);
            if region[i] == Region::Spine || !(above || region[p] == Region::Spine) {
                continue;
            }
            region[i] = match carries[i] {
                LEFT => Region::LeftArm,
                RIGHT => Region::RightArm,
                HEAD => Region::Head,
                // Nothing of a role: with what it hangs from (an accessory
                // on the chest moves with the trunk, one on the lower
                // spine with the hips).
                0 if p == chest => Region::Trunk,
                0 if above => region[p],
                0 => Region::Lower,
                _ => Region::Trunk,
            };
        }
        Some(Self { spine, region })
    }

    /// The regions `def` takes when layered: the arm of its primary part,
    /// the other arm where its hand moves in the action's clips, the head
    /// and the spine always.
    #[must_use]
    pub fn mask(&self, lib: &Library, roles: &RoleMap, def: &ActionDef) -> Mask {
        let moves = |hand: Role| {
            def.clips
                .iter()
                .filter_map(|c| lib.clips.get(c))
                .any(|clip| {
                    let chest = roles.get(Role::Chest);
                    let h = roles.get(hand);
                    let mut first = None;
                    clip.frames.iter().any(|f| {
                        let w = forward_kinematics(&lib.skeleton, f);
                        let p =
                            w.rotations[chest].inverse() * (w.positions[h] - w.positions[chest]);
                        (p - *first.get_or_insert(p)).length() > ARM_MOVES_M
                    })
                })
        };
        let primary = bit(def.primary);
        Mask {
            left_arm: primary == LEFT || moves(Role::LeftHand),
            right_arm: primary == RIGHT || moves(Role::RightHand),
        }
    }

    /// The posture `base` with the action's posture `top` laid over its
    /// upper body, by `weight` (0: the base, 1: the action's upper body).
    #[must_use]
    pub fn lay(
        &self,
        skeleton: &Skeleton,
        roles: &RoleMap,
        base: &Pose,
        top: &Pose,
        mask: Mask,
        weight: f64,
    ) -> Pose {
        let weight = weight.clamp(0.0, 1.0);
        let mut out = base.clone();
        if weight <= 0.0 {
            return out;
        }
        let wb = forward_kinematics(skeleton, base);
        let wt = forward_kinematics(skeleton, top);
        let hb = DQuat::from_rotation_y(facing_yaw(&wb, roles));
        let ht = DQuat::from_rotation_y(facing_yaw(&wt, roles));
        // The spine, each joint turned in the body's frame part of the way
        // from the base's to the action's: nothing at the pelvis, `weight`
        // at the chest.
        let n = self.spine.len() as f64;
        let mut parent_world = None;
        for (k, &j) in self.spine.iter().enumerate() {
            let w = weight * (k + 1) as f64 / n;
            let from = hb.inverse() * wb.rotations[j];
            let to = ht.inverse() * wt.rotations[j];
            let world = (hb * from.slerp(to, w)).normalize();
            let parent = parent_world.unwrap_or_else(|| {
                skeleton.joints[j]
                    .parent
                    .map_or(DQuat::IDENTITY, |p| wb.rotations[p])
            });
            out.rotations[j] = (parent.inverse() * world).normalize();
            parent_world = Some(world);
        }
        for (j, region) in self.region.iter().enumerate() {
            let takes = match region {
                Region::Lower | Region::Spine => false,
                Region::Trunk | Region::Head => true,
                Region::LeftArm => mask.left_arm,
                Region::RightArm => mask.right_arm,
            };
            if takes {
                out.rotations[j] = base.rotations[j]
                    .slerp(top.rotations[j], weight)
                    .normalize();
                out.translations[j] = base.translations[j].lerp(top.translations[j], weight);
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::character::body::Placement;

    use crate::character::library::default_library;

    #[test]
    fn the_regions_of_the_default_skeleton_split_arms_head_spine_and_legs() {
        let lib = default_library();
        let roles = &lib.clips.values().next().unwrap().roles;
        let r = Regions::new(&lib.skeleton, roles).unwrap();
        assert_eq!(r.spine.last(), Some(&roles.get(Role::Chest)));
        assert_eq!(r.region[roles.get(Role::LeftHand)], Region::LeftArm);
        assert_eq!(r.region[roles.get(Role::RightElbow)], Region::RightArm);
        assert_eq!(r.region[roles.get(Role::Head)], Region::Head);
        assert_eq!(r.region[roles.get(Role::LeftKnee)], Region::Lower);
        assert_eq!(r.region[roles.get(Role::Pelvis)], Region::Lower);
    }

    #[test]
    fn a_wave_takes_its_own_arm_and_a_bow_keeps_the_arms_it_does_not_move() {
        let lib = default_library();
        let roles = &lib.clips.values().next().unwrap().roles;
        let r = Regions::new(&lib.skeleton, roles).unwrap();
        let def = |name: &str| lib.actions.iter().find(|a| a.name == name).unwrap();
        let wave = r.mask(&lib, roles, def("wave_left"));
        assert!(wave.left_arm && !wave.right_arm, "{wave:?}");
        let punch = r.mask(&lib, roles, def("punch_right"));
        assert!(punch.right_arm, "{punch:?}");
    }

    #[test]
    fn laid_fully_the_chest_and_arms_stand_to_the_body_as_the_action_has_them() {
        let lib = default_library();
        let roles = &lib.clips.values().next().unwrap().roles;
        let r = Regions::new(&lib.skeleton, roles).unwrap();
        let walk = &lib.clips["walk_path.bvh"];
        let wave = &lib.clips[&lib
            .actions
            .iter()
            .find(|a| a.name == "wave_left")
            .unwrap()
            .clips[0]];
        let mask = Mask {
            left_arm: true,
            right_arm: false,
        };
        let hand = roles.get(Role::LeftHand);
        let mut worst: f64 = 0.0;
        for i in (0..walk.frames.len().min(wave.frames.len())).step_by(7) {
            let (base, top) = (&walk.frames[i], &wave.frames[i]);
            let out = r.lay(&lib.skeleton, roles, base, top, mask, 1.0);
            let local = |pose: &Pose| {
                let at = Placement::of(&lib.skeleton, roles, pose);
                let w = forward_kinematics(&lib.skeleton, pose);
                DQuat::from_rotation_y(at.yaw).inverse() * (w.positions[hand] - at.position)
            };
            worst = worst.max((local(&out) - local(top)).length());
            // The legs are the walk's.
            let foot = roles.get(Role::LeftFoot);
            let (wo, wb) = (
                forward_kinematics(&lib.skeleton, &out),
                forward_kinematics(&lib.skeleton, base),
            );
            assert!(wo.positions[foot].distance(wb.positions[foot]) < 1e-9);
        }
        // The pelvis a walk carries lower and swaying: 2.9 cm at most.
        assert!(worst < 0.035, "the hand {worst} m from the wave's");
        // Nothing laid: the base.
        let none = r.lay(
            &lib.skeleton,
            roles,
            &walk.frames[0],
            &wave.frames[0],
            mask,
            0.0,
        );
        assert_eq!(none, walk.frames[0]);
    }
}
