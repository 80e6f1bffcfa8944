//! A visitor who yanks the character, as a recording (`marionette
//! author-abuse`): random multi-finger abuse of the table for as long as
//! asked, the same for a seed. Fingers go down on or near a body part
//! (where a controller fed the same touches shows it then: the character
//! walks, the camera turns) and flick it fast, drag it, hold it, up to
//! five at once; now and then the kernel's buffer overflows
//! (`SYN_DROPPED`) and the moves in it are lost, or a lift is. Replayed
//! with `replay --metrics`, it says whether the body pops, slides or sinks
//! under such treatment.

use std::sync::Arc;

use crate::character::roles::Role;
use crate::control::action::trials::Lcg;
use crate::control::character::Character;
use crate::control::controller::{Controller, Settings};
use crate::control::stage::Stage;
use crate::input::calibration::RawPoint;
use crate::input::touch::{Phase, ScreenContact, ScreenFrame, Tool};
use crate::screen::{Picture, ScreenPoint};
use crate::tools::synth::{Synth, panel};

/// Frame interval of the panel (60 Hz).
const DT_US: i64 = 16_667;
const DT: f64 = DT_US as f64 / 1e6;

/// Axis maximum of the panel.
const MAX: i32 = 4095;

/// Fingers the panel tracks (a visitor and a friend).
const SLOTS: i32 = 5;

/// New fingers go down at this mean rate (per second) while a slot is
/// free.
const DOWN_PER_S: f64 = 2.5;

/// The kernel's buffer overflows this often on average (per second).
const DROPPED_PER_S: f64 = 0.05;

/// What a finger does.
#[derive(Clone, Copy, Debug)]
struct Finger {
    /// The contact the following controller knows it by.
    id: u64,
    at: (f64, f64),
    /// Velocity (px/s) and its turn (rad/s), for curving drags.
    v: (f64, f64),
    turn: f64,
    /// Seconds left before it lifts.
    left: f64,
}

impl Finger {
    /// A finger going down near `aim` on a picture of `size`: a flick
    /// (fast and short), a curving drag or a hold.
    fn new(rng: &mut Lcg, id: u64, aim: ScreenPoint, (w, h): (f64, f64)) -> Self {
        let at = (
            (aim.x + (rng.unit() * 2.0 - 1.0) * 25.0).clamp(0.0, w),
            (aim.y + (rng.unit() * 2.0 - 1.0) * 25.0).clamp(0.0, h),
        );
        let dir = rng.unit() * std::f64::consts::TAU;
        let kind = rng.unit();
        let (speed, left, turn) = if kind < 0.6 {
            // A flick: fast and short.
            (rng.range(800.0, 4000.0), rng.range(0.05, 0.35), 0.0)
        } else if kind < 0.9 {
            // A drag, curving.
            (
                rng.range(100.0, 700.0),
                rng.range(0.4, 3.0),
                rng.range(-3.0, 3.0),
            )
        } else {
            // A hold.
            (0.0, rng.range(0.3, 4.0), 0.0)
        };
        Self {
            id,
            at,
            v: (speed * dir.cos(), speed * dir.sin()),
            turn,
            left,
        }
    }

    /// One step on: the velocity turned, the finger moved, kept on the
    /// picture (`size`).
    fn advance(&mut self, (w, h): (f64, f64)) {
        let (c, s) = (self.turn * DT).sin_cos();
        self.v = (self.v.0 * s - self.v.1 * c, self.v.0 * c + self.v.1 * s);
        self.at = (
            (self.at.0 + self.v.0 * DT).clamp(0.0, w),
            (self.at.1 + self.v.1 * DT).clamp(0.0, h),
        );
    }
}

