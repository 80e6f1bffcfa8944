//! Drags judged against the actions' trajectories (the paper's section 5),
//! and the marks drawn for the fingers and the trajectories.

use super::{Controller, Grab, Matching, Mode, RecogniserKind};
use crate::character::camera::Camera;
use crate::character::roles::Role;
use crate::control::action::model::{ActionModel, recognize};
use crate::control::action::player::ActionPlayer;
use crate::control::action::recogniser::{Decision, DragMatch, Thresholds};
use crate::control::action::timeline::{ActionEvent, Decided};
use crate::control::action::trail::{TrailPoint, view_angle_deg};
use crate::control::marks::{Marks, TrajectoryMark};
use crate::screen::ScreenPoint;

impl Matching {
    /// Feed the match the points of `trail` it has not seen, the pelvis's
    /// way on the screen (`drift`) taken out.
    fn feed(&mut self, trail: &[TrailPoint], drift: glam::DVec2) {
        for p in &trail[self.fed..] {
            self.drag.push(TrailPoint {
                at: ScreenPoint::new(p.at.x - drift.x, p.at.y - drift.y),
                t: p.t,
            });
        }
        self.fed = trail.len();
    }

    /// The drag lifted at `t` having started nothing: what it came nearest
    /// to, and which threshold held it back, for a closer look (the debug
    /// log) and for the record of what visitors do (`events`).
    fn started_nothing(
        &self,
        actions: &[ActionModel],
        thresholds: &Thresholds,
        t: f64,
        events: &mut Vec<ActionEvent>,
    ) {
        let Some(c) = self.drag.closest() else {
            return;
        };
        let cost_limit_m = actions[c.action]
            .def
            .threshold_m
            .unwrap_or(thresholds.cost_m);
        tracing::debug!(
            nearest = %actions[c.action].def.name,
            clip = %c.clip,
            cost_m = c.cost_m,
            cost_limit_m,
            margin_m = c.margin_m,
            margin_needed_m = thresholds.margin_m,
            coverage = c.coverage,
            "drag started no action"
        );
        events.push(ActionEvent::NearMiss {
            action: actions[c.action].def.name.clone(),
            time_s: t,
            cost_m: c.cost_m,
            cost_limit_m,
            margin_m: c.margin_m,
            margin_needed_m: thresholds.margin_m,
            coverage: c.coverage,
            held_by: if c.cost_m > cost_limit_m {
                "cost"
            } else {
                "margin"
            },
        });
    }
}

/// How the template recogniser's decision `d` was taken, as told with the
/// action's start.
pub(super) fn decided_by(d: &Decision) -> Decided {
    Decided {
        cost_m: d.cost_m,
        margin_m: d.margin_m,
        coverage: d.coverage,
    }
}

/// Tell `decided` with the starts among `events` (those of this step).
pub(super) fn tell_decision(events: &mut [ActionEvent], decided: Option<Decided>) {
    for e in events {
        if let ActionEvent::Started { decided: d, .. } = e {
            *d = decided;
        }
    }
}

impl Controller {
    /// A drag that starts an action, if any.
    pub(super) fn recognise(
        &mut self,
        camera: &crate::character::camera::Camera,
        t: f64,
    ) -> Option<ActionPlayer> {
        let (action, start_at, decided) = match self.settings.recogniser {
            RecogniserKind::Paper => {
                let found = self.recognise_paper(camera)?;
                (found.action, found.matched.coverage, None)
            }
            RecogniserKind::Templates => {
                let d = self.recognise_templates(camera, |_| true)?;
                (d.action, d.generalized, Some(decided_by(&d)))
            }
        };
        let told = self.motion.events.len();
        let name = self.ch.actions[action].def.name.clone();
        if self.ch.travels[action] && self.start_walk(camera, t, &name) {
            // A walk's drag: walk along the finger's path instead.
            tracing::debug!(
                action = %self.ch.actions[action].def.name,
                "a travelling action's drag walks along the finger's path"
            );
            tell_decision(&mut self.motion.events[told..], decided);
            return None;
        }
        let at = self.placement_now();
        let player = ActionPlayer::start(
            &self.ch.actions,
            action,
            start_at,
            at,
            t,
            &mut self.motion.events,
        );
        tell_decision(&mut self.motion.events[told..], decided);
        self.fingers.restart_drags(t);
        self.fingers.forget_matches();
        Some(player)
    }

