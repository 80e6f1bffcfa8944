//! Drags judged against the actions' trajectories (the paper's section 5),
//! and the marks drawn for the fingers and the trajectories.

use super::{Controller, Grab, Mode};
use crate::control::action::model::recognize;
use crate::control::action::player::ActionPlayer;
use crate::control::action::trail::{TrailPoint, view_angle_deg};
use crate::control::marks::{FingerMark, FingerUse, Marks, TrajectoryMark};

impl Controller {
    pub(super) fn reset_trails(&mut self, t: f64) {
        for g in self.grabs.values_mut() {
            if let Grab::Part {
                at,
                trail,
                trail_start,
                ..
            } = g
            {
                trail.clear();
                trail.push(TrailPoint { at: *at, t: 0.0 });
                *trail_start = t;
            }
        }
    }

    /// A drag that starts an action, if any.
    pub(super) fn recognise(
        &mut self,
        camera: &crate::character::camera::Camera,
        t: f64,
    ) -> Option<ActionPlayer> {
        let at = self.placement_now();
        let found = self.grabs.values().find_map(|g| match g {
            Grab::Part {
                role,
                trail,
                moved: true,
                ..
            } if trail.len() >= 2 => recognize(
                &self.ch.actions,
                *role,
                trail,
                camera,
                &at,
                &self.settings.rule,
            ),
            _ => None,
        })?;
        let a = &self.ch.actions[found.action];
        tracing::info!(
            action = %a.def.name,
            cost_px = found.matched.cost,
            coverage = found.matched.coverage,
            "drag recognised"
        );
        let player = ActionPlayer::start(
            &self.ch.actions,
            found.action,
            found.matched.coverage,
            at,
            t,
            &mut self.events,
        );
        self.reset_trails(t);
        Some(player)
    }

    /// Finger marks and, while a part is held in posing, the trajectories
    /// of the actions that part can start (executable ones marked).
    #[must_use]
    pub fn marks(&self, trajectories: bool) -> Marks {
        let mut marks = Marks::default();
        for g in self.grabs.values() {
            marks.fingers.push(match g {
                Grab::Part { role, at, .. } => FingerMark {
                    at: *at,
                    usage: FingerUse::Part(*role),
                    tint: None,
                },
                Grab::Camera { at } => FingerMark {
                    at: *at,
                    usage: FingerUse::Camera,
                    tint: None,
                },
            });
        }
        if trajectories && matches!(self.mode, Mode::Posing) {
            let camera = self.rig.camera();
            let at = self.placement_now();
            let eye = camera.eye_vector();
            for role in self.held() {
                for a in self.ch.actions.iter().filter(|a| a.def.primary == role) {
                    let dir = glam::DQuat::from_rotation_y(at.yaw) * a.direction;
                    marks.trajectories.push(TrajectoryMark {
                        points: a.projected(&camera, &at).iter().map(|p| p.at).collect(),
                        executable: view_angle_deg(dir, eye)
                            > self.settings.rule.min_view_angle_deg,
                        tint: None,
                    });
                }
            }
        }
        marks
    }
}
