//! Scores to postures: interpolate the channels at the frame rate, solve
//! arms and legs by two-bone IK, and write BVH files and the generated
//! `library.toml`.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use glam::{DQuat, DVec3};

use super::rig::{self, ANKLE_HEIGHT, FOREARM, SHIN, THIGH, UPPER_ARM, body_rotation, j, two_bone};
use super::score::{Kind, Score, ScoreError, Variant, sample};
use crate::character::bvh;
use crate::character::library::Release;
use crate::character::skeleton::{Pose, Skeleton, WorldPose, forward_kinematics};

/// Frames per second of the authored library.
pub const FPS: f64 = 30.0;

/// Neutral values of every channel: standing relaxed, arms hanging, feet
/// under the hips with the toes turned slightly out.
#[must_use]
pub fn neutral(channel: &str) -> Vec<f64> {
    match channel {
        "pelvis" => vec![0.0, 0.93, 0.0],
        "spine" => vec![3.0, 0.0, 0.0],
        "left_hand" => vec![0.21, 0.86, 0.04],
        "right_hand" => vec![-0.21, 0.86, 0.04],
        "left_foot" => vec![0.10, ANKLE_HEIGHT, 0.0],
        "right_foot" => vec![-0.10, ANKLE_HEIGHT, 0.0],
        "left_foot_rot" => vec![0.0, 8.0],
        "right_foot_rot" => vec![0.0, -8.0],
        "left_elbow_out" | "right_elbow_out" => vec![0.2],
        _ => vec![0.0; 3],
    }
}

