//! The table: one character or several, the camera they share, which
//! finger belongs to which character, and their bodies meeting.
//!
//! - **Ownership.** A finger that goes down on a body part belongs to the
//!   character whose part it is (the nearest part on the screen when two
//!   characters' parts are within reach) until it lifts: only that
//!   character's controller sees it, so posing, action recognition and
//!   playback, tracking and foot IK run per character.
//! - **Camera.** The table owns the camera and decides, for each finger
//!   going down, which character's part it takes (picking through the
//!   camera everyone sees); the controllers receive both. A finger on
//!   empty floor turns, tilts or zooms the camera. With several characters
//!   it does so only while none is held; while one is, such a finger does
//!   nothing until it lifts (a visitor's stray finger never swings the view
//!   from under another visitor's drag), and the view does not follow the
//!   characters while any is held. A lone character's view follows it
//!   always and its floor fingers always turn the camera. Idle, the camera
//!   eases home: for several, a view across the line the characters stand
//!   on, far enough back to frame all of them.
//! - **Contact.** After each step the characters' body capsules are tested
//!   pairwise. Where two overlap they are pushed apart on the floor at once
//!   (the push fades as the bodies recover, feet staying planted), and when
//!   a contact begins with the bodies closing, it is a hit: an impulse on
//!   the struck segment's ragdoll body (and its reaction on the striker's),
//!   which shows through the physical effects (eq. 5-7) on the regions no
//!   finger holds. Every hit is logged and counted.
//!
//! A table of one character is a table like any other: the same calls,
//! the two rules above aside.

use std::borrow::Cow;
use std::collections::{BTreeMap, BTreeSet};

use glam::{DMat4, DVec3};

mod contact;

use super::controller::{Controller, Mode};
use super::marks::{FingerMark, FingerUse, Marks};
use super::rig::{Orbit, Rig};
use crate::character::gltf::{Hold, Skin};
use crate::character::roles::Role;
use crate::character::skeleton::{Pose, WorldPose};
use crate::control::action::timeline::ActionEvent;
use crate::control::posing::pick::pick_with;
use crate::input::touch::{ContactId, Phase, ScreenContact, ScreenFrame, Tool};
use crate::physics::ragdoll::Capsule;
use crate::screen::ScreenPoint;

/// One character on the table.
#[derive(Clone)]
pub struct Actor {
    pub ctl: Controller,
    /// Colour of its clothes (`None`: the default).
    pub tint: Option<[f32; 3]>,
    /// The skinned figure shown for it (`None`: the capsule figure).
    pub figure: Option<std::sync::Arc<crate::character::gltf::Skin>>,
    /// Hits it landed and took.
    pub hits_landed: usize,
    pub hits_taken: usize,
    /// The posture its figure was last posed for, with the figure's
    /// joints, and where the figure's feet came down.
    posed: Option<(WorldPose, Vec<DMat4>)>,
    hold: Hold,
}

impl Actor {
    /// Show `figure` for it (`None`: the capsule figure); a touch on a
    /// glTF figure's surface grabs the part nearest it.
    pub fn set_figure(&mut self, figure: Option<std::sync::Arc<crate::character::gltf::Skin>>) {
        self.figure = figure;
        self.posed = None;
        self.hold = Hold::default();
        self.pose_figure();
    }

    /// Poses its figure for the posture it now has, the figure's feet
    /// staying where they came down in the postures before (done as the
    /// stage advances; see [`crate::character::gltf::Drive::pose_held`]).
    pub fn pose_figure(&mut self) {
        let Some(skin) = self.figure.as_deref() else {
            return;
        };
        let world = self.ctl.world();
        if self.posed.as_ref().is_some_and(|(w, _)| w == world) {
            return;
        }
        let joints = skin.joints_held(world, &mut self.hold);
        self.posed = Some((world.clone(), joints));
    }

    /// Its figure with the joints it is shown with: as last posed, for
    /// the posture it has; posed for that posture alone where it has
    /// changed since.
    #[must_use]
    pub fn figure_joints(&self) -> Option<(&Skin, Cow<'_, [DMat4]>)> {
        let skin = self.figure.as_deref()?;
        let world = self.ctl.world();
        Some(match &self.posed {
            Some((w, joints)) if w == world => (skin, Cow::Borrowed(joints.as_slice())),
            _ => (skin, Cow::Owned(skin.joints(world))),
        })
    }

