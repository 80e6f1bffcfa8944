//! Files come in through one door and go out through one: a device, a pipe
//! or a folder given as an input is refused at once (never read until
//! memory runs out, never waited on), and an output that is a link is
//! refused with the file it points to left as it was. (A glTF's buffer
//! linked from outside its folder: `tests/gltf.rs`.)

mod common;

use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::Duration;

/// Run marionette with `args`, killed if it has not ended within `limit`
/// (a hang is a failure of its own).
fn within(limit: Duration, args: &[&str]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_marionette"))
        .args(args)
        .env_remove("RUST_LOG")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run marionette");
    // Counted in naps rather than read from a clock: a slow machine only
    // waits longer.
    let mut naps = limit.as_millis() / 20;
    while child.try_wait().expect("wait").is_none() {
        if naps == 0 {
            let _ = child.kill();
            let _ = child.wait();
            panic!("marionette {args:?} still running after {limit:?}");
        }
        naps -= 1;
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().expect("output")
}

fn fifo(path: &Path) {
    nix::unistd::mkfifo(path, nix::sys::stat::Mode::S_IRWXU).unwrap();
}

#[test]
fn devices_pipes_and_folders_given_as_inputs_are_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let pipe = dir.path().join("pipe.glb");
    fifo(&pipe);
    let pipe_evemu = dir.path().join("pipe.evemu");
    fifo(&pipe_evemu);
    let pipe_toml = dir.path().join("pipe.toml");
    fifo(&pipe_toml);
    let metrics = dir.path().join("m.json");
    let metrics = metrics.to_str().unwrap();
    // An input that cannot be read is missing input (66); a configuration
    // that cannot be read is a configuration error (78).
    let cases: Vec<(Vec<&str>, i32)> = vec![
        (vec!["inspect", "/dev/zero"], 66),
        (vec!["inspect", pipe.to_str().unwrap()], 66),
        (vec!["replay", "/dev/zero", "--metrics", metrics], 66),
        (
            vec!["replay", pipe_evemu.to_str().unwrap(), "--metrics", metrics],
            66,
        ),
        (vec!["--config", "/dev/zero", "list-devices"], 78),
        (
            vec!["--config", pipe_toml.to_str().unwrap(), "list-devices"],
            78,
        ),
        (
            vec!["--config", dir.path().to_str().unwrap(), "list-devices"],
            78,
        ),
    ];
    for (args, code) in cases {
        let out = within(Duration::from_secs(60), &args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(code), "{args:?}: {err}");
        assert!(
            err.contains("not a regular file"),
            "{args:?} says why: {err}"
        );
    }
}

/// A short real recording replayed headless into `out_dir`.
fn replay_headless_into(out_dir: &Path) -> Output {
    let rec = common::data_dir().join("tracking-ids.evemu");
    within(
        Duration::from_secs(300),
        &[
            "replay",
            rec.to_str().unwrap(),
            "--headless",
            "--out",
            out_dir.to_str().unwrap(),
            "--fps",
            "1",
        ],
    )
}

#[test]
fn an_output_that_is_a_link_is_refused_and_what_it_points_to_kept() {
    let dir = tempfile::tempdir().unwrap();
    let precious = dir.path().join("precious.txt");
    std::fs::write(&precious, "keep").unwrap();
    let out_dir = dir.path().join("out");
    std::fs::create_dir(&out_dir).unwrap();
    std::os::unix::fs::symlink(&precious, out_dir.join("summary.json")).unwrap();
    let out = replay_headless_into(&out_dir);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(err.contains("a symbolic link"), "{err}");
    assert_eq!(std::fs::read_to_string(&precious).unwrap(), "keep");
}

