//! `marionette eval pose`: how well posing control reconstructs held-out
//! postures from a few constrained parts.
//!
//! For frames spread evenly over the test clips: place the character where
//! the true frame stands and faces, constrain the first N of [right_hand,
//! left_hand, right_foot, left_foot, head] to the true frame (touch mode:
//! half-lines from a camera 3 m away at the character's side or 45°
//! front-side, alternating; targets mode: the true 3-D points), synthesise,
//! and measure.

use std::time::Instant;

use glam::{DQuat, DVec3};
use serde::Serialize;

use crate::character::camera::Camera;
use crate::character::motion::Clip;
use crate::character::roles::Role;
use crate::character::skeleton::{Skeleton, forward_kinematics};
use crate::control::posing::constraint::{Constraint, SynthOptions, Target};
use crate::control::posing::ik::apply_ik;
use crate::control::posing::model::LearnedModel;
use crate::control::posing::sample::{Placement, pose_of};
use crate::control::posing::synth::synthesize;

/// The order in which parts are constrained.
pub const PARTS: [Role; 5] = [
    Role::RightHand,
    Role::LeftHand,
    Role::RightFoot,
    Role::LeftFoot,
    Role::Head,
];

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    Touch,
    Targets,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// The learned model with the grid, blending and IK.
    Model,
    /// The same without the grid: every sample scored.
    Scan,
    /// The single best sample.
    Nearest,
    /// CCD IK alone, from the library's first posing frame.
    CcdRest,
}

/// What `eval pose` prints.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct EvalResult {
    pub mpjpe_cm: f64,
    pub constraint_err_px: f64,
    pub constraint_err_cm: f64,
    pub ms_per_pose: f64,
    pub poses: usize,
}

/// The evaluation camera for test frame `k`: 3 m from the chest, at the
/// character's side (even `k`) or 45° front-side (odd `k`), 1280 × 720.
#[must_use]
pub fn camera_for(k: usize, chest: DVec3, yaw: f64) -> Camera {
    let angle = if k % 2 == 0 { 90f64 } else { 45f64 };
    let dir = DQuat::from_rotation_y(yaw + angle.to_radians()) * DVec3::Z;
    Camera {
        eye: chest + dir * 3.0,
        target: chest,
        fov_y_deg: 45.0,
        width: 1280.0,
        height: 720.0,
    }
}

/// What to evaluate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EvalSetup {
    /// Constrain the first `parts` of [`PARTS`].
    pub parts: usize,
    pub mode: Mode,
    pub method: Method,
    /// Frames sampled evenly from the test clips.
    pub frames: usize,
    /// For [`Method::Model`]: blocks and cells the grid search looks into
    /// (`None`: [`SynthOptions::default`]'s), to measure what a larger or
    /// smaller search gains.
    pub blocks: Option<usize>,
    pub cells: Option<usize>,
}