    /// A character of `ch` at rest at floor point `at` facing `yaw`
    /// (see [`Controller::standing`]), in `tint`.
    #[must_use]
    pub fn standing(
        ch: std::sync::Arc<crate::control::character::Character>,
        settings: super::controller::Settings,
        at: DVec3,
        yaw: f64,
        tint: Option<[f32; 3]>,
    ) -> Self {
        Self::of(Controller::standing(ch, settings, 0.0, at, yaw), tint)
    }

    /// `ctl`'s character, in `tint`, shown as capsules.
    #[must_use]
    pub fn of(ctl: Controller, tint: Option<[f32; 3]>) -> Self {
        Self {
            ctl,
            tint,
            figure: None,
            hits_landed: 0,
            hits_taken: 0,
            posed: None,
            hold: Hold::default(),
        }
    }
}

/// A blow from one character's body on another's.
#[derive(Clone, Debug, PartialEq)]
pub struct Hit {
    pub time_s: f64,
    /// Index of the character whose segment moved into the other.
    pub striker: usize,
    pub struck: usize,
    /// The joints whose segments met.
    pub striker_part: String,
    pub struck_part: String,
    /// Impulse on the struck segment (N·s).
    pub impulse_ns: f64,
    /// How fast the segments closed (m/s).
    pub speed_m_s: f64,
}

/// Whom a finger belongs to.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Owner {
    Character(usize),
    Camera(ScreenPoint),
    /// On empty floor while a character is held: ignored until it lifts.
    Parked(ScreenPoint),
}

/// Contacts closing slower than this are bodies resting against each
/// other, not hits (m/s).
const HIT_SPEED_M_S: f64 = 0.3;
/// Share of a hit's relative velocity kept in the bounce (0 dead, 1
/// elastic).
const RESTITUTION: f64 = 0.3;
/// Passes of pushing apart per step.
const SEPARATION_PASSES: usize = 6;

/// A finger landing on the table or lifting, as the table saw it (for
/// the record of what visitors do).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TouchEvent {
    Down {
        id: ContactId,
        t: f64,
        at: ScreenPoint,
        took: Took,
    },
    Up {
        id: ContactId,
        t: f64,
    },
}

/// What a finger going down took.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Took {
    /// A character's body part.
    Part { character: usize, role: Role },
    /// The camera (a finger on empty floor).
    Camera,
    /// Nothing until it lifts (empty floor while another visitor holds a
    /// character of several).
    Nothing,
}

/// Touch events kept for a caller that takes them; more are dropped (a
/// caller that never takes them keeps no growing list).
const TOUCH_EVENTS_KEPT: usize = 4096;

/// The table's state between frames.
#[derive(Clone)]
pub struct Stage {
    actors: Vec<Actor>,
    /// The camera everyone sees through.
    rig: Rig,
    owners: BTreeMap<ContactId, Owner>,
    /// Each character's capsules last step, for the segments' speeds.
    last: Vec<Vec<Capsule>>,
    /// Segment pairs `(i, a, j, b)` overlapping last step.
    touching: BTreeSet<(usize, usize, usize, usize)>,
    hits: Vec<Hit>,
    /// Deepest overlap left after the last step's separation (m).
    depth_left: f64,
    /// The same for the trunks alone (m).
    trunk_depth_left: f64,
    time: f64,
    last_touch: f64,
    /// Fingers down and up since the caller last took them.
    touches: Vec<TouchEvent>,
}

impl Stage {
    /// A table of `actors` (at least one), its picture `width` x `height`
    /// pixels, at time `t`.
    ///
    /// # Panics
    /// With no actor.
    #[must_use]
    pub fn new(actors: Vec<Actor>, width: f64, height: f64, t: f64) -> Self {
        assert!(!actors.is_empty(), "a table needs a character");
        let mut rig = Rig::new(width, height);
        if actors.len() > 1 {
            rig.home = home_view(&actors, &rig);
            rig.orbit = rig.home;
            rig.target = centre(&actors).with_y(rig.target.y);
        }
        let last = actors.iter().map(|a| caps(&a.ctl)).collect();
        Self {
            actors,
            rig,
            owners: BTreeMap::new(),
            last,
            touching: BTreeSet::new(),
            hits: Vec::new(),
            depth_left: 0.0,
            trunk_depth_left: 0.0,
            time: t,
            last_touch: t,
            touches: Vec::new(),
        }
    }

