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

use crate::character::body::Placement;
use crate::character::camera::Camera;
use crate::character::motion::Clip;
use crate::character::roles::Role;
use crate::character::roles::RoleMap;
use crate::character::skeleton::{Pose, Skeleton, WorldPose, forward_kinematics};
use crate::control::controller::MAX_SUBSTEP;
use crate::control::posing::constraint::{Constraint, SynthOptions, Target};
use crate::control::posing::ik::apply_ik;
use crate::control::posing::model::LearnedModel;
use crate::control::posing::sample::pose_of;
use crate::control::posing::synth::synthesize;
use crate::control::tracking::accel::{AccelTracker, Gains};

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

/// Sums behind an [`EvalResult`].
#[derive(Default)]
struct Scores {
    mpjpe: f64,
    err_cm: f64,
    err_px: f64,
    elapsed: f64,
    constrained: usize,
    poses: usize,
}

impl Scores {
    /// Score `pose` against `truth` and the constraints it was given.
    fn add(
        &mut self,
        skeleton: &Skeleton,
        roles: &RoleMap,
        pose: &Pose,
        truth: &WorldPose,
        constraints: &[Constraint],
        cam: &Camera,
    ) {
        let w = forward_kinematics(skeleton, pose);
        self.mpjpe += w
            .positions
            .iter()
            .zip(&truth.positions)
            .map(|(a, b)| (*a - *b).length())
            .sum::<f64>()
            / w.positions.len() as f64;
        for c in constraints {
            let got = w.positions[roles.get(c.role)];
            let want = truth.positions[roles.get(c.role)];
            self.err_cm += c.target.distance(got);
            if let (Some(a), Some(b)) = (cam.project(got), cam.project(want)) {
                self.err_px += a.distance(b);
            }
            self.constrained += 1;
        }
        self.poses += 1;
    }

    fn result(&self) -> EvalResult {
        let round = |v: f64| (v * 1000.0).round() / 1000.0;
        let n = self.poses.max(1) as f64;
        let c = self.constrained.max(1) as f64;
        EvalResult {
            mpjpe_cm: round(self.mpjpe / n * 100.0),
            constraint_err_px: round(self.err_px / c),
            constraint_err_cm: round(self.err_cm / c * 100.0),
            ms_per_pose: round(self.elapsed / n * 1000.0),
            poses: self.poses,
        }
    }
}

/// The constraints on `parts` of the true posture `truth`: its points, or
/// the rays through them from `cam`.
fn constraints_of(
    truth: &WorldPose,
    roles: &RoleMap,
    cam: &Camera,
    parts: &[Role],
    mode: Mode,
) -> Vec<Constraint> {
    parts
        .iter()
        .map(|&role| {
            let p = truth.positions[roles.get(role)];
            let target = match mode {
                Mode::Targets => Target::Point(p),
                Mode::Touch => Target::Ray(cam.ray(cam.project(p).unwrap_or_default())),
            };
            Constraint { role, target }
        })
        .collect()
}

/// A posture for `constraints` by `method`, the character at `at` with
/// its feet `planted` (if any).
#[allow(clippy::too_many_arguments)]
fn solve(
    skeleton: &Skeleton,
    roles: &RoleMap,
    model: &LearnedModel,
    constraints: &[Constraint],
    at: &Placement,
    planted: Option<[DVec3; 2]>,
    method: Method,
    model_options: SynthOptions,
) -> Pose {
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
    match options {
        Some(opts) => synthesize(skeleton, roles, model, constraints, at, planted, &opts),
        None => {
            let mut pose = pose_of(skeleton, &model.samples[0], at);
            apply_ik(
                skeleton,
                roles,
                &mut pose,
                constraints,
                planted,
                f64::INFINITY,
            );
            pose
        }
    }
}

impl EvalSetup {
    fn model_options(&self) -> SynthOptions {
        let defaults = SynthOptions::default();
        SynthOptions {
            blocks: self.blocks.unwrap_or(defaults.blocks),
            cells: self.cells.unwrap_or(defaults.cells),
            ..defaults
        }
    }

