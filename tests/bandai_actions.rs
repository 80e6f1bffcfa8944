//! Action recognition on a studio's capture the library was not built
//! from: the Bandai share, a library made by `library init` from six styles
//! (active, angry, feminine, happy, masculinity, proud; and the only
//! takes of punch, kick and slash), tested on the four other styles
//! (childish, giant, musical, normal) of the ten actions that have them.
//! `library check` on the same library names what an exhibit builder can
//! act on, and its leave-one-out figures are close to the held-out ones.

#![allow(
    clippy::print_stdout,
    clippy::print_stderr,
    reason = "measurements are printed for the reader of the run"
)]

mod common;

use std::path::Path;
use std::process::Command;

fn run(args: &[&str], cache: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_marionette"))
        .args(args)
        .env("CACHE_DIRECTORY", cache)
        .env_remove("RUST_LOG")
        .output()
        .unwrap()
}

fn json(out: &std::process::Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn bandai_styles_left_out_and_what_library_check_says() {
    let tmp = tempfile::tempdir().unwrap();
    let (takes, held, lib, cache) = (
        tmp.path().join("takes"),
        tmp.path().join("held"),
        tmp.path().join("lib"),
        tmp.path().join("cache"),
    );
    for d in [&takes, &held] {
        std::fs::create_dir(d).unwrap();
    }
    common::bandai::split(&takes, Some(&held));
    let s = |p: &Path| p.to_str().unwrap().to_owned();
    let init = run(&["library", "init", &s(&takes), "--out", &s(&lib)], &cache);
    assert!(
        init.status.success(),
        "{}",
        String::from_utf8_lossy(&init.stderr)
    );
    // The first 20 frames of the feminine bow (standing, a hand to the
    // chest: the head hardly moves) are no bow of their own.
    let said = String::from_utf8_lossy(&init.stdout);
    assert!(
        said.contains("bow_feminine_001.bvh#0-19: the head moves")
            && said.contains("no action of its own"),
        "{said}"
    );

    // What a drag can start, from the library alone.
    let explained = tmp.path().join("left-out.jsonl");
    let check = json(&run(
        &[
            "library",
            "check",
            &s(&lib),
            "--json",
            "--explain",
            &s(&explained),
        ],
        &cache,
    ));
    let advice: Vec<String> = check["advice"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a.as_str().unwrap().to_owned())
        .collect();
    eprintln!("library check: {}", serde_json::to_string(&check).unwrap());
    // (named by side where one hand or foot leads: `punch_left`,
    // `kick_right`; slash is swung with both.)
    for one in ["punch_left", "kick_right", "slash"] {
        assert!(
            advice
                .iter()
                .any(|a| a.starts_with(&format!("`{one}` has one take"))),
            "{advice:#?}"
        );
    }
    // The walks go the same way from the 45° view of their start.
    assert!(
        advice
            .iter()
            .any(|a| a.starts_with("`walk` drags from the 45° view start `walk-right`")),
        "{advice:#?}"
    );
    // The styles' takes of an action differ in size (2 to 5 times) where
    // its left-out drags start it seldom, and one take of `byebye` goes
    // another way than its others (108 degrees from them).
    for name in ["bow", "bye_right", "bye_left", "byebye"] {
        assert!(
            advice
                .iter()
                .any(|a| a.starts_with(&format!("`{name}`'s takes differ in size"))),
            "{advice:#?}"
        );
    }
    assert!(
        advice
            .iter()
            .any(|a| a.contains("a take of `byebye`, goes another way than its other takes")),
        "{advice:#?}"
    );
    // A walk's takes go on for 5 to 8 m, of which a drag shows 1.5 s
    // (about 2 m): its drags start it seldom, and the builder is told.
    assert!(
        advice
            .iter()
            .any(|a| a.starts_with("`walk`: a drag shows the first 1.5 s of its takes' movement")),
        "{advice:#?}"
    );
    // Left out in turn (540 drags; the feminine bye-bye, whose hands
    // hardly move, is no action, nor are the pieces of a bow and a guide
    // take in which the part hardly moves, and bye-bye and slash, both
    // hands alike, have no mirror image): correct 0.187, wrong 0.043, slow
    // 0.007.
    let f = |v: &serde_json::Value, k: &str| v[k].as_f64().unwrap();
    assert_eq!(check["drags"], 540);
    // Every left-out drag explained, deciding as the report counts them.
    let drags: Vec<serde_json::Value> = std::fs::read_to_string(&explained)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let (slow, true_drags): (Vec<_>, Vec<_>) = drags.iter().partition(|d| d["slow"] == true);
    assert_eq!(true_drags.len(), 540);
    let share = |n: usize, of: usize| (n as f64 / of as f64 * 1000.0).round() / 1000.0;
    let right = true_drags
        .iter()
        .filter(|d| d["started"] == d["action"])
        .count();
    let wrong = true_drags
        .iter()
        .filter(|d| !d["started"].is_null() && d["started"] != d["action"])
        .count();
    let slow_started = slow.iter().filter(|d| !d["started"].is_null()).count();
    assert_eq!(share(right, 540), f(&check, "correct"), "{check}");
    assert_eq!(share(wrong, 540), f(&check, "wrong_action"), "{check}");
    assert_eq!(
        share(slow_started, slow.len()),
        f(&check, "false_trigger_slow"),
        "{check}"
    );
    assert!(
        true_drags.iter().all(|d| {
            let points = d["points"].as_array().unwrap();
            !points.is_empty()
                && (d["started"].is_null() || points.last().unwrap()["held"] == "starts")
        }),
        "each drag explained up to where it started"
    );
    assert!((f(&check, "correct") - 0.187).abs() < 0.03, "{check}");
    assert!(f(&check, "wrong_action") < 0.05, "{check}");
    assert!(f(&check, "false_trigger_slow") <= 0.01, "{check}");

    // The styles nobody recorded for the library, through the recogniser
    // (`marionette eval actions` without `--models-only` runs them through
    // the controller: see docs/measurements.md).
    let eval = json(&run(
        &[
            "eval",
            "actions",
            "--library",
            &s(&lib),
            "--test",
            &s(&held),
            "--models-only",
        ],
        &cache,
    ));
    eprintln!(
        "held out: {}",
        serde_json::to_string(&serde_json::json!({
            "trials": eval["trials"], "correct": eval["correct"], "wrong_action": eval["wrong_action"],
            "missed": eval["missed"], "false_trigger_slow": eval["false_trigger_slow"],
            "decided_at": eval["decided_at"], "views": eval["views"], "confusion": eval["confusion"],
        }))
        .unwrap()
    );
    assert_eq!(eval["trials"], 240);
    // Measured: correct 0.271, wrong 0.029, slow 0.004, decided at 0.248
    // (before templates were also matched from a pause after a drift:
    // 0.246; the paper's rule on the same trials: 0.171 correct, 0.108
    // slow, decided at 0.593).
    assert!(f(&eval, "correct") >= 0.26, "{eval}");
    assert!(f(&eval, "wrong_action") <= 0.04, "{eval}");
    assert!(f(&eval, "false_trigger_slow") <= 0.01, "{eval}");
    assert!(f(&eval, "decided_at") <= 0.27, "{eval}");
    assert_eq!(eval["views"].as_array().unwrap().len(), 2);
    // What the builder is told is what held-out performers get, within 0.1.
    assert!(
        (f(&eval, "correct") - f(&check, "correct")).abs() <= 0.1,
        "{eval} against {check}"
    );
}

#[test]
fn library_check_of_a_library_that_does_not_load_exits_65() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(
        tmp.path().join("library.toml"),
        "[[action]]\nname = \"x\"\nclips = [\"missing.bvh\"]\nprimary = \"right_hand\"\nsegments = [{ until = 1, still = false, release = \"forward\" }]\n",
    )
    .unwrap();
    let out = run(
        &["library", "check", tmp.path().to_str().unwrap()],
        tmp.path(),
    );
    assert_eq!(out.status.code(), Some(65), "{out:?}");
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("missing.bvh"),
        "{out:?}"
    );
}
