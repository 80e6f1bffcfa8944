//! A motion clip in marionette's conventions: metres, the converter's
//! T-pose frame (if any) set aside, roles filled.

use std::collections::BTreeMap;

use glam::DVec3;

use super::body::leg_length_mean;
use super::bvh::BvhFile;
use super::roles::{self, Role, RoleMap, RolesError};
use super::skeleton::{Pose, Skeleton, forward_kinematics};

/// How to import a clip.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ImportSettings {
    /// File units to metres; detected from the skeleton's height when `None`.
    pub scale_to_m: Option<f64>,
    /// Role → joint name overrides.
    pub roles: BTreeMap<String, String>,
}

/// A clip ready for the method.
#[derive(Clone, Debug, PartialEq)]
pub struct Clip {
    /// Skeleton in metres.
    pub skeleton: Skeleton,
    /// Postures in metres, without a converter's T-pose frame.
    pub frames: Vec<Pose>,
    pub frame_time: f64,
    /// Joints with translation channels in the source.
    pub translates: Vec<bool>,
    pub scale_to_m: f64,
    /// Whether the source's first frame was a T-pose that was set aside.
    pub dropped_tpose: bool,
    pub roles: RoleMap,
    /// Stature from the bone lengths (m): how tall the skeleton stands,
    /// whatever posture the clip starts in (seated, crouched, stretching).
    pub height_m: f64,
    /// Floor to top of head in the first frame (m), as the clip begins.
    pub first_frame_height_m: f64,
}

/// Typical human height the unit detection aims for.
const TYPICAL_HEIGHT_M: f64 = 1.7;

/// Units BVH files come in, as metres per unit: metres, centimetres,
/// millimetres, inches, and the CMU ASF unit (inches / 0.45) of the cgspeed
/// conversions. Rarer units (decimetres, feet) would be confused with these
/// for small or large figures; a library sets `scale_to_m` for them.
pub const KNOWN_UNITS: [(f64, &str); 5] = [
    (1.0, "m"),
    (0.01, "cm"),
    (0.001, "mm"),
    (0.0254, "in"),
    (0.0254 / 0.45, "CMU ASF unit"),
];

/// Metres per file unit for a skeleton `height` units tall: the known unit
/// that makes it a plausible person (0.9–2.3 m, nearest 1.7 m), else the
/// factor that makes it exactly 1.7 m.
#[must_use]
pub fn detect_scale(height: f64) -> f64 {
    if !(height.is_finite() && height > 0.0) {
        return 1.0;
    }
    KNOWN_UNITS
        .iter()
        .map(|(s, _)| *s)
        .filter(|s| (0.9..=2.3).contains(&(height * s)))
        .min_by(|a, b| {
            let da = (height * a / TYPICAL_HEIGHT_M).ln().abs();
            let db = (height * b / TYPICAL_HEIGHT_M).ln().abs();
            da.total_cmp(&db)
        })
        .unwrap_or(TYPICAL_HEIGHT_M / height)
}

/// The skeleton's stature from its bone lengths alone, whatever the pose:
/// the chain from a foot up through the hip, pelvis and spine to the top of
/// the head (the head's End Site, or its furthest descendant; where the rig
/// ends at the head joint, the crown estimated from the rest of the chain).
/// A standing person is about this tall; used to find the file's unit.
#[must_use]
pub fn chain_stature(skeleton: &Skeleton, roles: &RoleMap) -> f64 {
    let head = roles.get(Role::Head);
    let foot = roles.get(Role::LeftFoot);
    let path_up = |mut j: usize, to: usize| {
        let mut len = 0.0;
        while j != to {
            len += skeleton.joints[j].offset.length();
            match skeleton.joints[j].parent {
                Some(p) => j = p,
                None => break,
            }
        }
        len
    };
    let pelvis = skeleton.common_ancestor(foot, head);
    // Lateral offsets (hip joints) do not add to height: of the leg, count
    // the thigh and shin bones only.
    let knee = roles.get(Role::LeftKnee);
    let leg = skeleton.joints[foot].offset.length() + skeleton.joints[knee].offset.length();
    let trunk = path_up(head, pelvis);
    let head_top = (0..skeleton.len())
        .filter(|&i| skeleton.is_ancestor(head, i))
        .map(|i| path_up(i, head) + skeleton.joints[i].end_site.map_or(0.0, |e| e.length()))
        .fold(0.0, f64::max);
    // Ankle to ground: the foot's End Site or its child's offset, roughly.
    let ankle = 0.04 * (leg + trunk);
    let below = leg + trunk + ankle;
    below + head_top.max(head_extent(below, head_top))
}

