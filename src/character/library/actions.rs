//! A library's actions as its file declares them: each checked (names,
//! clips, parts, condition segments), clips of one frame refused, and the
//! mirror images of those that ask for one.

use std::collections::BTreeMap;

use super::{ActionDef, LibraryFile, NAME_CHARS, Segment, repeated};
use crate::character::motion::Clip;
use crate::character::roles::Role;
use crate::reading::quote;

/// The actions of a library file, each checked (what is wrong goes to
/// `problems`); those whose primary part is a role.
pub(super) fn action_defs(file: &LibraryFile, problems: &mut Vec<String>) -> Vec<ActionDef> {
    let mut actions = Vec::new();
    let mut seen = BTreeMap::new();
    for (i, a) in file.action.iter().enumerate() {
        let label = if a.name.is_empty() {
            format!("action #{}", i + 1)
        } else {
            format!("action {}", quote(&a.name))
        };
        if a.name.is_empty() {
            problems.push(format!("{label}: needs a name"));
        }
        if a.name.chars().count() > NAME_CHARS || a.name.chars().any(char::is_control) {
            problems.push(format!(
                "{label}: a name is shown on the screen and in the journal: at most {NAME_CHARS} characters, none of them a control character"
            ));
        }
        repeated(&format!("{label} clips"), &a.clips, problems);
        if seen.insert(a.name.clone(), i).is_some() {
            problems.push(format!("{label}: the name is used twice"));
        }
        if a.clips.is_empty() {
            problems.push(format!("{label}: needs at least one clip"));
        }
        let primary = Role::from_name(&a.primary);
        if primary.is_none() {
            problems.push(format!(
                "{label}: primary {} is not a role; roles are {}",
                quote(&a.primary),
                Role::ALL.map(Role::name).join(", ")
            ));
        }
        problems.extend(
            check_segments(&a.segments)
                .into_iter()
                .map(|p| format!("{label}: {p}")),
        );
        if let Some(t) = a.threshold_m.filter(|t| !(*t > 0.0 && *t <= 1.0)) {
            problems.push(format!("{label}: threshold_m = {t} is not a cost in metres: give one above 0 and at most 1 (0.05 to 0.2 is usual), or leave it out to use the calibrated one"));
        }
        if let Some(primary) = primary {
            actions.push(ActionDef {
                name: a.name.clone(),
                clips: a.clips.clone(),
                primary,
                segments: a.segments.clone(),
                threshold_m: a.threshold_m,
            });
        }
    }
    actions
}

/// An action is a motion: a clip of one frame has none to learn, and is
/// refused (said in `problems`).
pub(super) fn one_frame_clips(
    actions: &[ActionDef],
    clips: &BTreeMap<String, Clip>,
    problems: &mut Vec<String>,
) {
    for a in actions {
        for c in &a.clips {
            if clips.get(c).is_some_and(|clip| clip.frames.len() < 2) {
                problems.push(format!(
                    "action {}: clip {} has one frame; an action's clips show the motion, two frames at least",
                    quote(&a.name),
                    quote(c)
                ));
            }
        }
    }
}

/// The mirror images of the `actions` whose entry in `file` asks for
/// one: the same action with the other side's part, its clips mirrored
/// into `clips`.
pub(super) fn mirror_actions(
    actions: &[ActionDef],
    file: &LibraryFile,
    clips: &mut BTreeMap<String, Clip>,
    problems: &mut Vec<String>,
) -> Vec<ActionDef> {
    let mut mirrored = Vec::new();
    for (a, file_a) in actions.iter().zip(
        file.action
            .iter()
            .filter(|f| Role::from_name(&f.primary).is_some()),
    ) {
        if !file_a.mirror {
            continue;
        }
        let label = format!("action {}", quote(&a.name));
        let primary = a.primary.mirrored();
        if primary == a.primary {
            problems.push(format!("{label}: mirror = true, but its primary `{}` is on the middle line: its mirror image is the same action", a.primary.name()));
            continue;
        }
        let name = mirrored_name(&a.name);
        if file.action.iter().any(|f| f.name == name) {
            problems.push(format!(
                "{label}: mirror = true would add {}, which the library has already; drop one",
                quote(&name)
            ));
            continue;
        }
        let mut names = Vec::new();
        for c in &a.clips {
            let Some(clip) = clips.get(c) else { continue };
            match clip.mirrored() {
                Ok(m) => {
                    let n = format!("{c}~mirror");
                    clips.insert(n.clone(), m);
                    names.push(n);
                }
                Err(e) => problems.push(format!(
                    "{label}: mirror = true, but {c} has no mirror image: {e}"
                )),
            }
        }
        mirrored.push(ActionDef {
            name,
            clips: names,
            primary,
            segments: a.segments.clone(),
            threshold_m: a.threshold_m,
        });
    }
    mirrored
}

/// The name of an action's mirror image: left and right swapped in its
/// name, or `_mirror` added.
#[must_use]
pub fn mirrored_name(name: &str) -> String {
    // Words between `_` and `-`, the separators kept.
    let mut swapped = String::new();
    for piece in name.split_inclusive(['_', '-']) {
        let (word, sep) = piece
            .strip_suffix(['_', '-'])
            .map_or((piece, ""), |w| (w, &piece[w.len()..]));
        swapped.push_str(match word {
            "left" => "right",
            "right" => "left",
            "l" => "r",
            "r" => "l",
            w => w,
        });
        swapped.push_str(sep);
    }
    if swapped == name {
        format!("{name}_mirror")
    } else {
        swapped
    }
}

fn check_segments(segments: &[Segment]) -> Vec<String> {
    let mut p = Vec::new();
    if segments.is_empty() {
        p.push("needs condition segments (`segments = [{ until = 1.0, still = true, release = \"forward\" }]` at least)".to_owned());
        return p;
    }
    let mut prev = 0.0;
    for (i, s) in segments.iter().enumerate() {
        if !(s.until > prev && s.until <= 1.0) {
            p.push(format!(
                "segment {} ends at {}, which must be after {prev} and at most 1",
                i + 1,
                s.until
            ));
        }
        prev = s.until;
    }
    if (prev - 1.0).abs() > 1e-9 {
        p.push(format!(
            "the last segment must end at 1 (generalized time), not {prev}"
        ));
    }
    p
}
