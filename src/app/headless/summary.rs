//! What a headless run did: the summary printed and written to
//! `summary.json`.

use std::path::PathBuf;

use serde::Serialize;

use crate::control::action::timeline::ActionEvent;

/// An action as it happened.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ActionRecord {
    pub action: String,
    pub started_s: f64,
    /// `finished`, `cancelled`, or `playing` at the end of the replay.
    pub outcome: String,
    pub ended_s: Option<f64>,
}

/// A drag that started nothing: the action it came nearest to starting,
/// when, and the threshold that held it back (`cost` or `margin`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct NearMissRecord {
    pub action: String,
    pub time_s: f64,
    pub held_by: String,
}

/// What a run did.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Summary {
    pub duration_s: f64,
    pub touch_frames: usize,
    pub steps: usize,
    pub frames_written: usize,
    pub actions: Vec<ActionRecord>,
    /// Drags that started nothing, with the action each came nearest to.
    pub near_misses: Vec<NearMissRecord>,
    /// Fingers that went down on a body part.
    pub grabs: usize,
    /// What `--visits` recorded, and the rows written.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub visits: Option<(
        crate::app::visits::record::Counts,
        crate::app::visits::writer::Written,
    )>,
    /// Body parts fingers held.
    pub parts_held: Vec<String>,
    /// Most parts held at once.
    pub most_held_at_once: usize,
    /// Whether fingers on empty space moved the camera.
    pub camera_moved: bool,
    /// Render plus readback, per written frame (ms; 0 without rendering).
    pub frame_ms_mean: f64,
    pub frame_ms_max: f64,
    /// FNV-1a digest of every posture stepped: equal digests, equal runs.
    pub pose_digest: String,
    pub sheet: Option<PathBuf>,
    /// Where the frames, sheet and summary are.
    pub out: Option<PathBuf>,
    /// Every stepped posture, with [`Options::keep_poses`].
    #[serde(skip)]
    pub poses: Vec<crate::character::skeleton::Pose>,
    /// Motion quality, with [`Options::measure`].
    #[serde(skip)]
    pub metrics: Option<crate::tools::metrics::Metrics>,
    /// Each character of a table of several: its actions and hits.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub characters: Vec<CharacterSummary>,
}

/// One character of a table of several, in [`Summary::characters`].
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct CharacterSummary {
    /// Its library folder.
    pub library: String,
    pub actions: Vec<ActionRecord>,
    /// Hits it landed on another character or took from one.
    pub hits: Vec<HitRecord>,
    pub hits_landed: usize,
    pub hits_taken: usize,
    pub parts_held: Vec<String>,
}

/// A hit as it happened, from one character's side.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HitRecord {
    pub time_s: f64,
    /// `landed` or `taken`.
    pub role: String,
    /// The other character's index.
    pub other: usize,
    /// Its own segment and the other's (joint names).
    pub part: String,
    pub other_part: String,
    pub impulse_ns: f64,
    pub speed_m_s: f64,
}

impl Summary {
    /// A hit on the table, recorded for both characters.
    pub(super) fn hit(&mut self, h: &crate::control::stage::Hit) {
        for (k, role, other, part, other_part) in [
            (
                h.striker,
                "landed",
                h.struck,
                &h.striker_part,
                &h.struck_part,
            ),
            (
                h.struck,
                "taken",
                h.striker,
                &h.struck_part,
                &h.striker_part,
            ),
        ] {
            if let Some(c) = self.characters.get_mut(k) {
                c.hits.push(HitRecord {
                    time_s: h.time_s,
                    role: role.to_owned(),
                    other,
                    part: part.clone(),
                    other_part: other_part.clone(),
                    impulse_ns: h.impulse_ns,
                    speed_m_s: h.speed_m_s,
                });
            }
        }
    }

    /// Action event `e` of character `k`, recorded: an action started, or
    /// the one of that name playing ended.
    pub(super) fn event(&mut self, k: usize, e: ActionEvent) {
        let records = if self.characters.is_empty() {
            &mut self.actions
        } else {
            match self.characters.get_mut(k) {
                Some(c) => &mut c.actions,
                None => return,
            }
        };
        match e {
            ActionEvent::NearMiss {
                action,
                time_s,
                held_by,
                ..
            } => self.near_misses.push(NearMissRecord {
                action,
                time_s,
                held_by: held_by.to_owned(),
            }),
            ActionEvent::Started { action, time_s, .. } => records.push(ActionRecord {
                action,
                started_s: time_s,
                outcome: "playing".into(),
                ended_s: None,
            }),
            ActionEvent::Finished {
                ref action, time_s, ..
            }
            | ActionEvent::Cancelled {
                ref action, time_s, ..
            } => {
                // The action of that name still playing (a walk and an
                // action laid over it end apart).
                let open = records
                    .iter_mut()
                    .rev()
                    .find(|r| r.ended_s.is_none() && r.action == *action);
                if let Some(r) = open {
                    r.outcome = if matches!(e, ActionEvent::Finished { .. }) {
                        "finished".into()
                    } else {
                        "cancelled".into()
                    };
                    r.ended_s = Some(time_s);
                }
            }
            _ => {}
        }
    }
}

impl std::fmt::Display for Summary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "replayed {:.1} s: {} touch frames, {} controller steps",
            self.duration_s, self.touch_frames, self.steps
        )?;
        writeln!(
            f,
            "posing: parts held {} (at most {} at once); camera moved: {}",
            if self.parts_held.is_empty() {
                "none".to_owned()
            } else {
                self.parts_held.join(", ")
            },
            self.most_held_at_once,
            if self.camera_moved { "yes" } else { "no" }
        )?;
        writeln!(
            f,
            "grabs: {}; drags that started nothing: {}",
            self.grabs,
            self.near_misses.len()
        )?;
        writeln!(f, "actions started by drags: {}", self.actions.len())?;
        for a in &self.actions {
            writeln!(
                f,
                "  {:6.2} s  {:<12} {}{}",
                a.started_s,
                a.action,
                a.outcome,
                a.ended_s
                    .map(|e| format!(" at {e:.2} s"))
                    .unwrap_or_default()
            )?;
        }
        if self.frames_written > 0 {
            writeln!(
                f,
                "frames: {} written, render + readback {:.1} ms mean, {:.1} ms max",
                self.frames_written, self.frame_ms_mean, self.frame_ms_max
            )?;
        }
        if let Some(s) = &self.sheet {
            writeln!(f, "contact sheet: {}", s.display())?;
        }
        if let Some(o) = &self.out {
            writeln!(f, "frames and summary.json in {}", o.display())?;
        }
        write!(f, "pose digest: {}", self.pose_digest)
    }
}