/// A head joint at the top of the neck is about this share of a person's
/// stature below the crown.
const HEAD_TOP_SHARE: f64 = 0.12;

/// The crown's height above the head joint where the rig ends there (no
/// bone or End Site above it, as in some studios' rigs): `below` is the
/// stature up to the head joint and `measured` what the rig shows above
/// it. Zero where the rig has its own head.
fn head_extent(below: f64, measured: f64) -> f64 {
    if measured >= 0.02 * below {
        0.0
    } else {
        below * HEAD_TOP_SHARE / (1.0 - HEAD_TOP_SHARE)
    }
}

/// Floor to top of head of a pose, in the skeleton's units.
#[must_use]
pub fn standing_height(skeleton: &Skeleton, roles: &RoleMap, pose: &Pose) -> f64 {
    let w = forward_kinematics(skeleton, pose);
    let mut floor = f64::INFINITY;
    for i in 0..skeleton.len() {
        floor = floor.min(w.positions[i].y);
        if let Some(e) = w.end_site(skeleton, i) {
            floor = floor.min(e.y);
        }
    }
    let head = roles.get(Role::Head);
    let mut top = f64::NEG_INFINITY;
    for i in 0..skeleton.len() {
        if skeleton.is_ancestor(head, i) {
            top = top.max(w.positions[i].y);
            if let Some(e) = w.end_site(skeleton, i) {
                top = top.max(e.y);
            }
        }
    }
    // A rig that ends at the head joint: the crown above it, as tall as
    // the bones say it is (upright; a bowed head is over-counted a little).
    let above = top - w.positions[head].y;
    let below = w.positions[head].y - floor;
    top + head_extent(below, above) - floor
}

/// Whether frame 0 is a converter's T-pose: arms straight out sideways at
/// shoulder height, and a jump to frame 1.
#[must_use]
pub fn first_frame_is_tpose(skeleton: &Skeleton, roles: &RoleMap, frames: &[Pose]) -> bool {
    if frames.len() < 2 {
        return false;
    }
    let w0 = forward_kinematics(skeleton, &frames[0]);
    let w1 = forward_kinematics(skeleton, &frames[1]);
    let arm = |w: &[DVec3], s: Role, e: Role, h: Role| {
        let (s, e, h) = (w[roles.get(s)], w[roles.get(e)], w[roles.get(h)]);
        let reach = (h - s).length();
        let length = (e - s).length() + (h - e).length();
        (reach, length, (h - s).y.abs())
    };
    let straight_out = |w: &[DVec3], s, e, h| {
        let (reach, length, dy) = arm(w, s, e, h);
        length > 0.0 && reach > 0.95 * length && dy < 0.2 * reach
    };
    let tpose = straight_out(
        &w0.positions,
        Role::LeftShoulder,
        Role::LeftElbow,
        Role::LeftHand,
    ) && straight_out(
        &w0.positions,
        Role::RightShoulder,
        Role::RightElbow,
        Role::RightHand,
    );
    if !tpose {
        return false;
    }
    // A prepended T-pose jumps to the motion; a clip that starts in a T-pose
    // and moves on smoothly keeps its first frame.
    let (_, arm_len, _) = arm(
        &w0.positions,
        Role::LeftShoulder,
        Role::LeftElbow,
        Role::LeftHand,
    );
    let jump = [
        Role::LeftHand,
        Role::RightHand,
        Role::LeftElbow,
        Role::RightElbow,
    ]
    .iter()
    .map(|r| {
        let j = roles.get(*r);
        let root = skeleton
            .joints
            .iter()
            .position(|j| j.parent.is_none())
            .unwrap_or(0);
        ((w0.positions[j] - w0.positions[root]) - (w1.positions[j] - w1.positions[root])).length()
    })
    .fold(0.0, f64::max);
    jump > 0.15 * arm_len
}

