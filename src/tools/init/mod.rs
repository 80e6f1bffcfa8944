//! `marionette library init`: a motion library from a folder of takes as
//! an exhibit builder has them. Files named `<action>_<anything>.bvh` give
//! action `<action>` (the text before the first `_`), `pose_*.bvh` are
//! posing only, and every clip also feeds posing. What the motion says is
//! measured, not assumed: the units and roles of the rig, each action's
//! primary part (the one that moves most), long takes of a repeated action
//! cut into single actions at the primary part's pauses, and the condition
//! segments from the primary part's speed. The result is a commented
//! `library.toml` that references the clips where they are.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use glam::DVec3;

use crate::character::bvh;
use crate::character::library::{Release, Segment, hierarchy_difference};
use crate::character::motion::{Clip, ImportSettings, KNOWN_UNITS};
use crate::character::roles::Role;
use crate::control::locomotion::gait::{MIN_TRAVEL_M, travel_m};

mod motion;

pub use self::motion::{PartMotion, bursts, cuts, part_motion};
use self::motion::{active_span, median};

/// The parts an action can be led by, in the order ties are broken.
const CANDIDATES: [Role; 6] = [
    Role::RightHand,
    Role::LeftHand,
    Role::RightFoot,
    Role::LeftFoot,
    Role::Head,
    Role::Pelvis,
];

/// A second part moving at least this share of the primary's range is
/// named beside it.
const ALSO_MOVES: f64 = 0.8;

/// Errors that stop `library init`.
#[derive(Debug, thiserror::Error)]
pub enum InitError {
    #[error("cannot list {path}: {source}")]
    List {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: no BVH files (named <action>_<anything>.bvh or pose_<anything>.bvh)")]
    NoFiles { path: PathBuf },
    #[error("{path}: no file could be used:\n  {}", reasons.join("\n  "))]
    NothingUsable { path: PathBuf, reasons: Vec<String> },
}

/// One file of the source folder, imported.
struct Take {
    file: String,
    clip: Clip,
    /// Frames of the file before the clip's first (a converter's T-pose).
    skipped: usize,
}

/// An action as `init` decided it.
#[derive(Clone, Debug, PartialEq)]
pub struct PlannedAction {
    pub name: String,
    pub primary: Role,
    /// Every candidate part's range summed over the clips (m), largest
    /// first.
    pub ranges: Vec<(Role, f64)>,
    /// Clip names: files, or `file#first-last` pieces of a long take.
    pub clips: Vec<String>,
    pub segments: Vec<Segment>,
    /// Whether its mirror image is offered (`mirror = true`).
    pub mirror: bool,
    /// What was decided and why, a line each.
    pub notes: Vec<String>,
}

/// What `library init` decided.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    pub src: PathBuf,
    /// The files, every one feeding posing.
    pub posing: Vec<String>,
    pub actions: Vec<PlannedAction>,
    /// Role → joint name, as found.
    pub roles: BTreeMap<String, String>,
    /// Units, as found.
    pub unit: String,
    /// Files left out, with the reason.
    pub skipped: Vec<(String, String)>,
    /// Takes named after an action that feed posing only, with the reason
    /// (one frame, or a body that hardly moves: no drag could start it).
    pub not_actions: Vec<(String, String)>,
    /// Takes whose pelvis travels, with how far it comes from where it
    /// starts (m): locomotion, for walking where a finger leads.
    pub locomotion: Vec<(String, f64)>,
}

/// A take whose every part stays within this (m) shows no action.
const MIN_ACTION_RANGE_M: f64 = 0.1;

/// A piece cut from a take whose part moves less than this share of the
/// take's largest piece (or under [`MIN_ACTION_RANGE_M`]) is no action.
const MIN_PIECE_SHARE: f64 = 0.35;

/// The diagonal of the box `path` fills (m).
fn box_diagonal(path: &[DVec3]) -> f64 {
    let (lo, hi) = path.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    if path.is_empty() {
        0.0
    } else {
        (hi - lo).length()
    }
}

