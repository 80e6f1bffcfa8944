//! Walking where the finger leads: a finger holding the pelvis that goes
//! across the screen farther over the floor than posing can take the body
//! (the pelvis cannot follow without stepping), or whose drag matches a
//! travelling action's (a walk's) template, starts a walk along the
//! finger's path; the walk ends standing near where the finger stopped or
//! lifted, and posing resumes. The same finger going on walks on, and if
//! it lifts out of reach before the walk on began, the character walks to
//! where it lifted. A library without locomotion clips keeps posing.

use glam::DVec3;

use super::fingers::Holding;
use super::{Controller, Mode};
use crate::character::camera::Camera;
use crate::character::roles::Role;
use crate::control::action::timeline::ActionEvent;
use crate::control::locomotion::walker::{ARRIVE_M, Walker, smoothed_speed};
use crate::input::touch::ContactId;
use crate::screen::ScreenPoint;

/// A pelvis finger's floor point farther than this from the pelvis (m)
/// is out of posing's reach.
pub const WALK_REACH_M: f64 = 0.35;

/// ... for this long (s) before a walk starts. A finger gone across the
/// screen walks so; one gone up or down it moves the pelvis up or down
/// (posing, a jump, a squat), as the camera sees the floor from low,
/// until it goes higher or lower than the body takes the pelvis (see
/// [`PAST_BODY_M`]); a walk towards the camera also starts by the walk's
/// own template. A finger that has led a walk and stopped walks on
/// whichever way it goes.
const WALK_CONFIRM_S: f64 = 0.1;

/// A finger up or down the screen that points this far (m) above the
/// highest or below the lowest the library takes the pelvis (at the
/// pelvis's place, seen from the camera) asks for more than posing can
/// do: it walks the character away or towards the camera.
const PAST_BODY_M: f64 = 0.1;

/// A floor point that moves more than this (m) for a pixel up or down
/// the screen is seen too obliquely (a camera looking level) to walk to.
const MAX_M_PER_PX: f64 = 0.03;

/// ... and for a finger that points past the body (see [`PAST_BODY_M`]),
/// whose height is no longer in question, a floor point that moves more
/// than this (m) for a pixel is too uncertain to walk to (two pixels of a
/// finger's jitter, 20 cm of floor).
const PAST_BODY_M_PER_PX: f64 = 0.1;

/// What a walk started by the pelvis finger's reach is told as (not an
/// action's name: no action template started it).
pub const WALKING: &str = "walking";

/// The farthest a finger's floor point is taken to be (m from the
/// camera's foot): a finger above the horizon points there.
const FAR_M: f64 = 8.0;

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

/// The walk part: where a finger holding the pelvis leads (the floor
/// point under it), since when it has been out of posing's reach, the
/// finger a walk under way follows, and what that walk is told as.
#[derive(Clone, Debug, Default)]
pub(super) struct Lead {
    /// The pelvis's standing height (m): the finger moves the pelvis in
    /// the level plane at this height.
    height: f64,
    /// The lowest and highest the library takes the pelvis (m over the
    /// floor).
    body: (f64, f64),
    /// Since when the finger has been out of reach, and where it led
    /// there last (a floor point).
    beyond: Option<(f64, DVec3)>,
    /// The finger the walk under way follows (or the last walk followed,
    /// while it stays down).
    finger: Option<ContactId>,
    /// What the walk under way is told as.
    told: String,
    /// The finger holding the pelvis as it was last seen (where it lifts).
    last: Option<Holding>,
    /// Where the last walk ended (the pelvis over the floor).
    stood: Option<DVec3>,
    /// The finger holding the pelvis while posing: which, where it led
    /// last and when, and how fast it goes over the floor (m/s, smoothed
    /// as a walk smooths its finger's).
    pace: Option<(ContactId, f64, DVec3, f64)>,
}

