//! Scores: the editable source of the default library's clips.
//!
//! A score is a TOML file of keyframes per body part with timing and easing:
//!
//! ```toml
//! kind = "action"              # or "posing", or "locomotion" (clips that travel)
//! action = "punch_right"       # action model name (actions only)
//! primary = "right_hand"       # the body part a finger drags to start it
//! segments = [{ until = 0.3, still = true, release = "backward" }, { until = 1.0, still = false, release = "forward" }]
//! duration = 1.2               # seconds
//!
//! [[variant]]                  # one BVH file each
//! file = "punch_right_a"
//! [[variant]]
//! file = "punch_right_slow"
//! speed = 0.8                  # slower (time ÷ 0.8)
//! reach = 1.1                  # 10 % more movement away from the first key
//! lift = 0.05                  # hands 5 cm higher
//! mirror = true                # left and right swapped
//!
//! [[key]]
//! t = 0.0
//! right_hand = [-0.2, 1.3, 0.1]
//! [[key]]
//! t = 0.3
//! ease = "inout"               # how the channels set here arrive here
//! right_hand = [-0.2, 1.4, 0.6]
//! ```
//!
//! Channels (any subset per key; each channel is interpolated between the
//! keys that set it, and holds before its first and after its last key):
//!
//! | channel | values | meaning |
//! |---|---|---|
//! | `pelvis` | x, y, z (m) | hip centre; standing is y = 0.93 |
//! | `pelvis_rot` | pitch, yaw, roll (°) | forward tilt, turn left, lean left |
//! | `spine` | pitch, yaw, roll (°) | chest relative to pelvis (bend, twist, side bend) |
//! | `head` | pitch, yaw, roll (°) | head relative to chest (nod, look left, tilt) |
//! | `left_hand`, `right_hand` | x, y, z (m) | wrist, relative to the pelvis's place on the floor and its facing |
//! | `left_foot`, `right_foot` | x, y, z (m) | ankle of the flat foot, on the floor (y = 0.08 stands) |
//! | `left_foot_rot`, `right_foot_rot` | pitch, yaw (°) | toes down (heel up, pivoting on the toes), toes turned left |
//! | `left_elbow_out`, `right_elbow_out` | 0..1 | elbow points down and back (0) or out sideways (1) |
//!
//! The character stands at the origin facing +Z, its left on +X; feet are
//! where they are on the floor (a foot keyed twice in one place is planted),
//! hands move with the body. Easing:
//! `smooth` (default: a monotone cubic through the keys that never
//! overshoots, so a foot keyed twice in one place stays there), `inout`
//! (comes to rest at the key), `linear`, `step` (jumps at the key).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;
use thiserror::Error;

use crate::character::library::Segment;

/// Errors in a score.
#[derive(Debug, Error)]
pub enum ScoreError {
    #[error("cannot read {path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    Invalid { path: PathBuf, message: String },
}

/// Interpolation into a key.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Ease {
    #[default]
    Smooth,
    Inout,
    Linear,
    Step,
}

#[derive(Debug, Deserialize)]
struct KeyFile {
    t: f64,
    #[serde(default)]
    ease: Ease,
    #[serde(flatten)]
    channels: BTreeMap<String, Vec<f64>>,
}

/// A variant of a score: one output clip.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Variant {
    /// Output file name, without `.bvh`.
    pub file: String,
    #[serde(default = "one")]
    pub speed: f64,
    #[serde(default = "one")]
    pub reach: f64,
    #[serde(default)]
    pub lift: f64,
    #[serde(default)]
    pub mirror: bool,
    /// This variant belongs to another action (a mirrored punch is
    /// `punch_left`); defaults to the score's.
    #[serde(default)]
    pub action: Option<String>,
    /// The other action's primary body part.
    #[serde(default)]
    pub primary: Option<String>,
}

