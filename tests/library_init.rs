//! `marionette library init` on a real studio's capture (the Bandai share,
//! renamed as an exhibit builder names takes): the library it writes
//! loads, and what it measured matches what the takes hold.

mod common;

use std::path::Path;

use marionette::character::library::Library;
use marionette::character::roles::Role;

use common::marionette;

/// A folder of takes linked from the Bandai share: `(action, style)` files
/// `d1_<action>_<style>_001.bvh` appear as `<name>_<style>_001.bvh`.
fn takes(dir: &Path, files: &[(&str, &str, &str)]) {
    let bandai = common::shared_dir().join("mocap/bandai");
    for (action, style, name) in files {
        std::os::unix::fs::symlink(
            bandai.join(format!("d1_{action}_{style}_001.bvh")),
            dir.join(format!("{name}_{style}_001.bvh")),
        )
        .unwrap();
    }
}

#[test]
fn a_folder_of_takes_becomes_a_library_that_loads() {
    let src = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();
    takes(
        src.path(),
        &[
            ("bow", "active", "bow"),
            ("bow", "proud", "bow"),
            ("punch", "normal", "punch"),
            ("kick", "normal", "kick"),
            ("slash", "normal", "slash"),
            ("byebye", "happy", "byebye"),
            ("walk", "active", "walk"),
            ("guide", "normal", "pose"),
        ],
    );
    let lib_dir = out.path().join("lib");
    let run = marionette(&[
        "library",
        "init",
        src.path().to_str().unwrap(),
        "--out",
        lib_dir.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let lib = Library::load(&lib_dir).unwrap_or_else(|e| panic!("{e}"));
    // Every file feeds posing; the pose take starts no action.
    assert_eq!(lib.posing.len(), 8);
    let action = |name: &str| {
        lib.actions
            .iter()
            .find(|a| a.name == name)
            .unwrap_or_else(|| panic!("no action {name}: {stdout}"))
    };
    assert!(lib.actions.iter().all(|a| a.name != "pose"));
    // The report ends with what to do next.
    let last = stdout.lines().last().unwrap_or_default();
    assert!(
        last.starts_with("next: `marionette library check") && last.contains("demo --library"),
        "{stdout}"
    );
    // Six actions, and the mirror images of the two led by one side's
    // hand or foot alone (punch, kick): both hands wave bye-bye and swing
    // the slash, so those are their own mirror images.
    assert_eq!(lib.actions.len(), 8, "{stdout}");
    for symmetric in ["byebye", "slash"] {
        assert!(
            lib.actions
                .iter()
                .all(|a| a.name != format!("{symmetric}_mirror")),
            "{stdout}"
        );
    }
    assert_eq!(
        stdout
            .matches("so the action is its own mirror image")
            .count(),
        2,
        "{stdout}"
    );
    // Named by side: the punch taught with the left hand is `punch_left`,
    // its mirror image `punch_right`.
    let mirrored = action("punch_right");
    assert_eq!(mirrored.primary, Role::RightHand);
    assert!(mirrored.clips.iter().all(|c| c.ends_with("~mirror")));
    assert_eq!(action("kick_left").primary, Role::LeftFoot);
    // The studio's punch take is five left punches, the kick three kicks,
    // the slash three slashes: each is cut into single actions.
    let punch = action("punch_left");
    assert_eq!(punch.primary, Role::LeftHand);
    assert_eq!(punch.clips.len(), 5, "{:?}", punch.clips);
    let kick = action("kick_right");
    assert_eq!(kick.primary, Role::RightFoot);
    assert_eq!(kick.clips.len(), 3, "{:?}", kick.clips);
    assert_eq!(action("slash").clips.len(), 3);
    // A bow is led by the head and is one movement, its pause bowed down
    // not a cut; a walk by the pelvis.
    let bow = action("bow");
    assert_eq!(bow.primary, Role::Head);
    assert_eq!(bow.clips.len(), 2, "{:?}", bow.clips);
    assert_eq!(action("walk").primary, Role::Pelvis);
    // Both hands wave bye-bye: said, since the primary is one part.
    assert!(
        stdout.contains("byebye") && stdout.contains("moves about as much"),
        "{stdout}"
    );
    // Segments: prepared and cancellable, then moving, then recovering.
    for a in &lib.actions {
        assert_eq!(a.segments.len(), 3);
        assert!(a.segments[0].still && !a.segments[1].still && a.segments[2].still);
    }
    // The file says what it decided, and where the clips are.
    let text = std::fs::read_to_string(lib_dir.join("library.toml")).unwrap();
    assert!(
        text.contains("# primary left_hand: it moves most"),
        "{text}"
    );
    assert!(
        text.contains("units: cm") || text.contains("Units: cm"),
        "{text}"
    );
    assert!(text.contains("punch_normal_001.bvh#"), "{text}");

    // Run again: the library is not overwritten without --force.
    let again = marionette(&[
        "library",
        "init",
        src.path().to_str().unwrap(),
        "--out",
        lib_dir.to_str().unwrap(),
    ]);
    assert_eq!(again.status.code(), Some(73));
    assert!(String::from_utf8_lossy(&again.stderr).contains("--force"));
    assert_eq!(
        std::fs::read_to_string(lib_dir.join("library.toml")).unwrap(),
        text
    );
}

#[test]
fn folders_without_usable_takes_are_refused_with_the_reason() {
    let out = tempfile::tempdir().unwrap();
    let empty = tempfile::tempdir().unwrap();
    let run = marionette(&[
        "library",
        "init",
        empty.path().to_str().unwrap(),
        "--out",
        out.path().to_str().unwrap(),
    ]);
    assert_eq!(run.status.code(), Some(66));
    assert!(String::from_utf8_lossy(&run.stderr).contains("no BVH files"));
    let broken = tempfile::tempdir().unwrap();
    std::fs::write(
        broken.path().join("wave_a.bvh"),
        "HIERARCHY\nROOT Hips\n{\n",
    )
    .unwrap();
    let run = marionette(&[
        "library",
        "init",
        broken.path().to_str().unwrap(),
        "--out",
        out.path().to_str().unwrap(),
    ]);
    assert_eq!(run.status.code(), Some(65));
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(err.contains("wave_a.bvh"), "{err}");
    assert!(!out.path().join("library.toml").exists());
}

#[test]
fn a_take_named_with_a_hash_makes_a_library_that_loads() {
    let src = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();
    takes(
        src.path(),
        &[("punch", "normal", "punch_#2"), ("bow", "active", "bow_#1")],
    );
    let lib_dir = out.path().join("lib");
    let run = marionette(&[
        "library",
        "init",
        src.path().to_str().unwrap(),
        "--out",
        lib_dir.to_str().unwrap(),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let lib = Library::load(&lib_dir).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        lib.posing.iter().any(|c| c.contains("punch_#2")),
        "{:?}",
        lib.posing
    );
}