/// Why `take` cannot be an action, if it cannot.
fn no_action(take: &Take) -> Option<String> {
    if take.clip.frames.len() < 2 {
        return Some("one frame: an action moves".to_owned());
    }
    let most = part_motion(&take.clip)
        .iter()
        .map(|m| m.range_m)
        .fold(0.0, f64::max);
    (most.is_nan() || most < MIN_ACTION_RANGE_M).then(|| {
        format!(
            "no part moves more than {most:.3} m: an action moves (at least {MIN_ACTION_RANGE_M} m); it feeds posing only"
        )
    })
}

/// Read the takes in `src` and decide the library.
pub fn plan(src: &Path) -> Result<Plan, InitError> {
    let files = bvh::files_in(src).map_err(|source| InitError::List {
        path: src.to_owned(),
        source,
    })?;
    if files.is_empty() {
        return Err(InitError::NoFiles {
            path: src.to_owned(),
        });
    }
    let (takes, skipped) = read_takes(&files);
    let Some(first) = takes.first() else {
        return Err(InitError::NothingUsable {
            path: src.to_owned(),
            reasons: skipped.iter().map(|(f, w)| format!("{f}: {w}")).collect(),
        });
    };
    let unit = KNOWN_UNITS
        .iter()
        .find(|(s, _)| (s - first.clip.scale_to_m).abs() < 1e-12)
        .map_or_else(
            || format!("{} m per unit", first.clip.scale_to_m),
            |(_, name)| (*name).to_owned(),
        );
    let roles = first.clip.roles.names(&first.clip.skeleton);
    let (by_action, not_actions) = by_action(&takes);
    let mut actions: Vec<PlannedAction> = by_action
        .into_iter()
        .map(|(name, takes)| plan_action(name, &takes))
        .collect();
    // An action led by one side's part is offered with the other side's
    // too, unless the folder has that action already.
    let names: Vec<String> = actions.iter().map(|a| a.name.clone()).collect();
    for a in &mut actions {
        offer_mirror(a, &names);
    }
    let locomotion = takes
        .iter()
        .filter_map(|t| {
            let m = travel_m(&t.clip);
            (m >= MIN_TRAVEL_M).then(|| (t.file.clone(), m))
        })
        .collect();
    Ok(Plan {
        src: src.to_owned(),
        locomotion,
        posing: takes.iter().map(|t| t.file.clone()).collect(),
        actions,
        roles,
        unit,
        skipped,
        not_actions,
    })
}

/// A file left out, and why.
type Skipped = (String, String);

/// The takes read from `files`, each on the first one's skeleton, and the
/// files skipped with why.
fn read_takes(files: &[PathBuf]) -> (Vec<Take>, Vec<Skipped>) {
    let mut takes: Vec<Take> = Vec::new();
    let mut skipped = Vec::new();
    for path in files {
        let file = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let read = bvh::read_file(path)
            .map_err(|e| e.to_string())
            .and_then(|f| {
                let n = f.frames.len();
                Clip::from_bvh(f, &ImportSettings::default())
                    .map(|c| (n, c))
                    .map_err(|e| format!("{}: {e}", path.display()))
            });
        let (n, clip) = match read {
            Ok(r) => r,
            Err(why) => {
                skipped.push((file, why));
                continue;
            }
        };
        if let Some(first) = takes.first() {
            if let Some(why) = hierarchy_difference(&first.clip.skeleton, &clip.skeleton) {
                skipped.push((
                    file,
                    format!("another skeleton than {}'s ({why})", first.file),
                ));
                continue;
            }
        }
        takes.push(Take {
            file,
            skipped: n - clip.frames.len(),
            clip,
        });
    }
    (takes, skipped)
}

