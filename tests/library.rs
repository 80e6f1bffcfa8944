//! Motion libraries over real motion capture: a valid library loads; a
//! broken one reports every problem at once, each naming what to fix.

mod common;

use std::path::Path;

use marionette::character::library::{Library, Release};
use marionette::character::roles::Role;

fn write_library(dir: &Path, clips_dir: &Path, body: &str) {
    let text = format!(
        "[settings]\nclips_dir = {:?}\n\n{body}",
        clips_dir.display().to_string()
    );
    std::fs::write(dir.join("library.toml"), text).unwrap();
}

const CMU_CC: &str = r#"
[posing]
clips = ["005_01.bvh", "006_01.bvh", "007_02.bvh"]

[[action]]
name = "punch"
clips = ["002_05.bvh"]
primary = "right_hand"
segments = [
  { until = 0.3, still = true, release = "backward" },
  { until = 0.7, still = false, release = "forward" },
  { until = 1.0, still = true, release = "forward" },
]

[[action]]
name = "jump"
clips = ["002_04.bvh"]
primary = "pelvis"
segments = [
  { until = 0.35, still = true, release = "backward" },
  { until = 1.0, still = false, release = "forward" },
]
"#;

#[test]
fn a_cmu_library_loads() {
    let dir = tempfile::tempdir().unwrap();
    write_library(
        dir.path(),
        &common::shared_dir().join("mocap/cmu-cc"),
        CMU_CC,
    );
    let lib = Library::load(dir.path()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(lib.clips.len(), 5);
    assert_eq!(lib.posing.len(), 3);
    assert_eq!(lib.actions.len(), 2);
    assert_eq!(lib.actions[0].primary, Role::RightHand);
    assert_eq!(lib.actions[0].segment_at(0.1).release, Release::Backward);
    assert!(!lib.actions[0].segment_at(0.5).still);
    assert_eq!(lib.actions[0].segment_at(1.0).release, Release::Forward);
    assert!(lib.clips.values().all(|c| c.scale_to_m == 0.01));
}

#[test]
fn a_broken_library_reports_every_problem_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let clips = dir.path().join("clips");
    std::fs::create_dir(&clips).unwrap();
    // A good clip, a clip of another skeleton, a malformed clip.
    std::fs::copy(
        common::shared_dir().join("mocap/cmu-cc/005_01.bvh"),
        clips.join("good.bvh"),
    )
    .unwrap();
    std::fs::copy(
        common::shared_dir().join("mocap/cmu-mixed/kick/74_05.bvh"),
        clips.join("other.bvh"),
    )
    .unwrap();
    std::fs::write(
        clips.join("broken.bvh"),
        "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0\n}\n",
    )
    .unwrap();
    write_library(
        dir.path(),
        &clips,
        r#"
[posing]
clips = ["good.bvh", "missing.bvh", "broken.bvh"]

[[action]]
name = "kick"
clips = ["other.bvh"]
primary = "right_foot"
segments = [{ until = 0.5, still = true, release = "forward" }, { until = 0.4, still = false, release = "forward" }]

[[action]]
name = "kick"
clips = []
primary = "tail"
segments = []
"#,
    );
    let e = Library::load(dir.path()).unwrap_err();
    let text = e.to_string();
    let expect = [
        "missing.bvh",                      // a file that is not there
        "broken.bvh:5",                     // a malformed clip, with its line
        "other.bvh: its hierarchy differs", // another skeleton
        "segment 2 ends at 0.4",            // segments out of order
        "the last segment must end at 1",
        "the name is used twice",
        "needs at least one clip",
        "primary `tail` is not a role",
        "needs condition segments",
    ];
    for want in expect {
        assert!(text.contains(want), "missing `{want}` in:\n{text}");
    }
    assert!(e.problems.len() >= expect.len(), "{text}");
}

#[test]
fn unknown_keys_and_a_missing_file_are_clear() {
    let dir = tempfile::tempdir().unwrap();
    let e = Library::load(dir.path()).unwrap_err().to_string();
    assert!(e.contains("library.toml"), "{e}");
    std::fs::write(dir.path().join("library.toml"), "[posing]\nclip = []\n").unwrap();
    let e = Library::load(dir.path()).unwrap_err().to_string();
    assert!(
        e.contains("unknown field `clip`") && e.contains("clips"),
        "{e}"
    );
}
