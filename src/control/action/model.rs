//! Action models: for each action of a library, a learned model of its
//! clips' postures (each sample knowing its generalized time), the average
//! 3-D trajectory of its primary body part in the character's frame, the
//! representative direction of that trajectory, and its natural duration.

use glam::DVec3;

use super::trail::{Match, StartRule, TrailPoint, match_trail, view_angle_deg};
use crate::character::body::Placement;
use crate::character::camera::Camera;
use crate::character::library::{ActionDef, Library};
use crate::control::posing::model::{LearnedModel, sample_stride};
use crate::control::posing::sample::{Sample, samples_of};

/// Points of an action's average trajectory, at generalized times k/32:
/// an odd count, so that "more than half of its points" is reached at
/// generalized time 0.5 exactly (17 of 33).
pub const TRAJECTORY_POINTS: usize = 33;

/// One action model.
#[derive(Clone, Debug)]
pub struct ActionModel {
    pub def: ActionDef,
    pub model: LearnedModel,
    /// The primary part's average path, at evenly spaced generalized
    /// times, relative to the clip start (the character's frame).
    pub trajectory: Vec<DVec3>,
    /// Where the path goes over its first half (unit vector, character
    /// frame): what a drag shows.
    pub direction: DVec3,
    /// Mean length of the clips (s).
    pub duration: f64,
    /// Each clip's own path of the primary part, as the template
    /// recogniser matches drags against (one per clip, in `def.clips`
    /// order; clips missing from the library are left out).
    pub templates: Vec<ClipPath>,
}

/// One clip's path of its action's primary part: positions in the
/// character's frame relative to the clip start, `dt` seconds apart.
#[derive(Clone, Debug, PartialEq)]
pub struct ClipPath {
    pub clip: String,
    pub points: Vec<DVec3>,
    pub dt: f64,
    /// The still lead-in: the part starts its movement at this point
    /// (where it last moved slowly before first passing a quarter of its
    /// peak speed).
    pub lead_in: usize,
    /// The part's peak speed (m/s, over three points).
    pub peak_speed: f64,
}

impl ClipPath {
    /// The part's path on screen from the end of its still lead-in, for a
    /// character placed at `at`, with times in seconds at the clip's speed.
    #[must_use]
    pub fn projected(&self, camera: &Camera, at: &Placement) -> Vec<TrailPoint> {
        self.points
            .iter()
            .enumerate()
            .skip(self.lead_in)
            .filter_map(|(k, p)| {
                camera.project(at.place(*p)).map(|s| TrailPoint {
                    at: s,
                    t: (k - self.lead_in) as f64 * self.dt,
                })
            })
            .collect()
    }
}

/// Speeds along a path (m per point), each over three points so that one
/// noisy sample does not count.
fn speeds(points: &[DVec3]) -> Vec<f64> {
    (0..points.len())
        .map(|k| {
            let (a, b) = (k.saturating_sub(1), (k + 1).min(points.len() - 1));
            if b > a {
                points[a].distance(points[b]) / (b - a) as f64
            } else {
                0.0
            }
        })
        .collect()
}

/// Where a path's still lead-in ends: the last point under a tenth of
/// the peak speed before the speed first passes a quarter of it.
#[must_use]
pub fn lead_in(points: &[DVec3]) -> usize {
    let speed = speeds(points);
    let peak = speed.iter().copied().fold(0.0, f64::max);
    if peak <= 0.0 {
        return 0;
    }
    let Some(first) = speed.iter().position(|v| *v > 0.25 * peak) else {
        return 0;
    };
    speed[..first]
        .iter()
        .rposition(|v| *v < 0.1 * peak)
        .unwrap_or(0)
}

/// Templates keep at most this many points per second of their clip.
const TEMPLATE_HZ: f64 = 30.0;

