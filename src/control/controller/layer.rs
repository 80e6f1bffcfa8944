//! An action laid over a walk (the paper's future work: "waving a hand
//! while walking"). While the character walks, or plays an action led by
//! the legs or the pelvis, a second finger's drag of an arm or the head is
//! matched against the actions that part leads; one that starts plays on
//! the upper body (its own timeline, driven by its finger) while the legs
//! go on: the two postures are laid together region by region
//! ([`crate::control::action::layer`]), faded in and out. Tracking and the
//! physical effects work on the result.
//!
//! The body moves under the finger while it walks: the drag is judged
//! relative to the body, the pelvis's movement on the screen taken out of
//! it, and the action's clips are kept placed under the walking body.

use glam::DVec2;

use super::{Controller, Mode};
use crate::character::camera::Camera;
use crate::character::roles::Role;
use crate::character::skeleton::Pose;
use crate::control::action::layer::Mask;
use crate::control::action::player::ActionPlayer;
use crate::control::action::timeline::Status;
use crate::control::character::upper;
use crate::control::posing::constraint::Constraint;

/// A layered action fades in over this long, and out as long again once
/// it is over (s).
const LAYER_FADE_S: f64 = 0.2;

/// An action played on the upper body over another motion.
#[derive(Clone, Debug)]
pub(super) struct Layer {
    player: ActionPlayer,
    mask: Mask,
    /// How much of the upper body is the action's (0 to 1).
    weight: f64,
    /// The action's own posture, as it alone would be shown.
    alone: Pose,
}

/// Where the pelvis has gone on the screen while walking: drags are
/// judged with it taken out.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Drift {
    pub(super) px: DVec2,
    last: Option<DVec2>,
}

/// An action laid over the body's motion, as [`Controller::layered`]
/// tells it.
#[derive(Clone, Copy, Debug)]
pub struct Layered<'a> {
    /// The action's name.
    pub action: &'a str,
    /// How much of the upper body is the action's now (0 to 1).
    pub weight: f64,
    /// The action's generalized time (0 to 1).
    pub time: f64,
    /// The action's own posture, as it alone would put the body.
    pub alone: &'a Pose,
}

impl Controller {
    /// The action laid over the walk (or over an action led by the
    /// legs), if one plays.
    #[must_use]
    pub fn layered(&self) -> Option<Layered<'_>> {
        self.layer.as_ref().map(|l| Layered {
            action: self.ch.actions[l.player.action()].def.name.as_str(),
            weight: l.weight,
            time: l.player.time(),
            alone: &l.alone,
        })
    }

    /// Whether an action can be laid over what the body does now.
    fn layerable(&self) -> bool {
        match &self.mode {
            Mode::Walk(_) => true,
            Mode::Action(p) => !upper(self.ch.actions[p.action()].def.primary),
            Mode::Posing => false,
        }
    }

    /// Start a layered action if a finger on the upper body dragged one,
    /// play the one under way, and lay it over the target posture.
    pub(super) fn layer_step(
        &mut self,
        camera: &Camera,
        constraints: &[Constraint],
        t: f64,
        dt: f64,
    ) {
        if self.layer.is_none() {
            if !self.layerable() || self.ch.regions.is_none() {
                return;
            }
            let Some(d) = self.recognise_templates(camera, upper) else {
                return;
            };
            let Some(mask) = self.ch.layers[d.action] else {
                return;
            };
            tracing::debug!(
                action = %self.ch.actions[d.action].def.name,
                "laid over the legs' motion"
            );
            let at = self.placement_now();
            let player = ActionPlayer::start(
                &self.ch.actions,
                d.action,
                d.generalized,
                at,
                t,
                &mut self.events,
            );
            self.layer = Some(Box::new(Layer {
                player,
                mask,
                weight: 0.0,
                alone: self.target.clone(),
            }));
            self.fingers.restart_drags(t);
            self.fingers.forget_matches();
        }
        let moved = self.fingers.moved(upper);
        let at = self.placement_now();
        let (Some(layer), Some(regions)) = (self.layer.as_mut(), self.ch.regions.as_ref()) else {
            return;
        };
        if layer.player.status() == Status::Playing {
            let mine: Vec<Constraint> = constraints
                .iter()
                .copied()
                .filter(|c| upper(c.role))
                .collect();
            layer.player.follow(&self.ch.actions, at);
            layer.alone = layer.player.step(
                &self.ch.lib,
                &self.ch.actions,
                &mine,
                !moved,
                dt,
                &mut self.events,
            );
            layer.weight = (layer.weight + dt / LAYER_FADE_S).min(1.0);
        } else {
            layer.weight -= dt / LAYER_FADE_S;
        }
        let (weight, mask) = (layer.weight, layer.mask);
        self.target = regions.lay(
            &self.ch.lib.skeleton,
            &self.ch.roles,
            &self.target,
            &layer.alone,
            mask,
            weight,
        );
        if weight <= 0.0 {
            tracing::debug!("the layered action is over");
            self.layer = None;
            self.fingers.restart_drags(t);
            if matches!(self.mode, Mode::Posing) && !self.held().is_empty() {
                // The fingers still down pose the body again.
                self.begin_posing();
            }
        }
    }

    /// Follow the pelvis on the screen while the character walks (after
    /// the frame's posture is known).
    pub(super) fn follow_drift(&mut self, camera: &Camera) {
        let pelvis = self.world.positions[self.ch.roles.get(Role::Pelvis)];
        let now = camera.project(pelvis).map(|p| DVec2::new(p.x, p.y));
        if let (Some(now), Some(last), Mode::Walk(_)) = (now, self.drift.last, &self.mode) {
            self.drift.px += now - last;
        }
        self.drift.last = now;
    }
}
