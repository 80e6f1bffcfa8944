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
use crate::character::body::Placement;
use crate::character::camera::Camera;
use crate::character::roles::Role;
use crate::character::skeleton::Pose;
use crate::control::action::layer::{Mask, Regions};
use crate::control::action::player::ActionPlayer;
use crate::control::action::timeline::ActionEvent;
use crate::control::action::timeline::Status;
use crate::control::character::Character;
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
struct Drift {
    px: DVec2,
    last: Option<DVec2>,
}

/// The layer part: the action laid over the body's motion, if one
/// plays, and where the pelvis has gone on the screen while walking.
#[derive(Clone, Debug, Default)]
pub(super) struct Layering {
    layer: Option<Box<Layer>>,
    drift: Drift,
}

/// How much of the upper body a layered action has after `dt` more
/// seconds from `weight`: fading in while it plays, out once it is over.
fn fade(weight: f64, playing: bool, dt: f64) -> f64 {
    if playing {
        (weight + dt / LAYER_FADE_S).min(1.0)
    } else {
        weight - dt / LAYER_FADE_S
    }
}

impl Layering {
    /// Whether an action is laid over the body's motion now.
    pub fn playing(&self) -> bool {
        self.layer.is_some()
    }

    /// Lay the action `player` starts over the body, on the regions of
    /// `mask`, fading in from the body's posture `now`.
    pub fn begin(&mut self, player: ActionPlayer, mask: Mask, now: &Pose) {
        self.layer = Some(Box::new(Layer {
            player,
            mask,
            weight: 0.0,
            alone: now.clone(),
        }));
    }

    /// One step of the layered action (its own player driven by the
    /// upper body's constraints `mine`, `held` while its fingers rest),
    /// laid over the posture `under` by `regions`; `None` once it has
    /// faded out (and is dropped).
    #[allow(clippy::too_many_arguments)]
    pub fn step(
        &mut self,
        ch: &Character,
        regions: &Regions,
        at: Placement,
        mine: &[Constraint],
        held: bool,
        under: &Pose,
        dt: f64,
        events: &mut Vec<ActionEvent>,
    ) -> Option<Pose> {
        let layer = self.layer.as_mut()?;
        let playing = layer.player.status() == Status::Playing;
        if playing {
            layer.player.follow(&ch.actions, at);
            layer.alone = layer
                .player
                .step(&ch.lib, &ch.actions, mine, held, dt, events);
        }
        layer.weight = fade(layer.weight, playing, dt);
        let posture = regions.lay(
            &ch.lib.skeleton,
            &ch.roles,
            under,
            &layer.alone,
            layer.mask,
            layer.weight,
        );
        if layer.weight <= 0.0 {
            self.layer = None;
        }
        Some(posture)
    }

    /// How far the pelvis has gone on the screen while walking (px).
    pub fn drift_px(&self) -> DVec2 {
        self.drift.px
    }

    /// The pelvis seen at `now` on the screen (none: off it); its way is
    /// added up while the body `walking`.
    pub fn follow_drift(&mut self, now: Option<DVec2>, walking: bool) {
        if let (Some(now), Some(last), true) = (now, self.drift.last, walking) {
            self.drift.px += now - last;
        }
        self.drift.last = now;
    }

    /// The layered action as [`Controller::layered`] tells it.
    fn told<'a>(&'a self, ch: &'a Character) -> Option<Layered<'a>> {
        self.layer.as_ref().map(|l| Layered {
            action: ch.actions[l.player.action()].def.name.as_str(),
            weight: l.weight,
            time: l.player.time(),
            alone: &l.alone,
        })
    }
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
        self.motion.layering.told(&self.ch)
    }

    /// Whether an action can be laid over what the body does now.
    fn layerable(&self) -> bool {
        match &self.motion.mode {
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
        if !self.motion.layering.playing() {
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
            let told = self.motion.events.len();
            let player = ActionPlayer::start(
                &self.ch.actions,
                d.action,
                d.generalized,
                at,
                t,
                &mut self.motion.events,
            );
            super::actions::tell_decision(
                &mut self.motion.events[told..],
                Some(super::actions::decided_by(&d)),
            );
            self.motion.layering.begin(player, mask, &self.target);
            self.fingers.restart_drags(t);
            self.fingers.forget_matches();
        }
        let moved = self.fingers.moved(upper);
        let at = self.placement_now();
        let Some(regions) = self.ch.regions.as_ref() else {
            return;
        };
        let mine: Vec<Constraint> = constraints
            .iter()
            .copied()
            .filter(|c| upper(c.role))
            .collect();
        let Some(posture) = self.motion.layering.step(
            &self.ch,
            regions,
            at,
            &mine,
            !moved,
            &self.target,
            dt,
            &mut self.motion.events,
        ) else {
            return;
        };
        self.target = posture;
        if !self.motion.layering.playing() {
            tracing::debug!("the layered action is over");
            self.fingers.restart_drags(t);
            if matches!(self.motion.mode, Mode::Posing) && !self.held().is_empty() {
                // The fingers still down pose the body again.
                self.begin_posing();
            }
        }
    }

    /// Follow the pelvis on the screen, seen through `camera` (the
    /// table's, settled after the step), while the character walks.
    pub fn follow_drift(&mut self, camera: &Camera) {
        let pelvis = self.shown.world().positions[self.ch.roles.get(Role::Pelvis)];
        let now = camera.project(pelvis).map(|p| DVec2::new(p.x, p.y));
        let walking = matches!(self.motion.mode, Mode::Walk(_));
        self.motion.layering.follow_drift(now, walking);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_layered_action_fades_in_while_it_plays_and_out_after() {
        let mut w = 0.0;
        for _ in 0..5 {
            w = fade(w, true, 0.02);
        }
        assert!((w - 0.5).abs() < 1e-12, "{w}");
        for _ in 0..10 {
            w = fade(w, true, 0.02);
        }
        assert_eq!(w, 1.0, "never more than the whole upper body");
        for _ in 0..10 {
            w = fade(w, false, 0.02);
        }
        assert!(w <= 1e-12, "{w}");
    }

    #[test]
    fn the_pelvis_way_on_the_screen_adds_up_only_while_walking() {
        let mut l = Layering::default();
        l.follow_drift(Some(DVec2::new(100.0, 50.0)), true);
        l.follow_drift(Some(DVec2::new(110.0, 50.0)), true);
        l.follow_drift(Some(DVec2::new(130.0, 45.0)), false);
        l.follow_drift(Some(DVec2::new(135.0, 45.0)), true);
        // Off the screen: nothing to add, and the next step starts anew.
        l.follow_drift(None, true);
        l.follow_drift(Some(DVec2::new(500.0, 45.0)), true);
        assert_eq!(l.drift_px(), DVec2::new(15.0, 0.0));
        assert!(!l.playing());
    }
}
