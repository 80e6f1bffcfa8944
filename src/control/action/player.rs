//! Playing an action (the paper's section 5): each frame the action's
//! learned model turns the touches into sample weights; their weighted
//! generalized time drives the [`ActionTimeline`]; the weights, gathered per
//! sample motion (clip), blend each clip's posture at the current time.
//! When every finger lifts the last weights are kept. Fingers on other parts
//! still constrain them through IK. At either end the caller returns to
//! posing.

use std::collections::BTreeMap;

use super::model::ActionModel;
use super::timeline::{ActionEvent, ActionTimeline, Drive, Status};
use crate::character::body::Placement;
use crate::character::library::Library;
use crate::character::skeleton::Pose;
use crate::control::posing::constraint::{Constraint, SynthOptions};
use crate::control::posing::ik::apply_ik;
use crate::control::posing::model::LearnedModel;
use crate::control::posing::sample::samples_of;
use crate::control::posing::synth::{blend, choose};

/// The clips' blend weights follow the touches with this time constant (s).
const CLIP_WEIGHT_TAU_S: f64 = 0.25;

/// An action being played.
#[derive(Clone, Debug)]
pub struct ActionPlayer {
    action: usize,
    timeline: ActionTimeline,
    /// Weight of each of the action's clips, kept when the fingers lift.
    clip_weights: Vec<f64>,
    at: Placement,
}

impl ActionPlayer {
    /// Start action `action` (index into `actions`) at generalized time
    /// `t0`, the character placed at `at` (clip-start anchoring).
    #[must_use]
    pub fn start(
        actions: &[ActionModel],
        action: usize,
        t0: f64,
        at: Placement,
        time_s: f64,
        events: &mut Vec<ActionEvent>,
    ) -> Self {
        let a = &actions[action];
        let n = a.def.clips.len().max(1);
        // Started part-way (the drag already covered part of it): place the
        // clips so that their posture at `t0` stands where the character
        // stands, not where the clips' start would put it.
        let mut at = at;
        at.position -= glam::DQuat::from_rotation_y(at.yaw) * root_offset(a, t0);
        Self {
            action,
            timeline: ActionTimeline::start(a.def.clone(), a.duration, t0, time_s, events),
            clip_weights: vec![1.0 / n as f64; n],
            at,
        }
    }

    /// Keep the clips placed under a body that moves on its own (a walk
    /// that an action is layered on): their posture now stands where `at`
    /// (the body's placement now) stands.
    pub fn follow(&mut self, actions: &[ActionModel], at: Placement) {
        let off = root_offset(&actions[self.action], self.timeline.time());
        self.at = Placement {
            position: at.position - glam::DQuat::from_rotation_y(at.yaw) * off,
            ..at
        };
    }

    /// Which action (index into the action models).
    #[must_use]
    pub fn action(&self) -> usize {
        self.action
    }

    #[must_use]
    pub fn status(&self) -> Status {
        self.timeline.status()
    }

    #[must_use]
    pub fn time(&self) -> f64 {
        self.timeline.time()
    }

    /// One frame: `constraints` are the current touches (the primary part's
    /// among them while its finger is down; empty when every finger has
    /// lifted), `resting` whether the fingers stand still.
    pub fn step(
        &mut self,
        lib: &Library,
        actions: &[ActionModel],
        constraints: &[Constraint],
        resting: bool,
        dt: f64,
        events: &mut Vec<ActionEvent>,
    ) -> Pose {
        let a = &actions[self.action];
        let roles = &lib.clips[&a.def.clips[0]].roles;
        let primary_down = constraints.iter().any(|c| c.role == a.def.primary);
        let target = if primary_down {
            let weights = choose(&a.model, constraints, &self.at, &SynthOptions::ACTION);
            // The clips' weights follow the touches' choice smoothly: the
            // clips of a walk travel different distances, and a blend that
            // jumped from one to another would move the body (and slide a
            // planted foot) by their difference in one frame.
            let target = per_clip(&a.model, &weights, a.def.clips.len());
            let k = (dt / CLIP_WEIGHT_TAU_S).min(1.0);
            for (w, t) in self.clip_weights.iter_mut().zip(&target) {
                *w += (t - *w) * k;
            }
            let total: f64 = self.clip_weights.iter().sum();
            if total > 1e-12 {
                for w in &mut self.clip_weights {
                    *w /= total;
                }
            }
            Some(
                weights
                    .iter()
                    .map(|(i, w)| a.model.samples[*i].time * w)
                    .sum::<f64>(),
            )
        } else {
            None
        };
        self.timeline.step(dt, Drive { target, resting }, events);
        let mut pose = self.pose_at(lib, a, self.timeline.time());
        // Other fingers still hold their parts.
        let others: Vec<Constraint> = constraints
            .iter()
            .copied()
            .filter(|c| c.role != a.def.primary)
            .collect();
        if !others.is_empty() {
            apply_ik(
                &lib.skeleton,
                roles,
                &mut pose,
                &others,
                None,
                SynthOptions::default().max_ik_m,
            );
        }
        pose
    }

    /// The blend of each clip's posture at generalized time `t`.
    fn pose_at(&self, lib: &Library, a: &ActionModel, t: f64) -> Pose {
        let mut samples = Vec::new();
        let mut weights = Vec::new();
        for (ci, name) in a.def.clips.iter().enumerate() {
            let Some(clip) = lib.clips.get(name) else {
                continue;
            };
            let frame = (t * (clip.frames.len().saturating_sub(1)) as f64).round() as usize;
            samples.extend(samples_of(ci, clip, std::iter::once(frame)));
            weights.push((
                samples.len() - 1,
                self.clip_weights.get(ci).copied().unwrap_or(0.0),
            ));
        }
        let model = LearnedModel::with_coords(samples, vec![[0.0, 0.0]; weights.len()]);
        weights.sort_by(|x, y| y.1.total_cmp(&x.1));
        blend(&lib.skeleton, &model, &weights, &self.at)
    }
}

