//! The character controller: one call per frame turns the touches into the
//! character's posture, following the paper. A finger that goes down on a
//! body part holds it until it lifts (posing control, section 4); a drag
//! that matches an action's trajectory starts the action, which the
//! fingers then drive (action control, section 5), and at its end the
//! character returns to posing; the output follows the target posture by
//! acceleration-based tracking (section 6). The table
//! ([`crate::control::stage`]) owns the camera and decides which part a
//! finger takes; a controller receives both. Time comes only from the
//! frames and the caller's clock, so a replay gives the same postures
//! every run.

use std::collections::BTreeMap;
use std::sync::Arc;

use glam::DVec3;

mod actions;
mod contact;
mod effects;
mod feet;
mod fingers;
mod jerk;
mod layer;
mod posing;
mod shown;
mod step;
#[cfg(test)]
mod testbody;
mod walk;

use self::feet::Feet;
use self::fingers::{Fingers, Grab, Matching};
pub use self::layer::Layered;
pub use self::walk::{WALK_REACH_M, WALKING, floor_point};
use super::character::Character;
use crate::character::body::{Anchor, Placement, leg_length_shorter};
use crate::character::camera::Camera;
use crate::character::roles::Role;
use crate::character::skeleton::{Pose, WorldPose, forward_kinematics};
use crate::control::action::player::ActionPlayer;
use crate::control::action::timeline::ActionEvent;
use crate::control::action::trail::StartRule;
use crate::control::posing::constraint::Constraint;
use crate::input::touch::{ContactId, ScreenFrame};
use crate::physics::effects::Attenuation;

/// How the controller behaves; the recognition thresholds come from the
/// configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// Which recogniser starts actions.
    pub recogniser: RecogniserKind,
    /// The paper's start rule (for [`RecogniserKind::Paper`]).
    pub rule: StartRule,
    /// A finger within this distance of a body part grabs it (px).
    pub pick_radius_px: f64,
    /// The camera eases back home after this long without a touch (s).
    pub home_after_s: f64,
    /// Tracking control settles in about this long (s); 0 turns tracking
    /// off (the output is the synthesised posture).
    pub settle_s: f64,
    /// A finger resting this long starts a new drag for recognition (s).
    pub rest_s: f64,
    /// Physics-based tracking: the ragdoll's physical effects (eq. 5–7)
    /// are added to the tracked posture (needs tracking on).
    pub physics: bool,
    /// Attenuation of the physical effects (eq. 6).
    pub attenuation: Attenuation,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            recogniser: RecogniserKind::default(),
            rule: StartRule::default(),
            pick_radius_px: 45.0,
            home_after_s: 8.0,
            settle_s: 0.12,
            rest_s: 0.8,
            physics: true,
            attenuation: Attenuation::default(),
        }
    }
}

/// Which recogniser starts actions from drags.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RecogniserKind {
    /// One template per clip, thresholds calibrated for the library
    /// ([`crate::control::action::recogniser`]).
    #[default]
    Templates,
    /// The paper's: the average trajectory and the configured start rule.
    Paper,
}

/// Posing, or playing an action.
#[derive(Clone, Debug)]
pub enum Mode {
    Posing,
    Action(Box<ActionPlayer>),
    /// Walking where the pelvis finger leads.
    Walk(Box<crate::control::locomotion::walker::Walker>),
}

/// The controller's state between frames.
#[derive(Clone)]
pub struct Controller {
    ch: Arc<Character>,
    pub settings: Settings,
    /// What the body does: posing, an action or a walk, and what is laid
    /// over it.
    motion: Motion,
    /// The fingers on the table and what they hold.
    fingers: Fingers,
    /// Where posing places its samples, and the feet it keeps.
    posing: posing::Posing,
    target: Pose,
    /// The posture tracking shows, and its world pose.
    shown: shown::Shown,
    /// The feet that carry the body: planted, stepping, sweeping.
    feet: Feet,
    /// Physics-based tracking: the ragdoll, the effects taken from it,
    /// and a push from another body fading.
    physical: effects::Physical,
    time: f64,
}

/// What the body does, and what it has told since the caller last asked.
#[derive(Clone)]
struct Motion {
    /// Posing, an action playing, or a walk.
    mode: Mode,
    /// Where a finger on the pelvis leads, for walking, and what the walk
    /// under way is told as.
    lead: walk::Lead,
    /// An arm or head action laid over the walk (or an action led by the
    /// legs), and where the pelvis went on the screen while walking.
    layering: layer::Layering,
    /// Actions started and finished, for the caller.
    events: Vec<ActionEvent>,
}

/// The longest drag kept for recognition (s): longer than any action.
const MAX_TRAIL_S: f64 = 4.0;

/// Longest tracking sub-step (s): explicit integration stays stable.
pub const MAX_SUBSTEP: f64 = 0.004;

/// The lowest and highest the library's postures take the pelvis over
/// the floor (m).
fn pelvis_range(ch: &Character) -> (f64, f64) {
    let pelvis = ch.roles.get(Role::Pelvis);
    ch.posing
        .samples
        .iter()
        .filter_map(|s| s.aligned.get(pelvis).map(|p| p.y))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), y| {
            (lo.min(y), hi.max(y))
        })
}

