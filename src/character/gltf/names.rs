//! What a joint's name says: its side and the part it is, in the naming
//! conventions exhibit builders meet (Mixamo, Rigify and its layers, the
//! Unreal mannequin, Unity-like rigs, KayKit, Kenney, Godot, VRM,
//! Character Creator, Daz, MakeHuman, `l-arm`, and names of where a joint
//! is), helpers, faces and fingers told apart.

use crate::character::roles::{Role, words};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Side {
    Left,
    Right,
}

/// The part a joint's name says it is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Seg {
    Pelvis,
    Spine,
    Chest,
    Neck,
    Head,
    Clavicle,
    UpperArm,
    Forearm,
    Hand,
    Thigh,
    /// `leg`: the thigh in some conventions (`Left leg`), the shin in
    /// others (`LeftLeg` under `LeftUpLeg`); the hierarchy decides.
    Leg,
    Shin,
    Foot,
    Toe,
    Finger,
    /// Face, hair, accessories: not part of the body's chains.
    Face,
    /// IK targets, poles, controls, twist and roll bones, ends.
    Helper,
    Unknown,
}

/// Words that carry no part: prefixes of exporters and rigs.
const NOISE: [&str; 16] = [
    "def",
    "mixamorig",
    "cc",
    "base",
    "bip01",
    "bip",
    "jnt",
    "joint",
    "bone",
    "bn",
    "skeleton",
    "sk",
    "j",
    "b",
    "rig",
    "c",
];

/// Whole words that make a joint a helper.
const HELPER_WORDS: [&str; 22] = [
    "ik", "pt", "end", "nub", "top", "tip", "leaf", "roll", "twist", "share", "pole", "ctrl",
    "mch", "org", "slot", "heel", "target", "tgt", "orient", "null", "dummy", "aux",
];

/// Pieces that make a joint a helper wherever they stand in a word
/// (`l-LEGCONTROL`, `headtracker`, `handslot`).
const HELPER_PIECES: [&str; 12] = [
    "control",
    "ctrl",
    "target",
    "orient",
    "twist",
    "tracker",
    "helper",
    "socket",
    "weapon",
    "slot",
    "corrective",
    "pole",
];

const FACE: [&str; 16] = [
    "eye", "eyes", "jaw", "tongue", "teeth", "brow", "lid", "cheek", "lip", "hair", "ear", "nose",
    "face", "mouth", "chin", "bust",
];

const FINGERS: [&str; 10] = [
    "thumb", "index", "middle", "ring", "pinky", "little", "finger", "fingers", "palm", "f",
];

/// A name's side and part (`mixamorig:LeftForeArm` → left forearm,
/// `DEF-upper_arm.L` → left upper arm, `lShldrBend` → left upper arm,
/// `Left knee` → left shin).
pub(super) fn classify(name: &str) -> (Option<Side>, Seg) {
    let all = words(name);
    let lower = name.to_ascii_lowercase();
    let mut side = None;
    let mut rest: Vec<String> = Vec::new();
    for w in &all {
        match w.as_str() {
            "left" | "l" | "lft" => side = Some(Side::Left),
            "right" | "r" | "rt" | "rgt" => side = Some(Side::Right),
            _ => rest.push(w.clone()),
        }
    }
    // Digits at a word's end are a count (`spine01`, `index1`), not a part.
    let mut parts: Vec<String> = rest
        .iter()
        .map(|w| w.trim_end_matches(|c: char| c.is_ascii_digit()).to_owned())
        .filter(|w| !w.is_empty() && !NOISE.contains(&w.as_str()))
        .collect();
    if side.is_none() {
        // A side letter glued to a part (`lhand`, `rthigh`), as one word.
        for w in &mut parts {
            for (prefix, s) in [("l", Side::Left), ("r", Side::Right)] {
                if let Some(tail) = w.strip_prefix(prefix) {
                    if segment(tail).is_some() && segment(w).is_none() {
                        side = Some(s);
                        *w = tail.to_owned();
                    }
                }
            }
        }
    }
    if parts.iter().any(|w| HELPER_WORDS.contains(&w.as_str()))
        || HELPER_PIECES.iter().any(|p| lower.contains(p))
    {
        return (side, Seg::Helper);
    }
    if parts.iter().any(|w| FACE.contains(&w.as_str())) {
        return (side, Seg::Face);
    }
    if parts.iter().any(|w| FINGERS.contains(&w.as_str())) {
        return (side, Seg::Finger);
    }
    let joined: String = parts.concat();
    let mut seg = segment(&joined)
        .or_else(|| {
            // The first word that names a part (`shldr` of `ShldrBend`).
            parts.iter().find_map(|w| segment(w))
        })
        .unwrap_or(Seg::Unknown);
    // `Hips` is the pelvis; a hip with a side is where the thigh starts.
    if seg == Seg::Pelvis && side.is_some() {
        seg = Seg::Thigh;
    }
    if seg == Seg::Thigh && side.is_none() && joined.starts_with("hip") {
        seg = Seg::Pelvis;
    }
    (side, seg)
}