/// The clips' root offset from their start at generalized time `t` (the
/// mean over the clips of their nearest samples), on the floor.
fn root_offset(a: &ActionModel, t: f64) -> glam::DVec3 {
    let mut off = glam::DVec3::ZERO;
    let mut count = 0.0;
    for clip in 0..a.def.clips.len() {
        let nearest = a
            .model
            .samples
            .iter()
            .filter(|s| s.clip == clip)
            .min_by(|x, y| (x.time - t).abs().total_cmp(&(y.time - t).abs()));
        if let Some(s) = nearest {
            off += glam::DVec3::new(s.root_offset.x, 0.0, s.root_offset.z);
            count += 1.0;
        }
    }
    if count > 0.0 { off / count } else { off }
}

/// Sample weights gathered per clip and normalised.
fn per_clip(model: &LearnedModel, weights: &[(usize, f64)], clips: usize) -> Vec<f64> {
    let mut by: BTreeMap<usize, f64> = BTreeMap::new();
    for (i, w) in weights {
        *by.entry(model.samples[*i].clip).or_default() += w;
    }
    let total: f64 = by.values().sum();
    (0..clips)
        .map(|c| by.get(&c).copied().unwrap_or(0.0) / total.max(1e-12))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::character::body::Anchor;
    use crate::character::roles::Role;
    use crate::character::skeleton::forward_kinematics;
    use glam::DVec3;

    use crate::character::library::default_library;

    fn model(lib: &Library, name: &str) -> ActionModel {
        let def = lib.actions.iter().find(|a| a.name == name).unwrap();
        ActionModel::build(lib, def)
    }

    fn pelvis_on_floor(lib: &Library, a: &ActionModel, pose: &Pose) -> DVec3 {
        let roles = &lib.clips[&a.def.clips[0]].roles;
        forward_kinematics(&lib.skeleton, pose).positions[roles.get(Role::Pelvis)].with_y(0.0)
    }

    #[test]
    fn with_the_fingers_lifted_past_its_wind_up_an_action_plays_to_its_end() {
        // Lifted in the wind-up an action runs back and is cancelled (the
        // timeline's own tests); past it, it plays on at its own pace.
        let lib = default_library();
        let actions = vec![model(&lib, "bow")];
        let mut events = Vec::new();
        let at = Placement {
            position: DVec3::ZERO,
            yaw: 0.0,
            anchor: Anchor::ClipStart,
        };
        let mut p = ActionPlayer::start(&actions, 0, 0.7, at, 10.0, &mut events);
        assert_eq!(p.status(), Status::Playing);
        let mut last = p.time();
        let mut frames = 0;
        while p.status() == Status::Playing && frames < 2000 {
            p.step(&lib, &actions, &[], true, 1.0 / 60.0, &mut events);
            assert!(
                p.time() >= last - 1e-12,
                "time went back: {last} -> {}",
                p.time()
            );
            last = p.time();
            frames += 1;
        }
        assert_eq!(p.status(), Status::Finished, "after {frames} frames");
        // At the action's own pace: the rest of its clips' length.
        let seconds = f64::from(frames) / 60.0;
        let rest = 0.3 * actions[0].duration;
        assert!(
            (seconds - rest).abs() <= 0.1 * rest + 1.0 / 60.0,
            "{seconds} s against {rest} s"
        );
        assert!(
            matches!(events.first(), Some(ActionEvent::Started { .. })),
            "{events:?}"
        );
        assert!(
            matches!(events.last(), Some(ActionEvent::Finished { .. })),
            "{events:?}"
        );
    }

    #[test]
    fn an_action_started_part_way_stands_where_the_character_stands() {
        // The drag already covered half the action: its clips are placed
        // so that their posture at that time stands where the character
        // does, not where their start would put it.
        let lib = default_library();
        let actions = vec![model(&lib, "kick_right")];
        let at = Placement {
            position: DVec3::new(1.0, 0.0, 2.0),
            yaw: 0.7,
            anchor: Anchor::ClipStart,
        };
        let mut events = Vec::new();
        let mut p = ActionPlayer::start(&actions, 0, 0.5, at, 0.0, &mut events);
        let pose = p.step(&lib, &actions, &[], true, 0.0, &mut events);
        let from_start = ActionPlayer::start(&actions, 0, 0.0, at, 0.0, &mut events).pose_at(
            &lib,
            &actions[0],
            0.0,
        );
        let (now, start) = (
            pelvis_on_floor(&lib, &actions[0], &pose),
            pelvis_on_floor(&lib, &actions[0], &from_start),
        );
        assert!(
            (now - at.position).length() < 0.05,
            "{now} against {}",
            at.position
        );
        assert!((start - at.position).length() < 0.05, "{start}");
    }

    #[test]
    fn sample_weights_are_gathered_per_clip() {
        let lib = default_library();
        let a = model(&lib, "walk");
        let clips = a.def.clips.len();
        assert!(clips >= 2, "{clips}");
        let first = a.model.samples.iter().position(|s| s.clip == 0).unwrap();
        let second = a.model.samples.iter().position(|s| s.clip == 1).unwrap();
        let w = per_clip(
            &a.model,
            &[(first, 0.3), (second, 0.1), (first, 0.4)],
            clips,
        );
        assert!(
            (w[0] - 0.875).abs() < 1e-12 && (w[1] - 0.125).abs() < 1e-12,
            "{w:?}"
        );
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }
}