    fn parts(&self) -> &'static [Role] {
        &PARTS[..self.parts.min(PARTS.len())]
    }
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
    let roles = &rest.roles;
    let all: Vec<(&Clip, usize)> = tests
        .iter()
        .flat_map(|c| (0..c.frames.len()).map(move |k| (*c, k)))
        .collect();
    if all.is_empty() || setup.frames == 0 {
        return EvalResult::default();
    }
    let n = setup.frames.min(all.len());
    let mut scores = Scores::default();
    for k in 0..n {
        let (clip, f) = all[k * (all.len() - 1) / (n - 1).max(1)];
        let truth = forward_kinematics(skeleton, &clip.frames[f]);
        let at = Placement::of(skeleton, roles, &clip.frames[f]);
        let cam = camera_for(k, truth.positions[roles.get(Role::Chest)], at.yaw);
        let constraints = constraints_of(&truth, roles, &cam, setup.parts(), setup.mode);
        let started = Instant::now();
        let pose = solve(
            skeleton,
            roles,
            model,
            &constraints,
            &at,
            None,
            setup.method,
            setup.model_options(),
        );
        scores.elapsed += started.elapsed().as_secs_f64();
        scores.add(skeleton, roles, &pose, &truth, &constraints, &cam);
    }
    scores.result()
}

/// What `eval pose --sequence` prints: the touches follow each test clip
/// frame by frame as in use, and the same frames posed one by one.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SequenceResult {
    pub frame_by_frame: EvalResult,
    pub single_frames: EvalResult,
}

/// Posing as in use: the touches follow each test clip from its first
/// frame, every frame (`setup.frames` of each clip at most), from one
/// camera (the side, or 45° front-side for every other clip). The
/// character stays placed where the clip began, its feet planted where its
/// first posture put them (as when a visitor's fingers go down), and the
/// shown posture tracks the synthesised one with the controller's
/// critically damped tracking (`settle_s`), each frame continuing from the
/// last. Scored on the shown posture.
#[must_use]
pub fn eval_sequence(
    skeleton: &Skeleton,
    model: &LearnedModel,
    rest: &Clip,
    tests: &[&Clip],
    setup: EvalSetup,
    settle_s: f64,
) -> SequenceResult {
    let roles = &rest.roles;
    let mut scores = Scores::default();
    for (i, clip) in tests.iter().enumerate() {
        let Some(first) = clip.frames.first() else {
            continue;
        };
        let at = Placement::of(skeleton, roles, first);
        let truth0 = forward_kinematics(skeleton, first);
        let cam = camera_for(i, truth0.positions[roles.get(Role::Chest)], at.yaw);
        let gains = Gains::critical(settle_s);
        let mut planted = None;
        let mut tracker: Option<AccelTracker> = None;
        for (f, frame) in clip.frames.iter().enumerate().take(setup.frames) {
            let truth = forward_kinematics(skeleton, frame);
            let constraints = constraints_of(&truth, roles, &cam, setup.parts(), setup.mode);
            let started = Instant::now();
            let pose = solve(
                skeleton,
                roles,
                model,
                &constraints,
                &at,
                planted,
                setup.method,
                setup.model_options(),
            );
            scores.elapsed += started.elapsed().as_secs_f64();
            if planted.is_none() {
                let w = forward_kinematics(skeleton, &pose);
                planted = Some([
                    w.positions[roles.get(Role::LeftFoot)],
                    w.positions[roles.get(Role::RightFoot)],
                ]);
            }
            let shown = match &mut tracker {
                Some(t) if f > 0 => {
                    let steps = (clip.frame_time / MAX_SUBSTEP).ceil().max(1.0) as usize;
                    for _ in 0..steps {
                        t.step(&pose, gains, clip.frame_time / steps as f64);
                    }
                    t.pose.clone()
                }
                _ => {
                    tracker = Some(AccelTracker::new(pose.clone()));
                    pose
                }
            };
            scores.add(skeleton, roles, &shown, &truth, &constraints, &cam);
        }
    }
    // The same frames, each posed on its own.
    let n = scores.poses;
    let single_frames = if n == 0 {
        EvalResult::default()
    } else {
        let picked: Vec<Clip> = tests
            .iter()
            .map(|c| Clip {
                frames: c.frames.iter().take(setup.frames).cloned().collect(),
                ..(*c).clone()
            })
            .collect();
        let refs: Vec<&Clip> = picked.iter().collect();
        eval_pose(
            skeleton,
            model,
            rest,
            &refs,
            EvalSetup { frames: n, ..setup },
        )
    };
    SequenceResult {
        frame_by_frame: scores.result(),
        single_frames,
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
