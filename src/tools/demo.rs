//! Authoring the bundled demo recording against the character itself: each
//! gesture starts where the body part is at that moment, as the controller
//! sees it, so the drags land on the parts and follow the actions'
//! trajectories from the camera's view. The recording is plain evemu;
//! `marionette demo` replays it like any other.

use std::sync::Arc;

use crate::character::roles::Role;
use crate::control::action::timeline::ActionEvent;
use crate::control::action::trail::TrailPoint;
use crate::control::character::Character;
use crate::control::controller::{Controller, Mode, Settings};
use crate::control::locomotion::walker::{path_length, point_along};
use crate::control::stage::Stage;
use crate::control::ticker::Ticker;
use crate::input::config::InputConfig;
use crate::input::pipeline;
use crate::input::touch::Phase;
use crate::screen::{Picture, ScreenPoint};
use crate::tools::eval::layer::SecondFinger;
use crate::tools::synth::{Synth, panel};

/// Frame interval of the authored panel (60 Hz).
const DT_US: i64 = 16_667;
const DT: f64 = DT_US as f64 / 1e6;
/// Controller rate used while authoring (the demo's).
pub const TICK_HZ: f64 = 30.0;
/// The longest a travelling action's drag goes on (s).
const TRAVEL_DRAG_S: f64 = 1.5;
/// The views a library's action is tried from, in order: home, then
/// the camera turned by a drag of this many pixels (about 45 and 90
/// degrees either way at the rig's 0.006 rad a pixel).
const VIEW_TURNS_PX: [f64; 5] = [0.0, 130.0, -130.0, 260.0, -260.0];
/// Axis maximum of the authored panel.
const MAX: i32 = 4095;

#[derive(Clone)]
struct Author<'a> {
    synth: Synth,
    ctl: Stage,
    ticker: Ticker,
    input: &'a InputConfig,
    picture: Picture,
    width: f64,
    height: f64,
    time: f64,
    /// Actions are dragged along their clip drawn longest (else along the
    /// action's average trajectory, as the default demo was authored).
    from_template: bool,
}

impl<'a> Author<'a> {
    /// A panel named `name` over `stage`: its first frame, then a breath.
    fn start(name: &str, stage: Stage, input: &'a InputConfig, picture: Picture) -> Self {
        let (width, height) = picture.size();
        let mut a = Author {
            synth: Synth::new(panel(name, 10, MAX)),
            ctl: stage,
            ticker: Ticker::new(Vec::new(), TICK_HZ),
            input,
            picture,
            width: f64::from(width),
            height: f64::from(height),
            time: 0.0,
            from_template: false,
        };
        a.frame();
        a.wait(0.8);
        a
    }

    /// The demo panel over one character standing at the origin.
    fn alone(
        ch: Arc<Character>,
        settings: Settings,
        input: &'a InputConfig,
        picture: Picture,
    ) -> Self {
        let (w, h) = picture.size();
        let controller = Controller::new(ch, settings, 0.0);
        Self::start(
            "marionette demo panel",
            Stage::single(controller, f64::from(w), f64::from(h)),
            input,
            picture,
        )
    }

    /// Run the controller over what is authored so far.
    fn sync(&mut self) {
        let rec = self.synth.finish();
        let frames = pipeline::replay(&rec, self.input, self.picture)
            .expect("the authored panel calibrates");
        self.ticker.extend(frames);
        while self.ticker.time() + 1.0 / TICK_HZ <= self.time + 1e-9 {
            self.ticker.step(&mut self.ctl);
        }
    }

    fn raw(&self, p: ScreenPoint) -> (i32, i32) {
        let f = |v: f64, size: f64| ((v / size).clamp(0.0, 1.0) * f64::from(MAX)).round() as i32;
        (f(p.x, self.width), f(p.y, self.height))
    }

    fn frame(&mut self) {
        self.synth.frame(DT_US);
        self.time += DT;
    }

    fn wait(&mut self, s: f64) {
        let n = (s / DT).round() as usize;
        for _ in 0..n {
            self.frame();
        }
    }

    /// Where a body part of the first character is on the screen now.
    fn part(&mut self, role: Role) -> ScreenPoint {
        self.part_of(0, role)
    }