fn one() -> f64 {
    1.0
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ScoreFile {
    kind: String,
    #[serde(default)]
    action: Option<String>,
    #[serde(default)]
    primary: Option<String>,
    #[serde(default)]
    segments: Vec<Segment>,
    duration: f64,
    variant: Vec<Variant>,
    key: Vec<KeyFile>,
}

/// The channels and their number of values.
pub const CHANNELS: [(&str, usize); 12] = [
    ("pelvis", 3),
    ("pelvis_rot", 3),
    ("spine", 3),
    ("head", 3),
    ("left_hand", 3),
    ("right_hand", 3),
    ("left_foot", 3),
    ("right_foot", 3),
    ("left_foot_rot", 2),
    ("right_foot_rot", 2),
    ("left_elbow_out", 1),
    ("right_elbow_out", 1),
];

/// One key of one channel.
#[derive(Clone, Debug, PartialEq)]
pub struct ChannelKey {
    pub t: f64,
    pub ease: Ease,
    pub value: Vec<f64>,
}

/// What a score makes.
#[derive(Clone, Debug, PartialEq)]
pub enum Kind {
    Posing,
    /// Walking where a finger leads: `[locomotion]` in `library.toml`.
    Locomotion,
    Action {
        name: String,
        primary: String,
        segments: Vec<Segment>,
    },
}

/// A parsed, validated score.
#[derive(Clone, Debug, PartialEq)]
pub struct Score {
    pub name: String,
    pub kind: Kind,
    pub duration: f64,
    pub variants: Vec<Variant>,
    /// Keys per channel, in time order.
    pub channels: BTreeMap<String, Vec<ChannelKey>>,
}

/// The largest score file read (bytes).
const MAX_SCORE_BYTES: u64 = 1 << 20;

impl Score {
    /// Read and validate a score file.
    pub fn load(path: &Path) -> Result<Self, ScoreError> {
        let text =
            crate::reading::read_text(path, MAX_SCORE_BYTES).map_err(|e| ScoreError::Io {
                path: path.to_owned(),
                source: e.into(),
            })?;
        let invalid = |message: String| ScoreError::Invalid {
            path: path.to_owned(),
            message,
        };
        let file: ScoreFile =
            toml::from_str(&text).map_err(|e| invalid(crate::reading::toml_error(&text, &e)))?;
        let kind = file.kind().map_err(invalid)?;
        file.check().map_err(invalid)?;
        let channels = file.channels().map_err(invalid)?;
        Ok(Self {
            name: path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
            kind,
            duration: file.duration,
            variants: file.variant,
            channels,
        })
    }
}

impl ScoreFile {
    /// What the score makes, from `kind` and what that kind needs.
    fn kind(&self) -> Result<Kind, String> {
        let file = self;
        Ok(match file.kind.as_str() {
            "posing" => Kind::Posing,
            "locomotion" => Kind::Locomotion,
            "action" => Kind::Action {
                name: file
                    .action
                    .clone()
                    .ok_or_else(|| "an action score needs `action = \"name\"`".to_owned())?,
                primary: file.primary.clone().ok_or_else(|| {
                    "an action score needs `primary = \"right_hand\"` (a role)".to_owned()
                })?,
                segments: file.segments.clone(),
            },
            other => {
                return Err(format!(
                    "kind must be \"posing\", \"locomotion\" or \"action\", found \"{other}\""
                ));
            }
        })
    }

    /// The duration and each variant within bounds.
    fn check(&self) -> Result<(), String> {
        let file = self;
        if !(file.duration > 0.0 && file.duration <= 60.0) {
            return Err(format!(
                "duration must be above 0 and at most 60 s, found {}",
                file.duration
            ));
        }
        if file.variant.is_empty() {
            return Err("needs at least one [[variant]] (its `file` names the output)".into());
        }
        for v in &file.variant {
            let sane = v.speed > 0.1
                && v.speed < 10.0
                && v.reach > 0.0
                && v.reach < 5.0
                && v.lift.is_finite();
            if !sane {
                return Err(format!(
                    "variant {}: speed must be in 0.1..10, reach in 0..5, lift finite",
                    v.file
                ));
            }
            if v.file.is_empty()
                || !v
                    .file
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
            {
                return Err(format!(
                    "variant file name {} must be letters, digits, _ and -",
                    crate::reading::quote(&v.file)
                ));
            }
        }
        Ok(())
    }

    /// Each channel's keys, checked: in time order within the duration,
    /// known channels of the right number of finite values.
    fn channels(&self) -> Result<BTreeMap<String, Vec<ChannelKey>>, String> {
        let file = self;
        let mut channels: BTreeMap<String, Vec<ChannelKey>> = BTreeMap::new();
        let mut last_t = -1.0;
        for (i, k) in file.key.iter().enumerate() {
            if !(k.t >= 0.0 && k.t <= file.duration) {
                return Err(format!(
                    "key {} (t = {}): times run from 0 to the duration {}",
                    i + 1,
                    k.t,
                    file.duration
                ));
            }
            if k.t <= last_t {
                return Err(format!(
                    "key {} (t = {}): keys must be in increasing time",
                    i + 1,
                    k.t
                ));
            }
            last_t = k.t;
            for (name, value) in &k.channels {
                let Some((_, arity)) = CHANNELS.iter().find(|(n, _)| n == name) else {
                    return Err(format!(
                        "key {} (t = {}): unknown channel {}; channels are {}",
                        i + 1,
                        k.t,
                        crate::reading::quote(name),
                        CHANNELS
                            .iter()
                            .map(|(n, _)| *n)
                            .collect::<Vec<_>>()
                            .join(", ")
                    ));
                };
                if value.len() != *arity || value.iter().any(|v| !v.is_finite()) {
                    return Err(format!(
                        "key {} (t = {}): {} takes {arity} finite numbers, found {value:?}",
                        i + 1,
                        k.t,
                        crate::reading::quote(name)
                    ));
                }
                channels.entry(name.clone()).or_default().push(ChannelKey {
                    t: k.t,
                    ease: k.ease,
                    value: value.clone(),
                });
            }
        }
        Ok(channels)
    }
}

/// The value of a channel's keys at time `t`.
#[must_use]
pub fn sample(keys: &[ChannelKey], t: f64) -> Vec<f64> {
    let n = keys.len();
    if n == 0 {
        return Vec::new();
    }
    if t <= keys[0].t || n == 1 {
        return keys[0].value.clone();
    }
    if t >= keys[n - 1].t {
        return keys[n - 1].value.clone();
    }
    let i = keys.windows(2).position(|w| t < w[1].t).unwrap_or(n - 2);
    let (k0, k1) = (&keys[i], &keys[i + 1]);
    let h = k1.t - k0.t;
    let s = (t - k0.t) / h;
    (0..k0.value.len())
        .map(|c| {
            let (v0, v1) = (k0.value[c], k1.value[c]);
            match k1.ease {
                Ease::Step => v0,
                Ease::Linear => v0 + (v1 - v0) * s,
                Ease::Inout => v0 + (v1 - v0) * s * s * (3.0 - 2.0 * s),
                Ease::Smooth => {
                    let (m0, m1) = monotone_tangents(keys, i, c);
                    hermite(v0, v1, m0 * h, m1 * h, s)
                }
            }
        })
        .collect()
}

/// Fritsch–Carlson tangents at keys `i` and `i + 1` of component `c`: zero
/// at the ends, at extrema and across flat stretches, so the curve never
/// overshoots its keys.
fn monotone_tangents(keys: &[ChannelKey], i: usize, c: usize) -> (f64, f64) {
    let secant = |j: usize| (keys[j + 1].value[c] - keys[j].value[c]) / (keys[j + 1].t - keys[j].t);
    let tangent = |j: usize| -> f64 {
        if j == 0 || j + 1 >= keys.len() {
            return 0.0;
        }
        let (a, b) = (secant(j - 1), secant(j));
        if a * b <= 0.0 {
            0.0
        } else {
            // Harmonic mean keeps the curve monotone.
            2.0 * a * b / (a + b)
        }
    };
    (tangent(i), tangent(i + 1))
}

fn hermite(v0: f64, v1: f64, m0: f64, m1: f64, s: f64) -> f64 {
    let s2 = s * s;
    let s3 = s2 * s;
    (2.0 * s3 - 3.0 * s2 + 1.0) * v0
        + (s3 - 2.0 * s2 + s) * m0
        + (-2.0 * s3 + 3.0 * s2) * v1
        + (s3 - s2) * m1
}

#[cfg(test)]
mod tests {
    use super::*;

    fn k(t: f64, v: f64) -> ChannelKey {
        ChannelKey {
            t,
            ease: Ease::Smooth,
            value: vec![v],
        }
    }

    #[test]
    fn smooth_never_overshoots_and_holds_repeated_keys() {
        let keys = [
            k(0.0, 0.0),
            k(1.0, 0.0),
            k(2.0, 1.0),
            k(3.0, 1.0),
            k(4.0, 0.5),
        ];
        for i in 0..=400 {
            let t = f64::from(i) / 100.0;
            let v = sample(&keys, t)[0];
            assert!((-1e-12..=1.0 + 1e-12).contains(&v), "t {t}: {v}");
            if t <= 1.0 || (2.0..=3.0).contains(&t) {
                assert!(
                    (v - sample(&keys, t.floor())[0]).abs() < 1e-12,
                    "flat between equal keys at {t}"
                );
            }
        }
        assert_eq!(sample(&keys, 9.0)[0], 0.5);
    }
}
