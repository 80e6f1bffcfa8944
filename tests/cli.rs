//! The command line as an operator or a script sees it: output, messages on
//! stderr, exit codes (sysexits) that systemd can act on.

mod common;

use std::path::Path;
use std::process::{Command, Output};

fn marionette(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_marionette"))
        .args(args)
        .env_remove("RUST_LOG")
        .output()
        .expect("run marionette")
}

fn recording(name: &str) -> String {
    common::shared_dir()
        .join("recordings/evemu")
        .join(name)
        .display()
        .to_string()
}

#[test]
fn inspect_prints_one_json_object() {
    let out = marionette(&["inspect", &recording("evemu-data.3m-microtouch-usb.evemu")]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert_eq!(stdout.lines().count(), 1);
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(
        v["device"],
        "3M-3M-MicroTouch-USB-controller Virtual Device"
    );
    assert_eq!(v["protocol"], "B");
    assert_eq!(v["direct"], true);
    assert_eq!(v["frames"], 3422);
    assert_eq!(v["max_contacts"], 10);
    assert_eq!(v["touch_sequences"], 34);
    assert!((v["duration_s"].as_f64().unwrap() - 29.1).abs() < 0.1);
    // The truncated last frame is mentioned on stderr.
    assert!(String::from_utf8_lossy(&out.stderr).contains("middle of a frame"));
}

#[test]
fn inspect_of_a_touchpad_says_it_is_not_direct() {
    let out = marionette(&["inspect", &recording("evemu-data.bcm5974-touchpad.evemu")]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["protocol"], "A");
    assert_eq!(v["direct"], false);
}

#[test]
fn malformed_recording_exits_65_with_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.evemu");
    std::fs::write(
        &path,
        "# EVEMU 1.3\nN: x\nI: 0003 0001 0002 0003\nE: 0.000000 0003 zz 1\n",
    )
    .unwrap();
    let out = marionette(&["inspect", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(65));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.evemu:4") && err.contains("hex event code"),
        "{err}"
    );
    assert!(out.stdout.is_empty());
}

#[test]
fn missing_recording_exits_66() {
    let out = marionette(&["inspect", "/nonexistent/x.evemu"]);
    assert_eq!(out.status.code(), Some(66));
    assert!(String::from_utf8_lossy(&out.stderr).contains("/nonexistent/x.evemu"));
}

#[test]
fn bad_config_exits_78_naming_file_and_key() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("marionette.toml");
    std::fs::write(&path, "[display]\nrotation = 45\n").unwrap();
    let out = marionette(&[
        "--config",
        path.to_str().unwrap(),
        "inspect",
        &recording("quanta-optical.evemu"),
    ]);
    assert_eq!(out.status.code(), Some(78));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("marionette.toml") && err.contains("display.rotation"),
        "{err}"
    );
    std::fs::write(&path, "[input]\ngrab = \"yes\"\n").unwrap();
    let out = marionette(&["--config", path.to_str().unwrap(), "demo"]);
    assert_eq!(out.status.code(), Some(78));
    let out = marionette(&["--config", "/nonexistent/marionette.toml", "demo"]);
    assert_eq!(out.status.code(), Some(78));
    std::fs::write(&path, "[tracking]\ns1 = 1.5\n").unwrap();
    let out = marionette(&["--config", path.to_str().unwrap(), "demo"]);
    assert_eq!(out.status.code(), Some(78));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("tracking.s1") && err.contains("between 0 and 0.95"),
        "{err}"
    );
}

#[test]
fn replay_contacts_are_json_lines_in_screen_pixels() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("m.toml");
    std::fs::write(&cfg, "[display]\nwidth = 1920\nheight = 1080\n").unwrap();
    let out = marionette(&[
        "--config",
        cfg.to_str().unwrap(),
        "replay",
        &recording("quanta-optical.touch-on-left.evemu"),
        "--contacts",
    ]);
    assert!(out.status.success());
    let lines: Vec<serde_json::Value> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert!(!lines.is_empty());
    let first = &lines[0]["contacts"][0];
    assert_eq!(first["phase"], "down");
    // This panel's raw range is 0..1920 x 0..1080: identity maps 1:1.
    let raw = (
        first["raw"]["x"].as_f64().unwrap(),
        first["raw"]["y"].as_f64().unwrap(),
    );
    let screen = (
        first["screen"]["x"].as_f64().unwrap(),
        first["screen"]["y"].as_f64().unwrap(),
    );
    assert!((raw.0 - screen.0).abs() < 1e-9 && (raw.1 - screen.1).abs() < 1e-9);
    assert!(screen.0 < 960.0, "the touch is on the left");
    assert_eq!(lines.last().unwrap()["contacts"][0]["phase"], "up");
}

#[test]
fn list_devices_reports_an_empty_or_missing_folder_clearly() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("m.toml");
    std::fs::write(
        &cfg,
        format!(
            "[input]\ndev_dir = \"{}\"\n",
            dir.path().join("none").display()
        ),
    )
    .unwrap();
    let out = marionette(&["--config", cfg.to_str().unwrap(), "list-devices"]);
    assert_eq!(
        out.status.code(),
        Some(69),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("none") && err.contains("input.dev_dir"),
        "{err}"
    );
    std::fs::create_dir(dir.path().join("none")).unwrap();
    let out = marionette(&["--config", cfg.to_str().unwrap(), "list-devices"]);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("no input devices in"));
}

