//! The limbs that carry hands, feet and head, as the posing blend sees
//! them: a limb hangs from its base joint (the clavicle, if the skeleton has
//! one, else the shoulder; the hip; for the head, the spine's first joint
//! above the root) and its reach is where its end lies from there, in the
//! frame of the base's parent. A limb's reach depends only on its own
//! joints' rotations, so a limb can be blended from other samples than the
//! body it hangs from.

use glam::{DQuat, DVec3};

use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::Skeleton;

/// The limbs, in the order of [`crate::control::posing::sample::Sample::reach`].
pub const LIMBS: [Role; 5] = [
    Role::Head,
    Role::RightHand,
    Role::LeftHand,
    Role::RightFoot,
    Role::LeftFoot,
];

/// Position of `role` in [`LIMBS`], if it ends a limb.
#[must_use]
pub fn limb_index(role: Role) -> Option<usize> {
    LIMBS.iter().position(|r| *r == role)
}

/// The joints from a limb's base down to its end (head, hand or foot),
/// base first; `None` for a role that ends no limb.
#[must_use]
pub fn chain(skeleton: &Skeleton, roles: &RoleMap, role: Role) -> Option<Vec<usize>> {
    let upper = match role {
        Role::RightHand => Role::RightShoulder,
        Role::LeftHand => Role::LeftShoulder,
        Role::RightFoot => Role::RightHip,
        Role::LeftFoot => Role::LeftHip,
        Role::Head => Role::Head,
        _ => return None,
    };
    let upper = roles.get(upper);
    if role == Role::Head {
        // The spine: from the root's child on the way to the head.
        let mut joints = vec![upper];
        while let Some(p) = skeleton.joints[*joints.last()?].parent {
            joints.push(p);
        }
        joints.pop();
        joints.reverse();
        return (joints.len() > 1).then_some(joints);
    }
    // A hand's limb starts at the joint between shoulder and chest.
    let base = match role {
        Role::RightHand | Role::LeftHand => skeleton.joints[upper]
            .parent
            .filter(|&p| p != roles.get(Role::Chest))
            .unwrap_or(upper),
        _ => upper,
    };
    let mut joints = vec![roles.get(role)];
    while *joints.last()? != base {
        joints.push(skeleton.joints[*joints.last()?].parent?);
    }
    joints.reverse();
    Some(joints)
}

/// Where a limb's end lies from its base, in the frame of the base's
/// parent, for the local `rotations` of a pose.
#[must_use]
pub fn reach(skeleton: &Skeleton, chain: &[usize], rotations: &[DQuat]) -> DVec3 {
    let (mut p, mut rot) = (DVec3::ZERO, DQuat::IDENTITY);
    for pair in chain.windows(2) {
        rot *= rotations[pair[0]];
        p += rot * skeleton.joints[pair[1]].offset;
    }
    p
}

/// Whether joint `j` is `base` or lies below it.
#[must_use]
pub fn hangs_from(skeleton: &Skeleton, j: usize, base: usize) -> bool {
    let mut x = Some(j);
    while let Some(y) = x {
        if y == base {
            return true;
        }
        x = skeleton.joints[y].parent;
    }
    false
}
