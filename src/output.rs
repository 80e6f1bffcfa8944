//! Files written whole or not at all: the bytes go to a temporary file
//! beside the target, are flushed to disk, and the temporary file is
//! renamed over the target. Only a regular file (or nothing) is replaced:
//! a directory, a device, a pipe or a symbolic link at the target is
//! refused, so an output path given by mistake (`/dev/sda`, a link into
//! another folder) destroys nothing. The temporary file is removed on
//! every path that fails, so a full disk leaves the old file as it was and
//! nothing beside it.

use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// What stands at `path`, if it is not a regular file: refused as a target.
fn not_regular(path: &Path) -> io::Result<Option<&'static str>> {
    match std::fs::symlink_metadata(path) {
        Ok(m) => {
            let t = m.file_type();
            Ok(if t.is_file() {
                None
            } else if t.is_symlink() {
                Some("a symbolic link")
            } else if t.is_dir() {
                Some("a folder")
            } else {
                Some("a device, pipe or socket")
            })
        }
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(e),
    }
}

/// Refuse to `doing` (replace, write into) anything at `path` but a
/// regular file or nothing.
fn only_a_regular_file(path: &Path, doing: &str) -> io::Result<()> {
    match not_regular(path)? {
        None => Ok(()),
        Some(what) => Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "{} is {what}, not a regular file: refusing to {doing} it (give the path of a file)",
                path.display()
            ),
        )),
    }
}

/// The temporary file beside `path`.
fn temporary(path: &Path) -> io::Result<PathBuf> {
    let name = path.file_name().ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("{} names no file", path.display()),
        )
    })?;
    Ok(path.with_file_name(format!(
        ".{}.{}.tmp",
        name.to_string_lossy(),
        std::process::id()
    )))
}

/// Write `bytes` to `path` whole (see the module's documentation).
pub fn replace_file(path: &Path, bytes: &[u8]) -> io::Result<()> {
    only_a_regular_file(path, "replace")?;
    let tmp = temporary(path)?;
    let written = (|| {
        // A temporary file left by a process of the same id is stale.
        let _ = std::fs::remove_file(&tmp);
        let mut f = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        drop(f);
        std::fs::rename(&tmp, path)
    })();
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written
}

/// Whether `output` is the same file as `input` (same device and inode,
/// whatever the paths say): writing it would replace what is being read.
#[must_use]
pub fn same_file(input: &Path, output: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (std::fs::metadata(input), std::fs::metadata(output)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

/// A file written as it goes (a live recording, whose every frame must
/// be on disk as it comes): created, or a regular file there truncated;
/// a link, a folder, a device, a pipe or a socket there is refused as
/// [`replace_file`] refuses it, and the file is opened without following
/// a link put there since.
pub fn create(path: &Path) -> io::Result<std::fs::File> {
    use std::os::unix::fs::OpenOptionsExt;
    only_a_regular_file(path, "write into")?;
    let file = std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(true)
        .custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK | libc::O_CLOEXEC)
        .open(path)?;
    if !file.metadata()?.is_file() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "{} is not a regular file: refusing to write into it",
                path.display()
            ),
        ));
    }
    Ok(file)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_is_replaced_whole_and_nothing_is_left_beside_it() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out.txt");
        replace_file(&out, b"one").unwrap();
        replace_file(&out, b"two").unwrap();
        assert_eq!(std::fs::read(&out).unwrap(), b"two");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn the_same_file_is_known_by_any_path() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("a.evemu");
        std::fs::write(&a, b"x").unwrap();
        let link = dir.path().join("b.evemu");
        std::os::unix::fs::symlink(&a, &link).unwrap();
        assert!(same_file(&a, &dir.path().join(".").join("a.evemu")));
        assert!(same_file(&a, &link));
        assert!(!same_file(&a, &dir.path().join("c.evemu")));
    }

    #[test]
    fn a_file_written_as_it_goes_is_never_a_link_or_a_device() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("precious.txt");
        std::fs::write(&target, b"keep").unwrap();
        let link = dir.path().join("link.txt");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        for path in [link.as_path(), dir.path(), Path::new("/dev/null")] {
            assert!(create(path).is_err(), "{}", path.display());
        }
        assert_eq!(std::fs::read(&target).unwrap(), b"keep");
        let out = dir.path().join("rec.evemu");
        create(&out).unwrap().write_all(b"one").unwrap();
        assert_eq!(std::fs::read(&out).unwrap(), b"one");
    }

    #[test]
    fn links_folders_and_devices_are_refused_and_left_alone() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("precious.txt");
        std::fs::write(&target, b"keep").unwrap();
        let link = dir.path().join("link.txt");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        for (path, what) in [
            (link.as_path(), "a symbolic link"),
            (dir.path(), "a folder"),
            (Path::new("/dev/null"), "a device"),
        ] {
            let e = replace_file(path, b"gone").unwrap_err();
            assert!(e.to_string().contains(what), "{e}");
        }
        assert_eq!(std::fs::read(&target).unwrap(), b"keep");
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
    }

    #[test]
    fn a_write_that_fails_leaves_the_old_file_and_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        // The rename fails: a folder stands where the file's folder should.
        let missing = dir.path().join("no/such/out.txt");
        assert!(replace_file(&missing, b"x").is_err());
        let ro = dir.path().join("ro");
        std::fs::create_dir(&ro).unwrap();
        let out = ro.join("out.txt");
        std::fs::write(&out, b"old").unwrap();
        let mut perm = std::fs::metadata(&ro).unwrap().permissions();
        std::os::unix::fs::PermissionsExt::set_mode(&mut perm, 0o555);
        std::fs::set_permissions(&ro, perm.clone()).unwrap();
        let r = replace_file(&out, b"new");
        std::os::unix::fs::PermissionsExt::set_mode(&mut perm, 0o755);
        std::fs::set_permissions(&ro, perm).unwrap();
        // As root the folder's mode does not stop the write; either way
        // the file is whole and no temporary is left.
        let now = std::fs::read(&out).unwrap();
        assert!(
            (r.is_err() && now == b"old") || (r.is_ok() && now == b"new"),
            "{r:?}"
        );
        assert_eq!(std::fs::read_dir(&ro).unwrap().count(), 1);
    }
}