impl ActionModel {
    /// Build the model of `def` from the library's clips.
    #[must_use]
    pub fn build(lib: &Library, def: &ActionDef) -> Self {
        let mut samples: Vec<Sample> = Vec::new();
        let mut paths: Vec<Vec<DVec3>> = Vec::new();
        let mut durations = Vec::new();
        let mut templates = Vec::new();
        for (ci, name) in def.clips.iter().enumerate() {
            let Some(clip) = lib.clips.get(name) else {
                continue;
            };
            durations.push(clip.frame_time * clip.frames.len().saturating_sub(1) as f64);
            let all = samples_of(ci, clip, 0..clip.frames.len());
            let primary = clip.roles.get(def.primary);
            // The path at evenly spaced generalized times (nearest frame).
            paths.push(
                (0..TRAJECTORY_POINTS)
                    .map(|k| {
                        let g = k as f64 / (TRAJECTORY_POINTS - 1) as f64;
                        let f = (g * (all.len().saturating_sub(1)) as f64).round() as usize;
                        all[f].placed[primary]
                    })
                    .collect(),
            );
            let step = ((1.0 / TEMPLATE_HZ / clip.frame_time).round() as usize).max(1);
            let points: Vec<DVec3> = all
                .iter()
                .step_by(step)
                .map(|s| s.placed[primary])
                .collect();
            let dt = clip.frame_time * step as f64;
            templates.push(ClipPath {
                clip: name.clone(),
                lead_in: lead_in(&points),
                peak_speed: speeds(&points).into_iter().fold(0.0, f64::max) / dt,
                points,
                dt,
            });
            let stride = sample_stride(clip.frame_time);
            samples.extend(all.into_iter().step_by(stride));
        }
        let trajectory: Vec<DVec3> = (0..TRAJECTORY_POINTS)
            .map(|k| paths.iter().map(|p| p[k]).sum::<DVec3>() / paths.len().max(1) as f64)
            .collect();
        // The direction a drag shows: over the first half of the action
        // (the part recognition sees), else to the furthest point.
        let start = trajectory.first().copied().unwrap_or(DVec3::ZERO);
        let half = trajectory
            .get(TRAJECTORY_POINTS / 2)
            .copied()
            .unwrap_or(start);
        let far = trajectory
            .iter()
            .copied()
            .max_by(|a, b| (*a - start).length().total_cmp(&(*b - start).length()))
            .unwrap_or(start);
        let direction = if (half - start).length() > 0.05 {
            half - start
        } else {
            far - start
        };
        let direction = direction.try_normalize().unwrap_or(DVec3::Z);
        Self {
            def: def.clone(),
            model: LearnedModel::build(samples),
            trajectory,
            direction,
            duration: durations.iter().sum::<f64>() / durations.len().max(1) as f64,
            templates,
        }
    }

    /// The path of its take drawn longest on `camera`'s screen (a visitor
    /// draws what they see), as [`ClipPath::projected`] gives it; empty
    /// without templates.
    #[must_use]
    pub fn most_drawn(&self, camera: &Camera, at: &Placement) -> Vec<TrailPoint> {
        let length =
            |p: &[TrailPoint]| -> f64 { p.windows(2).map(|w| w[0].at.distance(w[1].at)).sum() };
        self.templates
            .iter()
            .map(|t| t.projected(camera, at))
            .max_by(|a, b| length(a).total_cmp(&length(b)))
            .unwrap_or_default()
    }

    /// The trajectory on screen for a character placed at `at`, with times
    /// in seconds at natural speed.
    #[must_use]
    pub fn projected(&self, camera: &Camera, at: &Placement) -> Vec<TrailPoint> {
        let n = self.trajectory.len().max(2) - 1;
        self.trajectory
            .iter()
            .enumerate()
            .filter_map(|(k, p)| {
                camera.project(at.place(*p)).map(|s| TrailPoint {
                    at: s,
                    t: k as f64 / n as f64 * self.duration,
                })
            })
            .collect()
    }
}

/// A recognised action: which, how well it matched, how far along.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Recognition {
    pub action: usize,
    pub matched: Match,
}

/// Among `actions` whose primary part is the dragged one, the best match
/// of the drag's trail that satisfies the start rule, if any.
#[must_use]
pub fn recognize(
    actions: &[ActionModel],
    dragged: crate::character::roles::Role,
    trail: &[TrailPoint],
    camera: &Camera,
    at: &Placement,
    rule: &StartRule,
) -> Option<Recognition> {
    let eye = camera.eye_vector();
    actions
        .iter()
        .enumerate()
        .filter(|(_, a)| a.def.primary == dragged)
        .filter_map(|(i, a)| {
            let world_dir = glam::DQuat::from_rotation_y(at.yaw) * a.direction;
            let angle = view_angle_deg(world_dir, eye);
            let m = match_trail(trail, &a.projected(camera, at), rule.h, rule.tempo)?;
            rule.starts(&m, trail, angle).then_some(Recognition {
                action: i,
                matched: m,
            })
        })
        .min_by(|a, b| a.matched.cost.total_cmp(&b.matched.cost))
}
