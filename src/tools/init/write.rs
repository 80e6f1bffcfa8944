//! A plan written out: the commented `library.toml` and the report of
//! what was decided. File and joint names from the takes go into comments
//! on one line each (control characters shown as `?`), and into strings
//! escaped as TOML wants, so no name can break the file.

use crate::control::locomotion::gait::MIN_TRAVEL_M;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::Plan;
use crate::character::library::Release;

/// `s` fit for a comment: control characters (a newline in a file name)
/// would end the comment and break the file.
fn one_line(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_control() { '?' } else { c })
        .collect()
}

impl Plan {
    /// The library file, commented, for a library in `out` (clips are
    /// referenced in the source folder, relative to `out` when they can
    /// be).
    #[must_use]
    pub fn to_toml(&self, out: &Path) -> String {
        let dir = relative_to(&self.src, out);
        let mut t = String::new();
        let _ = writeln!(
            t,
            "# A motion library made by `marionette library init` from the takes in\n# {}.\n# Every decision below is measured from the motion and can be edited;\n# `marionette bake --library DIR` loads it and says what is wrong, if\n# anything.",
            one_line(&self.src.display().to_string())
        );
        let _ = writeln!(
            t,
            "\n[settings]\n# The clips stay where they are.\nclips_dir = {}\n# Units: {} (from the skeleton's bone lengths); set scale_to_m\n# (metres per file unit) if that is wrong.",
            toml_string(&dir.display().to_string()),
            self.unit
        );
        let _ = writeln!(
            t,
            "\n# Roles found from the joint names; a [roles] table overrides them,\n# e.g. left_hand = \"LeftWrist\".\n#"
        );
        for (role, joint) in &self.roles {
            let _ = writeln!(t, "#   {role} = {}", one_line(joint));
        }
        if !self.skipped.is_empty() {
            let _ = writeln!(t, "\n# Files left out:");
            for (file, why) in &self.skipped {
                let _ = writeln!(t, "#   {}: {}", one_line(file), one_line(why));
            }
        }
        if !self.not_actions.is_empty() {
            let _ = writeln!(t, "\n# Takes named after an action that feed posing only:");
            for (file, why) in &self.not_actions {
                let _ = writeln!(t, "#   {}: {}", one_line(file), one_line(why));
            }
        }
        let _ = writeln!(t, "\n[posing]\n# Every clip feeds posing.\nclips = [");
        for c in &self.posing {
            let _ = writeln!(t, "  {},", toml_string(c));
        }
        let _ = writeln!(t, "]");
        if !self.locomotion.is_empty() {
            let _ = writeln!(
                t,
                "\n[locomotion]\n# Takes whose pelvis travels (comes at least {MIN_TRAVEL_M} m from where it\n# starts): the character walks along a finger's path with them.\nclips = ["
            );
            for (c, m) in &self.locomotion {
                let _ = writeln!(t, "  {},  # {m:.1} m", toml_string(c));
            }
            let _ = writeln!(t, "]");
        }
        for a in &self.actions {
            let _ = writeln!(t, "\n[[action]]");
            for n in &a.notes {
                let _ = writeln!(t, "# {}", one_line(n));
            }
            let _ = writeln!(t, "name = {}", toml_string(&a.name));
            let _ = writeln!(t, "primary = {}", toml_string(a.primary.name()));
            if a.mirror {
                let _ = writeln!(t, "mirror = true");
            }
            let _ = writeln!(t, "clips = [");
            for c in &a.clips {
                let _ = writeln!(t, "  {},", toml_string(c));
            }
            let _ = writeln!(t, "]\nsegments = [");
            for s in &a.segments {
                let _ = writeln!(
                    t,
                    "  {{ until = {}, still = {}, release = \"{}\" }},",
                    s.until,
                    s.still,
                    match s.release {
                        Release::Forward => "forward",
                        Release::Backward => "backward",
                    }
                );
            }
            let _ = writeln!(t, "]");
        }
        t
    }

    /// What was decided, for a person: a line each.
    #[must_use]
    pub fn report(&self) -> Vec<String> {
        let mut lines = vec![format!(
            "{} clips, units {}, every clip feeds posing",
            self.posing.len(),
            self.unit
        )];
        for (file, why) in &self.skipped {
            lines.push(format!("left out {file}: {why}"));
        }
        for (file, why) in &self.not_actions {
            lines.push(format!("not an action {file}: {why}"));
        }
        if self.locomotion.is_empty() {
            lines.push(format!("no take travels (its pelvis {MIN_TRAVEL_M} m or more from where it starts): the character will not walk where a finger leads; record walks to give it locomotion"));
        } else {
            let mut named: Vec<String> = self
                .locomotion
                .iter()
                .take(4)
                .map(|(c, m)| format!("{c} ({m:.1} m)"))
                .collect();
            if self.locomotion.len() > named.len() {
                named.push(format!("and {} more", self.locomotion.len() - named.len()));
            }
            lines.push(format!(
                "locomotion (walking where a finger leads): {} takes that travel: {}",
                self.locomotion.len(),
                named.join(", ")
            ));
        }
        for a in &self.actions {
            lines.push(format!("action {}: {} clips", a.name, a.clips.len()));
            lines.extend(a.notes.iter().map(|n| format!("  {n}")));
        }
        lines
    }
}

/// A TOML basic string.
fn toml_string(s: &str) -> String {
    toml::Value::String(s.to_owned()).to_string()
}

/// `path` as seen from `from` when both are absolute or both relative
/// (`..` steps up), else `path` itself.
pub(super) fn relative_to(path: &Path, from: &Path) -> PathBuf {
    let (Ok(path), Ok(from)) = (
        std::path::absolute(path).map(|p| normalise(&p)),
        std::path::absolute(from).map(|p| normalise(&p)),
    ) else {
        return path.to_owned();
    };
    let common = path
        .components()
        .zip(from.components())
        .take_while(|(a, b)| a == b)
        .count();
    let mut out = PathBuf::new();
    for _ in from.components().skip(common) {
        out.push("..");
    }
    for c in path.components().skip(common) {
        out.push(c);
    }
    if out.as_os_str().is_empty() {
        out.push(".");
    }
    out
}

/// `.` and `..` folded away without touching the file system.
fn normalise(p: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            std::path::Component::CurDir => {}
            std::path::Component::ParentDir => {
                out.pop();
            }
            c => out.push(c),
        }
    }
    out
}
