//! Clip names in `library.toml`: a BVH file inside the library's clips
//! folder, or frames of one (`take.bvh#120-185`); a file's own `#`
//! (`punch_#2.bvh`) stays in its name.

use std::path::{Component, Path};

/// A clip named in `library.toml`: a BVH file, or frames of one
/// (`take.bvh#120-185`, both ends included, counted from 0).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ClipRef<'a> {
    pub file: &'a str,
    pub frames: Option<(usize, usize)>,
}

/// Why a clip name cannot be read.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ClipRefError {
    #[error("{} is not a frame range; write it as FIRST-LAST, e.g. {}", crate::reading::quote(&format!("#{}", .range)), crate::reading::quote(&format!("{}#120-185", .file)))]
    NotARange { file: String, range: String },
    #[error("the frame range {first}-{last} must end after it begins")]
    Backwards { first: usize, last: usize },
    #[error("names no file before `#`")]
    NoFile,
    #[error(
        "{} is outside the library's clips folder: name clips by their path inside it (an absolute path, or `..` that leaves the folder, is refused)",
        crate::reading::quote(.file)
    )]
    Outside { file: String },
}

impl<'a> ClipRef<'a> {
    /// Split a clip name into its file and frame range. The file must lie
    /// inside the clips folder: relative, and never above it.
    pub fn parse(name: &'a str) -> Result<Self, ClipRefError> {
        // A `#` followed by a name with a dot (`punch_#2.bvh`, a take's own
        // name) is part of the file's name, not a frame range.
        let split = name
            .rsplit_once('#')
            .filter(|(_, after)| !after.contains('.'));
        let Some((file, range)) = split else {
            inside(name)?;
            return Ok(Self {
                file: name,
                frames: None,
            });
        };
        inside(file)?;
        let bad = || ClipRefError::NotARange {
            file: file.to_owned(),
            range: range.to_owned(),
        };
        let (a, b) = range.split_once('-').ok_or_else(bad)?;
        let a: usize = a.trim().parse().map_err(|_| bad())?;
        let b: usize = b.trim().parse().map_err(|_| bad())?;
        if b <= a {
            return Err(ClipRefError::Backwards { first: a, last: b });
        }
        if file.is_empty() {
            return Err(ClipRefError::NoFile);
        }
        Ok(Self {
            file,
            frames: Some((a, b)),
        })
    }
}

/// Refuse a file name that leaves the clips folder: absolute, or with more
/// `..` than folders before them.
fn inside(file: &str) -> Result<(), ClipRefError> {
    let outside = || ClipRefError::Outside {
        file: file.to_owned(),
    };
    let mut depth = 0usize;
    for c in Path::new(file).components() {
        match c {
            Component::Normal(_) => depth += 1,
            Component::CurDir => {}
            Component::ParentDir => depth = depth.checked_sub(1).ok_or_else(outside)?,
            Component::RootDir | Component::Prefix(_) => return Err(outside()),
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_hash_in_a_takes_name_is_part_of_the_file() {
        assert_eq!(
            ClipRef::parse("punch_#2.bvh").unwrap(),
            ClipRef {
                file: "punch_#2.bvh",
                frames: None
            }
        );
        assert_eq!(
            ClipRef::parse("punch_#2.bvh#10-40").unwrap(),
            ClipRef {
                file: "punch_#2.bvh",
                frames: Some((10, 40))
            }
        );
        assert!(matches!(
            ClipRef::parse("take.bvh#12O-185"),
            Err(ClipRefError::NotARange { .. })
        ));
    }

    #[test]
    fn clip_names_stay_inside_the_clips_folder() {
        for ok in ["a.bvh", "takes/a.bvh", "takes/../a.bvh", "./a.bvh#1-5"] {
            assert!(ClipRef::parse(ok).is_ok(), "{ok}");
        }
        for bad in [
            "../../../../etc/passwd",
            "/etc/passwd",
            "../a.bvh#1-5",
            "takes/../../a.bvh",
        ] {
            assert!(
                matches!(ClipRef::parse(bad), Err(ClipRefError::Outside { .. })),
                "{bad}"
            );
        }
        assert_eq!(
            ClipRef::parse("t.bvh#3-9"),
            Ok(ClipRef {
                file: "t.bvh",
                frames: Some((3, 9))
            })
        );
    }
}