/// Errors turning a BVH file into a clip.
#[derive(Debug, thiserror::Error)]
pub enum ClipError {
    #[error(transparent)]
    Roles(#[from] RolesError),
    #[error("the file has no frames")]
    NoFrames,
    #[error("scale_to_m must be a positive number, found {0}")]
    BadScale(f64),
    #[error(
        "the character would be {height_m:.3} m tall at {scale} m per file unit: a person is {MIN_STATURE_M} to {MAX_STATURE_M} m; set scale_to_m (metres per file unit) to the file's unit"
    )]
    Stature { height_m: f64, scale: f64 },
    #[error(
        "{what} is out of range ({value:e} m): positions must lie within {MAX_REACH_M} m of the origin"
    )]
    OutOfRange { what: String, value: f64 },
}

/// The shortest and tallest character a clip may show (m).
pub const MIN_STATURE_M: f64 = 0.3;
pub const MAX_STATURE_M: f64 = 10.0;
/// Bones and positions further than this from the origin are no capture
/// (m).
pub const MAX_REACH_M: f64 = 1000.0;

/// The first bone offset, translation or rotation of `skeleton` and
/// `frames` (in metres) that is not finite or lies beyond
/// [`MAX_REACH_M`].
fn out_of_range(skeleton: &Skeleton, frames: &[Pose]) -> Option<ClipError> {
    let bad = |v: f64| !v.is_finite() || v.abs() > MAX_REACH_M;
    for j in &skeleton.joints {
        let o = j.offset;
        if bad(o.length()) {
            return Some(ClipError::OutOfRange {
                what: format!("the bone to joint {}", j.name),
                value: o.length(),
            });
        }
    }
    for (k, f) in frames.iter().enumerate() {
        for (j, t) in f.translations.iter().enumerate() {
            let r = f.rotations[j];
            if bad(t.length()) || !r.is_finite() {
                return Some(ClipError::OutOfRange {
                    what: format!("frame {k}, joint {}", skeleton.joints[j].name),
                    value: t.length(),
                });
            }
        }
    }
    None
}

impl Clip {
    /// Resolve units, the T-pose frame and roles of a parsed file.
    pub fn from_bvh(file: BvhFile, settings: &ImportSettings) -> Result<Self, ClipError> {
        let BvhFile {
            mut skeleton,
            channels,
            frame_time,
            mut frames,
        } = file;
        if frames.is_empty() {
            return Err(ClipError::NoFrames);
        }
        let mut channels = channels;
        let mut roles = roles::fill(&skeleton, &settings.roles)?;
        // Bones above the pelvis (a static `joint_Root`, `RL_BoneRoot`, an
        // armature's turned root) are folded into it: the pelvis carries
        // the character's placement and facing, whichever bone moved.
        let mut folded = Vec::new();
        while let Some(name) = fold_top_bone(
            &mut skeleton,
            &mut channels,
            &mut frames,
            roles.get(Role::Pelvis),
        ) {
            folded.push(name);
            roles = roles::fill(&skeleton, &settings.roles)?;
        }
        if !folded.is_empty() {
            tracing::debug!(bones = ?folded, "top bones above the pelvis folded into it");
        }
        let dropped_tpose = first_frame_is_tpose(&skeleton, &roles, &frames);
        if dropped_tpose {
            frames.remove(0);
        }
        let first_frame_units = standing_height(&skeleton, &roles, &frames[0]);
        let stature_units = chain_stature(&skeleton, &roles);
        let scale = match settings.scale_to_m {
            Some(s) if s.is_finite() && s > 0.0 => s,
            Some(s) => return Err(ClipError::BadScale(s)),
            None => detect_scale(stature_units),
        };
        skeleton.scale(scale);
        for f in &mut frames {
            for t in &mut f.translations {
                *t *= scale;
            }
        }
        let height_m = stature_units * scale;
        if !(MIN_STATURE_M..=MAX_STATURE_M).contains(&height_m) {
            return Err(ClipError::Stature { height_m, scale });
        }
        if let Some(e) = out_of_range(&skeleton, &frames) {
            return Err(e);
        }
        Ok(Self {
            translates: channels
                .iter()
                .map(|c| {
                    c.iter().any(|ch| {
                        matches!(
                            ch,
                            super::bvh::Channel::Xposition
                                | super::bvh::Channel::Yposition
                                | super::bvh::Channel::Zposition
                        )
                    })
                })
                .collect(),
            skeleton,
            frames,
            frame_time,
            scale_to_m: scale,
            dropped_tpose,
            roles,
            height_m,
            first_frame_height_m: first_frame_units * scale,
        })
    }