    /// Where a body part of character `k` is on the screen now.
    fn part_of(&mut self, k: usize, role: Role) -> ScreenPoint {
        self.sync();
        let cam = self.ctl.rig().camera();
        let c = &self.ctl.actors()[k].ctl;
        let p = c.world().positions[c.character().roles.get(role)];
        cam.project(p)
            .unwrap_or(ScreenPoint::new(self.width / 2.0, self.height / 2.0))
    }

    fn down(&mut self, slot: i32, p: ScreenPoint) {
        let (x, y) = self.raw(p);
        self.synth.down(slot, x, y);
    }

    fn to(&mut self, slot: i32, p: ScreenPoint) {
        let (x, y) = self.raw(p);
        self.synth.to(slot, x, y);
    }

    /// Move fingers along paths given as functions of 0..1, over `s`
    /// seconds, easing in and out.
    fn glide(&mut self, fingers: &[(i32, &dyn Fn(f64) -> ScreenPoint)], s: f64) {
        let n = (s / DT).round().max(1.0) as usize;
        for k in 1..=n {
            let u = k as f64 / n as f64;
            let e = u * u * (3.0 - 2.0 * u);
            for (slot, path) in fingers {
                self.to(*slot, path(e));
            }
            self.frame();
        }
    }

    /// Drag the pelvis along a floor path (`path`: metres in the
    /// character's frame as it stands now, x to its right, z ahead, from
    /// its pelvis) at `speed` m/s, the finger kept over each point at the
    /// pelvis's height as the camera shows it then; lift at the end and
    /// wait for the walk to end.
    /// With `layer`, a second finger drags that action on the upper body
    /// as the character walks (see [`SecondFinger`]).
    fn walk_along(&mut self, path: &[(f64, f64)], speed: f64, layer: Option<&str>) {
        let mut second = layer
            .and_then(|name| {
                let c = &self.ctl.actors()[0].ctl;
                c.character()
                    .actions
                    .iter()
                    .position(|a| a.def.name == name)
            })
            .map(SecondFinger::new);
        let start = self.part(Role::Pelvis);
        let c = &self.ctl.actors()[0].ctl;
        let pelvis = c.world().positions[c.character().roles.get(Role::Pelvis)];
        let turn = glam::DQuat::from_rotation_y(c.placement_now().yaw);
        let points: Vec<glam::DVec3> = path
            .iter()
            .map(|(x, z)| pelvis + turn * glam::DVec3::new(-x, 0.0, *z))
            .collect();
        let total = path_length(&points);
        self.down(0, start);
        self.frame();
        let mut s = 0.0;
        while s < total {
            s = (s + speed * DT).min(total);
            let p = point_along(&points, s);
            self.sync();
            let at = self.ctl.rig().camera().project(p).unwrap_or(start);
            self.to(0, at);
            if let Some(f) = second.as_mut() {
                self.second_finger(f);
            }
            self.frame();
        }
        self.synth.up(0);
        self.frame();
        // The layered action's finger goes its way to the end.
        if let Some(f) = second.as_mut() {
            for _ in 0..300 {
                if f.lifted() {
                    break;
                }
                self.second_finger(f);
                self.frame();
            }
        }
        self.settle();
    }

    /// The second finger's touch in this frame (slot 1).
    fn second_finger(&mut self, f: &mut SecondFinger) {
        self.sync();
        let c = self.ctl.ctl();
        let camera = self.ctl.rig().camera();
        match f.contact(c.character(), c, &camera, self.time) {
            Some((Phase::Down, p)) => self.down(1, p),
            Some((Phase::Up, _)) => {
                self.synth.up(1);
            }
            Some((_, p)) => self.to(1, p),
            None => {}
        }
    }

    /// Drag an action's primary part along its trajectory as seen now, at
    /// the action's own speed, through its first 70 % and on to its
    /// farthest point from where it began if that comes later (a kick's
    /// foot returns to where it started, which would leave the finger's
    /// place ambiguous), then lift and wait for the action to finish by
    /// itself.
    fn action(&mut self, name: &str) {
        self.actions(&[(0, 0, name)]);
    }

