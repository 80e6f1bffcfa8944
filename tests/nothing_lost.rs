//! Inputs an operator gets wrong or a stranger's files carry, and outputs
//! over the wrong thing: each is refused with a clear error and an exit
//! code, and no file is destroyed (regressions of what a careless or
//! hostile operator found).

mod common;

use std::path::{Path, PathBuf};

use common::marionette;

/// A real capture file (Bandai, centimetres, 30 fps).
fn bandai(name: &str) -> PathBuf {
    common::shared_dir().join("mocap/bandai").join(name)
}

/// `text` with its first motion frame's first value replaced by `value`.
fn with_first_value(text: &str, value: &str) -> String {
    let motion = text.find("Frame Time:").unwrap();
    let line_end = motion + text[motion..].find('\n').unwrap() + 1;
    let rest = &text[line_end..];
    let first_end = rest.find(char::is_whitespace).unwrap();
    format!("{}{value}{}", &text[..line_end], &rest[first_end..])
}

fn stderr(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn a_position_of_1e308_is_refused_naming_the_joint_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(bandai("d1_bow_active_001.bvh")).unwrap();
    let bad = dir.path().join("far.bvh");
    std::fs::write(&bad, with_first_value(&text, "1e308")).unwrap();
    let out = marionette(&["inspect", bad.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(65), "{}", stderr(&out));
    assert!(stderr(&out).contains("frame 0, joint"), "{}", stderr(&out));
    // Through the posing evaluation that used to panic in the IK, with a
    // library of the same rig.
    let takes = dir.path().join("takes");
    std::fs::create_dir(&takes).unwrap();
    for style in ["angry", "happy"] {
        std::os::unix::fs::symlink(
            bandai(&format!("d1_bow_{style}_001.bvh")),
            takes.join(format!("pose_{style}.bvh")),
        )
        .unwrap();
    }
    let lib = dir.path().join("lib");
    let out = marionette(&[
        "library",
        "init",
        takes.to_str().unwrap(),
        "--out",
        lib.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_marionette"))
        .args(["eval", "pose", "--library"])
        .arg(&lib)
        .arg("--test")
        .arg(&bad)
        .env("CACHE_DIRECTORY", dir.path().join("cache"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(65), "{}", stderr(&out));
    assert!(stderr(&out).contains("frame 0, joint"), "{}", stderr(&out));
}

#[test]
fn frame_times_and_sizes_no_capture_has_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(bandai("d1_bow_active_001.bvh")).unwrap();
    let quick = dir.path().join("quick.bvh");
    let frame_time = text[text.find("Frame Time:").unwrap()..]
        .lines()
        .next()
        .unwrap()
        .to_owned();
    std::fs::write(&quick, text.replace(&frame_time, "Frame Time: 1e-300")).unwrap();
    let out = marionette(&["inspect", quick.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(65), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("frame time must be between 0.001 and 1 seconds"),
        "{}",
        stderr(&out)
    );
    // Metres taken for centimetres: a character of 1.6 km.
    let out = marionette(&[
        "convert-bvh",
        bandai("d1_bow_active_001.bvh").to_str().unwrap(),
        "--out",
        dir.path().join("big.bvh").to_str().unwrap(),
        "--scale-to-m",
        "10",
    ]);
    assert_eq!(out.status.code(), Some(65), "{}", stderr(&out));
    assert!(stderr(&out).contains("m tall"), "{}", stderr(&out));
    assert!(!dir.path().join("big.bvh").exists());
}

#[test]
fn an_error_quotes_at_most_120_characters_of_the_input_escaped() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("long.bvh");
    let token = format!("{}\u{7}{}", "X".repeat(100_000), "Y".repeat(10));
    std::fs::write(&bad, format!("HIERARCHY\n{token}\n")).unwrap();
    let out = marionette(&["inspect", bad.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(65), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(err.len() < 1000, "{} bytes", err.len());
    assert!(err.contains("(100011 characters)"), "{err}");
    assert!(!err.contains('\u{7}'));
}

#[test]
fn outputs_over_links_devices_and_folders_are_refused_and_kept() {
    let dir = tempfile::tempdir().unwrap();
    let precious = dir.path().join("precious.bvh");
    std::fs::write(&precious, "keep me").unwrap();
    let link = dir.path().join("link.bvh");
    std::os::unix::fs::symlink(&precious, &link).unwrap();
    let src = bandai("d1_bow_active_001.bvh");
    for target in [link.as_path(), Path::new("/dev/null"), dir.path()] {
        let out = marionette(&[
            "convert-bvh",
            src.to_str().unwrap(),
            "--out",
            target.to_str().unwrap(),
        ]);
        assert_eq!(out.status.code(), Some(73), "{}", stderr(&out));
        assert!(
            stderr(&out).contains("not a regular file"),
            "{}",
            stderr(&out)
        );
    }
    assert_eq!(std::fs::read_to_string(&precious).unwrap(), "keep me");
    assert!(
        std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    // Nothing was left beside them.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
    // A regular file is replaced whole.
    let out_file = dir.path().join("out.bvh");
    std::fs::write(&out_file, "old").unwrap();
    let out = marionette(&[
        "convert-bvh",
        src.to_str().unwrap(),
        "--out",
        out_file.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        std::fs::read_to_string(&out_file)
            .unwrap()
            .starts_with("HIERARCHY")
    );
}

#[test]
fn a_take_named_with_a_newline_makes_a_library_that_loads() {
    // The name used to end a comment of library.toml: `--force` then
    // replaced a working library with one that did not load.
    let dir = tempfile::tempdir().unwrap();
    let takes = dir.path().join("takes");
    std::fs::create_dir(&takes).unwrap();
    for (src, name) in [
        ("d1_bow_active_001.bvh", "bow_a\nb_001.bvh"),
        ("d1_bow_angry_001.bvh", "bow_angry_001.bvh"),
    ] {
        std::os::unix::fs::symlink(bandai(src), takes.join(name)).unwrap();
    }
    let lib = dir.path().join("lib");
    std::fs::create_dir(&lib).unwrap();
    std::fs::write(lib.join("library.toml"), "# the working library\n").unwrap();
    let out = marionette(&[
        "library",
        "init",
        takes.to_str().unwrap(),
        "--out",
        lib.to_str().unwrap(),
        "--force",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let lib = marionette::character::library::Library::load(&lib).unwrap();
    assert_eq!(lib.posing.len(), 2);
    assert_eq!(
        std::fs::read_dir(dir.path().join("lib")).unwrap().count(),
        1
    );
}

#[test]
fn a_picture_larger_than_the_adapter_renders_is_a_configuration_error() {
    // Inside the documented range of display.width and display.height, but
    // over what the adapter allocates: wgpu used to panic (exit 101).
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("big.toml");
    std::fs::write(&config, "[display]\nwidth = 16384\nheight = 8192\n").unwrap();
    let out = marionette(&[
        "--config",
        config.to_str().unwrap(),
        "demo",
        "--out",
        dir.path().join("out").to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(78), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("lower display.width and display.height"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn usage_errors_name_the_flag_and_exit_2() {
    let bow = bandai("d1_bow_active_001.bvh");
    for scale in ["0", "nan", "inf", "-1"] {
        let out = marionette(&[
            "convert-bvh",
            bow.to_str().unwrap(),
            "--out",
            "/tmp/never-written.bvh",
            &format!("--scale-to-m={scale}"),
        ]);
        assert_eq!(out.status.code(), Some(2), "{scale}: {}", stderr(&out));
        assert!(stderr(&out).contains("--scale-to-m"), "{}", stderr(&out));
    }
    let out = marionette(&[
        "eval",
        "pose",
        "--library",
        "assets/library",
        "--leave-one-out",
        "--frames",
        "0",
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("--frames"), "{}", stderr(&out));
    let out = marionette(&[
        "contact-sheet",
        "--frames",
        "0",
        "--out",
        "/tmp/never-written",
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("--frames"), "{}", stderr(&out));
}

#[test]
fn eval_actions_without_test_clips_says_so_and_a_folder_is_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = marionette(&[
        "eval",
        "actions",
        "--library",
        "assets/library",
        "--test",
        dir.path().to_str().unwrap(),
        "--models-only",
    ]);
    assert_eq!(out.status.code(), Some(66), "{}", stderr(&out));
    assert!(stderr(&out).contains("no test clips"), "{}", stderr(&out));
    // A folder where a file is expected: 66, as the table of docs/commands.md says.
    for args in [
        vec!["inspect", dir.path().to_str().unwrap()],
        vec![
            "convert-bvh",
            dir.path().to_str().unwrap(),
            "--out",
            "/tmp/never-written.bvh",
        ],
    ] {
        let out = marionette(&args);
        assert_eq!(out.status.code(), Some(66), "{args:?}: {}", stderr(&out));
    }
}

/// `text`'s first frame, `n` times.
fn still(text: &str, n: usize) -> String {
    let i = text.find("Frames:").unwrap();
    let rest: Vec<&str> = text[i..].lines().collect();
    let frame_time = rest[1];
    let first = rest[2];
    format!(
        "{}Frames: {n}\n{frame_time}\n{}",
        &text[..i],
        format!("{first}\n").repeat(n)
    )
}

#[test]
fn one_frame_and_motionless_takes_are_no_actions() {
    let dir = tempfile::tempdir().unwrap();
    let takes = dir.path().join("takes");
    std::fs::create_dir(&takes).unwrap();
    let text = std::fs::read_to_string(bandai("d1_kick_normal_001.bvh")).unwrap();
    std::fs::write(takes.join("kick_one.bvh"), still(&text, 1)).unwrap();
    std::fs::write(takes.join("wave_still.bvh"), still(&text, 30)).unwrap();
    std::os::unix::fs::symlink(
        bandai("d1_bow_active_001.bvh"),
        takes.join("bow_active.bvh"),
    )
    .unwrap();
    let lib = dir.path().join("lib");
    let out = marionette(&[
        "library",
        "init",
        takes.to_str().unwrap(),
        "--out",
        lib.to_str().unwrap(),
    ]);
    let report = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        report.contains("not an action kick_one.bvh: one frame"),
        "{report}"
    );
    assert!(
        report.contains("not an action wave_still.bvh: no part moves"),
        "{report}"
    );
    assert!(!report.contains("NaN"), "{report}");
    let lib = marionette::character::library::Library::load(&lib).unwrap();
    let names: Vec<&str> = lib.actions.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["bow"]);
    assert_eq!(lib.posing.len(), 3);
}

#[test]
fn contacts_with_metrics_is_a_usage_error_not_ignored() {
    let out = marionette(&[
        "replay",
        "assets/recordings/demo-two-hands.evemu",
        "--metrics",
        "/tmp/never-written.json",
        "--contacts",
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("--contacts"), "{}", stderr(&out));
    assert!(!Path::new("/tmp/never-written.json").exists());
}

#[test]
fn a_clip_over_the_size_limit_is_refused_before_it_is_read() {
    // settings.max_file_mb bounds what a library reads (256 MB unless set).
    let dir = tempfile::tempdir().unwrap();
    std::os::unix::fs::symlink(bandai("d1_bow_active_001.bvh"), dir.path().join("bow.bvh"))
        .unwrap();
    std::fs::write(
        dir.path().join("library.toml"),
        "[settings]\nmax_file_mb = 0\n\n[posing]\nclips = [\"bow.bvh\"]\n",
    )
    .unwrap();
    let err = marionette::character::library::Library::load(dir.path())
        .unwrap_err()
        .to_string();
    assert!(err.contains("over settings.max_file_mb (0 MB)"), "{err}");
}
