//! Any bytes as a library's `library.toml`, beside two real clips: a
//! library or an error naming what is wrong, never a panic; every clip it
//! loads is read from inside its clips folder.
#![no_main]

use std::path::PathBuf;
use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;
use marionette::character::library::Library;

/// A folder with two of the default library's clips, made once.
fn folder() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("marionette-fuzz-lib-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let assets = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../assets/library");
        for clip in ["pose_stance.bvh", "bow_a.bvh"] {
            std::fs::copy(assets.join(clip), dir.join(clip)).unwrap();
        }
        dir
    })
}

fuzz_target!(|data: &[u8]| {
    let dir = folder();
    let toml = dir.join("library.toml");
    std::fs::write(&toml, data).unwrap();
    if let Ok(lib) = Library::load(dir) {
        let root = std::fs::canonicalize(&lib.clips_dir).unwrap();
        for name in lib.clips.keys() {
            let file = std::fs::canonicalize(lib.clip_path(name)).unwrap();
            assert!(file.starts_with(&root), "{name} read from {}", file.display());
        }
    }
});