    /// Carry the clip onto `onto`, a skeleton of the same hierarchy with
    /// other proportions (another performer): every joint keeps its
    /// rotations, bones take `onto`'s offsets, and translated joints (the
    /// pelvis's placement and height, strides) scale with the ratio of the
    /// leg lengths, so that feet plant and strides fit the new legs (a
    /// joint whose translation channels only repeat its bone keeps the
    /// new bone).
    /// Returns that ratio (1 when the proportions already match, and then
    /// nothing changes).
    pub fn retarget(&mut self, onto: &Skeleton) -> f64 {
        debug_assert_eq!(onto.len(), self.skeleton.len());
        let same = onto
            .joints
            .iter()
            .zip(&self.skeleton.joints)
            .all(|(a, b)| a.offset == b.offset && a.end_site == b.end_site);
        if same {
            return 1.0;
        }
        let from = leg_length_mean(&self.skeleton, &self.roles);
        let to = leg_length_mean(onto, &self.roles);
        let ratio = if from > 0.0 && to > 0.0 {
            to / from
        } else {
            1.0
        };
        for f in &mut self.frames {
            for (j, t) in f.translations.iter_mut().enumerate() {
                let own = self.skeleton.joints[j].offset;
                *t = match (j, self.translates.get(j).copied().unwrap_or(false)) {
                    // The placement and height.
                    (0, true) => *t * ratio,
                    // A bone that stretches: its stretch scales.
                    (_, true) => onto.joints[j].offset + (*t - own) * ratio,
                    (_, false) => onto.joints[j].offset,
                };
            }
        }
        self.skeleton = onto.clone();
        self.first_frame_height_m = standing_height(&self.skeleton, &self.roles, &self.frames[0]);
        self.height_m = chain_stature(&self.skeleton, &self.roles);
        ratio
    }
}

/// Fold the root into its only child when the pelvis hangs below it: every
/// frame's child gets the root's motion composed into its own, so every
/// remaining joint keeps its world position and rotation, and the root's
/// name is returned. Nothing changes (and `None` is returned) when the
/// root is the pelvis or has several children.
fn fold_top_bone(
    skeleton: &mut Skeleton,
    channels: &mut Vec<Vec<super::bvh::Channel>>,
    frames: &mut [Pose],
    pelvis: usize,
) -> Option<String> {
    if pelvis == 0 || skeleton.len() < 2 {
        return None;
    }
    let children: Vec<usize> = (1..skeleton.len())
        .filter(|&j| skeleton.joints[j].parent == Some(0))
        .collect();
    let &[child] = children.as_slice() else {
        return None;
    };
    // The child is the root's first descendant; every other joint hangs
    // below it.
    if child != 1 {
        return None;
    }
    for f in frames.iter_mut() {
        let (p, r) = (f.translations[0], f.rotations[0]);
        let (t, q) = (f.translations[1], f.rotations[1]);
        f.translations[1] = p + r * t;
        f.rotations[1] = (r * q).normalize();
        f.translations.remove(0);
        f.rotations.remove(0);
    }
    let root = skeleton.joints.remove(0);
    for j in &mut skeleton.joints {
        j.parent = j.parent.and_then(|p| p.checked_sub(1));
    }
    skeleton.joints[0].offset += root.offset;
    channels.remove(0);
    // The new root carries the placement: it translates.
    if let Some(c) = channels.first_mut() {
        use super::bvh::Channel::{Xposition, Yposition, Zposition};
        if !c
            .iter()
            .any(|ch| matches!(ch, Xposition | Yposition | Zposition))
        {
            c.splice(0..0, [Xposition, Yposition, Zposition]);
        }
    }
    Some(root.name)
}