    /// Character `k`'s action `name` planned as a drag of its trajectory
    /// by the finger in `slot` (put down on the part), ending where it is
    /// farthest from its start (a walk's after a few steps); `None` where
    /// the character has no such action or it draws nothing.
    fn plan_drag(&mut self, k: usize, slot: i32, name: &str) -> Option<Drag> {
        let index = self.ctl.actors()[k]
            .ctl
            .character()
            .actions
            .iter()
            .position(|a| a.def.name == name)?;
        let role = self.ctl.actors()[k].ctl.character().actions[index]
            .def
            .primary;
        let start = self.part_of(k, role);
        let cam = self.ctl.rig().camera();
        let c = &self.ctl.actors()[k].ctl;
        let at = c.placement_now();
        let model = &c.character().actions[index];
        let traj = if self.from_template {
            model.most_drawn(&cam, &at)
        } else {
            model.projected(&cam, &at)
        };
        let first = traj.first().copied()?;
        let end = traj
            .iter()
            .max_by(|a, b| {
                let d = |p: &TrailPoint| p.at.distance(first.at);
                d(a).total_cmp(&d(b))
            })
            .map_or(0.0, |p| p.t)
            .max(0.7 * traj.last().map_or(0.0, |p| p.t));
        // A walk's drag walks the character along it: a few steps,
        // not the take's whole length, so it stays in view.
        let end = if c.character().travels[index] && !c.character().gait.is_empty() {
            end.min(TRAVEL_DRAG_S)
        } else {
            end
        };
        self.down(slot, start);
        Some(Drag {
            slot,
            offset: (start.x - first.at.x, start.y - first.at.y),
            traj,
            end,
        })
    }

    /// Several drags at once, `(character, finger slot, action)`, each as
    /// [`Self::action`] describes; all lift once the last has gone its way.
    fn actions(&mut self, drags: &[(usize, i32, &str)]) {
        let mut planned = Vec::new();
        for &(k, slot, name) in drags {
            if let Some(d) = self.plan_drag(k, slot, name) {
                planned.push(d);
            }
        }
        if planned.is_empty() {
            return;
        }
        self.frame();
        let last = planned.iter().map(|d| d.end).fold(0.0, f64::max);
        let mut t = 0.0;
        while t < last {
            t += DT;
            for d in &planned {
                if t - DT >= d.end {
                    continue;
                }
                let traj = &d.traj;
                let k = traj.partition_point(|p| p.t <= t).clamp(1, traj.len() - 1);
                let (a, b) = (traj[k - 1], traj[k]);
                let s = ((t - a.t) / (b.t - a.t).max(1e-9)).clamp(0.0, 1.0);
                self.to(
                    d.slot,
                    ScreenPoint::new(
                        a.at.x + (b.at.x - a.at.x) * s + d.offset.0,
                        a.at.y + (b.at.y - a.at.y) * s + d.offset.1,
                    ),
                );
            }
            self.frame();
        }
        self.wait(0.1);
        for d in &planned {
            self.synth.up(d.slot);
        }
        self.frame();
        self.settle();
    }

    /// Whether dragging action `name` as [`Self::action`] does starts it
    /// and plays it through, from the view turned by a camera drag of
    /// `turn_px` pixels: tried on a copy of the table, nothing authored.
    fn starts(&self, turn_px: f64, name: &str) -> bool {
        let mut trial = self.clone();
        trial.sync();
        trial.ctl.take_events();
        if turn_px != 0.0 {
            trial.turn(turn_px);
        }
        trial.action(name);
        // A long action may still be playing: to its end (at most 20 s).
        for _ in 0..200 {
            trial.sync();
            if trial
                .ctl
                .actors()
                .iter()
                .all(|a| matches!(a.ctl.mode(), Mode::Posing))
            {
                break;
            }
            trial.wait(0.1);
        }
        // Started and played through (not let go in its wind-up): a start
        // comes before its end, so its finish tells both.
        trial
            .ctl
            .take_events()
            .iter()
            .any(|(_, e)| matches!(e, ActionEvent::Finished { action, .. } if action == name))
    }

