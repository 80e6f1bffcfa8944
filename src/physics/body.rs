//! The ragdoll's body plan from the character's skeleton: which bones make
//! which segment, each segment's mass (de Leva's table, scaled to the
//! skeleton's height), capsule radius, and the hinge or ball joint that
//! joins it to its parent, with human limits.

use glam::DVec3;

use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::{Skeleton, WorldPose};

/// Segment mass as a share of the body's (de Leva 1996, adjusting
/// Zatsiorsky–Seluyanov; male): head and neck, upper/middle/lower trunk,
/// upper arm, forearm, hand, thigh, shank, foot.
pub(crate) const MASS_SHARE: [(SegmentKind, f64); 10] = [
    (SegmentKind::Head, 0.0694),
    (SegmentKind::Thorax, 0.1596),
    (SegmentKind::Abdomen, 0.1633),
    (SegmentKind::Pelvis, 0.1117),
    (SegmentKind::UpperArm, 0.0271),
    (SegmentKind::Forearm, 0.0162),
    (SegmentKind::Hand, 0.0061),
    (SegmentKind::Thigh, 0.1416),
    (SegmentKind::Shank, 0.0433),
    (SegmentKind::Foot, 0.0137),
];

/// Body mass of the ragdoll (kg), for a character of [`REFERENCE_HEIGHT`].
pub(crate) const BODY_MASS: f64 = 70.0;

/// Stature the radii below are for (m); other characters scale.
pub(crate) const REFERENCE_HEIGHT: f64 = 1.70;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum SegmentKind {
    Pelvis,
    Abdomen,
    Thorax,
    Head,
    UpperArm,
    Forearm,
    Hand,
    Thigh,
    Shank,
    Foot,
}

impl SegmentKind {
    /// Share of the body's mass (the forearm carries the hand).
    fn mass_share(self) -> f64 {
        let share = |kind| {
            MASS_SHARE
                .iter()
                .find(|(k, _)| *k == kind)
                .map_or(0.0, |(_, m)| *m)
        };
        match self {
            SegmentKind::Forearm => share(SegmentKind::Forearm) + share(SegmentKind::Hand),
            kind => share(kind),
        }
    }

    /// Capsule radius for a 1.70 m body (m).
    fn radius(self) -> f64 {
        match self {
            SegmentKind::Pelvis => 0.11,
            SegmentKind::Abdomen => 0.12,
            SegmentKind::Thorax => 0.13,
            SegmentKind::Head => 0.10,
            SegmentKind::UpperArm => 0.045,
            SegmentKind::Forearm => 0.038,
            SegmentKind::Hand => 0.035,
            SegmentKind::Thigh => 0.07,
            SegmentKind::Shank => 0.05,
            SegmentKind::Foot => 0.035,
        }
    }
}

/// How a segment hangs on its parent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Hinge {
    /// Ball joint with limits about the rest axes X, Y, Z (rad).
    Ball([f64; 3]),
    /// Hinge about an axis (rest axes) with limits (rad).
    Hinge(DVec3, [f64; 2]),
}

/// A segment as built from the skeleton.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct SegmentDef {
    pub(crate) kind: SegmentKind,
    pub(crate) region: Region,
    /// The skeleton joint whose world rotation the segment carries.
    pub(crate) joint: usize,
    /// Parent segment (index), and how it hangs on it.
    pub(crate) parent: Option<(usize, Hinge)>,
    /// Capsule ends at rest (world).
    pub(crate) ends: [DVec3; 2],
    pub(crate) radius: f64,
    pub(crate) mass: f64,
}

/// The child of `from` on the way down to `to` (`to` itself if it is a
/// child).
pub(crate) fn child_toward(skeleton: &Skeleton, from: usize, to: usize) -> usize {
    let mut j = to;
    while let Some(p) = skeleton.joints[j].parent {
        if p == from {
            return j;
        }
        j = p;
    }
    to
}

/// The farthest point of a joint's own subtree (joints and End Sites)
/// from it, or `None` if it has none.
pub(crate) fn tip(skeleton: &Skeleton, w: &WorldPose, joint: usize) -> Option<DVec3> {
    let at = w.positions[joint];
    let mut best: Option<DVec3> = None;
    for i in 0..skeleton.len() {
        if !skeleton.is_ancestor(joint, i) {
            continue;
        }
        let points = (i != joint)
            .then_some(w.positions[i])
            .into_iter()
            .chain(w.end_site(skeleton, i));
        for p in points {
            if best.is_none_or(|b| (p - at).length() > (b - at).length()) {
                best = Some(p);
            }
        }
    }
    best.filter(|p| (*p - at).length() > 0.01)
}