/// A recording of `seconds` of abuse of `ch` over a picture `picture`.
#[must_use]
pub fn author_abuse(
    ch: &Arc<Character>,
    settings: Settings,
    picture: Picture,
    seconds: f64,
    seed: u64,
) -> Synth {
    let (w, h) = picture.size();
    let size = (f64::from(w), f64::from(h));
    let mut abuse = Abuse {
        rng: Lcg(seed.wrapping_mul(0x2545_f491_4f6c_dd1d) ^ 0x6a09_e667_f3bc_c909),
        synth: Synth::new(panel("marionette abuse panel", SLOTS, MAX)),
        fingers: vec![None; SLOTS as usize],
        next_id: 1,
        size,
    };
    // Where the parts are: a controller fed the same touches.
    let mut table = Stage::single(
        Controller::new(Arc::clone(ch), settings, 0.0),
        size.0,
        size.1,
    );
    abuse.synth.frame(DT_US);
    let mut t = 0.0;
    while t < seconds {
        t += DT;
        let contacts = abuse.frame(ch, &table);
        table.step(&[ScreenFrame { t, contacts }], t);
    }
    for (slot, f) in abuse.fingers.iter().enumerate() {
        if f.is_some() {
            abuse.synth.up(slot as i32);
        }
    }
    abuse.synth.frame(DT_US);
    abuse.synth
}

/// The abuse being written: its random numbers, the recording, the finger
/// in each slot, the next contact id, and the picture's size.
struct Abuse {
    rng: Lcg,
    synth: Synth,
    fingers: Vec<Option<Finger>>,
    next_id: u64,
    size: (f64, f64),
}

impl Abuse {
    /// One frame of every slot: a finger lifts when its time is up (the
    /// lift lost in an overflow now and then), moves, or goes down on a
    /// part of `table`'s character; the touches as the controller sees
    /// them.
    fn frame(&mut self, ch: &Character, table: &Stage) -> Vec<ScreenContact> {
        let (w, h) = self.size;
        let dropping = self.rng.unit() < DROPPED_PER_S * DT;
        let mut touches = Vec::new();
        for (slot, f) in self.fingers.iter_mut().enumerate() {
            let slot = slot as i32;
            match f {
                Some(g) => {
                    g.left -= DT;
                    if g.left <= 0.0 {
                        if dropping && self.rng.unit() < 0.5 {
                            // The lift is lost in the overflow.
                            self.synth.forget(slot);
                        } else {
                            self.synth.up(slot);
                        }
                        touches.push(contact(self.size, g.id, Phase::Up, g.at));
                        *f = None;
                        continue;
                    }
                    g.advance((w, h));
                    if !dropping {
                        let (x, y) = raw(self.size, g.at);
                        self.synth.to(slot, x, y);
                    }
                    touches.push(contact(self.size, g.id, Phase::Move, g.at));
                }
                None if !dropping && self.rng.unit() < DOWN_PER_S * DT => {
                    let role = Role::ALL[(self.rng.unit() * 16.0) as usize % 16];
                    let aim = table
                        .rig()
                        .camera()
                        .project(table.ctl().world().positions[ch.roles.get(role)])
                        .unwrap_or(ScreenPoint::new(w / 2.0, h / 2.0));
                    let g = Finger::new(&mut self.rng, self.next_id, aim, (w, h));
                    let at = g.at;
                    *f = Some(g);
                    touches.push(contact(self.size, self.next_id, Phase::Down, at));
                    self.next_id += 1;
                    let (x, y) = raw(self.size, at);
                    self.synth.down(slot, x, y);
                }
                None => {}
            }
        }
        if dropping {
            self.synth.dropped();
        }
        self.synth.frame(DT_US);
        touches
    }
}

/// A point on a picture of `size` as the panel's raw axes read it.
fn raw((w, h): (f64, f64), p: (f64, f64)) -> (i32, i32) {
    let f = |v: f64, size: f64| ((v / size).clamp(0.0, 1.0) * f64::from(MAX)).round() as i32;
    (f(p.0, w), f(p.1, h))
}

/// A finger's touch as the controller sees it.
fn contact(size: (f64, f64), id: u64, phase: Phase, p: (f64, f64)) -> ScreenContact {
    let (x, y) = raw(size, p);
    ScreenContact {
        id,
        phase,
        tool: Tool::Finger,
        raw: RawPoint { x, y },
        screen: ScreenPoint::new(p.0, p.1),
    }
}