impl Lead {
    /// No finger leading; the pelvis stands `height` over the floor and
    /// goes from `body.0` to `body.1` over it in the library.
    pub fn new(height: f64, body: (f64, f64)) -> Self {
        Self {
            height,
            body: (body.0.min(height), body.1.max(height)),
            ..Self::default()
        }
    }

    /// How high a finger at `at` points at the pelvis over floor point
    /// `pelvis`, seen from `camera`: where its ray passes the upright
    /// plane through the pelvis square to the view (m; none where the ray
    /// does not go that way).
    fn height_at(camera: &Camera, at: ScreenPoint, pelvis: DVec3) -> Option<f64> {
        let ray = camera.ray(at);
        let normal = camera.eye_vector().with_y(0.0).normalize_or_zero();
        let into = ray.dir.dot(normal);
        if normal == DVec3::ZERO || into < 1e-6 {
            return None;
        }
        let s = (pelvis - ray.origin).dot(normal) / into;
        Some(ray.origin.y + ray.dir.y * s)
    }

    /// Whether a finger at `at` points higher (`Some(true)`) or lower
    /// (`Some(false)`) than the body takes the pelvis, by [`PAST_BODY_M`],
    /// at the pelvis over floor point `pelvis`, seen from `camera`.
    fn past_body(&self, camera: &Camera, at: ScreenPoint, pelvis: DVec3) -> Option<bool> {
        let y = Self::height_at(camera, at, pelvis)?;
        (y < self.body.0 - PAST_BODY_M || y > self.body.1 + PAST_BODY_M).then_some(y > self.body.1)
    }

    /// How far the floor point under a finger at `at` moves for a pixel
    /// down the screen (m).
    fn oblique(&self, camera: &Camera, at: ScreenPoint) -> f64 {
        (self.goal(camera, ScreenPoint::new(at.x, at.y + 1.0)) - self.goal(camera, at)).length()
    }

    /// Where to walk to, if the pelvis finger `finger` points lower than
    /// the body takes the pelvis (by [`PAST_BODY_M`]) and out of posing's
    /// reach over the floor: an action of the pelvis (a squat) it started
    /// can go no lower, and the character walks towards the camera
    /// instead.
    pub fn below_body(&self, camera: &Camera, finger: Holding, pelvis: DVec3) -> Option<DVec3> {
        let goal = self.goal(camera, finger.at);
        ((goal - pelvis).length() > WALK_REACH_M
            && self.oblique(camera, finger.at) <= PAST_BODY_M_PER_PX
            && self.past_body(camera, finger.at, pelvis) == Some(false))
        .then_some(goal)
    }

    /// The floor point a finger on the pelvis at `at` leads to.
    pub fn goal(&self, camera: &Camera, at: ScreenPoint) -> DVec3 {
        floor_point(camera, at, self.height)
    }

    /// Where to walk to, if the pelvis finger `finger` has led out of
    /// posing's reach (from the pelvis over `pelvis` on the floor), across
    /// the screen and over a floor seen steeply enough, for long enough
    /// at `t`.
    pub fn out_of_reach(
        &mut self,
        camera: &Camera,
        finger: Option<Holding>,
        pelvis: DVec3,
        t: f64,
    ) -> Option<DVec3> {
        // How fast the finger goes, for a walk it starts to set off at.
        let led = finger.map(|f| (f.id, self.goal(camera, f.at)));
        self.pace = led.map(|(id, p)| match self.pace {
            Some((was, tq, q, v)) if was == id && t > tq + 1e-6 => {
                (id, t, p, smoothed_speed(v, (p - q).length(), t - tq))
            }
            Some(same) if same.0 == id => same,
            _ => (id, t, p, 0.0),
        });
        let Some(f) = finger else {
            // Lifted. A finger that led a walk, stopped and went on out of
            // reach, lifted before the walk on began: the character walks
            // to where it lifted all the same; so too where it lifted
            // farther than a walk arrives from where its walk ended, though
            // within posing's reach of the pelvis leaning after it (posing
            // no longer holds the pelvis there once it lifts: a finger that
            // went on 30 to 35 cm from a stop left the character standing
            // 28 to 33 cm from where it lifted). The next finger has walked
            // nowhere yet.
            let beyond = self.beyond.take();
            let last = self.last.take();
            let walked = self.finger.take();
            return walked.and_then(|id| {
                beyond.map(|(_, goal)| goal).or_else(|| {
                    let stood = self.stood?;
                    last.filter(|l| l.id == id)
                        .map(|l| self.goal(camera, l.at))
                        .filter(|goal| (*goal - stood).length() > ARRIVE_M)
                })
            });
        };
        self.last = Some(f);
        let Some(goal) = self.beyond_reach(camera, f, pelvis) else {
            self.beyond = None;
            return None;
        };
        let since = self.beyond.map_or(t, |(since, _)| since);
        self.beyond = Some((since, goal));
        (t - since >= WALK_CONFIRM_S).then_some(goal)
    }

