//! Any file name for a take given to `library init`: the planned
//! `library.toml` is valid TOML and names the take exactly as it is on
//! disk, whatever the name holds (newlines, quotes, `#`, `]`, non-ASCII).
#![no_main]

use std::path::PathBuf;
use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;
use marionette::tools::init::plan;

/// A short take (the first frames of a default-library clip), made once.
fn take() -> &'static String {
    static TAKE: OnceLock<String> = OnceLock::new();
    TAKE.get_or_init(|| {
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../assets/library/bow_a.bvh");
        let text = std::fs::read_to_string(path).unwrap();
        let (head, motion) = text.split_once("MOTION").unwrap();
        let mut lines = motion.lines().filter(|l| !l.trim().is_empty());
        let _frames = lines.next();
        let time = lines.next().unwrap();
        let frames: Vec<&str> = lines.take(20).collect();
        format!("{head}MOTION\nFrames: {}\n{time}\n{}\n", frames.len(), frames.join("\n"))
    })
}

fuzz_target!(|data: &[u8]| {
    let stem: String = String::from_utf8_lossy(data)
        .chars()
        .filter(|c| *c != '/' && *c != '\0')
        .take(100)
        .collect();
    if stem.is_empty() || stem == "." || stem == ".." {
        return;
    }
    let name = format!("{stem}.bvh");
    let dir = tempfile_dir();
    let src = dir.join("takes");
    let _ = std::fs::remove_dir_all(&src);
    std::fs::create_dir_all(&src).unwrap();
    if std::fs::write(src.join(&name), take()).is_err() {
        return; // a name the file system refuses (too long)
    }
    let Ok(p) = plan(&src) else { return };
    let text = p.to_toml(&dir.join("lib"));
    let value: toml::Value = toml::from_str(&text).unwrap_or_else(|e| panic!("{e}\n{text}"));
    let posing = value["posing"]["clips"].as_array().unwrap();
    assert!(posing.iter().any(|c| c.as_str() == Some(name.as_str())), "{name:?} in {text}");
});

fn tempfile_dir() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("marionette-fuzz-init-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    })
}