/// Run the evaluation.
#[must_use]
pub fn eval_pose(
    skeleton: &Skeleton,
    model: &LearnedModel,
    rest: &Clip,
    tests: &[&Clip],
    setup: EvalSetup,
) -> EvalResult {
    let EvalSetup {
        parts,
        mode,
        method,
        frames,
        blocks,
        cells,
    } = setup;
    let defaults = SynthOptions::default();
    let model_options = SynthOptions {
        blocks: blocks.unwrap_or(defaults.blocks),
        cells: cells.unwrap_or(defaults.cells),
        ..defaults
    };
    let roles = &rest.roles;
    let all: Vec<(&Clip, usize)> = tests
        .iter()
        .flat_map(|c| (0..c.frames.len()).map(move |k| (*c, k)))
        .collect();
    if all.is_empty() || frames == 0 {
        return EvalResult::default();
    }
    let n = frames.min(all.len());
    let parts = &PARTS[..parts.min(PARTS.len())];
    let (mut mpjpe, mut err_cm, mut err_px, mut elapsed) = (0.0, 0.0, 0.0, 0.0);
    let mut constrained = 0usize;
    for k in 0..n {
        let (clip, f) = all[k * (all.len() - 1) / (n - 1).max(1)];
        let truth = forward_kinematics(skeleton, &clip.frames[f]);
        let at = Placement::of(skeleton, roles, &clip.frames[f]);
        let cam = camera_for(k, truth.positions[roles.get(Role::Chest)], at.yaw);
        let constraints: Vec<Constraint> = parts
            .iter()
            .map(|&role| {
                let p = truth.positions[roles.get(role)];
                let target = match mode {
                    Mode::Targets => Target::Point(p),
                    Mode::Touch => Target::Ray(cam.ray(cam.project(p).unwrap_or_default())),
                };
                Constraint { role, target }
            })
            .collect();
        let started = Instant::now();
        let options = match method {
            Method::Model => Some(model_options),
            Method::Scan => Some(SynthOptions {
                use_grid: false,
                ..SynthOptions::default()
            }),
            Method::Nearest => Some(SynthOptions {
                use_grid: false,
                blend: 1,
                ik: false,
                limb_fit: 0.0,
                ..SynthOptions::default()
            }),
            Method::CcdRest => None,
        };
        let pose = match options {
            Some(opts) => synthesize(skeleton, roles, model, &constraints, &at, None, &opts),
            None => {
                let mut pose = pose_of(skeleton, &model.samples[0], &at);
                apply_ik(
                    skeleton,
                    roles,
                    &mut pose,
                    &constraints,
                    None,
                    f64::INFINITY,
                );
                pose
            }
        };
        elapsed += started.elapsed().as_secs_f64();
        let w = forward_kinematics(skeleton, &pose);
        mpjpe += w
            .positions
            .iter()
            .zip(&truth.positions)
            .map(|(a, b)| (*a - *b).length())
            .sum::<f64>()
            / w.positions.len() as f64;
        for c in &constraints {
            let got = w.positions[roles.get(c.role)];
            let want = truth.positions[roles.get(c.role)];
            err_cm += c.target.distance(got);
            if let (Some(a), Some(b)) = (cam.project(got), cam.project(want)) {
                err_px += a.distance(b);
            }
            constrained += 1;
        }
    }
    let round = |v: f64| (v * 1000.0).round() / 1000.0;
    EvalResult {
        mpjpe_cm: round(mpjpe / n as f64 * 100.0),
        constraint_err_px: round(err_px / constrained.max(1) as f64),
        constraint_err_cm: round(err_cm / constrained.max(1) as f64 * 100.0),
        ms_per_pose: round(elapsed / n as f64 * 1000.0),
        poses: n,
    }
}

/// One posing clip's result when it is left out of the model.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ClipResult {
    pub clip: String,
    #[serde(flatten)]
    pub result: EvalResult,
}

/// What `eval pose --leave-one-out` prints: each posing clip tested on a
/// model of the library's other samples, and the mean over the clips.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct LeaveOneOut {
    pub mean: EvalResult,
    pub clips: Vec<ClipResult>,
}

/// Test every posing clip of `lib` on a model built from the library's
/// samples of every other clip (`setup.frames` frames per clip), calling
/// `progress(done, of)` as clips finish. `None` when the library has
/// fewer than two posing clips.
#[must_use]
pub fn leave_one_out(
    lib: &crate::character::library::Library,
    setup: EvalSetup,
    progress: &mut dyn FnMut(usize, usize),
) -> Option<LeaveOneOut> {
    let (names, samples) = crate::control::posing::model::posing_samples(lib);
    if lib.posing.len() < 2 {
        return None;
    }
    let mut clips = Vec::new();
    for (done, held) in lib.posing.iter().enumerate() {
        let others: Vec<_> = samples
            .iter()
            .filter(|s| names[s.clip] != *held)
            .cloned()
            .collect();
        let model = LearnedModel::build(others);
        let rest = lib
            .posing
            .iter()
            .find(|name| *name != held)
            .and_then(|name| lib.clips.get(name))?;
        let test = lib.clips.get(held)?;
        let result = eval_pose(&lib.skeleton, &model, rest, &[test], setup);
        clips.push(ClipResult {
            clip: held.clone(),
            result,
        });
        progress(done + 1, lib.posing.len());
    }
    let n = clips.len() as f64;
    let mean = |f: fn(&EvalResult) -> f64| {
        (clips.iter().map(|c| f(&c.result)).sum::<f64>() / n * 1000.0).round() / 1000.0
    };
    Some(LeaveOneOut {
        mean: EvalResult {
            mpjpe_cm: mean(|r| r.mpjpe_cm),
            constraint_err_px: mean(|r| r.constraint_err_px),
            constraint_err_cm: mean(|r| r.constraint_err_cm),
            ms_per_pose: mean(|r| r.ms_per_pose),
            poses: clips.iter().map(|c| c.result.poses).sum(),
        },
        clips,
    })
}