    /// The floor point the pelvis finger `f` leads to, if it is out of
    /// posing's reach of the pelvis over `pelvis`: farther than
    /// [`WALK_REACH_M`] over a floor seen steeply enough, and across the
    /// screen or past the body (see [`PAST_BODY_M`]).
    fn beyond_reach(&self, camera: &Camera, f: Holding, pelvis: DVec3) -> Option<DVec3> {
        let goal = self.goal(camera, f.at);
        if (goal - pelvis).length() <= WALK_REACH_M {
            return None;
        }
        let (at, from) = (f.at, f.from);
        // A finger that has led a walk and stopped walks on whichever way
        // it goes (its drag began anew where it stopped: up the screen is
        // away from the camera, not a jump).
        let walked = self.finger == Some(f.id);
        let oblique = self.oblique(camera, at);
        let across = ((walked || (at.x - from.x).abs() >= (at.y - from.y).abs())
            && oblique <= MAX_M_PER_PX)
            || (self.past_body(camera, at, pelvis).is_some() && oblique <= PAST_BODY_M_PER_PX);
        across.then_some(goal)
    }

    /// How fast the finger holding the pelvis goes over the floor (m/s;
    /// 0 with none).
    pub fn pace(&self) -> f64 {
        self.pace.map_or(0.0, |p| p.3)
    }

    /// A walk began, told as `label`, following the finger `finger`.
    pub fn began(&mut self, label: &str, finger: Option<ContactId>) {
        label.clone_into(&mut self.told);
        self.beyond = None;
        self.last = None;
        self.stood = None;
        self.finger = finger;
    }

    /// Steer the walk under way after the pelvis finger (`finger`, none
    /// once it lifted: the walk stops where it can) at `t`.
    pub fn steer(&mut self, walker: &mut Walker, camera: &Camera, finger: Option<Holding>, t: f64) {
        let goal = finger.map(|f| self.goal(camera, f.at));
        let id = finger.map(|f| f.id);
        match goal {
            // Another finger holds the pelvis now: the walk follows it
            // from where the character is, not along the first one's path.
            Some(p) if id != self.finger => {
                tracing::debug!("another finger leads the walk");
                walker.lead_anew(p, t);
                self.finger = id;
            }
            Some(p) => walker.lead(p, t),
            None => walker.release(),
        }
    }

    /// What the walk under way is told as.
    pub fn told(&self) -> &str {
        &self.told
    }

    /// The walk is over, the pelvis over floor point `at`: what it was
    /// told as.
    pub fn finished(&mut self, at: DVec3) -> String {
        self.stood = Some(at);
        std::mem::take(&mut self.told)
    }
}

