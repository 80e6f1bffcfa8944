//! Where the configuration's library is: a relative `character.library` is
//! the configuration file's neighbour, whatever folder marionette is
//! started from, and the usual mistakes (a library.toml named instead of
//! its folder, a folder of takes with no library yet, a folder that is not
//! there) are said with the file, the key, the absolute path and what to
//! do.

mod common;

use std::path::Path;
use std::process::Command;

fn run_in(cwd: &Path, config: &Path, args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_marionette"))
        .current_dir(cwd)
        .arg("--config")
        .arg(config)
        .args(args)
        .env_remove("RUST_LOG")
        .env("CACHE_DIRECTORY", cwd.join("cache"))
        .output()
        .unwrap()
}

fn copy_default_library(to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    let from = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/library");
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
    }
}

#[test]
fn a_relative_library_is_found_beside_the_configuration() {
    let dir = tempfile::tempdir().unwrap();
    let etc = dir.path().join("etc");
    copy_default_library(&etc.join("mylib"));
    let config = etc.join("marionette.toml");
    std::fs::write(&config, "[character]\nlibrary = \"mylib\"\n").unwrap();
    // Started from another folder altogether.
    let elsewhere = dir.path().join("elsewhere");
    std::fs::create_dir(&elsewhere).unwrap();
    let out = run_in(
        &elsewhere,
        &config,
        &[
            "replay",
            &Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("assets/recordings/demo-two-hands.evemu")
                .display()
                .to_string(),
            "--metrics",
            "m.json",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(elsewhere.join("m.json").is_file());
}

#[test]
fn the_usual_mistakes_are_named_with_what_to_do() {
    let dir = tempfile::tempdir().unwrap();
    let takes = dir.path().join("takes");
    std::fs::create_dir(&takes).unwrap();
    std::os::unix::fs::symlink(
        common::shared_dir().join("mocap/bandai/d1_bow_active_001.bvh"),
        takes.join("bow_active.bvh"),
    )
    .unwrap();
    copy_default_library(&dir.path().join("lib"));
    let config = dir.path().join("marionette.toml");
    for (library, says) in [
        ("lib/library.toml", "is a file; name the library's folder"),
        (
            "takes",
            "holds BVH takes but no library.toml: run `marionette library init",
        ),
        ("missing", "does not exist"),
    ] {
        std::fs::write(&config, format!("[character]\nlibrary = \"{library}\"\n")).unwrap();
        let out = run_in(dir.path(), &config, &["demo", "--out", "out"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(78), "{library}: {err}");
        let absolute = dir.path().join(library);
        for part in [
            config.display().to_string(),
            "character.library".to_owned(),
            absolute.display().to_string(),
            says.to_owned(),
        ] {
            assert!(err.contains(&part), "{library}: `{part}` not in {err}");
        }
        assert!(!dir.path().join("out").exists());
    }
}

#[test]
fn bake_takes_the_configurations_library_and_a_flag_over_it() {
    let dir = tempfile::tempdir().unwrap();
    copy_default_library(&dir.path().join("etc/mylib"));
    let config = dir.path().join("etc/marionette.toml");
    std::fs::write(&config, "[character]\nlibrary = \"mylib\"\n").unwrap();
    let out = run_in(dir.path(), &config, &["bake"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains(&dir.path().join("etc/mylib").display().to_string()),
        "{stdout}"
    );
    // --library wins, and a wrong one is the command line's (66), not the
    // configuration's.
    let out = run_in(dir.path(), &config, &["bake", "--library", "nowhere"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(66), "{err}");
    assert!(err.contains("--library: the folder"), "{err}");
}

#[test]
fn inspect_of_a_library_points_at_library_check() {
    let lib = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/library");
    for target in [lib.join("library.toml"), lib.clone()] {
        let out = Command::new(env!("CARGO_BIN_EXE_marionette"))
            .arg("inspect")
            .arg(&target)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(65), "{err}");
        assert!(
            err.contains("is a motion library") && err.contains("library check"),
            "{err}"
        );
    }
}

#[test]
fn a_library_made_with_copy_clips_can_be_moved() {
    let dir = tempfile::tempdir().unwrap();
    let takes = dir.path().join("takes");
    std::fs::create_dir(&takes).unwrap();
    for (file, name) in [
        ("d1_bow_active_001.bvh", "bow_active.bvh"),
        ("d1_bow_angry_001.bvh", "bow_angry.bvh"),
        ("d1_punch_normal_001.bvh", "punch_normal.bvh"),
    ] {
        std::os::unix::fs::symlink(
            common::shared_dir().join("mocap/bandai").join(file),
            takes.join(name),
        )
        .unwrap();
    }
    let init = |out: &Path, extra: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_marionette"))
            .args(["library", "init"])
            .arg(&takes)
            .arg("--out")
            .arg(out)
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    // Without the flag, init says the library refers to the takes.
    let said = init(&dir.path().join("refers"), &[]);
    assert!(said.contains("the clips stay in"), "{said}");
    // With it, the folder stands on its own: moved, it still loads.
    let said = init(&dir.path().join("lib"), &["--copy-clips"]);
    assert!(said.contains("copied 3 takes"), "{said}");
    let moved = dir.path().join("elsewhere/lib");
    std::fs::create_dir_all(moved.parent().unwrap()).unwrap();
    std::fs::rename(dir.path().join("lib"), &moved).unwrap();
    std::fs::remove_dir_all(&takes).unwrap();
    let lib = marionette::character::library::Library::load(&moved).unwrap();
    assert_eq!(lib.clips_dir, moved.join("clips"));
    assert!(lib.actions.iter().any(|a| a.name.starts_with("punch")));
}
