//! Body-part roles: which joint is the head, the chest, a hand, a foot...
//!
//! Filled from joint names of the common conventions (CMU conversions,
//! 3ds Max exports, Mixamo `mixamorig:`, Character Creator `CC_Base_`,
//! `UpperArm_L`-style names) and from the hierarchy itself: only hands, feet
//! and the head are found by name; elbows, shoulders, knees and hips are the
//! joints above them (twist and helper bones skipped), the pelvis and chest
//! are where the legs and the arms branch. A library can override any role.

use std::collections::BTreeMap;
use std::fmt;

use serde::Serialize;
use thiserror::Error;

use super::skeleton::Skeleton;

/// A body part the method constrains or reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Role {
    Pelvis,
    Chest,
    Neck,
    Head,
    LeftShoulder,
    LeftElbow,
    LeftHand,
    RightShoulder,
    RightElbow,
    RightHand,
    LeftHip,
    LeftKnee,
    LeftFoot,
    RightHip,
    RightKnee,
    RightFoot,
}

impl Role {
    pub const ALL: [Role; 16] = [
        Role::Pelvis,
        Role::Chest,
        Role::Neck,
        Role::Head,
        Role::LeftShoulder,
        Role::LeftElbow,
        Role::LeftHand,
        Role::RightShoulder,
        Role::RightElbow,
        Role::RightHand,
        Role::LeftHip,
        Role::LeftKnee,
        Role::LeftFoot,
        Role::RightHip,
        Role::RightKnee,
        Role::RightFoot,
    ];

    /// Position in [`Role::ALL`].
    #[must_use]
    pub fn index(self) -> usize {
        self as usize
    }

    /// The name used in library files and JSON (`left_hand`).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Role::Pelvis => "pelvis",
            Role::Chest => "chest",
            Role::Neck => "neck",
            Role::Head => "head",
            Role::LeftShoulder => "left_shoulder",
            Role::LeftElbow => "left_elbow",
            Role::LeftHand => "left_hand",
            Role::RightShoulder => "right_shoulder",
            Role::RightElbow => "right_elbow",
            Role::RightHand => "right_hand",
            Role::LeftHip => "left_hip",
            Role::LeftKnee => "left_knee",
            Role::LeftFoot => "left_foot",
            Role::RightHip => "right_hip",
            Role::RightKnee => "right_knee",
            Role::RightFoot => "right_foot",
        }
    }

    #[must_use]
    pub fn from_name(s: &str) -> Option<Role> {
        Role::ALL.into_iter().find(|r| r.name() == s)
    }
}