impl Controller {
    /// The travelling action (a walk, a run) whose templates the pelvis
    /// finger's drag costs least against now, at any coverage: the walk is
    /// told as that action.
    fn nearest_travelling(&self) -> Option<String> {
        let m = self.fingers.matching.get(&self.pelvis_finger()?.id)?;
        let action = m.drag.cheapest(0, |_| true)?;
        self.ch.travels[action].then(|| self.ch.actions[action].def.name.clone())
    }

    /// The floor point under the pelvis as shown.
    fn pelvis_floor(&self) -> DVec3 {
        self.shown.world().positions[self.ch.roles.get(Role::Pelvis)].with_y(0.0)
    }

    /// The finger holding the pelvis.
    fn pelvis_finger(&self) -> Option<Holding> {
        self.fingers.holding(Role::Pelvis)
    }

    /// Whether the finger holding the pelvis leads out of posing's reach
    /// now, seen from `camera` (a walk starts once it has for
    /// [`WALK_CONFIRM_S`]): farther over the floor than posing takes the
    /// pelvis, across the screen or past the body.
    #[must_use]
    pub fn pelvis_finger_out_of_reach(&self, camera: &Camera) -> bool {
        let pelvis = self.pelvis_floor();
        self.pelvis_finger()
            .and_then(|f| self.motion.lead.beyond_reach(camera, f, pelvis))
            .is_some()
    }

    /// Start a walk if the pelvis finger has been out of posing's reach
    /// long enough (and the library can walk).
    pub(super) fn try_walk(&mut self, camera: &Camera, t: f64) -> bool {
        if self.ch.gait.is_empty() {
            return false;
        }
        let pelvis = self.pelvis_floor();
        let finger = self.pelvis_finger();
        let Some(goal) = self.motion.lead.out_of_reach(camera, finger, pelvis, t) else {
            return false;
        };
        tracing::debug!("the pelvis finger left posing's reach");
        let label = self
            .nearest_travelling()
            .unwrap_or_else(|| WALKING.to_owned());
        self.walk_to(goal, t, &label, true);
        true
    }

    /// An action of the pelvis that its finger took lower than the body
    /// goes (a squat dragged on down the screen) gives way to a walk
    /// towards where the finger leads: the action is cancelled. Whether it
    /// did.
    pub(super) fn walk_past_action(&mut self, camera: &Camera, t: f64) -> bool {
        let Mode::Action(player) = &self.motion.mode else {
            return false;
        };
        let action = player.action();
        if self.ch.gait.is_empty()
            || self.ch.travels[action]
            || self.ch.actions[action].def.primary != Role::Pelvis
        {
            return false;
        }
        let pelvis = self.pelvis_floor();
        let Some(goal) = self
            .pelvis_finger()
            .and_then(|f| self.motion.lead.below_body(camera, f, pelvis))
        else {
            return false;
        };
        let name = self.ch.actions[action].def.name.clone();
        tracing::debug!(action = %name, "the pelvis finger went lower than the body goes: the action gives way to a walk");
        self.motion.events.push(ActionEvent::Cancelled {
            action: name,
            time_s: t,
        });
        self.walk_to(goal, t, WALKING, true);
        true
    }

    /// Walk to where the pelvis finger leads, if one does (and the
    /// library can walk).
    pub(super) fn start_walk(&mut self, camera: &Camera, t: f64, label: &str) -> bool {
        match self
            .pelvis_finger()
            .map(|f| self.motion.lead.goal(camera, f.at))
        {
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
            (goal, t, self.motion.lead.pace()),
        );
        tracing::debug!(to_x = goal.x, to_z = goal.z, "walking");
        self.motion.events.push(ActionEvent::Started {
            action: label.to_owned(),
            time_s: t,
            by_reach,
            decided: None,
        });
        self.motion.mode = Mode::Walk(Box::new(walker));
        self.motion
            .lead
            .began(label, self.pelvis_finger().map(|f| f.id));
        self.fingers.forget_matches();
    }