/// The segments of a skeleton, from its rest posture (world transforms).
pub(crate) fn segment_defs(
    skeleton: &Skeleton,
    roles: &RoleMap,
    rest: &WorldPose,
) -> Vec<SegmentDef> {
    let at = |r: Role| rest.positions[roles.get(r)];
    let height = (rest.positions[roles.get(Role::Head)].y
        - at(Role::LeftFoot).y.min(at(Role::RightFoot).y))
    .max(0.5);
    let scale = (height / (REFERENCE_HEIGHT * 0.87)).clamp(0.3, 3.0);
    let mass_scale = scale.powi(3);
    let mut defs: Vec<SegmentDef> = Vec::new();
    let mut add = |kind, region, joint, parent, ends: [DVec3; 2]| {
        defs.push(SegmentDef {
            kind,
            region,
            joint,
            parent,
            ends,
            radius: SegmentKind::radius(kind) * scale,
            mass: SegmentKind::mass_share(kind) * BODY_MASS * mass_scale,
        });
        defs.len() - 1
    };
    let pelvis_j = roles.get(Role::Pelvis);
    let chest_j = roles.get(Role::Chest);
    // Axes of the rest posture: the character's left and its front.
    let left = (at(Role::LeftHip) - at(Role::RightHip))
        .with_y(0.0)
        .try_normalize()
        .unwrap_or(DVec3::X);
    let front = left.cross(DVec3::Y).normalize() * -1.0;
    let pelvis = add(
        SegmentKind::Pelvis,
        Region::Torso,
        pelvis_j,
        None,
        [at(Role::LeftHip), at(Role::RightHip)],
    );
    let spine_j = child_toward(skeleton, pelvis_j, chest_j);
    let abdomen = if spine_j == chest_j {
        pelvis
    } else {
        add(
            SegmentKind::Abdomen,
            Region::Torso,
            spine_j,
            Some((pelvis, Hinge::Ball([0.5, 0.4, 0.4]))),
            [rest.positions[spine_j], at(Role::Chest)],
        )
    };
    let thorax = add(
        SegmentKind::Thorax,
        Region::Torso,
        chest_j,
        Some((abdomen, Hinge::Ball([0.5, 0.4, 0.4]))),
        [at(Role::Chest), at(Role::Neck)],
    );
    let head_j = roles.get(Role::Neck);
    let head_top = tip(skeleton, rest, roles.get(Role::Head))
        .unwrap_or(at(Role::Head) + DVec3::Y * 0.2 * scale);
    add(
        SegmentKind::Head,
        Region::Torso,
        head_j,
        Some((thorax, Hinge::Ball([0.8, 1.0, 0.6]))),
        [at(Role::Neck), head_top],
    );
    for (region, [shoulder, elbow, hand]) in [
        (
            Region::LeftArm,
            [Role::LeftShoulder, Role::LeftElbow, Role::LeftHand],
        ),
        (
            Region::RightArm,
            [Role::RightShoulder, Role::RightElbow, Role::RightHand],
        ),
    ] {
        let upper = at(elbow) - at(shoulder);
        let fore = at(hand) - at(elbow);
        // The elbow bends the forearm towards the front.
        let axis = upper.cross(front).try_normalize().unwrap_or(left);
        let s = add(
            SegmentKind::UpperArm,
            region,
            roles.get(shoulder),
            Some((thorax, Hinge::Ball([2.6, 1.4, 2.6]))),
            [at(shoulder), at(elbow)],
        );
        // The hand goes with the forearm: a wrist is stiff next to the
        // swing of an arm, and a light hand on a ball joint only jitters.
        let fingers = tip(skeleton, rest, roles.get(hand))
            .unwrap_or(at(hand) + fore.normalize_or_zero() * 0.08 * scale);
        add(
            SegmentKind::Forearm,
            region,
            roles.get(elbow),
            Some((s, Hinge::Hinge(axis, [-0.05, 2.6]))),
            [at(elbow), fingers],
        );
    }
    for (region, [hip, knee, foot]) in [
        (
            Region::LeftLeg,
            [Role::LeftHip, Role::LeftKnee, Role::LeftFoot],
        ),
        (
            Region::RightLeg,
            [Role::RightHip, Role::RightKnee, Role::RightFoot],
        ),
    ] {
        let thigh = at(knee) - at(hip);
        // The knee bends the shank towards the back.
        let axis = front.cross(thigh).try_normalize().unwrap_or(left);
        let t = add(
            SegmentKind::Thigh,
            region,
            roles.get(hip),
            Some((pelvis, Hinge::Ball([2.0, 0.8, 0.9]))),
            [at(hip), at(knee)],
        );
        let k = add(
            SegmentKind::Shank,
            region,
            roles.get(knee),
            Some((t, Hinge::Hinge(axis, [-0.05, 2.5]))),
            [at(knee), at(foot)],
        );
        // The sole rests on the floor: the capsule's lower side, not its
        // axis, touches it.
        let radius = SegmentKind::Foot.radius() * scale;
        let toes = tip(skeleton, rest, roles.get(foot)).unwrap_or(at(foot) + front * 0.15 * scale);
        let toes = toes.with_y(toes.y.max(radius));
        add(
            SegmentKind::Foot,
            region,
            roles.get(foot),
            Some((k, Hinge::Ball([0.8, 0.4, 0.4]))),
            [at(foot), toes],
        );
    }
    defs
}

/// The five regions of the paper: physical effects apply per region.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Region {
    Torso,
    LeftArm,
    RightArm,
    LeftLeg,
    RightLeg,
}

impl Region {
    pub const ALL: [Region; 5] = [
        Region::Torso,
        Region::LeftArm,
        Region::RightArm,
        Region::LeftLeg,
        Region::RightLeg,
    ];

    /// Index into [`Region::ALL`].
    #[must_use]
    pub fn index(self) -> usize {
        self as usize
    }

    /// The region a role's part belongs to (the pelvis: the torso).
    #[must_use]
    pub fn of(role: Role) -> Self {
        match role {
            Role::LeftShoulder | Role::LeftElbow | Role::LeftHand => Region::LeftArm,
            Role::RightShoulder | Role::RightElbow | Role::RightHand => Region::RightArm,
            Role::LeftHip | Role::LeftKnee | Role::LeftFoot => Region::LeftLeg,
            Role::RightHip | Role::RightKnee | Role::RightFoot => Region::RightLeg,
            Role::Pelvis | Role::Chest | Role::Neck | Role::Head => Region::Torso,
        }
    }
}
