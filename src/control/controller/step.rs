//! One step of the controller, as a short list of stages, each a call on
//! a part: the target posture (posing, an action or a walk), an action
//! laid over it, tracking, the corrections of the shown posture (the
//! physical effects, a push fading, the feet, the bound on joint
//! accelerations), and what is shown (the world pose). The camera is the
//! table's: a step sees through it.

use super::feet::FeetStep;
use super::{Controller, Mode};
use crate::character::camera::Camera;
use crate::control::action::timeline::Status;
use crate::control::character::upper;
use crate::control::posing::constraint::Constraint;

impl Controller {
    /// Advance to time `t` (seconds), seen through `camera`: synthesise
    /// the target posture and track it.
    pub fn advance(&mut self, t: f64, camera: &Camera) {
        let dt = (t - self.time).clamp(0.0, 0.25);
        self.time = t;
        let constraints = self.constraints(camera);
        let switched = self.aim(camera, &constraints, t, dt);
        self.layer_step(camera, &constraints, t, dt);
        self.fingers.settle();
        self.track(dt);
        self.correct(dt, switched);
        self.shown.show(&self.ch.lib.skeleton);
    }

    /// The target posture: posing to the fingers' constraints, an action
    /// a drag started (or the one playing), or a walk. Whether the target
    /// switched controllers (its feet jumped).
    fn aim(&mut self, camera: &Camera, constraints: &[Constraint], t: f64, dt: f64) -> bool {
        let mut switched = false;
        // Under a layered action the arms and head are its own.
        let base: Vec<Constraint> = constraints
            .iter()
            .copied()
            .filter(|c| !self.motion.layering.playing() || !upper(c.role))
            .collect();
        let moved = self.fingers.moved(|_| true);
        if self.walk_past_action(camera, t) {
            switched = true;
        }
        match &mut self.motion.mode {
            Mode::Walk(_) => self.walk_step(camera, t, dt),
            Mode::Posing => {
                // An action laid over a walk that ended plays out first.
                let found = (!self.motion.layering.playing()).then(|| self.recognise(camera, t));
                if let Some(player) = found.flatten() {
                    self.motion.mode = Mode::Action(Box::new(player));
                    switched = true;
                } else if matches!(self.motion.mode, Mode::Walk(_)) || self.try_walk(camera, t) {
                    // A walk's drag started a walk, or the finger left reach.
                    self.walk_step(camera, t, dt);
                } else if !base.is_empty() {
                    self.target = self.posing.aim(&self.ch, &base);
                } else if self.posing.end() {
                    // The last finger on the body lifted.
                    self.feet.settle_stance(
                        &self.ch.lib.skeleton,
                        &self.ch.roles,
                        &mut self.target,
                    );
                }
            }
            Mode::Action(player) => {
                self.target = player.step(
                    &self.ch.lib,
                    &self.ch.actions,
                    &base,
                    !moved,
                    dt,
                    &mut self.motion.events,
                );
                if player.status() != Status::Playing {
                    let placed = self.placement_now();
                    self.posing.place(placed);
                    self.motion.mode = Mode::Posing;
                    switched = true;
                    if !self.held().is_empty() {
                        self.begin_posing();
                    }
                    self.fingers.restart_drags(t);
                }
            }
        }
        switched
    }

    /// Tracking control (section 6): the shown posture follows the target
    /// by bounded accelerations, in sub-steps short enough to stay stable.
    fn track(&mut self, dt: f64) {
        self.shown.track(&self.target, self.settings.settle_s, dt);
    }

    /// The tracked posture corrected: the physical effects (eq. 5-7), a
    /// push fading, the feet, then the bound on joint accelerations;
    /// `switched`: the target switched controllers this step.
    fn correct(&mut self, dt: f64, switched: bool) {
        let held = self.held();
        let (sk, roles) = (&self.ch.lib.skeleton, &self.ch.roles);
        if self.settings.physics && self.settings.settle_s > 0.0 {
            let planted = [self.feet.planted(0), self.feet.planted(1)];
            self.physical.effects(
                sk,
                roles,
                &self.target,
                self.shown.pose_mut(),
                &held,
                planted,
                dt,
            );
        }
        self.physical.recover(self.shown.pose_mut(), dt);
        let (shown_last, output, tracker) = self.shown.for_correction();
        let step = FeetStep {
            skeleton: sk,
            roles,
            target: &self.target,
            shown_last,
            held: &held,
            switched,
            settle_s: self.settings.settle_s,
            // While walking, the clip's own foot contacts say which foot
            // stands.
            contacts: match &self.motion.mode {
                Mode::Walk(w) => Some(w.contacts(&self.ch.gait)),
                _ => None,
            },
            dt,
        };
        self.feet.step(&step, output, tracker);
        if self.settings.settle_s > 0.0 {
            // Part of tracking: off, the synthesised postures are shown.
            let standing = [self.feet.standing(0), self.feet.standing(1)];
            self.shown.bound(sk, roles, &held, standing, dt);
            self.feet.keep_clear(sk, roles, self.shown.pose_mut());
        }
    }
}