#[test]
fn a_configuration_over_its_limit_is_refused_before_it_is_parsed() {
    let dir = tempfile::tempdir().unwrap();
    let big = dir.path().join("big.toml");
    // 1 MB of comments and one byte more.
    let mut text =
        "# a comment line of sixty-four bytes, padded out to the end....\n".repeat((1 << 20) / 64);
    text.push('\n');
    assert_eq!(text.len(), (1 << 20) + 1);
    std::fs::write(&big, text).unwrap();
    let out = within(
        Duration::from_secs(60),
        &["--config", big.to_str().unwrap(), "list-devices"],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(err.contains("over the 1 MB"), "{err}");
}

#[test]
fn an_output_that_is_the_input_is_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("a.evemu");
    std::fs::copy(common::data_dir().join("tracking-ids.evemu"), &rec).unwrap();
    let before = std::fs::read(&rec).unwrap();
    // The same file by another name, too.
    let again = dir.path().join(".").join("a.evemu");
    let config = dir.path().join("m.toml");
    std::fs::write(&config, "").unwrap();
    for args in [
        vec![
            "replay",
            rec.to_str().unwrap(),
            "--metrics",
            again.to_str().unwrap(),
        ],
        vec![
            "export-bvh",
            rec.to_str().unwrap(),
            "--out",
            rec.to_str().unwrap(),
        ],
        vec![
            "--config",
            config.to_str().unwrap(),
            "replay",
            rec.to_str().unwrap(),
            "--metrics",
            config.to_str().unwrap(),
        ],
    ] {
        let out = within(Duration::from_secs(60), &args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(73), "{args:?}: {err}");
        assert!(err.contains("is the file being read"), "{args:?}: {err}");
    }
    assert_eq!(std::fs::read(&rec).unwrap(), before);
    assert_eq!(std::fs::read_to_string(&config).unwrap(), "");
}

/// What a message may hold of its input: no control character but the
/// line breaks between records, and no more than a few lines of text.
fn plain_and_short(args: &[&str], err: &str) {
    assert!(
        err.len() < 1200,
        "{args:?}: {} bytes of messages: {}",
        err.len(),
        &err[..300]
    );
    assert!(
        !err.chars().any(|c| c.is_control() && c != '\n'),
        "{args:?}: a control character reached the terminal: {err:?}"
    );
}

#[test]
fn every_value_repeated_from_input_is_escaped_and_cut() {
    let dir = tempfile::tempdir().unwrap();
    let at = |name: &str, text: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_owned()
    };
    let head = "# EVEMU 1.3\nN: panel\nI: 0003 0eef 72a1 0001\n";
    let token = at(
        "token.evemu",
        &format!("{head}E: {} 0003 0035 100\n", "9".repeat(1_000_000)),
    );
    let esc = at(
        "esc.evemu",
        &format!("{head}E: \u{1b}[2J\0 0003 0035 100\n"),
    );
    let tag = at(
        "tag.evemu",
        &format!("{head}{}\u{1b}[2J: 1\n", "Q".repeat(500_000)),
    );
    // A recording whose last line was cut, under a name with an ESC: the
    // warning and the error name it escaped.
    let cut = at(
        "cut\u{1b}[2J.evemu",
        &format!("{head}E: 0.000001 0000 0000 0000\nE: 1.0 0003 \u{1b}[2J"),
    );
    let level = at(
        "level.toml",
        &format!(
            "[log]\nlevel = \"\\u001b[2J{}\\nforged\"\n",
            "a".repeat(500_000)
        ),
    );
    let syntax = at(
        "syntax.toml",
        &format!("[log]\nlevel = {}\u{1b}\n", "x".repeat(500_000)),
    );
    let joints = at(
        "joints.bvh",
        "HIERARCHY\nROOT a\u{1b}[2J\n{\nOFFSET 0 0 0\nCHANNELS 3 Xrotation Yrotation Zrotation\nJOINT a\u{1b}[2J\n{\nOFFSET 0 1 0\nCHANNELS 3 Xrotation Yrotation Zrotation\nEnd Site\n{\nOFFSET 0 1 0\n}\n}\n}\nMOTION\nFrames: 1\nFrame Time: 0.03\n0 0 0 0 0 0\n",
    );
    let lib = dir.path().join("lib");
    std::fs::create_dir(&lib).unwrap();
    std::fs::write(
        lib.join("library.toml"),
        "[[action]]\nname = \"wave\\u001b[2J\"\nprimary = \"left_hand\\u0007\"\nclips = [\"x\\u001b.bvh\"]\n",
    )
    .unwrap();
    let cases: Vec<Vec<&str>> = vec![
        vec!["inspect", &token],
        vec!["inspect", &esc],
        vec!["inspect", &tag],
        vec!["replay", &cut],
        vec!["--config", &level, "list-devices"],
        vec!["--config", &syntax, "list-devices"],
        vec!["inspect", &joints],
        vec!["library", "check", lib.to_str().unwrap()],
    ];
    for args in cases {
        let out = within(Duration::from_secs(60), &args);
        let err = String::from_utf8_lossy(&out.stderr);
        plain_and_short(&args, &err);
        assert!(
            String::from_utf8_lossy(&out.stdout)
                .chars()
                .all(|c| !c.is_control() || c == '\n'),
            "{args:?}"
        );
        // Every one but the cut recording (its complete events replay) is
        // refused; the cut one warns in one record.
        if args[0] == "replay" {
            assert_eq!(out.status.code(), Some(65), "{args:?}: {err}");
            assert!(err.contains("cut short"), "{err}");
        } else {
            assert!(!out.status.success(), "{args:?}: {err}");
            assert!(err.contains('`'), "{args:?}: the value is quoted: {err}");
        }
    }
}

