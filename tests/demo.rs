//! The headless pipeline end to end: the demo command, replays of real
//! recordings into images, determinism of the whole chain, and BVH export.

mod common;

use std::path::Path;

use marionette::app::config::Config;
use marionette::app::headless::{self, Options};
use marionette::input::evemu::Recording;
use marionette::input::pipeline;

use common::marionette;

fn demo_recording() -> Recording {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/recordings/demo.evemu");
    Recording::read_file(&path).unwrap()
}

#[test]
fn demo_renders_frames_a_contact_sheet_and_a_summary() {
    let dir = tempfile::tempdir().unwrap();
    let out = marionette(&["demo", "--out", dir.path().to_str().unwrap(), "--fps", "2"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("summary.json")).unwrap())
            .unwrap();
    // At least four different actions started by drags, each played out.
    let actions = summary["actions"].as_array().unwrap();
    let mut names: Vec<&str> = actions
        .iter()
        .map(|a| a["action"].as_str().unwrap())
        .collect();
    names.sort_unstable();
    names.dedup();
    assert!(names.len() >= 4, "{stdout}");
    assert!(
        actions.iter().all(|a| a["outcome"] == "finished"),
        "{stdout}"
    );
    // Posing with one and two fingers, and the camera moved.
    assert!(
        summary["most_held_at_once"].as_u64().unwrap() >= 2,
        "{stdout}"
    );
    assert_eq!(summary["camera_moved"], true, "{stdout}");
    // Frames and the sheet are real PNGs of the configured size.
    let frames = summary["frames_written"].as_u64().unwrap();
    let duration = summary["duration_s"].as_f64().unwrap();
    assert!(frames as f64 >= duration * 2.0 - 1.0, "{frames} frames");
    let first =
        marionette::render::headless::Image::read_png(&dir.path().join("frames/frame-00000.png"))
            .unwrap();
    assert_eq!((first.width, first.height), (1280, 720));
    let sheet =
        marionette::render::headless::Image::read_png(&dir.path().join("contact-sheet.png"))
            .unwrap();
    assert!(sheet.width > 1000 && sheet.height > 500);
    assert!(stdout.contains("actions started by drags"), "{stdout}");
    // The summary the README prints, line for line (its `...` aside).
    let readme =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md")).unwrap();
    let block = &readme[readme
        .find("a summary is printed:")
        .expect("the README shows the demo's summary")..];
    let block = &block[block.find("```\n").expect("a block") + 4..];
    let block = &block[..block.find("```").unwrap()];
    let lines: Vec<&str> = block.lines().filter(|l| l.trim() != "...").collect();
    assert!(lines.len() >= 8, "{block}");
    for line in lines {
        assert!(
            stdout.lines().any(|l| l == line),
            "the README's line {line:?} is not what the demo prints:\n{stdout}"
        );
    }
}

#[test]
fn a_replay_gives_the_same_poses_and_images_twice() {
    let ch = common::character();
    let config = Config::default();
    let frames =
        pipeline::replay(&demo_recording(), &config.input, config.display.picture()).unwrap();
    let opts = Options {
        keep_poses: true,
        ..Options::default()
    };
    let a = headless::run(ch.clone(), &config, frames.clone(), &opts).unwrap();
    let b = headless::run(ch.clone(), &config, frames.clone(), &opts).unwrap();
    assert_eq!(a.pose_digest, b.pose_digest);
    assert!(a.poses == b.poses, "postures differ between runs");
    assert!(a.actions.len() >= 4);
    // Images: the first seconds rendered twice, byte for byte.
    let short: Vec<_> = frames.iter().filter(|f| f.t < 2.5).cloned().collect();
    let mut images = Vec::new();
    for _ in 0..2 {
        let dir = tempfile::tempdir().unwrap();
        let opts = Options {
            out: Some(dir.path().to_owned()),
            fps: 2.0,
            tail_s: 0.0,
            adapter: marionette::render::gpu::AdapterChoice::Cpu,
            ..Options::default()
        };
        let s = headless::run(ch.clone(), &config, short.clone(), &opts).unwrap();
        assert!(s.frames_written >= 4);
        let pngs: Vec<Vec<u8>> = (0..s.frames_written)
            .map(|i| std::fs::read(dir.path().join(format!("frames/frame-{i:05}.png"))).unwrap())
            .collect();
        images.push(pngs);
    }
    assert!(images[0] == images[1], "frames differ between runs");
}

