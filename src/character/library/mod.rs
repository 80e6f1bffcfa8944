//! Motion libraries: a folder of BVH files that share one hierarchy, and a
//! `library.toml` that says which clips are for posing and which clips form
//! each action model, with its primary body part and its condition segments
//! (the paper's Fig. 5).
//!
//! ```toml
//! [settings]                 # optional
//! clips_dir = "clips"        # where the BVH files are, relative to this file (default: beside it)
//! scale_to_m = 0.01          # file units to metres; detected when left out
//! action_lead_in = 0.3       # how much of each action clip also feeds posing
//! max_file_mb = 256          # larger BVH files are refused before they are read
//!
//! [roles]                    # optional: joints the names do not give away
//! left_hand = "LeftWrist"
//!
//! [posing]
//! clips = ["idle.bvh", "reach_high.bvh"]
//! # A clip may be part of a file: "take.bvh#120-185" is frames 120 to 185
//! # (counted from 0 in the file's MOTION section, both included), so
//! # one long take can give several actions.
//!
//! [locomotion]              # optional: clips that travel, for walking where a finger leads
//! clips = ["walk.bvh", "run.bvh#0-240"]
//!
//! [[action]]
//! name = "punch"
//! clips = ["punch_1.bvh", "punch_2.bvh"]
//! primary = "right_hand"
//! segments = [               # generalized time 0..1, in order, the last ends at 1
//!   { until = 0.3, still = true,  release = "backward" },  # wind-up: may pause; cancels on lift
//!   { until = 0.7, still = false, release = "forward" },   # strike: keeps moving; completes on lift
//!   { until = 1.0, still = true,  release = "forward" },   # recovery
//! ]
//! ```
//!
//! Loading validates everything and reports every problem at once.

mod actions;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;
use thiserror::Error;

use super::bvh;
pub use super::clip_ref::{ClipRef, ClipRefError};
pub use super::digest::Fnv;
use super::floor;
use super::motion::{Clip, ImportSettings};
use super::roles::Role;
use super::skeleton::Skeleton;
use crate::reading::quote;

pub use self::actions::mirrored_name;
use self::actions::{action_defs, mirror_actions, one_frame_clips};

/// Everything wrong with a library, listed together.
#[derive(Debug, Error)]
#[error("motion library {dir} has {} problem{}:\n{}", .problems.len(), if .problems.len() == 1 { "" } else { "s" }, .problems.iter().map(|p| format!("  - {p}")).collect::<Vec<_>>().join("\n"))]
pub struct LibraryError {
    pub dir: PathBuf,
    pub problems: Vec<String>,
}

/// Which way an action runs by itself when the fingers lift.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Release {
    /// Finish the action.
    Forward,
    /// Cancel it, running back to the start.
    Backward,
}

