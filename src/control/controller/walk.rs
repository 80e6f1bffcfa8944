//! Walking where the finger leads: a finger holding the pelvis that goes
//! across the screen farther over the floor than posing can take the body
//! (the pelvis cannot follow without stepping), or whose drag matches a
//! travelling action's (a walk's) template, starts a walk along the
//! finger's path; the
//! walk ends standing near where the finger stopped or lifted, and posing
//! resumes. A library without locomotion clips keeps posing.

use glam::DVec3;

use super::fingers::Holding;
use super::{Controller, Mode};
use crate::character::camera::Camera;
use crate::character::roles::Role;
use crate::control::action::timeline::ActionEvent;
use crate::control::locomotion::walker::Walker;
use crate::input::touch::ContactId;
use crate::screen::ScreenPoint;

/// A pelvis finger's floor point farther than this from the pelvis (m)
/// is out of posing's reach.
pub const WALK_REACH_M: f64 = 0.35;

/// ... for this long (s) before a walk starts. Only a finger gone across
/// the screen walks so: one gone up or down it moves the pelvis up or
/// down (posing, a jump, a squat), as the camera sees the floor from low;
/// a walk towards the camera starts by the walk's own template.
const WALK_CONFIRM_S: f64 = 0.1;

/// A floor point that moves more than this (m) for a pixel up or down
/// the screen is seen too obliquely (a camera looking level) to walk to.
const MAX_M_PER_PX: f64 = 0.03;

/// What a walk started by the pelvis finger's reach is told as (not an
/// action's name: no action template started it).
pub const WALKING: &str = "walking";

/// The farthest a finger's floor point is taken to be (m from the
/// camera's foot): a finger above the horizon points there.
const FAR_M: f64 = 8.0;

/// Where a pelvis finger leads: the floor point under it, and since when
/// it has been out of reach.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Lead {
    /// The pelvis's standing height (m): the finger moves the pelvis in
    /// the level plane at this height.
    pub(super) height: f64,
    pub(super) beyond_since: Option<f64>,
    /// The finger the walk under way follows.
    pub(super) finger: Option<ContactId>,
}

/// The floor point below where the ray through `at` meets the level
/// plane at `height`.
#[must_use]
pub fn floor_point(camera: &Camera, at: ScreenPoint, height: f64) -> DVec3 {
    let ray = camera.ray(at);
    let foot = ray.origin.with_y(0.0);
    let p = if ray.dir.y < -1e-6 {
        let s = (height - ray.origin.y) / ray.dir.y;
        (ray.origin + ray.dir * s.max(0.0)).with_y(0.0)
    } else {
        foot + ray.dir.with_y(0.0).normalize_or_zero() * FAR_M
    };
    let d = p - foot;
    if d.length() > FAR_M {
        foot + d.normalize() * FAR_M
    } else {
        p
    }
}

impl Controller {
    /// The floor point the finger holding the pelvis leads to, if one does.
    fn pelvis_lead(&self, camera: &Camera) -> Option<DVec3> {
        self.pelvis_finger()
            .map(|f| floor_point(camera, f.at, self.lead.height))
    }

    /// The travelling action (a walk, a run) whose templates the pelvis
    /// finger's drag costs least against now, at any coverage: the walk is
    /// told as that action.
    fn nearest_travelling(&self) -> Option<String> {
        let m = self.fingers.matching.get(&self.pelvis_finger()?.id)?;
        let action = m.drag.cheapest(0, |_| true)?;
        self.ch.travels[action].then(|| self.ch.actions[action].def.name.clone())
    }

    /// The finger holding the pelvis.
    fn pelvis_finger(&self) -> Option<Holding> {
        self.fingers.holding(Role::Pelvis)
    }

