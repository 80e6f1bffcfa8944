//! Action recognition on real motion capture: the CMU action library in
//! tests/libraries/cmu-actions (punches, a jump and walks cut from subject
//! 2's and 7's takes on the Character Creator rig), tested with held-out
//! takes cut the same way: two punches of the same take that the model
//! does not use, jumps and a walk of other subjects on other rigs, and a
//! walk of subject 7 left out of the library. `marionette eval actions`
//! runs on them as an operator would run it.

#![allow(
    clippy::print_stdout,
    clippy::print_stderr,
    reason = "measurements are printed for the reader of the run"
)]

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use marionette::character::bvh;
use marionette::character::motion::{Clip, ImportSettings};

/// Held-out actions: (action, file under ../shared/mocap, first and last
/// frame of the clip as imported, a converter's T-pose frame set aside).
const HELD_OUT: [(&str, &str, usize, usize); 9] = [
    ("punch_high", "cmu-cc/002_05.bvh", 129, 217),
    ("punch_mid", "cmu-cc/002_05.bvh", 390, 477),
    ("punch_low", "cmu-cc/002_05.bvh", 651, 740),
    ("jump", "cmu-mixed/jump/01_01.bvh", 131, 348),
    ("jump", "cmu-mixed/jump/01_01.bvh", 337, 547),
    ("jump", "cmu-mixed/jump/01_01.bvh", 501, 715),
    ("jump", "cmu-mixed/jump/131_03.bvh", 713, 908),
    ("walk", "cmu-cc/007_12.bvh", 0, 89),
    ("walk", "cmu-mixed/walk/16_11.bvh", 0, 180),
];

/// Write the held-out clips into `dir` as `<action>_<n>.bvh`.
fn write_held_out(dir: &Path) {
    let mocap = common::shared_dir().join("mocap");
    for (n, (action, file, first, last)) in HELD_OUT.iter().enumerate() {
        let clip = Clip::from_bvh(
            bvh::read_file(&mocap.join(file)).unwrap(),
            &ImportSettings::default(),
        )
        .unwrap();
        let text = bvh::write(
            &clip.skeleton,
            &clip.translates,
            &clip.frames[*first..=*last],
            clip.frame_time,
        );
        std::fs::write(dir.join(format!("{action}_{n}.bvh")), text).unwrap();
    }
}

fn eval(library: &Path, tests: &Path, extra: &[&str]) -> serde_json::Value {
    let cache = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_marionette"))
        .args(["eval", "actions", "--library"])
        .arg(library)
        .arg("--test")
        .arg(tests)
        .args(extra)
        .env("CACHE_DIRECTORY", cache.path())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn cmu_actions_are_recognised_from_held_out_takes() {
    let library = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/libraries/cmu-actions");
    let tests = tempfile::tempdir().unwrap();
    write_held_out(tests.path());
    // (mode, a floor under the share of correct trials this library
    // reaches today with the template recogniser: 0.389 through the
    // controller, 0.426 alone; the paper's rule reached 0.278 and 0.185).
    // Each floor sits one trial (0.019) under the figure.
    for (mode, floor) in [(&[][..], 0.37), (&["--models-only"][..], 0.407)] {
        let r = eval(&library, tests.path(), mode);
        eprintln!("CMU actions {mode:?}: {r}");
        assert_eq!(r["trials"], HELD_OUT.len() * 6);
        let f = |k: &str| r[k].as_f64().unwrap();
        assert!(
            (f("correct") + f("wrong_action") + f("missed") - 1.0).abs() < 0.01,
            "{r}"
        );
        // Slow drags start an action in at most one trial of 54.
        assert!(f("false_trigger_slow") <= 0.02, "{r}");
        assert!(f("wrong_action") <= 0.12, "{r}");
        // One subject's takes do not carry over to everyone's as the
        // default library's variants do: the only jump of the set is one
        // person's (24 of the 54 trials), and the three punch heights are
        // near ties. What is asserted is what this library reaches today
        // (see docs/measurements.md), so that a change that loses it shows.
        assert!(f("correct") >= floor, "{r}");
    }
}