    /// Turn the view: one finger on empty floor near the picture's lower
    /// left corner goes `dx` pixels across and lifts.
    fn turn(&mut self, dx: f64) {
        let empty = ScreenPoint::new(self.width * 0.12, self.height * 0.85);
        self.down(0, empty);
        self.frame();
        self.glide(
            &[(0, &|u| ScreenPoint::new(empty.x + dx * u, empty.y))],
            0.8,
        );
        self.synth.up(0);
        self.frame();
        self.wait(0.3);
    }

    /// Let the characters finish what they do (at most 4 s), then a
    /// breath.
    fn settle(&mut self) {
        for _ in 0..40 {
            self.wait(0.1);
            self.sync();
            if self
                .ctl
                .actors()
                .iter()
                .all(|a| matches!(a.ctl.mode(), Mode::Posing) && a.ctl.layered().is_none())
            {
                break;
            }
        }
        self.wait(0.6);
    }
}

/// The demo recording: five actions started by drags (punch, kick, wave,
/// bow, jump), a walk along a curve to where the finger lifts, posing with one finger and with two, a part pinned by
/// one finger while another poses, camera turns and a pinch, and a rest
/// while the camera eases home.
#[must_use]
pub fn author_demo(
    ch: Arc<Character>,
    settings: Settings,
    input: &InputConfig,
    picture: Picture,
) -> Synth {
    let mut a = Author::alone(ch, settings, input, picture);
    for name in ["punch_left", "kick_right", "wave_left", "bow", "jump"] {
        a.action(name);
    }
    // A walk along a curve across the floor, to where the finger lifts.
    a.walk_along(
        &[
            (0.0, 0.0),
            (0.5, 0.15),
            (0.95, 0.5),
            (1.15, 1.0),
            (1.0, 1.4),
        ],
        0.9,
        None,
    );
    // Back across the floor, waving the right hand as it walks: a second
    // finger drags the wave while the first leads the pelvis.
    a.walk_along(
        &[(0.0, 0.0), (0.2, 0.7), (0.35, 1.4), (0.4, 2.1)],
        0.7,
        Some("wave_right"),
    );
    a.posing_tour(settings.home_after_s);
    a.synth
}

/// A demo recording for any library, authored against its own character
/// as the default one is: every action (mirror images included) dragged
/// along the path its primary part takes in the clip drawn longest from
/// the home view, then
/// the posing tour of [`author_demo`] (one finger, two, a pinned foot, the
/// camera turned and pinched, the table at rest). Returns the recording and
/// the actions it drags, in order.
#[must_use]
pub fn author_library_demo(
    ch: Arc<Character>,
    settings: Settings,
    input: &InputConfig,
    picture: Picture,
) -> (Synth, Vec<String>) {
    let names: Vec<String> = ch.actions.iter().map(|a| a.def.name.clone()).collect();
    let mut a = Author::alone(ch, settings, input, picture);
    a.from_template = true;
    for name in &names {
        // As a visitor is told to (`library check`): an action that a drag
        // from this view does not start is dragged from a turned one.
        match VIEW_TURNS_PX.into_iter().find(|&px| a.starts(px, name)) {
            Some(px) if px != 0.0 => {
                tracing::info!(action = %name, turn_px = px, "dragged from a turned view");
                a.turn(px);
                a.action(name);
                a.turn(-px);
            }
            _ => a.action(name),
        }
    }
    a.posing_tour(settings.home_after_s);
    (a.synth, names)
}