/// A condition segment of an action, in generalized time.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Segment {
    /// The segment ends at this generalized time (the previous one's end is
    /// its start).
    pub until: f64,
    /// Whether the character may stand still here while a finger rests.
    pub still: bool,
    /// Where time runs when all fingers lift here.
    pub release: Release,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct SettingsFile {
    clips_dir: Option<PathBuf>,
    scale_to_m: Option<f64>,
    action_lead_in: Option<f64>,
    max_file_mb: Option<u64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct PosingFile {
    #[serde(default)]
    clips: Vec<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ActionFile {
    name: String,
    clips: Vec<String>,
    primary: String,
    segments: Vec<Segment>,
    /// Also the mirror image: the same action with the other hand or foot.
    #[serde(default)]
    mirror: bool,
    /// The recogniser's cost threshold for this action (m), instead of the
    /// one calibrated for the library.
    #[serde(default)]
    threshold_m: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct LibraryFile {
    #[serde(default)]
    settings: SettingsFile,
    #[serde(default)]
    roles: BTreeMap<String, String>,
    #[serde(default)]
    posing: PosingFile,
    /// Clips that travel: the character walks along a finger's path with
    /// them (the same shape as `[posing]`).
    #[serde(default)]
    locomotion: PosingFile,
    #[serde(default)]
    action: Vec<ActionFile>,
}

/// An action model's definition.
#[derive(Clone, Debug, PartialEq)]
pub struct ActionDef {
    pub name: String,
    /// Names of its clips (keys of [`Library::clips`]).
    pub clips: Vec<String>,
    pub primary: Role,
    pub segments: Vec<Segment>,
    /// The recogniser's cost threshold (m), where `library.toml` sets one;
    /// else the library's calibrated threshold holds.
    pub threshold_m: Option<f64>,
}

impl ActionDef {
    /// The segment in force at generalized time `t`.
    #[must_use]
    pub fn segment_at(&self, t: f64) -> &Segment {
        self.segments
            .iter()
            .find(|s| t < s.until)
            .unwrap_or_else(|| {
                self.segments
                    .last()
                    .expect("validated: at least one segment")
            })
    }
}

/// Most characters in an action's name.
pub const NAME_CHARS: usize = 64;

/// The most actions a library holds, mirror images included (each is
/// models and templates in memory, and a drag is matched against those of
/// its part).
pub const MAX_ACTIONS: usize = 200;

/// A loaded, validated library.
#[derive(Clone, Debug)]
pub struct Library {
    pub dir: PathBuf,
    /// Where the clips are (`settings.clips_dir`, else `dir`).
    pub clips_dir: PathBuf,
    pub skeleton: Skeleton,
    /// Every clip by file name.
    pub clips: BTreeMap<String, Clip>,
    /// A digest of the library's content as it was read (`library.toml`
    /// and every clip's file): equal keys, equal libraries.
    pub content_key: u64,
    pub posing: Vec<String>,
    /// Clips that travel, for walking along a finger's path (may be
    /// empty: the character then only poses and acts where it stands).
    pub locomotion: Vec<String>,
    pub actions: Vec<ActionDef>,
    /// Fraction (generalized time) of each action clip that also feeds the
    /// posing model.
    pub action_lead_in: f64,
    /// How far the clips were moved up (m) to stand on the floor
    /// ([`floor::settle`]); other takes of the same capture are moved
    /// alike.
    pub floor_shift_m: f64,
}

impl Library {
    /// The file of a clip (a clip named `take.bvh#120-185` is in
    /// `take.bvh`).
    #[must_use]
    pub fn clip_path(&self, name: &str) -> PathBuf {
        self.clips_dir
            .join(ClipRef::parse(name).map_or(name, |r| r.file))
    }

    /// Load and validate `dir/library.toml` and its clips.
    pub fn load(dir: &Path) -> Result<Self, LibraryError> {
        Self::load_as(dir, &dir.join("library.toml"))
    }

    /// Load the library of folder `dir` described by `toml_path` (a
    /// `library.toml` about to replace the folder's, checked first).
    pub fn load_as(dir: &Path, toml_path: &Path) -> Result<Self, LibraryError> {
        let mut problems = Vec::new();
        let fail = |problems: Vec<String>| LibraryError {
            dir: dir.to_owned(),
            problems,
        };
        let text = crate::reading::read_text(toml_path, MAX_TOML_BYTES)
            .map_err(|e| fail(vec![format!("cannot read {}: {e}", toml_path.display())]))?;
        let file: LibraryFile = toml::from_str(&text).map_err(|e| {
            fail(vec![format!(
                "{}: {}",
                toml_path.display(),
                crate::reading::toml_error(&text, &e)
            )])
        })?;

        let max_bytes = file
            .settings
            .max_file_mb
            .map_or(bvh::MAX_FILE_BYTES, |mb| mb.saturating_mul(1 << 20));
        let (lead_in, settings) = settings_of(&file, &mut problems);
        let clips_dir = file
            .settings
            .clips_dir
            .as_ref()
            .map_or_else(|| dir.to_owned(), |d| dir.join(d));
        if !clips_dir.is_dir() {
            problems.push(format!(
                "settings.clips_dir: {} is not a folder",
                clips_dir.display()
            ));
        }
        repeated("[posing] clips", &file.posing.clips, &mut problems);
        repeated("[locomotion] clips", &file.locomotion.clips, &mut problems);
        let names = clip_names(&file);
        if names.is_empty() {
            problems.push("no clips: list posing clips in [posing] clips and action clips in [[action]] tables".to_owned());
        }
        let (mut clips, skeleton, files) =
            read_clips(names, &clips_dir, max_bytes, &settings, &mut problems);
        let floor_shift_m = floor::settle(&mut clips);
        let mirrors = file.action.iter().filter(|a| a.mirror).count();
        if file.action.len() + mirrors > MAX_ACTIONS {
            return Err(fail(vec![format!(
                "{} actions ({} and {mirrors} mirror images): a library holds at most {MAX_ACTIONS}",
                file.action.len() + mirrors,
                file.action.len()
            )]));
        }
        let mut actions = action_defs(&file, &mut problems);
        one_frame_clips(&actions, &clips, &mut problems);
        let mirrored = mirror_actions(&actions, &file, &mut clips, &mut problems);
        actions.extend(mirrored);
        if !problems.is_empty() {
            return Err(fail(problems));
        }
        let skeleton = skeleton.map(|(_, s)| s).unwrap_or_default();
        let content_key = content_key(&text, &clips, &files);
        Ok(Self {
            dir: dir.to_owned(),
            clips_dir,
            skeleton,
            clips,
            content_key,
            posing: file.posing.clips,
            locomotion: file.locomotion.clips,
            actions,
            action_lead_in: lead_in,
            floor_shift_m,
        })
    }
}

/// Each file a library's clips are cut from, read once: its BVH and the
/// digest of its bytes (`None` where it did not read).
type Files<'a> = BTreeMap<&'a str, Option<(bvh::BvhFile, u64)>>;

/// The `[settings]` and `[roles]` of a library file checked (what is
/// wrong goes to `problems`): the actions' lead-in and how clips import.
fn settings_of(file: &LibraryFile, problems: &mut Vec<String>) -> (f64, ImportSettings) {
    let lead_in = file.settings.action_lead_in.unwrap_or(0.3);
    if !(0.0..=1.0).contains(&lead_in) {
        problems.push(format!(
            "settings.action_lead_in must be between 0 and 1, found {lead_in}"
        ));
    }
    if let Some(s) = file.settings.scale_to_m {
        if !(s.is_finite() && s > 0.0) {
            problems.push(format!(
                "settings.scale_to_m must be a positive number, found {s}"
            ));
        }
    }
    for key in file.roles.keys() {
        if Role::from_name(key).is_none() {
            problems.push(format!(
                "[roles] {} is not a role; roles are {}",
                quote(key),
                Role::ALL.map(Role::name).join(", ")
            ));
        }
    }
    let settings = ImportSettings {
        scale_to_m: file
            .settings
            .scale_to_m
            .filter(|s| s.is_finite() && *s > 0.0),
        roles: file
            .roles
            .iter()
            .filter(|(k, _)| Role::from_name(k).is_some())
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect(),
    };
    (lead_in, settings)
}

/// The largest `library.toml` read (bytes).
const MAX_TOML_BYTES: u64 = 1 << 20;

/// Every clip named anywhere in a library file, once, in name order.
/// A list that names one clip twice is a mistake (a clip listed twice
/// counts twice, and a list repeated a hundred thousand times is read as
/// many times): each repeat goes to `problems`, the first named.
fn repeated(what: &str, list: &[String], problems: &mut Vec<String>) {
    let mut seen = std::collections::BTreeSet::new();
    let repeats: Vec<&String> = list.iter().filter(|c| !seen.insert(*c)).collect();
    if let Some(first) = repeats.first() {
        problems.push(format!(
            "{what}: {} is listed {} times; list each clip once",
            quote(first),
            1 + repeats.iter().filter(|r| *r == first).count()
        ));
        if repeats.iter().any(|r| r != first) {
            problems.push(format!(
                "{what}: {} more clips are listed more than once",
                repeats
                    .iter()
                    .filter(|r| *r != first)
                    .collect::<std::collections::BTreeSet<_>>()
                    .len()
            ));
        }
    }
}

fn clip_names(file: &LibraryFile) -> Vec<&String> {
    let mut names: Vec<&String> = file
        .posing
        .clips
        .iter()
        .chain(&file.locomotion.clips)
        .collect();
    for a in &file.action {
        names.extend(a.clips.iter());
    }
    names.sort();
    names.dedup();
    names
}

/// A BVH file of at most `max_bytes`, parsed, with the digest of its
/// bytes. A clip may be a link to a take kept elsewhere (a folder of takes
/// linked from a studio's share): it is read where it leads.
fn read_bvh(path: &Path, max_bytes: u64) -> Result<(bvh::BvhFile, u64), bvh::BvhError> {
    crate::reading::read(path, max_bytes)
        .map_err(|e| match e {
            crate::reading::ReadError::TooLarge { said, .. } => std::io::Error::other(format!(
                "{} MB, over settings.max_file_mb ({} MB)",
                said.div_ceil(1 << 20),
                max_bytes >> 20
            )),
            e => e.into(),
        })
        .map_err(|source| bvh::BvhError::Io {
            path: path.to_owned(),
            source,
        })
        .and_then(|bytes| {
            let parsed = bvh::parse(&String::from_utf8_lossy(&bytes), path)?;
            Ok((parsed, Fnv::digest(&bytes)))
        })
}

/// The clips `names`, read from `clips_dir` (each file once) and imported
/// with `settings`, each on the first clip's skeleton; what is wrong goes
/// to `problems`. The clips, the first clip's name and skeleton, and the
/// files read.
fn read_clips<'a>(
    names: Vec<&'a String>,
    clips_dir: &Path,
    max_bytes: u64,
    settings: &ImportSettings,
    problems: &mut Vec<String>,
) -> (
    BTreeMap<String, Clip>,
    Option<(String, Skeleton)>,
    Files<'a>,
) {
    let mut clips = BTreeMap::new();
    let mut skeleton: Option<(String, Skeleton)> = None;
    // Each file is read once, however many clips it gives.
    // Each file's digest feeds the library's content key.
    let mut files: Files<'a> = BTreeMap::new();
    for name in names {
        let clip_ref = match ClipRef::parse(name) {
            Ok(r) => r,
            Err(why) => {
                problems.push(format!("clip {}: {why}", quote(name)));
                continue;
            }
        };
        let file = files.entry(clip_ref.file).or_insert_with(|| {
            let path = clips_dir.join(clip_ref.file);
            let read = read_bvh(&path, max_bytes);
            match read {
                Ok(p) => Some(p),
                Err(e) => {
                    problems.push(e.to_string());
                    None
                }
            }
        });
        let Some((file, _)) = file.as_ref() else {
            continue;
        };
        let parsed = match clip_ref.frames {
            None => file.clone(),
            Some((a, b)) if b < file.frames.len() => bvh::BvhFile {
                skeleton: file.skeleton.clone(),
                channels: file.channels.clone(),
                frame_time: file.frame_time,
                frames: file.frames[a..=b].to_vec(),
            },
            Some((_, b)) => {
                problems.push(format!(
                    "clip {}: frame {b} is past the end of {} ({} frames, numbered from 0)",
                    quote(name),
                    quote(clip_ref.file),
                    file.frames.len()
                ));
                continue;
            }
        };
        let mut clip = match Clip::from_bvh(parsed, settings) {
            Ok(c) => c,
            Err(e) => {
                problems.push(format!("{name}: {e}"));
                continue;
            }
        };
        // Hierarchies are compared once top bones are folded away: a
        // file with an extra `RL_BoneRoot` joins the others. Other
        // proportions (another performer) are carried onto the first
        // clip's skeleton.
        match &skeleton {
            None => skeleton = Some((name.clone(), clip.skeleton.clone())),
            Some((first, s)) => {
                if let Some(why) = hierarchy_difference(s, &clip.skeleton) {
                    problems.push(format!("{name}: its hierarchy differs from {first}'s ({why}); a library's clips share one skeleton"));
                    continue;
                }
                let ratio = clip.retarget(s);
                if ratio != 1.0 {
                    tracing::debug!(clip = %name, onto = %first, leg_ratio = ratio, "clip retargeted onto the library's skeleton");
                }
            }
        }
        clips.insert(name.clone(), clip);
    }
    (clips, skeleton, files)
}

/// The content key: library.toml's `text`, then every clip's name and
/// its file's digest, in name order.
fn content_key(text: &str, clips: &BTreeMap<String, Clip>, files: &Files<'_>) -> u64 {
    let mut key = Fnv::new();
    key.write(text.as_bytes());
    for name in clips.keys() {
        key.write(name.as_bytes());
        let digest = ClipRef::parse(name)
            .ok()
            .and_then(|r| files.get(r.file))
            .and_then(|f| f.as_ref().map(|(_, d)| *d))
            .unwrap_or(0);
        key.write(&digest.to_le_bytes());
    }
    key.finish()
}

/// Why two hierarchies differ, if they do: joint count, names, parents.
#[must_use]
pub fn hierarchy_difference(a: &Skeleton, b: &Skeleton) -> Option<String> {
    if a.len() != b.len() {
        return Some(format!("{} joints against {}", b.len(), a.len()));
    }
    for (ja, jb) in a.joints.iter().zip(&b.joints) {
        if ja.name != jb.name {
            return Some(format!(
                "joint {} where {} was expected",
                quote(&jb.name),
                quote(&ja.name)
            ));
        }
        if ja.parent != jb.parent {
            return Some(format!("joint {} has another parent", quote(&jb.name)));
        }
    }
    None
}

/// The default library under `assets/` (the project's own), for unit
/// tests.
#[cfg(test)]
pub(crate) fn default_library() -> Library {
    Library::load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/assets/library"
    )))
    .unwrap()
}
