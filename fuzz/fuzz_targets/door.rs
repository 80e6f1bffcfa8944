//! The door in, with any file where an input should be: a regular file
//! of any bytes, a link to one inside or outside its folder, a dangling
//! link, a pipe, a folder, a link to `/dev/zero`. Each is read whole when
//! it is a regular file inside its folder within its limit, and refused
//! otherwise, at once (a pipe is never waited on, a device never read to
//! its end); never a panic. Any text it holds, quoted, is at most
//! `QUOTE_CHARS` characters shown with no control character.
#![no_main]

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;
use marionette::reading::{self, QUOTE_CHARS, ReadError};

/// `inside/` (the folder inputs must stay in) and `outside/` beside it.
fn scratch() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("marionette-door-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("inside")).unwrap();
        std::fs::create_dir_all(dir.join("outside")).unwrap();
        dir
    })
}

fuzz_target!(|data: &[u8]| {
    let Some((&kind, rest)) = data.split_first() else {
        return;
    };
    let (limit, content) = match rest {
        [a, b, content @ ..] => (u64::from(u16::from_le_bytes([*a, *b])), content),
        _ => (16, rest),
    };
    let root = scratch();
    let inside = root.join("inside");
    let input = inside.join("input");
    let target_in = inside.join("real");
    let target_out = root.join("outside").join("real");
    for p in [&input, &target_in, &target_out] {
        let _ = std::fs::remove_file(p);
        let _ = std::fs::remove_dir(p);
    }
    std::fs::write(&target_in, content).unwrap();
    std::fs::write(&target_out, content).unwrap();
    let link = |to: &Path| std::os::unix::fs::symlink(to, &input).unwrap();
    // Whether the door should hand the bytes over.
    let readable = match kind % 7 {
        0 => {
            std::fs::write(&input, content).unwrap();
            true
        }
        1 => {
            link(&target_in);
            true
        }
        2 => {
            link(&target_out);
            false
        }
        3 => {
            nix::unistd::mkfifo(&input, nix::sys::stat::Mode::S_IRWXU).unwrap();
            false
        }
        4 => {
            std::fs::create_dir(&input).unwrap();
            false
        }
        5 => {
            link(Path::new("/dev/zero"));
            false
        }
        _ => {
            link(&root.join("nothing-here"));
            false
        }
    };
    let fits = content.len() as u64 <= limit;
    match reading::read_inside(&input, &inside, limit) {
        Ok(bytes) => {
            assert!(readable && fits, "kind {} read", kind % 7);
            assert_eq!(bytes, content);
        }
        Err(ReadError::TooLarge { .. }) => assert!(readable && !fits),
        Err(e) => assert!(!readable, "kind {}: {e}", kind % 7),
    }
    // The plain door takes a link anywhere, but never anything that is
    // not a regular file.
    if let Ok(bytes) = reading::read(&input, limit) {
        assert!(matches!(kind % 7, 0..=2) && fits);
        assert_eq!(bytes, content);
    }
    let text = String::from_utf8_lossy(content);
    let q = reading::quote(&text);
    let shown = q.trim_start_matches('`');
    let shown = shown.split('`').next().unwrap_or("");
    assert!(shown.chars().count() <= QUOTE_CHARS + 1, "{q}");
    assert!(!q.chars().any(char::is_control), "{q:?}");
});