/// Every channel of a frame, after the variant's transforms.
struct Channels(BTreeMap<&'static str, Vec<f64>>);

impl Channels {
    fn v3(&self, name: &str) -> DVec3 {
        let v = &self.0[name];
        DVec3::new(v[0], v[1], v[2])
    }
}

fn swap_side(name: &str) -> String {
    if let Some(rest) = name.strip_prefix("left_") {
        format!("right_{rest}")
    } else if let Some(rest) = name.strip_prefix("right_") {
        format!("left_{rest}")
    } else {
        name.to_owned()
    }
}

/// The channels of `score` at time `t` (seconds of the score), with the
/// variant's reach, lift and mirror applied.
fn channels_at(score: &Score, variant: &Variant, t: f64) -> Channels {
    let mut out = BTreeMap::new();
    for (name, _) in super::score::CHANNELS {
        // Mirrored: this channel takes the other side's keys.
        let source = if variant.mirror {
            swap_side(name)
        } else {
            name.to_owned()
        };
        let mut value = match score.channels.get(&source) {
            Some(keys) => {
                let first = keys[0].value.clone();
                let now = sample(keys, t);
                now.iter()
                    .zip(&first)
                    .map(|(n, f)| f + (n - f) * variant.reach)
                    .collect()
            }
            None => neutral(&source),
        };
        if variant.mirror {
            match name {
                n if n.ends_with("hand") || n.ends_with("foot") || n == "pelvis" => {
                    value[0] = -value[0]
                }
                "pelvis_rot" | "spine" | "head" => {
                    value[1] = -value[1];
                    value[2] = -value[2];
                }
                n if n.ends_with("foot_rot") => value[1] = -value[1],
                _ => {}
            }
        }
        if name.ends_with("_hand") {
            value[1] += variant.lift;
        }
        out.insert(name, value);
    }
    Channels(out)
}

/// Solve one frame's pose from its channels.
fn solve(skel: &Skeleton, c: &Channels) -> Pose {
    let mut pose = skel.rest_pose();
    let deg = |name: &str, i: usize| c.0[name][i];
    pose.translations[j::HIPS] = c.v3("pelvis");
    let root = body_rotation(
        deg("pelvis_rot", 0),
        deg("pelvis_rot", 1),
        deg("pelvis_rot", 2),
    );
    pose.rotations[j::HIPS] = root;
    let half =
        |name: &str| body_rotation(deg(name, 0) / 2.0, deg(name, 1) / 2.0, deg(name, 2) / 2.0);
    pose.rotations[j::SPINE] = half("spine");
    pose.rotations[j::CHEST] = half("spine");
    pose.rotations[j::NECK] = half("head");
    pose.rotations[j::HEAD] = half("head");

    // Arms: hand targets move with the pelvis's place and facing; the
    // clavicle lifts a little as the hand rises above the shoulder, then the
    // arm reaches for the hand target.
    let w = forward_kinematics(skel, &pose);
    let body = c.v3("pelvis") * DVec3::new(1.0, 0.0, 1.0);
    let facing = DQuat::from_rotation_y(deg("pelvis_rot", 1).to_radians());
    for limb in [
        (
            1.0,
            j::L_CLAVICLE,
            j::L_ARM,
            j::L_FOREARM,
            j::L_HAND,
            "left_hand",
            "left_elbow_out",
        ),
        (
            -1.0,
            j::R_CLAVICLE,
            j::R_ARM,
            j::R_FOREARM,
            j::R_HAND,
            "right_hand",
            "right_elbow_out",
        ),
    ] {
        reach_arm(skel, c, &w, (body, facing), limb, &mut pose);
    }

    // Legs: hips to ankle targets, knees forward (and a little out); the
    // foot's own orientation from its channel, so a planted foot stays put
    // whatever the body does above it.
    for limb in [
        (
            1.0,
            j::L_THIGH,
            j::L_SHIN,
            j::L_FOOT,
            j::L_TOE,
            "left_foot",
            "left_foot_rot",
        ),
        (
            -1.0,
            j::R_THIGH,
            j::R_SHIN,
            j::R_FOOT,
            j::R_TOE,
            "right_foot",
            "right_foot_rot",
        ),
    ] {
        place_leg(skel, c, &w, (root, facing), limb, &mut pose);
    }
    pose
}

/// An arm reaching for its hand's target (channel `target`, moved with
/// the pelvis's place along the floor, `body`, and its `facing`); its
/// clavicle lifted a little as the hand rises above the shoulder, its
/// elbow out as far as channel `out`. `w`: the posture with the trunk
/// turned.
fn reach_arm(
    skel: &Skeleton,
    c: &Channels,
    w: &WorldPose,
    (body, facing): (DVec3, DQuat),
    (side, clav, arm, fore, hand, target, out): (f64, usize, usize, usize, usize, &str, &str),
    pose: &mut Pose,
) {
    let chest = w.rotations[j::CHEST];
    let target = body + facing * c.v3(target);
    let clav_pos = w.positions[clav];
    let shoulder_rest = clav_pos + chest * skel.joints[arm].offset;
    let rise = ((target.y - shoulder_rest.y) / 0.5).clamp(0.0, 1.0);
    let clav_rot = DQuat::from_rotation_z(side * (14.0 * rise).to_radians());
    pose.rotations[clav] = clav_rot;
    let clav_world = chest * clav_rot;
    let shoulder = clav_pos + clav_world * skel.joints[arm].offset;
    let out = c.0[out][0].clamp(0.0, 1.0);
    let pole = chest
        * DVec3::new(
            side * (0.2 + 0.8 * out),
            -0.6 * (1.0 - out),
            -0.8 * (1.0 - out) - 0.1,
        )
        .normalize();
    let limb = two_bone(
        shoulder,
        UPPER_ARM,
        FOREARM,
        target,
        pole,
        DVec3::X * side,
        DVec3::NEG_Z,
    );
    pose.rotations[arm] = clav_world.inverse() * limb.upper;
    pose.rotations[fore] = limb.upper.inverse() * limb.lower;
    pose.rotations[hand] = DQuat::IDENTITY;
}

/// A leg from the hip to its ankle's target (channel `target`), the knee
/// forward (and a little out), the foot turned by its channel `rot`, so a
/// planted foot stays put whatever the body does above it. `w`: the
/// posture with the trunk turned; `root`: the pelvis's turn.
fn place_leg(
    skel: &Skeleton,
    c: &Channels,
    w: &WorldPose,
    (root, facing): (DQuat, DQuat),
    (side, thigh, shin, foot, toe, target, rot): (f64, usize, usize, usize, usize, &str, &str),
    pose: &mut Pose,
) {
    let deg = |name: &str, i: usize| c.0[name][i];
    let hip = w.positions[j::HIPS] + root * skel.joints[thigh].offset;
    let pole = facing * DVec3::new(side * 0.15, 0.0, 1.0).normalize();
    let yaw = DQuat::from_rotation_y(deg(rot, 1).to_radians());
    let pitch = deg(rot, 0);
    let foot_world = yaw * DQuat::from_rotation_x(pitch.to_radians());
    // Toes down pivots the foot on the ball of the foot: the toe base
    // stays where the flat foot put it, the heel and ankle rise, and the
    // toes stay flat on the floor.
    let toe_offset = skel.joints[toe].offset;
    let flat_ankle = c.v3(target);
    let ankle = if pitch > 0.0 {
        flat_ankle + yaw * toe_offset - foot_world * toe_offset
    } else {
        flat_ankle
    };
    let limb = two_bone(hip, THIGH, SHIN, ankle, pole, DVec3::NEG_Y, DVec3::Z);
    pose.rotations[thigh] = root.inverse() * limb.upper;
    pose.rotations[shin] = limb.upper.inverse() * limb.lower;
    pose.rotations[foot] = limb.lower.inverse() * foot_world;
    pose.rotations[toe] = if pitch > 0.0 {
        DQuat::from_rotation_x(-pitch.to_radians())
    } else {
        DQuat::IDENTITY
    };
}

/// The frames of one variant of a score, at [`FPS`].
#[must_use]
pub fn frames(score: &Score, variant: &Variant) -> Vec<Pose> {
    let skel = rig::skeleton();
    let length = score.duration / variant.speed;
    let n = (length * FPS).round() as usize + 1;
    (0..n)
        .map(|i| {
            let t_out = i as f64 / FPS;
            let t = (t_out * variant.speed).min(score.duration);
            solve(&skel, &channels_at(score, variant, t))
        })
        .collect()
}

/// Errors compiling a library.
#[derive(Debug, thiserror::Error)]
pub enum AuthorError {
    #[error(transparent)]
    Score(#[from] ScoreError),
    #[error("cannot list {path}: {source}")]
    List {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot write {path}: {source}")]
    Write {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{0}")]
    Conflict(String),
    /// No score to compile: the library already there is kept.
    #[error("{} holds no scores (*.toml): nothing written, the library there kept", .0.display())]
    NoScores(PathBuf),
}

/// The compiled library: file name → BVH text, plus `library.toml`.
pub struct Compiled {
    pub files: BTreeMap<String, String>,
}

/// Compile every `*.toml` score in `src`.
pub fn compile(src: &Path) -> Result<Compiled, AuthorError> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(src)
        .map_err(|source| AuthorError::List {
            path: src.to_owned(),
            source,
        })?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    paths.sort();
    if paths.is_empty() {
        return Err(AuthorError::NoScores(src.to_owned()));
    }
    let skel = rig::skeleton();
    let translates: Vec<bool> = (0..skel.len()).map(|i| i == j::HIPS).collect();
    let mut files = BTreeMap::new();
    let mut posing = Vec::new();
    let mut locomotion = Vec::new();
    let mut actions = Actions::new();
    for path in &paths {
        let score = Score::load(path)?;
        for v in &score.variants {
            let name = format!("{}.bvh", v.file);
            let text = bvh::write(&skel, &translates, &frames(&score, v), 1.0 / FPS);
            if files.insert(name.clone(), text).is_some() {
                return Err(AuthorError::Conflict(format!(
                    "{}: output {name} is written by another score too",
                    path.display()
                )));
            }
            match &score.kind {
                Kind::Posing => posing.push(name),
                Kind::Locomotion => locomotion.push(name),
                Kind::Action {
                    name: action,
                    primary,
                    segments,
                } => {
                    let action = v.action.as_ref().unwrap_or(action);
                    let primary = v.primary.as_ref().unwrap_or(primary);
                    let entry = actions
                        .entry(action.clone())
                        .or_insert_with(|| (primary.clone(), segments.clone(), Vec::new()));
                    if entry.0 != *primary || entry.1 != *segments {
                        return Err(AuthorError::Conflict(format!(
                            "{}: action `{action}` has another primary or other segments in another score",
                            path.display()
                        )));
                    }
                    entry.2.push(name);
                }
            }
        }
    }
    let toml = library_toml(&posing, &locomotion, &actions);
    files.insert("library.toml".to_owned(), toml);
    Ok(Compiled { files })
}

/// Each action's primary part, segments and clips, by name.
type Actions = BTreeMap<String, (String, Vec<crate::character::library::Segment>, Vec<String>)>;

/// The library's `library.toml` naming its clips.
fn library_toml(posing: &[String], locomotion: &[String], actions: &Actions) -> String {
    let mut toml = String::from(
        "# The default motion library. Generated by `marionette author-library` from the\n# scores in assets/library-src: edit those, not this file or the BVH files.\n\n[settings]\nscale_to_m = 1.0\naction_lead_in = 0.3\n\n[posing]\nclips = [\n",
    );
    for p in posing {
        let _ = writeln!(toml, "  \"{p}\",");
    }
    toml.push_str("]\n");
    if !locomotion.is_empty() {
        toml.push_str("\n[locomotion]\nclips = [\n");
        for p in locomotion {
            let _ = writeln!(toml, "  \"{p}\",");
        }
        toml.push_str("]\n");
    }
    for (name, (primary, segments, clips)) in actions {
        let _ = write!(
            toml,
            "\n[[action]]\nname = \"{name}\"\nprimary = \"{primary}\"\nclips = [{}]\nsegments = [\n",
            clips
                .iter()
                .map(|c| format!("\"{c}\""))
                .collect::<Vec<_>>()
                .join(", ")
        );
        for s in segments {
            let release = match s.release {
                Release::Forward => "forward",
                Release::Backward => "backward",
            };
            let _ = writeln!(
                toml,
                "  {{ until = {}, still = {}, release = \"{release}\" }},",
                s.until, s.still
            );
        }
        toml.push_str("]\n");
    }
    toml
}

/// Compile `src` into `out`, replacing the BVH files and `library.toml`
/// there. Returns the number of files written.
pub fn author_library(src: &Path, out: &Path) -> Result<usize, AuthorError> {
    let compiled = compile(src)?;
    std::fs::create_dir_all(out).map_err(|source| AuthorError::Write {
        path: out.to_owned(),
        source,
    })?;
    for (name, text) in &compiled.files {
        let path = out.join(name);
        crate::output::replace_file(&path, text.as_bytes())
            .map_err(|source| AuthorError::Write { path, source })?;
    }
    Ok(compiled.files.len())
}
