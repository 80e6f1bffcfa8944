//! Real motion capture (../shared/mocap, CMU in several conversions): every
//! file imports with a plausible height, one unit per skeleton family, all
//! roles filled; export → import gives the same joint positions within
//! 0.1 mm on every frame.

mod common;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use marionette::character::bvh;
use marionette::character::motion::{Clip, ImportSettings};
use marionette::character::roles::Role;
use marionette::character::skeleton::forward_kinematics;

fn mocap_files() -> Vec<(PathBuf, String)> {
    let dir = common::shared_dir().join("mocap");
    let text = std::fs::read_to_string(dir.join("INDEX.tsv")).unwrap();
    text.lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let f: Vec<&str> = l.split('\t').collect();
            (dir.join(f[0]), f[1].to_owned())
        })
        .collect()
}

fn import(path: &Path) -> Clip {
    let file = bvh::read_file(path).unwrap_or_else(|e| panic!("{e}"));
    Clip::from_bvh(file, &ImportSettings::default())
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn every_mocap_file_imports_with_a_plausible_height() {
    let files = mocap_files();
    assert!(files.len() >= 60);
    let mut scales: HashMap<String, Vec<f64>> = HashMap::new();
    for (path, set) in &files {
        let clip = import(path);
        assert_eq!(clip.roles.0.len(), Role::ALL.len(), "{}", path.display());
        // Stature from the bones, whatever the first frame: 74_12
        // ("thinker") starts seated, 83_11 perched, 143_30 stretching.
        assert!(
            (1.2..2.1).contains(&clip.height_m),
            "{}: height {:.3} m",
            path.display(),
            clip.height_m
        );
        scales.entry(set.clone()).or_default().push(clip.scale_to_m);
        // The hands are where they should be: left hand on the left of the
        // body's facing direction at rest is too much to ask of every
        // conversion, but both hands must be distinct joints below the head.
        assert_ne!(
            clip.roles.get(Role::LeftHand),
            clip.roles.get(Role::RightHand)
        );
    }
    for (set, s) in &scales {
        assert!(
            s.iter().all(|x| (x - s[0]).abs() < 1e-12),
            "{set}: one skeleton family, one unit: {s:?}"
        );
    }
    assert!(
        (scales["cmu-cc"][0] - 0.01).abs() < 1e-12,
        "the CC rig is in centimetres"
    );
}

#[test]
fn converter_tpose_frames_are_detected() {
    // The cgspeed conversions start with an added T-pose; the retargeted
    // Holden-style copies do not (see the index's conversion notes). The
    // index says every CC rig file has a T-pose frame prepended, but only
    // some do: there frame 0 has the rig's rest rotation (root unrotated)
    // and the root jumps to where the motion starts. In the others (002_01,
    // say) frame 0 has the arms down and the root moves on from it at the
    // pace of every later frame. The raw data decides for those.
    for (path, _) in mocap_files() {
        let index = std::fs::read_to_string(common::shared_dir().join("mocap/INDEX.tsv")).unwrap();
        let rel = path
            .strip_prefix(common::shared_dir().join("mocap"))
            .unwrap()
            .to_string_lossy()
            .into_owned();
        let row = index.lines().find(|l| l.starts_with(&rel)).unwrap();
        let raw = bvh::read_file(&path).unwrap();
        let rest_then_jump = raw.frames[0].rotations[0].angle_between(glam::DQuat::IDENTITY)
            < 1f64.to_radians()
            && (raw.frames[0].translations[0] - raw.frames[1].translations[0]).length() > 10.0;
        let cc = rel.starts_with("cmu-cc/");
        let says_tpose = row.contains("frame 1 = added T-pose") || (cc && rest_then_jump);
        let says_none = row.contains("no T-pose frame") || (cc && !rest_then_jump);
        let clip = import(&path);
        if says_tpose {
            assert!(
                clip.dropped_tpose,
                "{rel}: its first frame is a converter's T-pose"
            );
        }
        if says_none {
            assert!(!clip.dropped_tpose, "{rel}: has no T-pose frame");
        }
    }
}

#[test]
fn export_then_import_keeps_joint_positions_within_a_tenth_of_a_millimetre() {
    let mut checked = 0;
    for (path, _) in mocap_files() {
        let clip = import(&path);
        let text = bvh::write(
            &clip.skeleton,
            &clip.translates,
            &clip.frames,
            clip.frame_time,
        );
        let again = bvh::parse(&text, Path::new("exported.bvh")).unwrap();
        assert_eq!(again.frames.len(), clip.frames.len());
        let mut worst = 0.0f64;
        for (a, b) in clip.frames.iter().zip(&again.frames) {
            let wa = forward_kinematics(&clip.skeleton, a);
            let wb = forward_kinematics(&again.skeleton, b);
            for i in 0..clip.skeleton.len() {
                worst = worst.max((wa.positions[i] - wb.positions[i]).length());
                if let (Some(ea), Some(eb)) = (
                    wa.end_site(&clip.skeleton, i),
                    wb.end_site(&again.skeleton, i),
                ) {
                    worst = worst.max((ea - eb).length());
                }
            }
        }
        assert!(
            worst < 1e-4,
            "{}: worst joint moved {:.6} mm",
            path.display(),
            worst * 1e3
        );
        // Re-importing the export finds the same unit (metres) and roles.
        let clip2 = Clip::from_bvh(again, &ImportSettings::default()).unwrap();
        assert_eq!(clip2.scale_to_m, 1.0, "{}", path.display());
        assert_eq!(clip2.roles, clip.roles);
        checked += 1;
    }
    assert!(checked >= 60);
}

#[test]
fn clips_that_differ_by_a_top_bone_import_to_one_skeleton() {
    // CMU 002_01 carries `RL_BoneRoot` above `CC_Base_Hip`; 005_01 does
    // not. Folded into the bone below it, both have the same hierarchy, so
    // they can share a library.
    let dir = common::shared_dir().join("mocap/cmu-cc");
    let with = import(&dir.join("002_01.bvh"));
    let without = import(&dir.join("005_01.bvh"));
    let names =
        |c: &Clip| -> Vec<String> { c.skeleton.joints.iter().map(|j| j.name.clone()).collect() };
    assert_eq!(names(&with), names(&without));
    assert_eq!(with.skeleton.joints[0].name, "CC_Base_Hip");
}

#[test]
fn stature_comes_from_the_bones_not_the_first_posture() {
    // Subject 74 starts 74_10 standing ("peeping") and 74_12 seated
    // ("thinker"): one skeleton, one stature; the first frames differ by
    // about 40 cm.
    let idle = common::shared_dir().join("mocap/cmu-mixed/idle");
    let standing = import(&idle.join("74_10.bvh"));
    let seated = import(&idle.join("74_12.bvh"));
    assert_eq!(standing.skeleton, seated.skeleton);
    assert_eq!(standing.height_m, seated.height_m);
    assert!(
        standing.first_frame_height_m - seated.first_frame_height_m > 0.3,
        "{} {}",
        standing.first_frame_height_m,
        seated.first_frame_height_m
    );
    // Standing upright, a person is about as tall as their bones say.
    let ratio = standing.first_frame_height_m / standing.height_m;
    assert!((0.95..1.05).contains(&ratio), "{ratio}");
}

#[test]
fn a_rig_that_ends_at_the_head_joint_gets_its_crown() {
    // The Bandai rig's Head has a zero End Site: its bones stop at the top
    // of the neck (1.327 m from the bones alone). The crown, 12% of the
    // stature above the head joint, is added; CMU's converted rig, whose
    // head has its own extent, is measured as it was.
    let shared = common::shared_dir().join("mocap");
    let bandai = import(&shared.join("bandai/d1_walk_giant_001.bvh"));
    assert!(
        (bandai.height_m - 1.508).abs() < 0.005,
        "{}",
        bandai.height_m
    );
    // Its first frame, walking crouched as a giant, a little less.
    assert!(
        (bandai.first_frame_height_m - 1.490).abs() < 0.005,
        "{}",
        bandai.first_frame_height_m
    );
    let cmu = import(&shared.join("cmu-cc/002_05.bvh"));
    assert!((cmu.height_m - 1.791).abs() < 0.005, "{}", cmu.height_m);
}

#[test]
fn limits_are_judged_from_the_body_not_the_rigs_axes() {
    // The Bandai rig's rest pose lies along X: judged by its pelvis's
    // joint axes, every standing frame read as hips spread 70-86° and the
    // chest turned 95-106°. From where the hips, shoulders and neck are,
    // a bow is within human limits and a high kick spreads the hip.
    use marionette::tools::checks::{Limits, check};
    let shared = common::shared_dir().join("mocap/bandai");
    let judge = |name: &str| {
        let c = import(&shared.join(name));
        check(&c.skeleton, &c.roles, &c.frames, 0.0, &Limits::default())
    };
    for bow in [
        "d1_bow_active_001.bvh",
        "d1_bow_feminine_001.bvh",
        "d1_bow_proud_001.bvh",
    ] {
        let r = judge(bow);
        assert!(r.violations.is_empty(), "{bow}: {:?}", r.violations);
    }
    let kick = judge("d1_kick_normal_001.bvh");
    assert!(
        kick.violations
            .iter()
            .any(|v| v.contains("right_hip spread")),
        "{:?}",
        kick.violations
    );
}
