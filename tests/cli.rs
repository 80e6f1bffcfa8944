//! The command line as an operator or a script sees it: output, messages on
//! stderr, exit codes (sysexits) that systemd can act on.

mod common;

use std::path::Path;
use std::process::Command;

use common::marionette;

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
    let out = marionette(&[
        "play",
        &recording("wacom-isdv4-e6-finger.2fg-tap.evemu"),
        "--settle-ms",
        "0",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    match out.status.code() {
        // Where uinput can be written (the VM test's guest, a root shell
        // with the module loaded) the recording is played through it.
        Some(0) => assert!(Path::new("/dev/uinput").exists(), "{stderr}"),
        // Elsewhere: what is missing and what to do, and 69.
        Some(69) => assert!(
            stderr.contains("/dev/uinput") && stderr.contains("modprobe uinput"),
            "{stderr}"
        ),
        other => panic!("exit {other:?}: {stderr}"),
    }
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

/// A real recording with its event times changed by `f` (seconds since its
/// first event in, seconds out).
fn with_times(name: &str, f: impl Fn(f64) -> f64) -> String {
    let text = std::fs::read_to_string(recording(name)).unwrap();
    let mut t0 = None;
    let mut out = String::new();
    for l in text.lines() {
        match l.strip_prefix("E: ") {
            Some(rest) => {
                let (ts, tail) = rest.split_once(' ').unwrap();
                let t: f64 = ts.parse().unwrap();
                let t0 = *t0.get_or_insert(t);
                out.push_str(&format!("E: {:.6} {tail}\n", t0 + f(t - t0)));
            }
            None => {
                out.push_str(l);
                out.push('\n');
            }
        }
    }
    out
}

fn inspect_json(path: &Path) -> serde_json::Value {
    let out = marionette(&["inspect", path.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn a_clock_that_jumps_or_goes_back_replays_in_recorded_time() {
    let dir = tempfile::tempdir().unwrap();
    // 29 s of ten fingers; after 10 s the clock jumps a day ahead.
    let jump = dir.path().join("jump.evemu");
    std::fs::write(
        &jump,
        with_times("evemu-data.3m-microtouch-usb.evemu", |t| {
            if t > 10.0 { t + 1e5 } else { t }
        }),
    )
    .unwrap();
    let v = inspect_json(&jump);
    assert_eq!(v["time_gaps"], 1);
    assert_eq!(v["time_backwards"], 0);
    let replay_s = v["replay_s"].as_f64().unwrap();
    // The pause around the jump (1.6 s in the recording) replays as 5 s.
    assert!((30.0..35.0).contains(&replay_s), "{v}");
    assert!(v["duration_s"].as_f64().unwrap() > 1e5);
    let out = dir.path().join("frames");
    let run = marionette(&[
        "replay",
        jump.to_str().unwrap(),
        "--headless",
        "--out",
        out.to_str().unwrap(),
        "--fps",
        "2",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let written = std::fs::read_dir(out.join("frames")).unwrap().count();
    // Every half second of the replay, and up to 16 thumbnails.
    assert!((60..=85).contains(&written), "{written} frames");
    let log = String::from_utf8_lossy(&run.stderr);
    assert!(
        log.contains("pauses longer than max_s are shortened"),
        "{log}"
    );

    // The clock steps back 3 s after 10 s and runs on from there.
    let back = dir.path().join("back.evemu");
    std::fs::write(
        &back,
        with_times("evemu-data.3m-microtouch-usb.evemu", |t| {
            if t > 10.0 { t - 3.0 } else { t }
        }),
    )
    .unwrap();
    let v = inspect_json(&back);
    assert_eq!(v["time_backwards"], 1, "{v}");
    assert_eq!(v["time_gaps"], 0, "{v}");
    // The step back is held at the frame before it: the replay loses the
    // 1.6 s pause there, not 3 s of touches.
    let replay_s = v["replay_s"].as_f64().unwrap();
    assert!((27.0..29.0).contains(&replay_s), "{v}");
    assert!(v["duration_s"].as_f64().unwrap() < replay_s, "{v}");
}

#[test]
fn a_headless_replay_refuses_more_frames_than_asked_for() {
    let dir = tempfile::tempdir().unwrap();
    // The same touches, 150 times slower: 73 minutes, no pause over 5 s.
    let slow = dir.path().join("slow.evemu");
    std::fs::write(
        &slow,
        with_times("evemu-data.3m-microtouch-usb.evemu", |t| t * 150.0),
    )
    .unwrap();
    let out = dir.path().join("out");
    let run = marionette(&[
        "replay",
        slow.to_str().unwrap(),
        "--headless",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(run.status.code(), Some(2));
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(
        err.contains("--max-frames") && err.contains("more than"),
        "{err}"
    );
    assert!(!out.join("frames").exists());
}

#[test]
fn a_recording_cut_mid_line_is_read_like_one_cut_between_lines() {
    let dir = tempfile::tempdir().unwrap();
    let text =
        std::fs::read_to_string(recording("atmel-maxtouch.1-finger-drag-up-down.evemu")).unwrap();
    // Cut inside the 200th event line, and at its start.
    let line_start = text
        .match_indices("\nE: ")
        .nth(200)
        .map(|(i, _)| i + 1)
        .unwrap();
    let mid = dir.path().join("mid.evemu");
    std::fs::write(&mid, &text[..line_start + 12]).unwrap();
    let between = dir.path().join("between.evemu");
    std::fs::write(&between, &text[..line_start]).unwrap();
    let inspect = |p: &Path| {
        let out = marionette(&["inspect", p.to_str().unwrap()]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        (v, String::from_utf8_lossy(&out.stderr).into_owned())
    };
    let (a, log) = inspect(&mid);
    let (b, _) = inspect(&between);
    assert!(log.contains("cut short"), "{log}");
    assert_eq!(a["frames"], b["frames"]);
    assert!(a["frames"].as_u64().unwrap() > 10);
    // A broken line inside the file is still an error naming its line.
    let broken = dir.path().join("broken.evemu");
    std::fs::write(
        &broken,
        format!("{}\n{}", &text[..line_start + 12], &text[line_start..]),
    )
    .unwrap();
    let out = marionette(&["inspect", broken.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(65));
}

#[test]
fn touchpads_and_pens_report_no_finger_contacts_anywhere() {
    for (name, tool) in [
        ("evemu-data.bcm5974-touchpad.evemu", "touchpad"),
        ("dell-canvas-pen.evemu", "pen"),
    ] {
        let v: serde_json::Value =
            serde_json::from_slice(&marionette(&["inspect", &recording(name)]).stdout).unwrap();
        assert_eq!(v["touch_sequences"], 0, "{name}: {v}");
        assert_eq!(v["max_contacts"], 0, "{name}: {v}");
        let out = marionette(&["replay", &recording(name), "--contacts"]);
        assert!(out.status.success());
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(text.contains(&format!("\"tool\":\"{tool}\"")), "{name}");
        assert!(!text.contains("\"tool\":\"finger\""), "{name}");
        // Replayed into the character: nothing is held, nothing starts.
        let dir = tempfile::tempdir().unwrap();
        let metrics = dir.path().join("m.json");
        let out = marionette(&[
            "replay",
            &recording(name),
            "--metrics",
            metrics.to_str().unwrap(),
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let m: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&metrics).unwrap()).unwrap();
        assert_eq!(m["actions"].as_array().unwrap().len(), 0, "{name}");
    }
}

#[test]
fn inspect_refuses_what_a_replay_refuses_with_the_same_reason() {
    let dir = tempfile::tempdir().unwrap();
    let text =
        std::fs::read_to_string(recording("atmel-maxtouch.1-finger-drag-up-down.evemu")).unwrap();
    for (what, from, to) in [
        ("swapped", "A: 35 0 799 0 0 0", "A: 35 799 0 0 0 0"),
        ("empty", "A: 35 0 799 0 0 0", "A: 35 5 5 0 0 0"),
    ] {
        let path = dir.path().join(format!("{what}.evemu"));
        assert!(text.contains(from));
        std::fs::write(&path, text.replace(from, to)).unwrap();
        let inspect = marionette(&["inspect", path.to_str().unwrap()]);
        let replay = marionette(&["replay", path.to_str().unwrap()]);
        assert_eq!(inspect.status.code(), Some(65), "{what}");
        assert_eq!(replay.status.code(), Some(65), "{what}");
        // inspect still describes the file before it says why.
        let v: serde_json::Value = serde_json::from_slice(&inspect.stdout).unwrap();
        assert_eq!(v["frames"], 150);
        let (a, b) = (
            String::from_utf8_lossy(&inspect.stderr).into_owned(),
            String::from_utf8_lossy(&replay.stderr).into_owned(),
        );
        let reason = b.lines().last().unwrap().to_owned();
        let reason = reason.split("Atmel").last().unwrap();
        assert!(
            a.contains(reason),
            "{what}: inspect said {a}\nreplay said {b}"
        );
    }
}

#[test]
fn watch_says_when_no_touchscreen_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("marionette.toml");
    let dev = dir.path().join("input");
    std::fs::create_dir(&dev).unwrap();
    std::fs::write(
        &cfg,
        format!("[input]\ndev_dir = {:?}\n", dev.display().to_string()),
    )
    .unwrap();
    let out = marionette(&[
        "--config",
        cfg.to_str().unwrap(),
        "watch",
        "--seconds",
        "0.3",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let lines: Vec<serde_json::Value> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 1, "{lines:?}");
    assert_eq!(lines[0]["event"], "no_touchscreen");
    assert!(lines[0]["hint"].as_str().unwrap().contains("list-devices"));
}