    /// A table of one character, its picture `width` x `height` pixels,
    /// at the controller's time.
    #[must_use]
    pub fn single(ctl: Controller, width: f64, height: f64) -> Self {
        let t = ctl.time();
        Self::new(vec![Actor::of(ctl, None)], width, height, t)
    }

    #[must_use]
    pub fn actors(&self) -> &[Actor] {
        &self.actors
    }

    pub fn actors_mut(&mut self) -> &mut [Actor] {
        &mut self.actors
    }

    fn many(&self) -> bool {
        self.actors.len() > 1
    }

    /// The camera everyone sees through.
    #[must_use]
    pub fn rig(&self) -> &Rig {
        &self.rig
    }

    pub fn rig_mut(&mut self) -> &mut Rig {
        &mut self.rig
    }

    /// The first character's controller (a lone character's).
    #[must_use]
    pub fn ctl(&self) -> &Controller {
        &self.actors[0].ctl
    }

    /// The first character's posture (a lone character's digest).
    #[must_use]
    pub fn pose(&self) -> &Pose {
        self.actors[0].ctl.pose()
    }

    /// Parts held, over every character.
    #[must_use]
    pub fn held(&self) -> Vec<Role> {
        self.actors.iter().flat_map(|a| a.ctl.held()).collect()
    }

    /// The first action playing (by character order), if any.
    #[must_use]
    pub fn action(&self) -> Option<(String, f64)> {
        self.actors
            .iter()
            .find_map(|a| match (a.ctl.action(), a.ctl.layered()) {
                // A wave laid over a walk: "walk + wave_right".
                (Some((name, time)), Some(l)) => Some((format!("{name} + {}", l.action), time)),
                (Some((name, time)), None) => Some((name.to_owned(), time)),
                (None, Some(l)) => Some((l.action.to_owned(), l.time)),
                (None, None) => None,
            })
    }

    /// Whether any character plays an action.
    #[must_use]
    pub fn any_action(&self) -> bool {
        self.actors
            .iter()
            .any(|a| matches!(a.ctl.mode(), Mode::Action(_)))
    }

    /// Whether a finger on empty floor is moving the camera.
    #[must_use]
    pub fn touching_camera(&self) -> bool {
        self.owners.values().any(|o| matches!(o, Owner::Camera(_)))
    }

    /// Seconds since anyone touched the table.
    #[must_use]
    pub fn idle_s(&self) -> f64 {
        if self.owners.is_empty() {
            self.time - self.last_touch
        } else {
            0.0
        }
    }

    /// Every character back to rest where it stands (see
    /// [`Controller::go_to_rest`]).
    pub fn go_to_rest(&mut self) {
        for a in &mut self.actors {
            a.ctl.go_to_rest();
        }
    }

    /// Action events since the last call, with the character's index.
    pub fn take_events(&mut self) -> Vec<(usize, ActionEvent)> {
        self.actors
            .iter_mut()
            .enumerate()
            .flat_map(|(k, a)| a.ctl.take_events().into_iter().map(move |e| (k, e)))
            .collect()
    }

    /// Fingers that went down (and what each took) and lifted since the
    /// last call.
    pub fn take_touches(&mut self) -> Vec<TouchEvent> {
        std::mem::take(&mut self.touches)
    }

    fn told(&mut self, e: TouchEvent) {
        if self.touches.len() < TOUCH_EVENTS_KEPT {
            self.touches.push(e);
        }
    }

    /// Hits since the last call.
    pub fn take_hits(&mut self) -> Vec<Hit> {
        std::mem::take(&mut self.hits)
    }

    /// Deepest overlap of two characters' bodies left after the last step
    /// (m).
    #[must_use]
    pub fn depth_left(&self) -> f64 {
        self.depth_left
    }