#[test]
fn a_file_that_is_not_motion_capture_is_refused_without_showing_it() {
    let dir = tempfile::tempdir().unwrap();
    let elsewhere = dir.path().join("elsewhere");
    std::fs::create_dir(&elsewhere).unwrap();
    std::fs::write(
        elsewhere.join("passwd"),
        "root:x:0:0:secret:/root:/bin/sh\n",
    )
    .unwrap();
    let lib = dir.path().join("lib");
    std::fs::create_dir(&lib).unwrap();
    std::fs::write(
        lib.join("library.toml"),
        format!(
            "[settings]\nclips_dir = \"{}\"\n[posing]\nclips = [\"passwd\"]\n",
            elsewhere.display()
        ),
    )
    .unwrap();
    let out = within(
        Duration::from_secs(60),
        &["library", "check", lib.to_str().unwrap()],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(65), "{err}");
    assert!(err.contains("not a BVH file"), "{err}");
    assert!(!err.contains("root:x"), "{err}");
}

/// A library folder in `dir` with `toml` and the shipped library's bows
/// (and a one-frame cut of one, `still.bvh`).
fn library_with(dir: &Path, toml: &str) -> String {
    let lib = dir.join("lib");
    std::fs::create_dir_all(&lib).unwrap();
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/library");
    for f in ["bow_a.bvh", "bow_deep.bvh"] {
        std::fs::copy(shipped.join(f), lib.join(f)).unwrap();
    }
    let bow = std::fs::read_to_string(shipped.join("bow_a.bvh")).unwrap();
    let (head, motion) = bow.split_once("MOTION").unwrap();
    let first = motion.lines().nth(3).unwrap();
    std::fs::write(
        lib.join("still.bvh"),
        format!("{head}MOTION\nFrames: 1\nFrame Time: 0.0333333\n{first}\n"),
    )
    .unwrap();
    std::fs::write(lib.join("library.toml"), toml).unwrap();
    lib.to_str().unwrap().to_owned()
}

#[test]
fn repeated_clips_and_one_frame_actions_are_refused() {
    let action = |clips: &str| {
        format!(
            "[posing]\nclips = [\"bow_a.bvh\"]\n[[action]]\nname = \"bow\"\nprimary = \"head\"\nclips = [{clips}]\nsegments = [{{ until = 1, still = true, release = \"forward\" }}]\n"
        )
    };
    let dir = tempfile::tempdir().unwrap();
    let good = library_with(dir.path(), &action("\"bow_a.bvh\", \"bow_deep.bvh\""));
    let out = within(Duration::from_secs(120), &["library", "check", &good]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let posing_twice =
        "[posing]\nclips = [\"bow_a.bvh\", \"bow_deep.bvh\", \"bow_a.bvh\", \"bow_a.bvh\"]\n";
    for (toml, says) in [
        (
            posing_twice.to_owned(),
            "[posing] clips: `bow_a.bvh` is listed 3 times",
        ),
        (
            action("\"bow_a.bvh\", \"bow_a.bvh\""),
            "action `bow` clips: `bow_a.bvh` is listed 2 times",
        ),
        (
            action("\"bow_a.bvh\", \"still.bvh\""),
            "action `bow`: clip `still.bvh` has one frame",
        ),
    ] {
        let lib = library_with(dir.path(), &toml);
        let out = within(Duration::from_secs(60), &["library", "check", &lib]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(65), "{err}");
        assert!(err.contains(says), "{says}: {err}");
    }
}

#[test]
fn library_check_and_the_library_flag_answer_alike() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("nowhere");
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let toml = dir.path().join("library.toml");
    std::fs::write(&toml, "").unwrap();
    let out_dir = dir.path().join("demo");
    for folder in [&missing, &empty, &toml] {
        let f = folder.to_str().unwrap();
        let check = within(Duration::from_secs(60), &["library", "check", f]);
        let flag = within(
            Duration::from_secs(60),
            &["demo", "--library", f, "--out", out_dir.to_str().unwrap()],
        );
        let (a, b) = (
            String::from_utf8_lossy(&check.stderr),
            String::from_utf8_lossy(&flag.stderr),
        );
        assert_eq!(check.status.code(), Some(66), "{a}");
        assert_eq!(flag.status.code(), Some(66), "{b}");
        let why = |s: &str| {
            s.lines()
                .last()
                .and_then(|l| l.strip_prefix("marionette: "))
                .and_then(|l| l.split_once(": "))
                .map(|(_, w)| w.to_owned())
        };
        assert_eq!(why(&a), why(&b), "{a}\n{b}");
        // A folder is never offered as the place to write a library into.
        assert!(!a.contains(&format!("--out {f}")), "{a}");
    }
}

