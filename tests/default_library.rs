//! The project's own default library (assets/library, compiled from the
//! scores in assets/library-src): it regenerates identically, loads, has
//! the actions the exhibit needs, and moves like a person: planted feet do
//! not slide, nothing goes through the floor, no joint beyond human limits,
//! anticipation before the big moves, weight over the supporting foot.

#![allow(
    clippy::print_stdout,
    clippy::print_stderr,
    reason = "measurements are printed for the reader of the run"
)]

use std::path::{Path, PathBuf};

use glam::DVec3;
use marionette::character::library::Library;
use marionette::character::motion::Clip;
use marionette::character::roles::Role;
use marionette::character::skeleton::forward_kinematics;
use marionette::tools::author;
use marionette::tools::checks;
use marionette::tools::checks::Limits;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn library() -> Library {
    Library::load(&root().join("assets/library")).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn regenerating_the_library_gives_the_committed_files() {
    let compiled = author::compile(&root().join("assets/library-src")).unwrap();
    let dir = root().join("assets/library");
    let mut on_disk: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(Result::ok)
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    on_disk.sort();
    let generated: Vec<String> = compiled.files.keys().cloned().collect();
    assert_eq!(
        on_disk, generated,
        "assets/library holds exactly what the scores make; run `marionette author-library`"
    );
    for (name, text) in &compiled.files {
        let committed = std::fs::read_to_string(dir.join(name)).unwrap();
        assert!(
            committed == *text,
            "{name} differs from what its score compiles to; run `marionette author-library`"
        );
    }
}

#[test]
fn the_library_has_the_actions_an_exhibit_needs() {
    let lib = library();
    assert!(lib.actions.len() >= 10, "{} actions", lib.actions.len());
    for needed in [
        "punch_right",
        "kick_right",
        "bow",
        "wave_right",
        "jump",
        "walk",
    ] {
        assert!(
            lib.actions.iter().any(|a| a.name == needed),
            "no `{needed}` action"
        );
    }
    for a in &lib.actions {
        assert!(
            (2..=4).contains(&a.clips.len()),
            "{} has {} variants",
            a.name,
            a.clips.len()
        );
    }
    assert!(lib.posing.len() >= 10);
    assert!(
        lib.clips
            .values()
            .all(|c| c.scale_to_m == 1.0 && !c.dropped_tpose)
    );
}

#[test]
fn every_clip_moves_within_human_limits() {
    let lib = library();
    let mut report = Vec::new();
    for (name, clip) in &lib.clips {
        let r = checks::check(
            &clip.skeleton,
            &clip.roles,
            &clip.frames,
            0.0,
            &Limits::default(),
        );
        if r.max_slide_mm > 5.0 {
            report.push(format!(
                "{name}: planted foot slides {:.2} mm/frame ({})",
                r.max_slide_mm, r.worst_slide
            ));
        }
        if r.max_penetration_mm > 5.0 {
            report.push(format!(
                "{name}: {:.1} mm below the floor",
                r.max_penetration_mm
            ));
        }
        if let Some(v) = r.violations.first() {
            report.push(format!("{name}: {v} ({} in all)", r.violations.len()));
        }
        // Some frames of every clip stand on the floor.
        assert!(r.planted_frames > 0, "{name} never touches the floor");
    }
    assert!(report.is_empty(), "{}", report.join("\n"));
}

/// Joint positions relative to the pelvis, turned into the pelvis's facing.
fn posture_key(clip: &Clip, k: usize) -> Vec<DVec3> {
    let w = forward_kinematics(&clip.skeleton, &clip.frames[k]);
    let pelvis = w.positions[clip.roles.get(Role::Pelvis)];
    let fwd = w.rotations[0] * DVec3::Z;
    let yaw = glam::DQuat::from_rotation_y(-fwd.x.atan2(fwd.z));
    w.positions.iter().map(|p| yaw * (*p - pelvis)).collect()
}

#[test]
fn the_library_holds_several_hundred_distinct_postures() {
    let lib = library();
    let mut kept: Vec<Vec<DVec3>> = Vec::new();
    for clip in lib.clips.values() {
        for k in 0..clip.frames.len() {
            let p = posture_key(clip, k);
            let distinct = kept.iter().all(|q| {
                let mean = p
                    .iter()
                    .zip(q)
                    .map(|(a, b)| (*a - *b).length())
                    .sum::<f64>()
                    / p.len() as f64;
                mean > 0.02
            });
            if distinct {
                kept.push(p);
            }
        }
    }
    eprintln!(
        "{} distinct postures (mean joint distance over 2 cm)",
        kept.len()
    );
    assert!(
        kept.len() >= 300,
        "only {} postures differ by more than 2 cm (mean joint distance)",
        kept.len()
    );
}

fn track(clip: &Clip, role: Role) -> Vec<DVec3> {
    (0..clip.frames.len())
        .map(|k| {
            forward_kinematics(&clip.skeleton, &clip.frames[k]).positions[clip.roles.get(role)]
        })
        .collect()
}

#[test]
fn big_moves_have_anticipation_and_follow_through() {
    let lib = library();
    // Punch: the right shoulder coils back before the strike, the fist
    // reaches out, and overshoots where it settles back to guard.
    let punch = &lib.clips["punch_right_a.bvh"];
    let hand = track(punch, Role::RightHand);
    let shoulder = track(punch, Role::RightShoulder);
    let peak = (0..hand.len())
        .max_by(|a, b| hand[*a].z.total_cmp(&hand[*b].z))
        .unwrap();
    let coil = shoulder[..peak]
        .iter()
        .map(|p| p.z)
        .fold(f64::INFINITY, f64::min);
    assert!(
        coil < shoulder[0].z - 0.03,
        "the shoulder coils back before the strike ({:.3} m)",
        shoulder[0].z - coil
    );
    assert!(hand[peak].z > hand[0].z + 0.4, "the strike reaches out");
    assert!(
        shoulder[peak].z > shoulder[0].z + 0.03,
        "the shoulder drives through with the strike"
    );
    // Jump: the pelvis goes down at least 15 cm before it goes up.
    let jump = &lib.clips["jump_a.bvh"];
    let pelvis = track(jump, Role::Pelvis);
    let top = (0..pelvis.len())
        .max_by(|a, b| pelvis[*a].y.total_cmp(&pelvis[*b].y))
        .unwrap();
    let crouch = pelvis[..top]
        .iter()
        .map(|p| p.y)
        .fold(f64::INFINITY, f64::min);
    assert!(crouch < pelvis[0].y - 0.15, "crouch before the jump");
    let landing = pelvis[top..]
        .iter()
        .map(|p| p.y)
        .fold(f64::INFINITY, f64::min);
    assert!(landing < pelvis[0].y - 0.1, "the knees absorb the landing");
}

#[test]
fn the_weight_is_over_the_supporting_foot_on_one_leg() {
    let lib = library();
    for name in ["kick_right_a.bvh", "kick_right_high.bvh", "kick_left_a.bvh"] {
        let clip = &lib.clips[name];
        let left_kick = name.starts_with("kick_left");
        let (kicking, standing) = if left_kick {
            (Role::LeftFoot, Role::RightFoot)
        } else {
            (Role::RightFoot, Role::LeftFoot)
        };
        let kick = track(clip, kicking);
        let stand = track(clip, standing);
        let pelvis = track(clip, Role::Pelvis);
        let mut one_leg = 0;
        for k in 0..clip.frames.len() {
            if kick[k].y > 0.2 {
                one_leg += 1;
                let off = (pelvis[k].x - stand[k].x).abs();
                assert!(
                    off < 0.06,
                    "{name} frame {k}: pelvis {off:.3} m beside the standing foot"
                );
            }
        }
        assert!(one_leg > 5, "{name}: the kicking foot leaves the floor");
    }
}

#[test]
fn a_score_error_names_the_file_and_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.toml");
    std::fs::write(
        &path,
        "kind = \"posing\"\nduration = 1.0\n[[variant]]\nfile = \"x\"\n[[key]]\nt = 0.0\nlef_hand = [0, 1, 0]\n",
    )
    .unwrap();
    let e = author::compile(dir.path()).err().unwrap().to_string();
    assert!(
        e.contains("bad.toml") && e.contains("lef_hand") && e.contains("left_hand"),
        "{e}"
    );
    std::fs::write(
        &path,
        "kind = \"posing\"\nduration = 1.0\n[[variant]]\nfile = \"x\"\n[[key]]\nt = 2.0\n",
    )
    .unwrap();
    let e = author::compile(dir.path()).err().unwrap().to_string();
    assert!(e.contains("t = 2"), "{e}");
    assert!(Path::new(&path).exists());
}