    /// Deepest overlap of two characters' trunks (pelvis to head) left
    /// after the last step (m): limbs can wrap round another body, trunks
    /// are kept apart.
    #[must_use]
    pub fn trunk_depth_left(&self) -> f64 {
        self.trunk_depth_left
    }

    /// A mark for every finger on the table (the part it holds, or the
    /// camera), and each character's trajectories; with several
    /// characters each in its tint.
    #[must_use]
    pub fn marks(&self, trajectories: bool) -> Marks {
        let camera = self.rig.camera();
        let tint = |a: &Actor| if self.many() { a.tint } else { None };
        let mut marks = Marks::default();
        for (id, o) in &self.owners {
            let mark = match *o {
                Owner::Character(k) => {
                    let a = &self.actors[k];
                    a.ctl
                        .finger_mark(*id)
                        .map(|m| FingerMark { tint: tint(a), ..m })
                }
                Owner::Camera(at) | Owner::Parked(at) => Some(FingerMark {
                    at,
                    usage: FingerUse::Camera,
                    tint: None,
                }),
            };
            marks.fingers.extend(mark);
        }
        for a in &self.actors {
            let mut t = a.ctl.trajectory_marks(&camera, trajectories);
            for m in &mut t {
                m.tint = tint(a);
            }
            marks.trajectories.extend(t);
        }
        marks
    }

    /// Apply one frame of touches: a finger going down takes the part
    /// nearest it of the characters within reach, else the camera (or, on
    /// a table of several with a character held, nothing until it
    /// lifts); each character hears its own fingers; fingers on the
    /// camera turn it.
    pub fn touch(&mut self, frame: &ScreenFrame) {
        let camera = self.rig.camera();
        let before: BTreeMap<ContactId, ScreenPoint> = self.camera_fingers().collect();
        let mut per: Vec<(Vec<ScreenContact>, BTreeMap<ContactId, Role>)> =
            vec![Default::default(); self.actors.len()];
        for c in frame.contacts.iter().filter(|c| c.tool == Tool::Finger) {
            let p = c.screen;
            if c.phase == Phase::Down {
                let owner = match self.grabbed(&camera, p) {
                    Some((k, role)) => {
                        self.told(TouchEvent::Down {
                            id: c.id,
                            t: frame.t,
                            at: p,
                            took: Took::Part { character: k, role },
                        });
                        if self.many() {
                            // A character is held now: fingers on the
                            // floor stop moving the camera.
                            for o in self.owners.values_mut() {
                                if let Owner::Camera(at) = *o {
                                    *o = Owner::Parked(at);
                                }
                            }
                        }
                        per[k].0.push(*c);
                        per[k].1.insert(c.id, role);
                        Owner::Character(k)
                    }
                    None if self.many() && self.held_any() => Owner::Parked(p),
                    None => Owner::Camera(p),
                };
                if !matches!(owner, Owner::Character(_)) {
                    self.told(TouchEvent::Down {
                        id: c.id,
                        t: frame.t,
                        at: p,
                        took: if matches!(owner, Owner::Camera(_)) {
                            Took::Camera
                        } else {
                            Took::Nothing
                        },
                    });
                }
                self.owners.insert(c.id, owner);
            } else if c.phase.is_down() {
                match self.owners.get_mut(&c.id) {
                    Some(Owner::Character(k)) => per[*k].0.push(*c),
                    Some(Owner::Camera(at) | Owner::Parked(at)) => *at = p,
                    None => {}
                }
            } else {
                let owner = self.owners.remove(&c.id);
                if owner.is_some() {
                    self.told(TouchEvent::Up {
                        id: c.id,
                        t: frame.t,
                    });
                }
                if let Some(Owner::Character(k)) = owner {
                    per[k].0.push(*c);
                }
            }
        }
        if !frame.contacts.is_empty() {
            self.last_touch = frame.t;
        }
        for (a, (contacts, picked)) in self.actors.iter_mut().zip(per) {
            if !contacts.is_empty() {
                a.ctl.touch(
                    &ScreenFrame {
                        t: frame.t,
                        contacts,
                    },
                    &picked,
                );
            }
        }
        // Fingers on the camera: where each was and is, a gesture.
        let moves: Vec<_> = self
            .camera_fingers()
            .filter_map(|(id, at)| before.get(&id).map(|b| (*b, at)))
            .collect();
        self.rig.gesture(&moves);
    }