/// The part one word (or several joined) names.
fn segment(w: &str) -> Option<Seg> {
    Some(match w {
        "hips" | "hip" | "pelvis" => Seg::Pelvis,
        "spine" | "abdomen" | "abdomenlower" | "abdomenupper" | "waist" | "torso" | "belly"
        | "lowerback" | "spinelower" | "spineupper" | "body" => Seg::Spine,
        "chest" | "upperchest" | "chestlower" | "chestupper" | "ribcage" | "thorax" => Seg::Chest,
        "neck" | "necklower" | "neckupper" => Seg::Neck,
        "head" => Seg::Head,
        "shoulder" | "clavicle" | "collar" | "collarbone" | "clav" => Seg::Clavicle,
        "upperarm" | "uparm" | "arm" | "shldr" | "shldrbend" | "humerus" | "armupper" => {
            Seg::UpperArm
        }
        "forearm" | "lowerarm" | "loarm" | "lowarm" | "elbow" | "forearmbend" | "armlower" => {
            Seg::Forearm
        }
        "hand" | "wrist" => Seg::Hand,
        "thigh" | "upleg" | "upperleg" | "thighbend" | "legupper" | "femur" => Seg::Thigh,
        "leg" => Seg::Leg,
        "shin" | "calf" | "lowerleg" | "knee" | "loleg" | "lowleg" | "leglower" | "tibia"
        | "shinbend" => Seg::Shin,
        "foot" | "ankle" => Seg::Foot,
        "toe" | "toes" | "ball" | "toebase" => Seg::Toe,
        _ => return None,
    })
}

/// The limb roles of (side, arm): upper, middle, end.
pub(super) fn limb_roles(side: Side, arm: bool) -> [Role; 3] {
    match (side, arm) {
        (Side::Left, true) => [Role::LeftShoulder, Role::LeftElbow, Role::LeftHand],
        (Side::Right, true) => [Role::RightShoulder, Role::RightElbow, Role::RightHand],
        (Side::Left, false) => [Role::LeftHip, Role::LeftKnee, Role::LeftFoot],
        (Side::Right, false) => [Role::RightHip, Role::RightKnee, Role::RightFoot],
    }
}

pub(super) const LIMBS: [(Side, bool); 4] = [
    (Side::Left, true),
    (Side::Right, true),
    (Side::Left, false),
    (Side::Right, false),
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_of_the_common_conventions_say_their_part() {
        for (name, side, seg) in [
            ("mixamorig:LeftForeArm", Some(Side::Left), Seg::Forearm),
            ("mixamorig:LeftUpLeg", Some(Side::Left), Seg::Thigh),
            ("mixamorig:LeftLeg", Some(Side::Left), Seg::Leg),
            ("mixamorig:Hips", None, Seg::Pelvis),
            ("DEF-upper_arm.L", Some(Side::Left), Seg::UpperArm),
            ("DEF-thigh.R", Some(Side::Right), Seg::Thigh),
            ("MCH-thigh_ik.L", Some(Side::Left), Seg::Helper),
            ("upperarm_l", Some(Side::Left), Seg::UpperArm),
            ("calf_r", Some(Side::Right), Seg::Shin),
            ("ball_l", Some(Side::Left), Seg::Toe),
            ("clavicle_l", Some(Side::Left), Seg::Clavicle),
            ("UpperLeg.L", Some(Side::Left), Seg::Thigh),
            ("LowerArm.R", Some(Side::Right), Seg::Forearm),
            ("Wrist.L", Some(Side::Left), Seg::Hand),
            ("CC_Base_L_Upperarm", Some(Side::Left), Seg::UpperArm),
            ("CC_Base_R_Calf", Some(Side::Right), Seg::Shin),
            ("lShldrBend", Some(Side::Left), Seg::UpperArm),
            ("rForearmBend", Some(Side::Right), Seg::Forearm),
            ("lThighBend", Some(Side::Left), Seg::Thigh),
            ("lShldrTwist", Some(Side::Left), Seg::Helper),
            ("rShin", Some(Side::Right), Seg::Shin),
            ("l-forearm", Some(Side::Left), Seg::Forearm),
            ("l-thigh", Some(Side::Left), Seg::Thigh),
            ("l-LEGCONTROL", Some(Side::Left), Seg::Helper),
            ("Left elbow", Some(Side::Left), Seg::Forearm),
            ("Left knee", Some(Side::Left), Seg::Shin),
            ("Left arm", Some(Side::Left), Seg::UpperArm),
            ("Right ankle", Some(Side::Right), Seg::Foot),
            ("kneeIK.l", Some(Side::Left), Seg::Helper),
            ("IK-foot.l", Some(Side::Left), Seg::Helper),
            ("handslot.l", Some(Side::Left), Seg::Helper),
            ("LeftHandIndex1", Some(Side::Left), Seg::Finger),
            ("DEF-f_index.01.L", Some(Side::Left), Seg::Finger),
            ("headtracker", None, Seg::Helper),
            ("HeadTop_End", None, Seg::Helper),
            ("LeftFootCtrl", Some(Side::Left), Seg::Helper),
            ("spine_01", None, Seg::Spine),
            ("leg-left", Some(Side::Left), Seg::Leg),
            ("LHand", Some(Side::Left), Seg::Hand),
            ("lhand", Some(Side::Left), Seg::Hand),
        ] {
            assert_eq!(classify(name), (side, seg), "{name}");
        }
    }
}