    /// One step of the walk; posing again once it is over.
    pub(super) fn walk_step(&mut self, camera: &Camera, t: f64, dt: f64) {
        let finger = self.pelvis_finger();
        let Mode::Walk(walker) = &mut self.motion.mode else {
            return;
        };
        self.motion.lead.steer(walker, camera, finger, t);
        self.target = walker.step(&self.ch.gait, &self.ch.lib.skeleton, dt);
        if walker.done() {
            tracing::debug!("the walk is over: posing");
            let at = self.pelvis_floor();
            self.motion.events.push(ActionEvent::Finished {
                action: self.motion.lead.finished(at),
                time_s: t,
            });
            self.motion.mode = Mode::Posing;
            let at = self.placement_now();
            self.posing.rest(at);
            if !self.held().is_empty() {
                self.begin_posing();
            }
            self.fingers.restart_drags(t);
        }
    }

    /// The path still ahead of a walk under way, on the floor.
    #[must_use]
    pub fn walk_ahead(&self) -> Option<Vec<DVec3>> {
        match &self.motion.mode {
            Mode::Walk(w) => Some(w.ahead()),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A camera 3.6 m in front of the body, looking down at it.
    fn camera() -> Camera {
        Camera {
            eye: DVec3::new(0.0, 1.6, 3.6),
            target: DVec3::new(0.0, 0.8, 0.0),
            fov_y_deg: 40.0,
            width: 1280.0,
            height: 720.0,
        }
    }

    /// The lowest and highest a library takes the pelvis (m).
    const BODY: (f64, f64) = (0.5, 1.0);

    fn finger(from: ScreenPoint, at: ScreenPoint) -> Option<Holding> {
        Some(Holding { id: 7, at, from })
    }

    #[test]
    fn a_finger_across_the_screen_out_of_reach_walks_once_it_stayed_there() {
        let cam = camera();
        let mut lead = Lead::new(0.95, BODY);
        let pelvis = DVec3::ZERO;
        let from = cam.project(DVec3::new(0.0, 0.95, 0.0)).unwrap();
        // Within reach: no walk.
        let near = ScreenPoint::new(from.x + 20.0, from.y);
        assert_eq!(
            lead.out_of_reach(&cam, finger(from, near), pelvis, 0.0),
            None
        );
        // Across the screen, a metre away: not before it stayed 0.1 s.
        let far = cam.project(DVec3::new(1.0, 0.95, 0.0)).unwrap();
        assert_eq!(
            lead.out_of_reach(&cam, finger(from, far), pelvis, 1.0),
            None
        );
        assert_eq!(
            lead.out_of_reach(&cam, finger(from, far), pelvis, 1.05),
            None
        );
        let goal = lead
            .out_of_reach(&cam, finger(from, far), pelvis, 1.1)
            .expect("out of reach for 0.1 s");
        assert!((goal - DVec3::new(1.0, 0.0, 0.0)).length() < 1e-6, "{goal}");
        // Lifted: the wait starts anew.
        assert_eq!(lead.out_of_reach(&cam, None, pelvis, 1.2), None);
        assert_eq!(
            lead.out_of_reach(&cam, finger(from, far), pelvis, 1.25),
            None
        );
    }

    #[test]
    fn a_finger_up_the_screen_walks_only_once_it_points_past_the_body() {
        let cam = camera();
        let mut lead = Lead::new(0.95, BODY);
        let from = cam.project(DVec3::new(0.0, 0.95, 0.0)).unwrap();
        // Up the screen to where the pelvis would stand 5 cm over the
        // highest the body takes it: it moves the pelvis, however long.
        let up = cam.project(DVec3::new(0.0, 1.05, 0.0)).unwrap();
        for k in 0..10 {
            let t = 0.05 * f64::from(k);
            assert_eq!(
                lead.out_of_reach(&cam, finger(from, up), DVec3::ZERO, t),
                None
            );
        }
        // 15 cm over it: away from the camera, once it stayed 0.1 s.
        let past = cam.project(DVec3::new(0.0, 1.15, 0.0)).unwrap();
        assert_eq!(
            lead.out_of_reach(&cam, finger(from, past), DVec3::ZERO, 1.0),
            None
        );
        let goal = lead
            .out_of_reach(&cam, finger(from, past), DVec3::ZERO, 1.1)
            .expect("walks away");
        assert!(goal.z < -WALK_REACH_M && goal.x.abs() < 1e-6, "{goal}");
        assert!((goal - lead.goal(&cam, past)).length() < 1e-9);
    }

    #[test]
    fn a_finger_down_the_screen_past_the_body_hands_its_squat_to_a_walk() {
        let cam = camera();
        let lead = Lead::new(0.95, BODY);
        let held = |y: f64| {
            let at = cam.project(DVec3::new(0.0, y, 0.0)).unwrap();
            Holding {
                id: 7,
                at,
                from: at,
            }
        };
        // As low as the body goes, and 5 cm lower: the squat goes on.
        assert_eq!(lead.below_body(&cam, held(0.5), DVec3::ZERO), None);
        assert_eq!(lead.below_body(&cam, held(0.45), DVec3::ZERO), None);
        // 15 cm lower: a walk towards the camera.
        let goal = lead
            .below_body(&cam, held(0.35), DVec3::ZERO)
            .expect("walks towards the camera");
        assert!(goal.z > WALK_REACH_M && goal.x.abs() < 1e-6, "{goal}");
        // Higher than the body goes is no reason to leave a squat.
        assert_eq!(lead.below_body(&cam, held(1.2), DVec3::ZERO), None);
    }

    #[test]
    fn a_finger_that_walked_walks_on_up_the_screen_and_to_where_it_lifted() {
        let cam = camera();
        let mut lead = Lead::new(0.95, BODY);
        let from = cam.project(DVec3::new(0.0, 0.95, 0.0)).unwrap();
        let away = cam.project(DVec3::new(0.1, 0.95, 1.0)).unwrap();
        assert!((away.y - from.y).abs() > (away.x - from.x).abs());
        // Finger 7 led a walk that ended; it goes on up the screen, a
        // metre away: it walks on there.
        lead.began("walking", Some(7));
        lead.finished(DVec3::ZERO);
        assert_eq!(
            lead.out_of_reach(&cam, finger(from, away), DVec3::ZERO, 0.0),
            None
        );
        let goal = lead
            .out_of_reach(&cam, finger(from, away), DVec3::ZERO, 0.1)
            .expect("walks on");
        assert!((goal - DVec3::new(0.1, 0.0, 1.0)).length() < 1e-6, "{goal}");
        // It lifts out of reach before the walk on began: the character
        // walks to where it lifted, once.
        lead.began("walking", Some(7));
        lead.finished(DVec3::ZERO);
        assert_eq!(
            lead.out_of_reach(&cam, finger(from, away), DVec3::ZERO, 1.0),
            None
        );
        let lifted = lead
            .out_of_reach(&cam, None, DVec3::ZERO, 1.02)
            .expect("walks to the lift");
        assert!((lifted - goal).length() < 1e-6, "{lifted}");
        assert_eq!(lead.out_of_reach(&cam, None, DVec3::ZERO, 1.04), None);
        // A finger that has not walked moves the pelvis up the screen.
        for k in 0..4 {
            let t = 2.0 + 0.05 * f64::from(k);
            assert_eq!(
                lead.out_of_reach(&cam, finger(from, away), DVec3::ZERO, t),
                None
            );
        }
    }

    #[test]
    fn a_walk_is_told_as_it_began_and_follows_its_finger() {
        let mut lead = Lead::new(0.95, BODY);
        lead.began("walk", Some(3));
        assert_eq!(lead.told(), "walk");
        assert_eq!(lead.finished(DVec3::ZERO), "walk");
        assert_eq!(lead.told(), "");
    }
}