    /// The fingers turning the camera, and where each is.
    fn camera_fingers(&self) -> impl Iterator<Item = (ContactId, ScreenPoint)> + '_ {
        self.owners.iter().filter_map(|(id, o)| match o {
            Owner::Camera(at) => Some((*id, *at)),
            _ => None,
        })
    }

    fn held_any(&self) -> bool {
        self.owners
            .values()
            .any(|o| matches!(o, Owner::Character(_)))
    }

    /// The character whose body part a finger at `p` grabs, and the part:
    /// of those with a part within reach, the one whose part is nearest on
    /// the screen.
    fn grabbed(
        &self,
        camera: &crate::character::camera::Camera,
        p: ScreenPoint,
    ) -> Option<(usize, Role)> {
        self.actors
            .iter()
            .enumerate()
            .filter_map(|(k, a)| {
                let ch = a.ctl.character();
                let figure = a.figure_joints();
                let role = pick_with(
                    camera,
                    &ch.lib.skeleton,
                    &ch.roles,
                    a.ctl.world(),
                    figure.as_ref().map(|(s, j)| (*s, j.as_ref())),
                    p,
                    a.ctl.settings.pick_radius_px,
                )?;
                let at = camera.project(a.ctl.world().positions[ch.roles.get(role)])?;
                Some((k, role, at.distance(p)))
            })
            .min_by(|a, b| a.2.total_cmp(&b.2))
            .map(|(k, role, _)| (k, role))
    }

    /// Advance every character to `t`, then let their bodies meet.
    pub fn advance(&mut self, t: f64) {
        let dt = (t - self.time).clamp(0.0, 0.25);
        self.time = t;
        let camera = self.rig.camera();
        for a in &mut self.actors {
            a.ctl.advance(t, &camera);
        }
        if self.many() {
            self.contacts(dt);
        }
        // With several, the view stays put while anyone holds a character:
        // a visitor's drag never moves the camera under another visitor's
        // finger.
        if !self.many() || !self.held_any() {
            let idle = self.idle_s() > self.actors[0].ctl.settings.home_after_s;
            let floor = centre(&self.actors);
            self.rig.settle(floor, idle, dt);
        }
        let camera = self.rig.camera();
        for a in &mut self.actors {
            a.ctl.follow_drift(&camera);
            a.pose_figure();
        }
    }

    /// Touches up to `t`, then advance to `t`.
    pub fn step(&mut self, frames: &[ScreenFrame], t: f64) {
        for f in frames {
            self.touch(f);
        }
        self.advance(t);
    }
}

fn caps(ctl: &Controller) -> Vec<Capsule> {
    ctl.capsules().into_iter().map(|(c, _)| c).collect()
}

/// The middle of the characters' floor points.
fn centre(actors: &[Actor]) -> DVec3 {
    let sum: DVec3 = actors
        .iter()
        .map(|a| {
            let c = a.ctl.character();
            a.ctl.world().positions[c.roles.get(Role::Pelvis)].with_y(0.0)
        })
        .sum();
    sum / actors.len().max(1) as f64
}

/// The home view of several characters: across the line from the first
/// to the last (from its +Z side), far enough back to frame them all.
fn home_view(actors: &[Actor], rig: &Rig) -> Orbit {
    let floor = |a: &Actor| {
        let c = a.ctl.character();
        a.ctl.world().positions[c.roles.get(Role::Pelvis)].with_y(0.0)
    };
    let (first, last) = (floor(&actors[0]), floor(&actors[actors.len() - 1]));
    let line = (last - first).try_normalize().unwrap_or(DVec3::X);
    let mut across = DVec3::new(-line.z, 0.0, line.x);
    if across.z < 0.0 {
        across = -across;
    }
    let c = centre(actors);
    let span = actors
        .iter()
        .map(|a| (floor(a) - c).length())
        .fold(0.0, f64::max);
    let home = Orbit::HOME;
    Orbit {
        yaw: across.x.atan2(across.z),
        pitch: home.pitch,
        distance: (home.distance + span * 1.2)
            .clamp(rig.limits.min_distance, rig.limits.max_distance),
    }
}