    /// The paper's rule: the average trajectory, eq. 1 and its thresholds.
    fn recognise_paper(
        &self,
        camera: &crate::character::camera::Camera,
    ) -> Option<crate::control::action::model::Recognition> {
        let at = self.placement_now();
        let found = self.fingers.grabs().find_map(|(_, g)| match g {
            Grab {
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
        tracing::debug!(
            action = %a.def.name,
            cost_px = found.matched.cost,
            coverage = found.matched.coverage,
            "drag recognised"
        );
        Some(found)
    }

    /// The template recogniser: each held part's trail is fed to its
    /// match as it grows (a new match where the trail began anew), relative
    /// to the body (what the pelvis moved on the screen while walking taken
    /// out); a decision is taken for the parts `only` allows.
    pub(super) fn recognise_templates(
        &mut self,
        camera: &crate::character::camera::Camera,
        only: fn(Role) -> bool,
    ) -> Option<Decision> {
        let at = self.placement_now();
        let now = self.time();
        let actions = &self.ch.actions;
        let thresholds = self.ch.recogniser.thresholds;
        let drift = self.motion.layering.drift_px();
        let events = &mut self.motion.events;
        let (grabs, matching) = self.fingers.grabs_and_matches();
        matching.retain(|id, m| {
            let held = grabs.contains_key(id);
            if !held {
                m.started_nothing(actions, &thresholds, now, events);
            }
            held
        });
        let mut found = None;
        for (id, g) in grabs {
            let Grab {
                role,
                trail,
                trail_start,
                moved,
                ..
            } = g;
            if !only(*role) {
                // Not a part that may start anything now (the pelvis
                // finger that walks the character): not matched.
                continue;
            }
            let fresh = || Matching {
                start: *trail_start,
                fed: 0,
                drag: DragMatch::new(
                    &self.ch.recogniser,
                    &self.ch.actions,
                    *role,
                    camera,
                    &at,
                    None,
                ),
            };
            let m = matching.entry(*id).or_insert_with(fresh);
            if m.start != *trail_start || m.fed > trail.len() {
                // The trail began anew (a rest, an action's end, or its
                // oldest points dropped): so does the match.
                *m = fresh();
            }
            m.feed(trail, drift);
            if !*moved || trail.len() < 2 || found.is_some() {
                continue;
            }
            found = m
                .drag
                .decide(&self.ch.actions, &self.ch.recogniser.thresholds);
        }
        let d = found?;
        // The kiosk logs each start once ("action started"); why it started
        // is for a closer look.
        tracing::debug!(
            action = %self.ch.actions[d.action].def.name,
            clip = %d.clip,
            cost_m = d.cost_m,
            margin_m = d.margin_m,
            coverage = d.coverage,
            tempo = d.tempo,
            generalized = d.generalized,
            "why: the best template, its cost, the lead over the next action, how much of its path is covered, and the drag's tempo against it"
        );
        Some(d)
    }

    /// The trajectory marks seen through `camera`: the path a walk will
    /// take and, while a part is held in posing (and `trajectories`), the
    /// trajectories of the actions that part can start (executable ones
    /// marked).
    #[must_use]
    pub fn trajectory_marks(&self, camera: &Camera, trajectories: bool) -> Vec<TrajectoryMark> {
        let mut marks = Marks::default();
        if let Some(ahead) = self.walk_ahead() {
            // The path the walk will take, on the floor.
            marks.trajectories.push(TrajectoryMark {
                points: ahead.iter().filter_map(|p| camera.project(*p)).collect(),
                executable: true,
                tint: None,
            });
        }
        if trajectories && matches!(self.motion.mode, Mode::Posing) {
            let at = self.placement_now();
            let eye = camera.eye_vector();
            for role in self.held() {
                // Which actions a drag can start from this view: for the
                // templates, those with a clip that can be drawn from here.
                let drawable = match self.settings.recogniser {
                    RecogniserKind::Templates => Some(DragMatch::new(
                        &self.ch.recogniser,
                        &self.ch.actions,
                        role,
                        camera,
                        &at,
                        None,
                    )),
                    RecogniserKind::Paper => None,
                };
                for (i, a) in self.ch.actions.iter().enumerate() {
                    if a.def.primary != role {
                        continue;
                    }
                    let dir = glam::DQuat::from_rotation_y(at.yaw) * a.direction;
                    marks.trajectories.push(TrajectoryMark {
                        points: a.projected(camera, &at).iter().map(|p| p.at).collect(),
                        executable: drawable.as_ref().map_or_else(
                            || view_angle_deg(dir, eye) > self.settings.rule.min_view_angle_deg,
                            |m| m.drawable(i) > 0,
                        ),
                        tint: None,
                    });
                }
            }
        }
        marks.trajectories
    }
}
