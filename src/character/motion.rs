//! A motion clip in marionette's conventions: metres, the converter's
//! T-pose frame (if any) set aside, roles filled.

use std::collections::BTreeMap;

use glam::DVec3;

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
    /// Standing height in the first frame, floor to top of head (m).
    pub height_m: f64,
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
/// the head (the head's End Site, or its furthest descendant). A standing
/// person is about this tall; used to find the file's unit.
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
    leg + trunk + head_top + ankle
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
    top - floor
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
        let roles = roles::fill(&skeleton, &settings.roles)?;
        let dropped_tpose = first_frame_is_tpose(&skeleton, &roles, &frames);
        if dropped_tpose {
            frames.remove(0);
        }
        let height_units = standing_height(&skeleton, &roles, &frames[0]);
        let scale = match settings.scale_to_m {
            Some(s) if s.is_finite() && s > 0.0 => s,
            Some(s) => return Err(ClipError::BadScale(s)),
            None => detect_scale(chain_stature(&skeleton, &roles)),
        };
        skeleton.scale(scale);
        for f in &mut frames {
            for t in &mut f.translations {
                *t *= scale;
            }
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
            height_m: height_units * scale,
        })
    }
}