impl Controller {
    /// A character at rest at the origin facing +Z, at time `t`
    /// (seconds).
    #[must_use]
    pub fn new(ch: Arc<Character>, settings: Settings, t: f64) -> Self {
        Self::standing(ch, settings, t, DVec3::ZERO, 0.0)
    }

    /// A character at rest at floor point `position` facing `yaw`
    /// (radians from +Z, positive towards +X).
    #[must_use]
    pub fn standing(
        ch: Arc<Character>,
        settings: Settings,
        t: f64,
        position: DVec3,
        yaw: f64,
    ) -> Self {
        let at = Placement {
            position: position.with_y(0.0),
            yaw,
            anchor: Anchor::ClipStart,
        };
        let pose = ch.rest_pose(&at);
        let world = forward_kinematics(&ch.lib.skeleton, &pose);
        let pelvis_h = world.positions[ch.roles.get(Role::Pelvis)].y;
        Self {
            physical: effects::Physical::new(
                &ch.lib.skeleton,
                &ch.roles,
                &world,
                settings.attenuation,
            ),
            feet: Feet::new(
                &ch.roles,
                &world,
                leg_length_shorter(&ch.lib.skeleton, &ch.roles),
            ),
            settings,
            motion: Motion {
                mode: Mode::Posing,
                lead: walk::Lead::new(pelvis_h, pelvis_range(&ch)),
                layering: layer::Layering::default(),
                events: Vec::new(),
            },
            fingers: Fingers::default(),
            posing: posing::Posing::new(at),
            shown: shown::Shown::new(pose.clone(), world),
            target: pose,
            time: t,
            ch,
        }
    }

    /// The character.
    #[must_use]
    pub fn character(&self) -> &Character {
        &self.ch
    }

    /// The posture shown now.
    #[must_use]
    pub fn pose(&self) -> &Pose {
        self.shown.pose()
    }

    /// The posture asked for now (before tracking and the physical
    /// effects).
    #[must_use]
    pub fn target(&self) -> &Pose {
        &self.target
    }

    /// World transforms of the posture shown now.
    #[must_use]
    pub fn world(&self) -> &WorldPose {
        self.shown.world()
    }

    #[must_use]
    pub fn mode(&self) -> &Mode {
        &self.motion.mode
    }

    /// The action playing (or the walk under way, with how much of its
    /// path is behind), if any.
    #[must_use]
    pub fn action(&self) -> Option<(&str, f64)> {
        match &self.motion.mode {
            Mode::Action(p) => Some((self.ch.actions[p.action()].def.name.as_str(), p.time())),
            Mode::Walk(w) => Some((self.motion.lead.told(), w.progress())),
            Mode::Posing => None,
        }
    }

    /// Action events since the last call.
    pub fn take_events(&mut self) -> Vec<ActionEvent> {
        std::mem::take(&mut self.motion.events)
    }

    /// Body parts held by fingers.
    #[must_use]
    pub fn held(&self) -> Vec<Role> {
        self.fingers.held()
    }

    /// Trail points kept for recognition, over all fingers (bounded).
    #[must_use]
    pub fn trail_points(&self) -> usize {
        self.fingers.trail_points()
    }

    /// The time of the last step (s).
    #[must_use]
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Where the character stands now (clip-start anchoring, for actions).
    #[must_use]
    pub fn placement_now(&self) -> Placement {
        Placement {
            anchor: Anchor::ClipStart,
            ..Placement::of(&self.ch.lib.skeleton, &self.ch.roles, &self.target)
        }
    }

    /// Return to the rest posture where the character stands (tracking
    /// makes it a smooth motion); an action playing is left to finish.
    /// For a kiosk nobody has touched for a while.
    pub fn go_to_rest(&mut self) {
        if matches!(self.motion.mode, Mode::Posing) && self.fingers.none_down() {
            let at = self.placement_now();
            self.target = self.ch.rest_pose(&at);
            self.posing.rest(at);
        }
    }

    /// Apply one frame of this body's touches (its time is `frame.t`):
    /// a finger going down takes the part the table `picked` for it; a
    /// part taken while none was held begins posing anew where the feet
    /// stand.
    pub fn touch(&mut self, frame: &ScreenFrame, picked: &BTreeMap<ContactId, Role>) {
        let first_part = self.fingers.touch(frame, self.settings.rest_s, picked);
        if first_part && matches!(self.motion.mode, Mode::Posing) {
            self.begin_posing();
        }
    }

    /// Posing begins anew: the feet kept where they stand.
    fn begin_posing(&mut self) {
        let w = forward_kinematics(&self.ch.lib.skeleton, &self.target);
        let r = &self.ch.roles;
        self.posing.begin([
            w.positions[r.get(Role::LeftFoot)],
            w.positions[r.get(Role::RightFoot)],
        ]);
    }

    /// The posing constraints of the parts the fingers hold, seen through
    /// `camera`.
    fn constraints(&self, camera: &Camera) -> Vec<Constraint> {
        let r = &self.ch.roles;
        self.fingers.constraints(
            camera,
            |role| self.shown.world().positions[r.get(role)],
            self.feet.ankle_rest(),
        )
    }

    /// The mark of finger `id`, if it holds one of this body's parts.
    #[must_use]
    pub fn finger_mark(&self, id: ContactId) -> Option<crate::control::marks::FingerMark> {
        self.fingers.mark(id)
    }
}
