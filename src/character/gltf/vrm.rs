//! What a VRM file says of itself: its humanoid bone map (VRM 0.x `VRM`,
//! VRM 1.0 `VRMC_vrm`), which names the roles directly, and who made the
//! character under what licence (its `meta`).

use std::collections::BTreeMap;

use serde::Serialize;

use crate::character::roles::Role;

/// VRM's humanoid bone names and the role each plays (`chest` is where
/// the arms branch: the upper chest where there is one).
pub(super) const VRM_BONES: [(&str, Role); 16] = [
    ("hips", Role::Pelvis),
    ("upperChest", Role::Chest),
    ("neck", Role::Neck),
    ("head", Role::Head),
    ("leftUpperArm", Role::LeftShoulder),
    ("leftLowerArm", Role::LeftElbow),
    ("leftHand", Role::LeftHand),
    ("rightUpperArm", Role::RightShoulder),
    ("rightLowerArm", Role::RightElbow),
    ("rightHand", Role::RightHand),
    ("leftUpperLeg", Role::LeftHip),
    ("leftLowerLeg", Role::LeftKnee),
    ("leftFoot", Role::LeftFoot),
    ("rightUpperLeg", Role::RightHip),
    ("rightLowerLeg", Role::RightKnee),
    ("rightFoot", Role::RightFoot),
];

/// The VRM humanoid map of a glTF's root `extensions` (VRM 0.x `VRM`, or
/// 1.0 `VRMC_vrm`): VRM bone name → node index.
pub(super) fn vrm_bones(ext: &serde_json::Value) -> BTreeMap<String, usize> {
    let mut out = BTreeMap::new();
    // 0.x: an array of { bone, node }.
    if let Some(list) = ext
        .pointer("/VRM/humanoid/humanBones")
        .and_then(|v| v.as_array())
    {
        for b in list.iter().take(256) {
            if let (Some(bone), Some(node)) = (
                b.get("bone").and_then(|v| v.as_str()),
                b.get("node").and_then(serde_json::Value::as_u64),
            ) {
                out.insert(bone.to_owned(), node as usize);
            }
        }
    }
    // 1.0: an object of bone → { node }.
    if let Some(map) = ext
        .pointer("/VRMC_vrm/humanoid/humanBones")
        .and_then(|v| v.as_object())
    {
        for (bone, b) in map.iter().take(256) {
            if let Some(node) = b.get("node").and_then(serde_json::Value::as_u64) {
                out.insert(bone.clone(), node as usize);
            }
        }
    }
    out
}

/// Who made a VRM character and under what licence (its `meta`), for the
/// operator to credit it.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Credit {
    pub vrm: String,
    pub title: String,
    pub authors: String,
    pub licence: String,
}

/// The credit fields of a VRM's meta, each cut to 120 characters with
/// control characters left out.
pub(super) fn vrm_credit(ext: &serde_json::Value) -> Option<Credit> {
    let s = |v: Option<&serde_json::Value>| -> String {
        let text = match v {
            Some(serde_json::Value::String(s)) => s.clone(),
            Some(serde_json::Value::Array(a)) => a
                .iter()
                .filter_map(|x| x.as_str())
                .collect::<Vec<_>>()
                .join(", "),
            _ => String::new(),
        };
        text.chars().filter(|c| !c.is_control()).take(120).collect()
    };
    if let Some(m) = ext.pointer("/VRMC_vrm/meta") {
        return Some(Credit {
            vrm: "1.0".to_owned(),
            title: s(m.get("name")),
            authors: s(m.get("authors")),
            licence: s(m.get("licenseUrl")),
        });
    }
    let m = ext.pointer("/VRM/meta")?;
    let licence = match s(m.get("licenseName")).as_str() {
        "Other" | "" => s(m.get("otherLicenseUrl")),
        name => name.to_owned(),
    };
    Some(Credit {
        vrm: "0.x".to_owned(),
        title: s(m.get("title")),
        authors: s(m.get("author")),
        licence,
    })
}