    /// Start a walk if the pelvis finger has been out of posing's reach
    /// long enough (and the library can walk).
    pub(super) fn try_walk(&mut self, camera: &Camera, t: f64) -> bool {
        if self.ch.gait.is_empty() {
            return false;
        }
        let Some(goal) = self.pelvis_lead(camera) else {
            self.lead.beyond_since = None;
            return false;
        };
        let pelvis = self.world.positions[self.ch.roles.get(Role::Pelvis)].with_y(0.0);
        if (goal - pelvis).length() <= WALK_REACH_M {
            self.lead.beyond_since = None;
            return false;
        }
        let across = self
            .pelvis_finger()
            .is_some_and(|Holding { at, from, .. }| {
                (at.x - from.x).abs() >= (at.y - from.y).abs()
                    && (floor_point(camera, ScreenPoint::new(at.x, at.y + 1.0), self.lead.height)
                        - goal)
                        .length()
                        <= MAX_M_PER_PX
            });
        if !across {
            self.lead.beyond_since = None;
            return false;
        }
        let since = *self.lead.beyond_since.get_or_insert(t);
        if t - since < WALK_CONFIRM_S {
            return false;
        }
        tracing::debug!("the pelvis finger left posing's reach");
        let label = self
            .nearest_travelling()
            .unwrap_or_else(|| WALKING.to_owned());
        self.walk_to(goal, t, &label, true);
        true
    }

    /// Walk to where the pelvis finger leads, if one does (and the
    /// library can walk).
    pub(super) fn start_walk(&mut self, camera: &Camera, t: f64, label: &str) -> bool {
        match self.pelvis_lead(camera) {
            Some(goal) if !self.ch.gait.is_empty() => {
                self.walk_to(goal, t, label, false);
                true
            }
            _ => false,
        }
    }

    /// Walk towards `goal`; the walk is told as the action `label`
    /// (started now, finished where it stops).
    fn walk_to(&mut self, goal: DVec3, t: f64, label: &str, by_reach: bool) {
        let walker = Walker::start(
            &self.ch.gait,
            &self.ch.lib.skeleton,
            &self.ch.roles,
            &self.target,
            goal,
            t,
        );
        tracing::debug!(to_x = goal.x, to_z = goal.z, "walking");
        self.events.push(ActionEvent::Started {
            action: label.to_owned(),
            time_s: t,
            by_reach,
        });
        self.walking = label.to_owned();
        self.mode = Mode::Walk(Box::new(walker));
        self.lead.beyond_since = None;
        self.lead.finger = self.pelvis_finger().map(|f| f.id);
        self.fingers.forget_matches();
    }

    /// One step of the walk; posing again once it is over.
    pub(super) fn walk_step(&mut self, camera: &Camera, t: f64, dt: f64) {
        let lead = self.pelvis_lead(camera);
        let finger = self.pelvis_finger().map(|f| f.id);
        let Mode::Walk(walker) = &mut self.mode else {
            return;
        };
        match lead {
            // Another finger holds the pelvis now: the walk follows it
            // from where the character is, not along the first one's path.
            Some(p) if finger != self.lead.finger => {
                tracing::debug!("another finger leads the walk");
                walker.lead_anew(p, t);
                self.lead.finger = finger;
            }
            Some(p) => walker.lead(p, t),
            None => walker.release(),
        }
        self.target = walker.step(&self.ch.gait, &self.ch.lib.skeleton, dt);
        if walker.done() {
            tracing::debug!("the walk is over: posing");
            self.events.push(ActionEvent::Finished {
                action: std::mem::take(&mut self.walking),
                time_s: t,
            });
            self.mode = Mode::Posing;
            self.at = self.placement_now();
            self.planted = None;
            if !self.held().is_empty() {
                self.begin_posing();
            }
            self.fingers.restart_drags(t);
        }
    }

    /// The path still ahead of a walk under way, on the floor.
    #[must_use]
    pub fn walk_ahead(&self) -> Option<Vec<DVec3>> {
        match &self.mode {
            Mode::Walk(w) => Some(w.ahead()),
            _ => None,
        }
    }
}