/// The takes of each action (by the file's name, `ACTION_...`; `pose_...`
/// takes are none), and those named as actions that show no action, with
/// why.
fn by_action(takes: &[Take]) -> (BTreeMap<String, Vec<&Take>>, Vec<Skipped>) {
    let mut by_action: BTreeMap<String, Vec<&Take>> = BTreeMap::new();
    let mut not_actions = Vec::new();
    for t in takes {
        let stem = t.file.rsplit_once('.').map_or(t.file.as_str(), |(s, _)| s);
        match stem.split_once('_') {
            Some(("pose", _)) => {}
            Some((action, _)) if !action.is_empty() => {
                if let Some(why) = no_action(t) {
                    not_actions.push((t.file.clone(), why));
                    continue;
                }
                by_action.entry(action.to_owned()).or_default().push(t);
            }
            _ => {}
        }
    }
    (by_action, not_actions)
}

/// Offer an action led by one side's part with the other side's too
/// (`mirror = true`), unless the takes have that action already or both
/// sides move alike; the notes say which.
fn offer_mirror(a: &mut PlannedAction, names: &[String]) {
    if a.primary.mirrored() == a.primary {
        return;
    }
    // A name that says no side gets its takes' side, so that the
    // mirror image's name says the other (`punch` taught with the left
    // hand: `punch_left` and `punch_right`).
    let sided = if crate::character::library::mirrored_name(&a.name).ends_with("_mirror") {
        let side = a.primary.name().split('_').next().unwrap_or_default();
        format!("{}_{side}", a.name)
    } else {
        a.name.clone()
    };
    let other = crate::character::library::mirrored_name(&sided);
    if names.contains(&other) {
        a.notes
            .push(format!("no mirror image: the takes have `{other}` already"));
        return;
    }
    // Both sides move alike (bye-bye with both hands): the action is
    // its own mirror image, and a mirrored copy would only compete
    // with it.
    let (best, other_side) = (
        a.ranges[0].1,
        a.ranges
            .iter()
            .find(|(r, _)| *r == a.primary.mirrored())
            .map_or(0.0, |(_, m)| *m),
    );
    if other_side >= ALSO_MOVES * best {
        a.notes.push(format!(
            "no mirror image: the {} moves as much as the {} ({:.0}%), so the action is its own mirror image",
            a.primary.mirrored().name(),
            a.primary.name(),
            100.0 * other_side / best
        ));
        return;
    }
    if sided != a.name {
        a.notes.push(format!(
            "named `{sided}` after the side of its takes ({}), its mirror image `{other}`",
            a.primary.name()
        ));
        a.name = sided;
    }
    a.mirror = true;
    a.notes.push(format!(
        "mirror = true: also `{other}`, led by the {}, from these clips mirrored",
        a.primary.mirrored().name()
    ));
}

fn plan_action(name: String, takes: &[&Take]) -> PlannedAction {
    let motions: Vec<Vec<PartMotion>> = takes.iter().map(|t| part_motion(&t.clip)).collect();
    let mut ranges: Vec<(Role, f64)> = CANDIDATES
        .iter()
        .enumerate()
        .map(|(i, r)| (*r, motions.iter().map(|m| m[i].range_m).sum::<f64>()))
        .collect();
    // Largest first; ties keep the candidates' order.
    ranges.sort_by(|a, b| b.1.total_cmp(&a.1));
    let (primary, best) = ranges[0];
    let index = CANDIDATES.iter().position(|r| *r == primary).unwrap_or(0);
    let mut notes = vec![format!(
        "primary {}: it moves most ({:.2} m over {} clip{}; then {})",
        primary.name(),
        best / takes.len() as f64,
        takes.len(),
        if takes.len() == 1 {
            ""
        } else {
            "s, on average"
        },
        ranges[1..]
            .iter()
            .map(|(r, m)| format!("{} {:.2}", r.name(), m / takes.len() as f64))
            .collect::<Vec<_>>()
            .join(", ")
    )];
    if let Some((other, m)) = ranges[1..].iter().find(|(_, m)| *m >= ALSO_MOVES * best) {
        notes.push(format!(
            "{} moves about as much ({:.0}% of {}): the action may need both; the primary is one part",
            other.name(),
            100.0 * m / best,
            primary.name()
        ));
    }
    let mut clips = Vec::new();
    let mut starts = Vec::new();
    let mut ends = Vec::new();
    for (take, motion) in takes.iter().zip(&motions) {
        for (a, b) in pieces(take, &motion[index], primary, &mut clips, &mut notes) {
            starts.push(a);
            ends.push(b);
        }
    }
    let segments = segments(median(&mut starts), median(&mut ends));
    notes.push(format!(
        "segments: still and cancelled until {:.2} (the {} starts moving), then moving to {:.2}, then still",
        segments.first().map_or(0.0, |s| s.until),
        primary.name(),
        segments.get(1).map_or(1.0, |s| s.until)
    ));
    PlannedAction {
        name,
        primary,
        ranges,
        clips,
        segments,
        mirror: false,
        notes,
    }
}