impl fmt::Display for Role {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Why roles cannot be filled.
#[derive(Debug, Error, PartialEq)]
pub enum RolesError {
    #[error("cannot find the joints for {}: name them in the library's [roles] table (e.g. left_hand = \"LeftWrist\")", list(.0))]
    Missing(Vec<Role>),
    #[error("[roles] names {}, which is not a role; roles are {all}", crate::reading::quote(.0), all = list(&Role::ALL))]
    UnknownRole(String),
    #[error("[roles] {role} = {}: the skeleton has no joint of that name", crate::reading::quote(.joint))]
    UnknownJoint { role: Role, joint: String },
    #[error("[roles] {first} and {second} both name {}: each role needs a joint of its own", crate::reading::quote(.joint))]
    SharedJoint {
        first: Role,
        second: Role,
        joint: String,
    },
}

fn list(roles: &[Role]) -> String {
    roles
        .iter()
        .map(|r| r.name())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Role → joint index.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RoleMap(pub BTreeMap<Role, usize>);

impl Role {
    /// The same part on the other side (itself on the middle line).
    #[must_use]
    pub fn mirrored(self) -> Self {
        match self {
            Role::LeftShoulder => Role::RightShoulder,
            Role::LeftElbow => Role::RightElbow,
            Role::LeftHand => Role::RightHand,
            Role::LeftHip => Role::RightHip,
            Role::LeftKnee => Role::RightKnee,
            Role::LeftFoot => Role::RightFoot,
            Role::RightShoulder => Role::LeftShoulder,
            Role::RightElbow => Role::LeftElbow,
            Role::RightHand => Role::LeftHand,
            Role::RightHip => Role::LeftHip,
            Role::RightKnee => Role::LeftKnee,
            Role::RightFoot => Role::LeftFoot,
            other => other,
        }
    }
}

impl RoleMap {
    /// The joint of a role (every role is present in a filled map).
    #[must_use]
    pub fn get(&self, role: Role) -> usize {
        self.0[&role]
    }

    /// Role → joint name, for JSON output.
    #[must_use]
    pub fn names(&self, skeleton: &Skeleton) -> BTreeMap<String, String> {
        self.0
            .iter()
            .map(|(r, j)| (r.name().to_owned(), skeleton.joints[*j].name.clone()))
            .collect()
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Side {
    Left,
    Right,
}

/// Lower-case words of a joint name: prefixes before `:` dropped, split at
/// separators and camel-case boundaries (`LHipJoint` → l, hip, joint).
pub(crate) fn words(name: &str) -> Vec<String> {
    let name = name.rsplit(':').next().unwrap_or(name);
    let mut out = Vec::new();
    for part in name.split(|c: char| !c.is_ascii_alphanumeric()) {
        let chars: Vec<char> = part.chars().collect();
        let mut cur = String::new();
        for (i, &c) in chars.iter().enumerate() {
            let boundary = i > 0
                && c.is_ascii_uppercase()
                && (chars[i - 1].is_ascii_lowercase()
                    || chars[i - 1].is_ascii_digit()
                    || chars.get(i + 1).is_some_and(|n| n.is_ascii_lowercase()));
            if boundary && !cur.is_empty() {
                out.push(std::mem::take(&mut cur).to_ascii_lowercase());
            }
            cur.push(c);
        }
        if !cur.is_empty() {
            out.push(cur.to_ascii_lowercase());
        }
    }
    out
}

const PARTS: [&str; 6] = ["hand", "wrist", "foot", "ankle", "shoulder", "hip"];
const HELPERS: [&str; 6] = ["twist", "share", "roll", "end", "nub", "top"];
const DIGITS: [&str; 8] = [
    "finger", "fingers", "thumb", "index", "mid", "middle", "ring", "pinky",
];

/// The side and the remaining words of a name.
fn side_and_words(name: &str) -> (Option<Side>, Vec<String>) {
    let mut w = words(name);
    let mut side = None;
    w.retain(|t| match t.as_str() {
        "left" | "l" => {
            side = Some(Side::Left);
            false
        }
        "right" | "r" => {
            side = Some(Side::Right);
            false
        }
        _ => true,
    });
    if side.is_none() {
        // `lhand`, `rfoot`: a side letter glued to a part name.
        for t in &mut w {
            for (prefix, s) in [("l", Side::Left), ("r", Side::Right)] {
                if let Some(rest) = t.strip_prefix(prefix) {
                    if PARTS.contains(&rest) {
                        side = Some(s);
                        *t = rest.to_owned();
                    }
                }
            }
        }
    }
    (side, w)
}

fn is_helper(name: &str) -> bool {
    words(name).iter().any(|w| HELPERS.contains(&w.as_str()))
}

/// The shallowest joint whose name has one of `parts` on `side`, and none
/// of the helper or finger words.
fn find_by_name(skeleton: &Skeleton, side: Option<Side>, parts: &[&str]) -> Option<usize> {
    (0..skeleton.len())
        .filter(|&i| {
            let (s, w) = side_and_words(&skeleton.joints[i].name);
            s == side
                && w.iter().any(|t| parts.contains(&t.as_str()))
                && !w.iter().any(|t| {
                    HELPERS.contains(&t.as_str()) || DIGITS.contains(&t.as_str()) || t == "toe"
                })
        })
        .min_by_key(|&i| skeleton.depth(i))
}

/// The first joint above `j` that is not a twist or helper bone.
fn limb_parent(skeleton: &Skeleton, j: usize) -> Option<usize> {
    let mut p = skeleton.joints[j].parent?;
    while is_helper(&skeleton.joints[p].name) {
        p = skeleton.joints[p].parent?;
    }
    Some(p)
}

/// Refused where a role given by hand names a joint another role given
/// by hand has already (every role on one joint: its actions would never
/// start).
pub(crate) fn shared(
    given: &BTreeMap<Role, usize>,
    role: Role,
    joint: usize,
    name: &str,
) -> Result<(), RolesError> {
    match given.iter().find(|&(r, &j)| j == joint && *r != role) {
        Some((&first, _)) => Err(RolesError::SharedJoint {
            first,
            second: role,
            joint: name.to_owned(),
        }),
        None => Ok(()),
    }
}

/// Fill every role, applying `overrides` (role name → joint name) first.
pub fn fill(
    skeleton: &Skeleton,
    overrides: &BTreeMap<String, String>,
) -> Result<RoleMap, RolesError> {
    let mut map = BTreeMap::new();
    for (role, joint) in overrides {
        let r = Role::from_name(role).ok_or_else(|| RolesError::UnknownRole(role.clone()))?;
        let j = skeleton
            .find(joint)
            .ok_or_else(|| RolesError::UnknownJoint {
                role: r,
                joint: joint.clone(),
            })?;
        shared(&map, r, j, joint)?;
        map.insert(r, j);
    }
    let put = |map: &mut BTreeMap<Role, usize>, role: Role, j: Option<usize>| {
        if let Some(j) = j {
            map.entry(role).or_insert(j);
        }
    };
    put(
        &mut map,
        Role::Head,
        find_by_name(skeleton, None, &["head"]),
    );
    for (side, hand, elbow, shoulder, foot, knee, hip) in [
        (
            Side::Left,
            Role::LeftHand,
            Role::LeftElbow,
            Role::LeftShoulder,
            Role::LeftFoot,
            Role::LeftKnee,
            Role::LeftHip,
        ),
        (
            Side::Right,
            Role::RightHand,
            Role::RightElbow,
            Role::RightShoulder,
            Role::RightFoot,
            Role::RightKnee,
            Role::RightHip,
        ),
    ] {
        put(
            &mut map,
            hand,
            find_by_name(skeleton, Some(side), &["hand", "wrist"]),
        );
        put(
            &mut map,
            foot,
            find_by_name(skeleton, Some(side), &["foot", "ankle"]),
        );
        let e = map.get(&hand).and_then(|&h| limb_parent(skeleton, h));
        put(&mut map, elbow, e);
        let s = map.get(&elbow).and_then(|&e| limb_parent(skeleton, e));
        put(&mut map, shoulder, s);
        let k = map.get(&foot).and_then(|&f| limb_parent(skeleton, f));
        put(&mut map, knee, k);
        let h = map.get(&knee).and_then(|&k| limb_parent(skeleton, k));
        put(&mut map, hip, h);
    }
    complete(skeleton, map)
}

/// The middle of the body from the limbs found in `map` (the pelvis where
/// the hips meet, the chest where the shoulders meet, the neck on the way
/// from the chest to the head), unless `map` has them; every role must
/// then be found.
pub fn complete(
    skeleton: &Skeleton,
    mut map: BTreeMap<Role, usize>,
) -> Result<RoleMap, RolesError> {
    let put = |map: &mut BTreeMap<Role, usize>, role: Role, j: Option<usize>| {
        if let Some(j) = j {
            map.entry(role).or_insert(j);
        }
    };
    if let (Some(&l), Some(&r)) = (map.get(&Role::LeftHip), map.get(&Role::RightHip)) {
        put(&mut map, Role::Pelvis, Some(skeleton.common_ancestor(l, r)));
    }
    if let (Some(&l), Some(&r)) = (map.get(&Role::LeftShoulder), map.get(&Role::RightShoulder)) {
        let chest = skeleton.common_ancestor(l, r);
        put(&mut map, Role::Chest, Some(chest));
        // The neck: the chest's child on the way to the head.
        if let Some(&head) = map.get(&Role::Head) {
            let mut j = head;
            while let Some(p) = skeleton.joints[j].parent {
                if p == chest {
                    break;
                }
                j = p;
            }
            put(
                &mut map,
                Role::Neck,
                (j != head && skeleton.is_ancestor(chest, j))
                    .then_some(j)
                    .or(Some(head)),
            );
        }
    }
    let missing: Vec<Role> = Role::ALL
        .into_iter()
        .filter(|r| !map.contains_key(r))
        .collect();
    if missing.is_empty() {
        Ok(RoleMap(map))
    } else {
        Err(RolesError::Missing(missing))
    }
}