#[cfg(test)]
mod tests {
    use glam::DQuat;

    use super::*;
    use crate::character::bvh::Channel;
    use crate::character::skeleton::Joint;

    fn joint(name: &str, parent: Option<usize>, offset: DVec3) -> Joint {
        Joint {
            name: name.to_owned(),
            parent,
            offset,
            end_site: None,
        }
    }

    #[test]
    fn a_top_bone_folds_into_the_pelvis_keeping_every_joint_where_it_was() {
        let mut skeleton = Skeleton {
            joints: vec![
                joint("joint_Root", None, DVec3::ZERO),
                joint("Hips", Some(0), DVec3::new(0.1, 0.9, -4.5)),
                joint("Spine", Some(1), DVec3::new(0.0, 0.2, 0.0)),
                joint("LeftUpLeg", Some(1), DVec3::new(0.1, -0.1, 0.0)),
            ],
        };
        // The top bone turned (an armature's Z-up to Y-up) and moving.
        let frames: Vec<Pose> = (0..3)
            .map(|i| {
                let i = f64::from(i);
                Pose {
                    translations: vec![
                        DVec3::new(i, 0.0, 0.0),
                        DVec3::new(0.1, 0.9 + 0.1 * i, -4.5),
                        DVec3::new(0.0, 0.2, 0.0),
                        DVec3::new(0.1, -0.1, 0.0),
                    ],
                    rotations: vec![
                        DQuat::from_rotation_x(-std::f64::consts::FRAC_PI_2),
                        DQuat::from_rotation_y(0.3 * i),
                        DQuat::from_rotation_z(0.1 * i),
                        DQuat::IDENTITY,
                    ],
                }
            })
            .collect();
        let before: Vec<_> = frames
            .iter()
            .map(|f| forward_kinematics(&skeleton, f))
            .collect();
        let mut channels = vec![
            vec![Channel::Zrotation, Channel::Xrotation, Channel::Yrotation],
            vec![Channel::Zrotation, Channel::Xrotation, Channel::Yrotation],
            vec![Channel::Zrotation],
            vec![Channel::Zrotation],
        ];
        let mut after = frames.clone();
        let name = fold_top_bone(&mut skeleton, &mut channels, &mut after, 1);
        assert_eq!(name.as_deref(), Some("joint_Root"));
        assert_eq!(skeleton.len(), 3);
        assert_eq!(skeleton.joints[0].name, "Hips");
        assert_eq!(skeleton.joints[0].parent, None);
        assert_eq!(skeleton.joints[2].parent, Some(0));
        assert!(matches!(channels[0][0], Channel::Xposition), "{channels:?}");
        for (b, f) in before.iter().zip(&after) {
            let w = forward_kinematics(&skeleton, f);
            for j in 0..3 {
                assert!(w.positions[j].abs_diff_eq(b.positions[j + 1], 1e-12));
                assert!(w.rotations[j].abs_diff_eq(b.rotations[j + 1], 1e-12));
            }
        }
        // The pelvis is the root now: nothing more to fold.
        assert_eq!(
            fold_top_bone(&mut skeleton, &mut channels, &mut after, 0),
            None
        );
    }

    #[test]
    fn a_root_with_several_children_stays() {
        let mut skeleton = Skeleton {
            joints: vec![
                joint("root", None, DVec3::ZERO),
                joint("Hips", Some(0), DVec3::Y),
                joint("prop", Some(0), DVec3::X),
            ],
        };
        let mut frames = vec![Pose {
            translations: vec![DVec3::ZERO, DVec3::Y, DVec3::X],
            rotations: vec![DQuat::IDENTITY; 3],
        }];
        let mut channels = vec![Vec::new(); 3];
        assert_eq!(
            fold_top_bone(&mut skeleton, &mut channels, &mut frames, 1),
            None
        );
        assert_eq!(skeleton.len(), 3);
    }
}