/// One take of an action cut into its movements of `part` (the primary's
/// motion): the clips named into `clips` (a piece in which the part
/// hardly moves feeds posing only, said in `notes`), and each kept
/// piece's active span as shares of its length.
fn pieces(
    take: &Take,
    part: &PartMotion,
    primary: Role,
    clips: &mut Vec<String>,
    notes: &mut Vec<String>,
) -> Vec<(f64, f64)> {
    let speed = &part.speed;
    let found = bursts(speed, take.clip.frame_time);
    let cut_at = cuts(part, &found);
    let mut edges = vec![0];
    edges.extend(&cut_at);
    edges.push(speed.len() - 1);
    // A piece in which the part hardly moves (a hand brought to the
    // chest before a bow) is no action of its own: posing only.
    let ranges: Vec<f64> = edges
        .windows(2)
        .map(|w| box_diagonal(&part.path[w[0]..=w[1]]))
        .collect();
    let largest = ranges.iter().copied().fold(0.0, f64::max);
    let kept: Vec<bool> = ranges
        .iter()
        .map(|r| *r >= largest || *r >= (MIN_PIECE_SHARE * largest).max(MIN_ACTION_RANGE_M))
        .collect();
    if cut_at.is_empty() {
        clips.push(take.file.clone());
    } else {
        notes.push(format!(
            "{}: {} movements of the {}, cut where it is back and slowest between them (frames {})",
            take.file,
            cut_at.len() + 1,
            primary.name(),
            cut_at
                .iter()
                .map(|c| (c + take.skipped).to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ));
        for ((w, range), keep) in edges.windows(2).zip(&ranges).zip(&kept) {
            let name = format!(
                "{}#{}-{}",
                take.file,
                w[0] + take.skipped,
                w[1] + take.skipped
            );
            if *keep {
                clips.push(name);
            } else {
                notes.push(format!(
                    "{name}: the {} moves {range:.2} m in it ({:.0}% of the take's largest movement): no action of its own, it feeds posing only",
                    primary.name(),
                    100.0 * range / largest.max(1e-9)
                ));
            }
        }
    }
    let mut spans = Vec::new();
    for (w, _) in edges.windows(2).zip(&kept).filter(|(_, k)| **k) {
        let piece = &speed[w[0]..=w[1]];
        if let Some((a, b)) = active_span(piece) {
            let last = (piece.len() - 1).max(1) as f64;
            spans.push((a as f64 / last, b as f64 / last));
        }
    }
    spans
}

/// Condition segments from when the primary part starts and stops moving
/// (generalized time): still and cancelled while it prepares, moving and
/// finished once it goes, still and finished as it recovers.
fn segments(start: Option<f64>, end: Option<f64>) -> Vec<Segment> {
    let round = |t: f64| (t * 100.0).round() / 100.0;
    let start = round(start.unwrap_or(0.3).clamp(0.05, 0.6));
    let end = round(end.unwrap_or(0.7).clamp(start + 0.1, 0.95));
    vec![
        Segment {
            until: start,
            still: true,
            release: Release::Backward,
        },
        Segment {
            until: end,
            still: false,
            release: Release::Forward,
        },
        Segment {
            until: 1.0,
            still: true,
            release: Release::Forward,
        },
    ]
}

mod write;

#[cfg(test)]
mod tests;