impl Author<'_> {
    /// Posing with one finger and with two, a part pinned by one finger
    /// while another poses, camera turns and a pinch, and a rest while the
    /// camera eases home (after `home_after_s` and a little more).
    fn posing_tour(&mut self, home_after_s: f64) {
        self.pose_hands();
        self.pin_a_foot();
        self.turn_the_view();
        // Idle: the camera eases back home.
        self.wait(home_after_s + 3.5);
    }

    /// One finger poses the right hand (up and out, held, let go), then two
    /// fingers pose both hands.
    fn pose_hands(&mut self) {
        let a = self;
        // One finger poses the right hand: up and out, held, let go.
        let hand = a.part(Role::RightHand);
        a.down(0, hand);
        a.frame();
        a.glide(
            &[(0, &|u| {
                ScreenPoint::new(hand.x - 90.0 * u, hand.y - 230.0 * u)
            })],
            1.8,
        );
        a.wait(0.5);
        a.synth.up(0);
        a.frame();
        a.wait(0.6);
        // Two fingers pose both hands.
        let (l, r) = (a.part(Role::LeftHand), a.part(Role::RightHand));
        a.down(0, l);
        a.down(1, r);
        a.frame();
        a.glide(
            &[
                (0, &|u| ScreenPoint::new(l.x + 60.0 * u, l.y - 200.0 * u)),
                (1, &|u| ScreenPoint::new(r.x - 40.0 * u, r.y + 140.0 * u)),
            ],
            1.8,
        );
        a.wait(0.4);
        a.synth.up(0).up(1);
        a.frame();
        a.wait(0.6);
    }

    /// A foot pinned by one finger while another moves the other hand
    /// around.
    fn pin_a_foot(&mut self) {
        let a = self;
        let foot = a.part(Role::LeftFoot);
        a.down(0, foot);
        a.frame();
        a.wait(0.4);
        // Holding the foot alone re-poses the body: find the hand afterwards.
        let hand = a.part(Role::LeftHand);
        a.down(1, hand);
        a.frame();
        a.glide(
            &[
                (0, &|_| foot),
                (1, &|u| {
                    let ang = u * std::f64::consts::PI;
                    ScreenPoint::new(hand.x + 120.0 * ang.sin(), hand.y - 160.0 * u)
                }),
            ],
            2.2,
        );
        a.wait(0.3);
        a.synth.up(1);
        a.frame();
        a.synth.up(0);
        a.frame();
        a.wait(0.6);
    }

    /// One finger on empty space turns the view, then two pinch and twist.
    fn turn_the_view(&mut self) {
        let a = self;
        let (width, height) = (a.width, a.height);
        let empty = ScreenPoint::new(width * 0.12, height * 0.85);
        a.down(0, empty);
        a.frame();
        a.glide(
            &[(0, &|u| {
                ScreenPoint::new(empty.x + 260.0 * u, empty.y - 40.0 * u)
            })],
            1.4,
        );
        a.synth.up(0);
        a.frame();
        a.wait(0.3);
        let (c, d) = (
            ScreenPoint::new(width * 0.15, height * 0.55),
            ScreenPoint::new(width * 0.3, height * 0.55),
        );
        a.down(0, c);
        a.down(1, d);
        a.frame();
        a.glide(
            &[
                (0, &|u| ScreenPoint::new(c.x - 60.0 * u, c.y + 30.0 * u)),
                (1, &|u| ScreenPoint::new(d.x + 60.0 * u, d.y - 30.0 * u)),
            ],
            1.4,
        );
        a.synth.up(0).up(1);
        a.frame();
        a.wait(0.5);
    }
}

/// An action's drag being played: its finger's slot, the trajectory, the
/// finger's offset from it and when the drag ends.
struct Drag {
    slot: i32,
    traj: Vec<TrailPoint>,
    offset: (f64, f64),
    end: f64,
}

/// The duel recording, for a table of two characters facing each other
/// (the first on the left of the home view, the second on the right): both
/// visitors grab their character at once and raise its hands, then each
/// starts actions by drags, the first punching, the second kicking back,
/// then both at once.
#[must_use]
pub fn author_duel(stage: Stage, input: &InputConfig, picture: Picture) -> Synth {
    let mut a = Author::start("marionette duel panel", stage, input, picture);
    // Both characters held at once: each visitor raises a hand.
    let (l, r) = (a.part_of(0, Role::RightHand), a.part_of(1, Role::LeftHand));
    a.down(0, l);
    a.down(1, r);
    a.frame();
    a.glide(
        &[
            (0, &|u| ScreenPoint::new(l.x - 30.0 * u, l.y - 170.0 * u)),
            (1, &|u| ScreenPoint::new(r.x + 30.0 * u, r.y - 170.0 * u)),
        ],
        1.5,
    );
    a.wait(0.4);
    a.synth.up(0).up(1);
    a.frame();
    a.wait(1.0);
    // The first punches, the second kicks back, then both at once.
    a.actions(&[(0, 0, "punch_right")]);
    a.actions(&[(1, 1, "kick_left")]);
    a.actions(&[(0, 0, "kick_right"), (1, 1, "punch_left")]);
    a.wait(1.5);
    a.synth
}