#[test]
fn a_walk_path_too_long_to_walk_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let paths = dir.path().join("paths.json");
    // Back and forth across 90 m, 2,000 times: 360 km.
    let points: Vec<[f64; 2]> = (0..4000)
        .map(|i| [if i % 2 == 0 { -45.0 } else { 45.0 }, 0.0])
        .collect();
    std::fs::write(
        &paths,
        serde_json::json!({"paths": [{"points": points, "speed_mps": 1.0}]}).to_string(),
    )
    .unwrap();
    let out = within(
        Duration::from_secs(10),
        &["eval", "walk", "--paths", paths.to_str().unwrap()],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(
        err.contains("a path on the table is at most 100 m"),
        "{err}"
    );
}

#[test]
fn clips_whose_names_make_one_sheet_name_get_a_sheet_each() {
    let dir = tempfile::tempdir().unwrap();
    let lib = library_with(
        dir.path(),
        "[posing]\nclips = [\"sub/pose.bvh\", \"sub_pose.bvh\"]\n",
    );
    let lib_dir = Path::new(&lib);
    std::fs::create_dir(lib_dir.join("sub")).unwrap();
    std::fs::copy(lib_dir.join("bow_a.bvh"), lib_dir.join("sub/pose.bvh")).unwrap();
    std::fs::copy(lib_dir.join("bow_deep.bvh"), lib_dir.join("sub_pose.bvh")).unwrap();
    let sheets = dir.path().join("sheets");
    let out = within(
        Duration::from_secs(120),
        &[
            "contact-sheet",
            "--library",
            &lib,
            "--out",
            sheets.to_str().unwrap(),
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut names: Vec<String> = std::fs::read_dir(&sheets)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["sub_pose-2.png", "sub_pose.png"]);
}

#[test]
fn frames_are_never_written_through_a_link_and_no_scores_keep_a_library() {
    let dir = tempfile::tempdir().unwrap();
    let victim = dir.path().join("victim");
    std::fs::create_dir(&victim).unwrap();
    std::fs::write(victim.join("frame-00000.png"), "keep").unwrap();
    let out_dir = dir.path().join("out");
    std::fs::create_dir(&out_dir).unwrap();
    std::os::unix::fs::symlink(&victim, out_dir.join("frames")).unwrap();
    let out = replay_headless_into(&out_dir);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(73), "{err}");
    assert!(err.contains("is a symbolic link"), "{err}");
    let left: Vec<_> = std::fs::read_dir(&victim).unwrap().collect();
    assert_eq!(left.len(), 1);
    assert_eq!(
        std::fs::read_to_string(victim.join("frame-00000.png")).unwrap(),
        "keep"
    );
    // author-library from a folder of no scores leaves the library there.
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let lib = library_with(dir.path(), "[posing]\nclips = [\"bow_a.bvh\"]\n");
    let before = std::fs::read(Path::new(&lib).join("library.toml")).unwrap();
    let out = within(
        Duration::from_secs(60),
        &[
            "author-library",
            "--src",
            empty.to_str().unwrap(),
            "--out",
            &lib,
        ],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(66), "{err}");
    assert!(err.contains("holds no scores"), "{err}");
    assert_eq!(
        std::fs::read(Path::new(&lib).join("library.toml")).unwrap(),
        before
    );
}