#[test]
fn replay_headless_takes_a_real_panel_recording() {
    // A real 3M capture (ten fingers, truncated mid-frame): it runs through
    // the whole pipeline into images without trouble.
    let file = common::shared_dir().join("recordings/evemu/evemu-data.3m-microtouch-usb.evemu");
    let dir = tempfile::tempdir().unwrap();
    let out = marionette(&[
        "replay",
        file.to_str().unwrap(),
        "--headless",
        "--out",
        dir.path().to_str().unwrap(),
        "--fps",
        "1",
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(dir.path().join("frames/frame-00010.png").is_file());
    assert!(dir.path().join("contact-sheet.png").is_file());
}

#[test]
fn replay_headless_needs_an_output_folder() {
    let out = marionette(&["replay", "x.evemu", "--headless"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--out"));
}

#[test]
fn export_bvh_writes_the_performed_motion() {
    let dir = tempfile::tempdir().unwrap();
    let bvh = dir.path().join("demo.bvh");
    let rec = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/recordings/demo.evemu");
    let out = marionette(&[
        "export-bvh",
        rec.to_str().unwrap(),
        "--out",
        bvh.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let file = marionette::character::bvh::read_file(&bvh).unwrap();
    let lib = common::character();
    assert_eq!(file.skeleton.len(), lib.lib.skeleton.len());
    let duration = pipeline::summarize(&demo_recording()).0.duration_s;
    let frames = file.frames.len() as f64;
    let frame_time = lib.lib.clips.values().next().unwrap().frame_time;
    assert!(
        (frames * frame_time - duration).abs() < 1.5,
        "{frames} frames"
    );
    // It moves: the right foot rises (the kick) and the walk travels.
    let foot = lib.roles.get(marionette::character::roles::Role::RightFoot);
    let world: Vec<_> = file
        .frames
        .iter()
        .map(|f| marionette::character::skeleton::forward_kinematics(&file.skeleton, f))
        .collect();
    let ys: Vec<f64> = world.iter().map(|w| w.positions[foot].y).collect();
    let (lo, hi) = ys
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), y| (a.min(*y), b.max(*y)));
    assert!(hi - lo > 0.3, "the foot rose {:.2} m", hi - lo);
    let travel = (world.last().unwrap().positions[0] - world[0].positions[0]).length();
    assert!(travel > 0.3, "the character moved {travel:.2} m");
}

#[test]
fn replay_metrics_meet_the_motion_targets_and_show_what_tracking_buys() {
    let dir = tempfile::tempdir().unwrap();
    let rec = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/recordings/demo.evemu");
    let run = |name: &str, extra: &[&str]| -> serde_json::Value {
        let out = dir.path().join(name);
        let mut args = vec![
            "replay",
            rec.to_str().unwrap(),
            "--metrics",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let o = marionette(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap()
    };
    let on = run("on.json", &[]);
    let off = run("off.json", &["--no-tracking"]);
    let f = |m: &serde_json::Value, k: &str| m[k].as_f64().unwrap();
    // The targets: no NaN, no pop, planted feet skate at most 5 mm per
    // frame, at most 5 mm into the floor; every action started finishes.
    assert!(f(&on, "frames") > 1000.0);
    assert_eq!(f(&on, "nan_frames"), 0.0);
    assert_eq!(f(&on, "pops"), 0.0, "{}", on["pop_list"]);
    assert!(f(&on, "max_joint_speed_jump_rad_s") <= 10.0);
    assert!(f(&on, "foot_skate_mm_per_frame") <= 5.0, "{on}");
    // The figures of docs/commands.md, `replay --metrics`: 0.25 mm per frame on average, the worst step
    // 5.90 mm.
    assert!(f(&on, "foot_skate_mm_per_frame") <= 0.26, "{on}");
    assert!(f(&on, "foot_skate_max_mm") <= 6.2, "{on}");
    assert!(f(&on, "ground_penetration_mm") <= 5.0, "{on}");
    let actions = on["actions"].as_array().unwrap();
    assert!(actions.len() >= 8);
    assert!(actions.iter().all(|a| a["outcome"] == "finished"), "{on}");
    // The wave laid over the walk back: started while that walk plays.
    let at = |name: &str| {
        actions
            .iter()
            .filter(|a| a["name"] == name)
            .map(|a| (f(a, "start_s"), f(a, "end_s")))
            .collect::<Vec<_>>()
    };
    let (walks, waves) = (at("walk"), at("wave_right"));
    assert!(
        waves
            .iter()
            .any(|w| walks.iter().any(|k| k.0 < w.0 && w.0 < k.1)),
        "{on}"
    );
    // Without tracking the switches between controllers pop.
    assert!(f(&off, "pops") > 20.0, "{off}");
    assert!(f(&off, "max_joint_speed_jump_rad_s") > 3.0 * f(&on, "max_joint_speed_jump_rad_s"));
}
