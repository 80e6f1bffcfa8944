//! A visitor who yanks the character: random multi-finger abuse authored
//! as a recording (`marionette author-abuse`), the same for a seed, and
//! replayed through the whole pipeline with `replay --metrics`.

#![allow(
    clippy::print_stderr,
    reason = "the measurements are printed for the reader of the run"
)]

mod common;

use common::marionette;

#[test]
fn abuse_is_the_same_for_a_seed_and_replays_without_nan() {
    let dir = tempfile::tempdir().unwrap();
    let file = |name: &str| dir.path().join(name);
    let author = |seed: &str, out: &str| {
        let o = marionette(&[
            "author-abuse",
            "--seconds",
            "60",
            "--seed",
            seed,
            "--out",
            file(out).to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        std::fs::read(file(out)).unwrap()
    };
    let (a, b, c) = (
        author("1", "a.evemu"),
        author("1", "b.evemu"),
        author("2", "c.evemu"),
    );
    assert_eq!(a, b, "the same seed, the same recording");
    assert_ne!(a, c, "another seed, another recording");
    let o = marionette(&[
        "replay",
        file("a.evemu").to_str().unwrap(),
        "--metrics",
        file("a.json").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let m: serde_json::Value =
        serde_json::from_slice(&std::fs::read(file("a.json")).unwrap()).unwrap();
    assert!(m["frames"].as_f64().unwrap() > 1700.0, "{m}");
    assert_eq!(m["nan_frames"], 0, "{m}");
    eprintln!("{m}");
    // A minute of it (seed 1): no pop, no joint's speed changing by more
    // than the bound's 8 rad/s in a frame (17 pops without the bound),
    // nothing into the floor.
    assert_eq!(m["pops"].as_f64().unwrap(), 0.0, "{m}");
    assert!(
        m["max_joint_speed_jump_rad_s"].as_f64().unwrap() <= 8.01,
        "{m}"
    );
    assert!(m["ground_penetration_mm"].as_f64().unwrap() <= 0.1, "{m}");
    // Fingers aimed at the body hold parts and start actions.
    assert!(!m["actions"].as_array().unwrap().is_empty(), "{m}");
    // Bad lengths are refused, nothing written.
    for bad in ["0", "7200", "nan"] {
        let o = marionette(&[
            "author-abuse",
            "--seconds",
            bad,
            "--out",
            file("d.evemu").to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(2), "{bad}");
        assert!(!file("d.evemu").exists());
    }
}