#[test]
fn play_without_uinput_says_what_to_do() {
    if Path::new("/dev/uinput").exists() {
        return; // covered by the VM test where uinput exists
    }
    let out = marionette(&[
        "play",
        &recording("wacom-isdv4-e6-finger.2fg-tap.evemu"),
        "--settle-ms",
        "0",
    ]);
    assert_eq!(out.status.code(), Some(69));
    assert!(String::from_utf8_lossy(&out.stderr).contains("uinput"));
}

#[test]
fn inspect_bvh_prints_skeleton_units_and_roles() {
    let path = common::shared_dir().join("mocap/cmu-mixed/jump/131_03.bvh");
    let out = marionette(&["inspect", path.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["joints"], 31);
    assert_eq!(v["frames"], 1102);
    assert!((v["frame_time"].as_f64().unwrap() - 0.0083333).abs() < 1e-9);
    assert!((v["scale_to_m"].as_f64().unwrap() - 0.0254 / 0.45).abs() < 1e-9);
    let h = v["height_m"].as_f64().unwrap();
    assert!((1.2..2.1).contains(&h), "{h}");
    // 3ds Max names: the "shoulder" joint is the upper arm, the wrist is the hand.
    assert_eq!(v["roles"]["left_hand"], "LeftWrist");
    assert_eq!(v["roles"]["left_elbow"], "LeftElbow");
    assert_eq!(v["roles"]["left_shoulder"], "LeftShoulder");
    assert_eq!(v["roles"]["right_knee"], "RightKnee");
    assert_eq!(v["roles"]["pelvis"], "Hips");
    assert_eq!(v["roles"].as_object().unwrap().len(), 16);
}

#[test]
fn malformed_bvh_exits_65_naming_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.bvh");
    std::fs::write(
        &path,
        "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 3 Xrotation Yrotation Qrotation\n}\n",
    )
    .unwrap();
    let out = marionette(&["inspect", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(65));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.bvh:5") && err.contains("Qrotation"),
        "{err}"
    );
    // A skeleton without recognisable body parts is malformed for marionette.
    std::fs::write(&path, "HIERARCHY\nROOT a\n{\n  OFFSET 0 0 0\n  CHANNELS 3 Xrotation Yrotation Zrotation\n}\nMOTION\nFrames: 1\nFrame Time: 0.1\n0 0 0\n").unwrap();
    let out = marionette(&["inspect", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(65));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot find the joints for pelvis"));
    let out = marionette(&["inspect", "/nonexistent/x.bvh"]);
    assert_eq!(out.status.code(), Some(66));
}

#[test]
fn list_outputs_without_drm_devices_exits_69_and_says_why() {
    let dir = tempfile::tempdir().unwrap();
    let out = marionette(&["list-outputs", "--dir", dir.path().to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(69));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("no DRM devices"), "{err}");
    // A file that is not a DRM device is refused, not a crash.
    std::fs::write(dir.path().join("card0"), b"not a device").unwrap();
    let out = marionette(&["list-outputs", "--dir", dir.path().to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(69));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("card0"), "{err}");
}

#[test]
fn demo_refuses_a_frame_rate_it_cannot_honour_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    for fps in ["0", "1000", "-3"] {
        let flag = format!("--fps={fps}");
        let out = marionette(&["demo", "--out", dir.path().to_str().unwrap(), &flag]);
        assert_eq!(out.status.code(), Some(2), "--fps {fps}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            stderr.contains("--fps must be above 0 and at most 30"),
            "{stderr}"
        );
        assert!(
            out.stdout.is_empty(),
            "--fps {fps} printed {:?}",
            out.stdout
        );
    }
    assert!(std::fs::read_dir(dir.path()).unwrap().next().is_none());
}

#[test]
fn replay_into_a_used_folder_keeps_only_its_own_frames() {
    let dir = tempfile::tempdir().unwrap();
    let frames = dir.path().join("frames");
    std::fs::create_dir_all(&frames).unwrap();
    std::fs::write(frames.join("frame-99999.png"), b"old").unwrap();
    std::fs::write(frames.join("notes.txt"), b"the operator's").unwrap();
    let out = marionette(&[
        "replay",
        &recording("atmel-maxtouch.1-finger-drag-up-down.evemu"),
        "--headless",
        "--out",
        dir.path().to_str().unwrap(),
        "--fps",
        "2",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        !frames.join("frame-99999.png").exists(),
        "an old frame stayed"
    );
    assert!(
        frames.join("notes.txt").exists(),
        "another file was removed"
    );
    assert!(frames.join("frame-00000.png").exists());
}

#[test]
fn a_configured_library_folder_that_is_missing_is_a_configuration_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("marionette.toml");
    std::fs::write(&path, "[character]\nlibrary = \"/nonexistent/library\"\n").unwrap();
    let out_dir = dir.path().join("out");
    let out = marionette(&[
        "--config",
        path.to_str().unwrap(),
        "demo",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(78));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("/nonexistent/library") && err.contains("character.library"),
        "{err}"
    );
    assert!(!out_dir.exists(), "nothing is written");
}

#[test]
fn bake_with_an_unwritable_cache_warns_and_succeeds() {
    let dir = tempfile::tempdir().unwrap();
    let blocked = dir.path().join("file");
    std::fs::write(&blocked, b"not a folder").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_marionette"))
        .args([
            "bake",
            "--library",
            concat!(env!("CARGO_MANIFEST_DIR"), "/assets/library"),
        ])
        .env_remove("RUST_LOG")
        .env("CACHE_DIRECTORY", blocked.join("cache"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("baked in memory") && err.contains("cannot write"),
        "{err}"
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("posing model of"));
}
