//! Walking along a finger's path, measured (`marionette eval walk`): the
//! pelvis is dragged along floor paths through a whole controller, as live
//! touches are (the kiosk's home view; the finger put each frame over the
//! path's point at the pelvis's standing height, as the picture shows it
//! then), and the walk is judged: did it reach the path's end, how far
//! from it did it settle, how far did it stray from the path, did planted
//! feet slide, did joints pop, how soon did it step, how fast did it go
//! for the finger's speed, did it stand where the finger stopped; a row
//! for each family of paths (see [`super::walk_paths`]).

use std::sync::Arc;

use glam::DVec3;
use serde::Serialize;

use super::walk_paths::world_points;
pub use super::walk_paths::{
    FAMILIES, WalkPath, check_paths, random_curves, random_paths, read_paths,
};
use crate::character::roles::Role;
use crate::control::character::Character;
use crate::control::controller::{Controller, Mode, Settings};
use crate::control::locomotion::walker::{path_length, point_along};
use crate::control::stage::Stage;
use crate::input::touch::{Phase, ScreenContact, ScreenFrame, Tool};
use crate::tools::eval::layer::{LayerReport, LayerRow, SecondFinger, summarise};
use crate::tools::metrics::Meter;

/// The frame rate the walk is stepped and measured at (as replays are).
const HZ: f64 = 30.0;

/// A path's end reached within this distance (m) counts as followed.
pub const FOLLOWED_M: f64 = 0.3;

/// A walk's speed along the path is measured from this long after its
/// first step (s, under way)...
const SPEED_FROM_S: f64 = 0.5;
/// ...until it is this far from the path's end (m, a stride: where it
/// slows to stand)...
const SPEED_UNTIL_M: f64 = 0.6;
/// ...over at least this long (s).
const SPEED_OVER_S: f64 = 0.5;
/// How far back and ahead along the path (m) the pelvis's place on it is
/// looked for, from where it was (a path that crosses itself is followed
/// in order).
const ALONG_BACK_M: f64 = 0.1;
const ALONG_AHEAD_M: f64 = 0.8;

/// A character stands where the finger stopped when, before the finger
/// moves on, neither foot has moved more than this (m) over
/// [`STOOD_OVER_S`] with its pelvis within [`FOLLOWED_M`] of the finger
/// (the finger still holds the pelvis: posing leans it there).
const STOOD_M: f64 = 0.01;
const STOOD_OVER_S: f64 = 0.2;

/// One path's figures.
#[derive(Clone, Debug, Default, Serialize)]
pub struct WalkRow {
    pub family: String,
    pub length_m: f64,
    pub speed_mps: f64,
    pub followed: bool,
    pub arrival_cm: f64,
    pub deviation_cm: f64,
    pub skate_mm: f64,
    pub skate_max_mm: f64,
    pub pops: usize,
    /// The first pops: time (s from the finger going down), joint, jump.
    pub pop_list: Vec<String>,
    /// The worst slide of a planted foot: which, and when.
    pub worst_skate: String,
    /// From the finger leaving posing's reach to the first step (s); -1
    /// if the character never stepped.
    pub start_s: f64,
    /// The character's speed along the path (how fast its place on the
    /// path moves on) over the finger's, from [`SPEED_FROM_S`] after its first step until [`SPEED_UNTIL_M`] from
    /// the end; none where that is shorter than [`SPEED_OVER_S`] or the
    /// finger stopped on the way.
    pub speed_ratio: Option<f64>,
    /// Whether the library has a gait as fast as the finger (its fastest
    /// locomotion clip's steady speed is the finger's or more): only then
    /// is `speed_ratio` a fair figure of the walk.
    pub in_gait: bool,
    /// Of the finger's stops, the share in which the character came to
    /// stand by the finger before it went on; none where it did not stop.
    pub stood: Option<f64>,
    /// The action a second finger laid over the walk, if one was asked.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub layered: Option<LayerRow>,
}

/// The figures of a set of walks (all, or a family's).
#[derive(Clone, Debug, Default, Serialize)]
pub struct FamilyRow {
    pub family: String,
    pub paths: usize,
    pub followed: f64,
    pub arrival_cm: f64,
    pub arrival_worst_cm: f64,
    pub deviation_cm: f64,
    pub skate_mm: f64,
    pub skate_max_mm: f64,
    pub pops: usize,
    /// Mean over the walks that stepped.
    pub start_s: f64,
    /// The slowest walk's first step.
    pub start_worst_s: f64,
    /// Mean over the walks measured whose finger the library has a gait
    /// for (`in_gait`), and their range.
    pub speed_ratio: Option<f64>,
    pub speed_ratio_range: Option<[f64; 2]>,
    /// Over every stop of the finger.
    pub stood: Option<f64>,
}

/// What `eval walk` prints: every walk's figures together (`all`, its
/// fields at the top of the JSON, family "all"), a row per family of
/// paths, and each walk's row.
#[derive(Clone, Debug, Default, Serialize)]
pub struct WalkReport {
    /// The library's slowest and fastest locomotion clips' steady speeds
    /// (m/s).
    pub gait_mps: [f64; 2],
    #[serde(flatten)]
    pub all: FamilyRow,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub layered: Option<LayerReport>,
    pub families: Vec<FamilyRow>,
    pub rows: Vec<WalkRow>,
}

/// How far along the polyline `pts` (m) its nearest point to `p` is,
/// looked for from [`ALONG_BACK_M`] behind `was` to [`ALONG_AHEAD_M`]
/// ahead of it.
fn along_path(pts: &[DVec3], p: DVec3, was: f64) -> f64 {
    let mut start = 0.0;
    let mut best = (f64::INFINITY, was);
    for w in pts.windows(2) {
        let ab = w[1] - w[0];
        let l = ab.length();
        let (lo, hi) = (was - ALONG_BACK_M - start, was + ALONG_AHEAD_M - start);
        if l > 1e-12 && hi >= 0.0 && lo <= l {
            let s = ((p - w[0]).dot(ab) / l).clamp(lo.max(0.0), hi.min(l));
            let d = (p - (w[0] + ab * (s / l))).length();
            if d < best.0 {
                best = (d, start + s);
            }
        }
        start += l;
    }
    best.1
}

/// Distance from `p` to the polyline `pts` (m).
fn off_path(pts: &[DVec3], p: DVec3) -> f64 {
    pts.windows(2)
        .map(|w| {
            let ab = w[1] - w[0];
            let s = if ab.length_squared() > 0.0 {
                ((p - w[0]).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (p - (w[0] + ab * s)).length()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Walk every path and measure; with `layer` (an action's index), a
/// second finger drags that action over each walk.
#[must_use]
pub fn eval_walk(ch: &Arc<Character>, paths: &[WalkPath], layer: Option<usize>) -> WalkReport {
    let rows: Vec<WalkRow> = paths.iter().map(|p| walk_one(ch, p, layer)).collect();
    let all = summary("all", &rows.iter().collect::<Vec<_>>());
    let mut families: Vec<&str> = Vec::new();
    for r in &rows {
        if !families.contains(&r.family.as_str()) {
            families.push(&r.family);
        }
    }
    let families = families
        .into_iter()
        .map(|f| {
            summary(
                f,
                &rows.iter().filter(|r| r.family == f).collect::<Vec<_>>(),
            )
        })
        .collect();
    let r3 = |v: f64| (v * 1000.0).round() / 1000.0;
    WalkReport {
        gait_mps: if ch.gait.is_empty() {
            [0.0; 2]
        } else {
            [r3(ch.gait.low_speed()), r3(ch.gait.top_speed())]
        },
        all,
        layered: layer.map(|a| {
            let played: Vec<&LayerRow> = rows.iter().filter_map(|r| r.layered.as_ref()).collect();
            summarise(&ch.actions[a].def.name, &played)
        }),
        families,
        rows,
    }
}

/// The figures of `rows` together, named `family`.
fn summary(family: &str, rows: &[&WalkRow]) -> FamilyRow {
    let n = rows.len().max(1) as f64;
    let mean = |f: &dyn Fn(&WalkRow) -> f64| rows.iter().map(|r| f(r)).sum::<f64>() / n;
    let most = |f: &dyn Fn(&WalkRow) -> f64| rows.iter().map(|r| f(r)).fold(0.0, f64::max);
    let starts: Vec<f64> = rows
        .iter()
        .map(|r| r.start_s)
        .filter(|s| *s >= 0.0)
        .collect();
    let ratios: Vec<f64> = rows
        .iter()
        .filter(|r| r.in_gait)
        .filter_map(|r| r.speed_ratio)
        .collect();
    let stops: Vec<f64> = rows.iter().filter_map(|r| r.stood).collect();
    let r3 = |v: f64| (v * 1000.0).round() / 1000.0;
    let mean_of = |v: &[f64]| (!v.is_empty()).then(|| r3(v.iter().sum::<f64>() / v.len() as f64));
    FamilyRow {
        family: family.into(),
        paths: rows.len(),
        followed: r3(rows.iter().filter(|r| r.followed).count() as f64 / n),
        arrival_cm: r3(mean(&|r| r.arrival_cm)),
        arrival_worst_cm: r3(most(&|r| r.arrival_cm)),
        deviation_cm: r3(mean(&|r| r.deviation_cm)),
        skate_mm: r3(mean(&|r| r.skate_mm)),
        skate_max_mm: r3(most(&|r| r.skate_max_mm)),
        pops: rows.iter().map(|r| r.pops).sum(),
        start_s: mean_of(&starts).unwrap_or(0.0),
        start_worst_s: r3(starts.iter().copied().fold(0.0, f64::max)),
        speed_ratio: mean_of(&ratios),
        speed_ratio_range: (!ratios.is_empty()).then(|| {
            [
                r3(ratios.iter().copied().fold(f64::INFINITY, f64::min)),
                r3(ratios.iter().copied().fold(0.0, f64::max)),
            ]
        }),
        stood: mean_of(&stops),
    }
}

fn contact(id: u64, phase: Phase, at: crate::screen::ScreenPoint) -> ScreenContact {
    ScreenContact {
        id,
        phase,
        tool: Tool::Finger,
        raw: crate::input::calibration::RawPoint {
            x: at.x as i32,
            y: at.y as i32,
        },
        screen: at,
    }
}

fn walk_one(ch: &Arc<Character>, path: &WalkPath, layer: Option<usize>) -> WalkRow {
    let mut second = layer.map(SecondFinger::new);
    let mut table = Stage::single(
        Controller::new(Arc::clone(ch), Settings::default(), 0.0),
        1280.0,
        720.0,
    );
    let dt = 1.0 / HZ;
    let pelvis_j = ch.roles.get(Role::Pelvis);
    let mut k = 0u32;
    let step = |table: &mut Stage, frames: &[ScreenFrame], k: &mut u32| {
        *k += 1;
        table.step(frames, f64::from(*k) * dt);
        f64::from(*k) * dt
    };
    for _ in 0..15 {
        step(&mut table, &[], &mut k);
    }
    // The path from under the pelvis, drawn at its height.
    let pelvis = table.ctl().world().positions[pelvis_j];
    let pts: Vec<DVec3> = world_points(path)
        .into_iter()
        .map(|p| p + pelvis.with_y(0.0))
        .collect();
    let total = path_length(&pts);
    let mut watch = Watch::new(ch, table.ctl(), dt, total);
    let screen = |table: &Stage, p: DVec3| {
        let at = table.rig().camera().project(p.with_y(pelvis.y));
        at.unwrap_or_default()
    };
    let t = step(&mut table, &[], &mut k);
    let contacts = vec![contact(1, Phase::Down, screen(&table, pts[0]))];
    step(&mut table, &[ScreenFrame { t, contacts }], &mut k);
    let start = f64::from(k) * dt;
    let mut lifted = false;
    let mut after_lift = 0.0;
    let mut was_still: Option<DVec3> = None;
    loop {
        let t = f64::from(k + 1) * dt;
        let (s, still) = path.finger_at(t - start);
        let mut contacts = Vec::new();
        if let Some((phase, at)) = second
            .as_mut()
            .and_then(|f| f.contact(ch, table.ctl(), &table.rig().camera(), t))
        {
            contacts.push(contact(2, phase, at));
        }
        if !lifted {
            let p = point_along(&pts, s);
            let phase = if s >= total { Phase::Up } else { Phase::Move };
            contacts.push(contact(1, phase, screen(&table, p)));
            // A stop: does the character stand by the finger before it
            // moves on?
            match (was_still, still) {
                (Some(q), true) => watch.stopped(table.ctl(), q),
                (Some(_), false) => watch.stop_ended(),
                _ => {}
            }
            was_still = still.then_some(p);
            lifted = s >= total;
        }
        let frames = if contacts.is_empty() {
            None
        } else {
            Some(ScreenFrame { t, contacts })
        };
        step(&mut table, frames.as_slice(), &mut k);
        // The finger leaves posing's reach as the exhibit's rules have it
        // (a drag up or down the screen poses the pelvis up or down until
        // it points past the body), or a walk began before (by its
        // template); a finger back within reach before the character
        // stepped (a zig-zag's first leg turning back towards the body)
        // leaves it anew.
        let out = table
            .ctl()
            .pelvis_finger_out_of_reach(&table.rig().camera())
            || matches!(table.ctl().mode(), Mode::Walk(_));
        if watch.left_reach.is_none() && out {
            watch.left(table.ctl(), t);
        } else if !out && watch.first_step.is_none() {
            watch.left_reach = None;
        }
        if let Some(f) = second.as_mut() {
            f.measure(ch, table.ctl());
        }
        watch.observe(table.ctl(), t, lifted, &pts);
        if lifted {
            after_lift += dt;
            let busy =
                matches!(table.ctl().mode(), Mode::Walk(_)) || table.ctl().layered().is_some();
            if (!busy && after_lift > 1.0) || after_lift > 15.0 {
                break;
            }
        }
    }
    let end = *pts.last().expect("a path has points");
    let arrival = (table.ctl().world().positions[pelvis_j].with_y(0.0) - end).length();
    let layered = second.map(SecondFinger::finish);
    let mut row = watch.row(path, total, arrival, layered);
    row.family.clone_from(&path.family);
    row.in_gait = !ch.gait.is_empty() && path.speed_mps <= ch.gait.top_speed();
    row
}

/// What a walk's frames show: the motion's meter, the pelvis's way off
/// the path, when the finger left the walk's reach and when a foot first
/// stepped.
struct Watch<'a> {
    meter: Meter<'a>,
    pelvis: usize,
    feet: [usize; 2],
    feet_rest: [DVec3; 2],
    dev: (f64, usize),
    left_reach: Option<f64>,
    first_step: Option<f64>,
    /// The pelvis's last places over the floor and the feet's (a frame
    /// each, the newest last), enough for [`STOOD_OVER_S`].
    recent: std::collections::VecDeque<[DVec3; 3]>,
    /// How far along the path the pelvis is (m, see [`along_path`]), and
    /// where and when the walk's speed began and ended being measured.
    along: f64,
    speed_from: Option<(f64, f64)>,
    speed_until: Option<(f64, f64)>,
    /// The finger's stops, at how many the character stood by it, and
    /// whether it stands by it in the stop now.
    stops: (usize, usize, bool),
    /// In the stop now: the least the feet moved over `STOOD_OVER_S` and
    /// the pelvis's distance from the finger then (m), for the debug log.
    stop_best: (f64, f64),
    dt: f64,
    /// The path's length (m).
    length_m: f64,
}

impl<'a> Watch<'a> {
    /// Watching `ch` walk a path `length_m` long, stepped every `dt`.
    fn new(ch: &'a Character, ctl: &Controller, dt: f64, length_m: f64) -> Self {
        let feet = [Role::LeftFoot, Role::RightFoot].map(|r| ch.roles.get(r));
        Self {
            meter: Meter::new(&ch.lib.skeleton, &ch.roles, dt),
            pelvis: ch.roles.get(Role::Pelvis),
            feet,
            feet_rest: feet.map(|f| ctl.world().positions[f]),
            dev: (0.0, 0),
            left_reach: None,
            first_step: None,
            recent: std::collections::VecDeque::new(),
            along: 0.0,
            speed_from: None,
            speed_until: None,
            length_m,
            stops: (0, 0, false),
            stop_best: (f64::INFINITY, f64::INFINITY),
            dt,
        }
    }

    /// The finger left posing's reach at `t`: the first step is looked
    /// for from here, the feet's places now the ones it leaves (posing
    /// moves them too: a foot that posing shifted is no step).
    fn left(&mut self, ctl: &Controller, t: f64) {
        self.left_reach = Some(t);
        self.feet_rest = self.feet.map(|f| ctl.world().positions[f]);
    }

    /// The finger stands still at floor point `at`: whether the character
    /// stands by it.
    fn stopped(&mut self, ctl: &Controller, at: DVec3) {
        let now = self.places(ctl);
        let over = (STOOD_OVER_S / self.dt).round() as usize;
        let moved = self
            .recent
            .iter()
            .rev()
            .nth(over)
            .map_or(f64::INFINITY, |p| {
                (now[1] - p[1]).length().max((now[2] - p[2]).length())
            });
        let from_finger = (now[0] - at).length();
        if moved < self.stop_best.0 {
            self.stop_best = (moved, from_finger);
        }
        self.stops.2 |= moved <= STOOD_M && from_finger <= FOLLOWED_M;
    }

    /// The finger moves on after a stop.
    fn stop_ended(&mut self) {
        tracing::debug!(
            stood = self.stops.2,
            feet_moved_m = self.stop_best.0,
            pelvis_from_finger_m = self.stop_best.1,
            "the finger moves on after a stop"
        );
        self.stop_best = (f64::INFINITY, f64::INFINITY);
        self.stops.0 += 1;
        self.stops.1 += usize::from(self.stops.2);
        self.stops.2 = false;
    }

    /// The pelvis's place over the floor, and the feet's.
    fn places(&self, ctl: &Controller) -> [DVec3; 3] {
        let w = ctl.world();
        [
            w.positions[self.pelvis].with_y(0.0),
            w.positions[self.feet[0]],
            w.positions[self.feet[1]],
        ]
    }

    /// One frame at time `t` along path `pts`, the pelvis held until
    /// `lifted`.
    fn observe(&mut self, ctl: &Controller, t: f64, lifted: bool, pts: &[DVec3]) {
        let held = if lifted { vec![] } else { vec![Role::Pelvis] };
        self.meter.push(ctl.pose(), &held);
        let w = ctl.world();
        let here = self.places(ctl);
        self.along = along_path(pts, here[0], self.along);
        if let Some(first) = self.first_step {
            if self.speed_from.is_none() && t >= first + SPEED_FROM_S {
                self.speed_from = Some((t, self.along));
            }
            if self.speed_until.is_none() && self.along >= self.length_m - SPEED_UNTIL_M {
                self.speed_until = Some((t, self.along));
            }
        }
        self.recent.push_back(here);
        if self.recent.len() > 64 {
            self.recent.pop_front();
        }
        if self.first_step.is_none()
            && self.left_reach.is_some()
            && self.feet.iter().zip(&self.feet_rest).any(|(f, r)| {
                let p = w.positions[*f];
                p.y > r.y + 0.02 || (p - *r).with_y(0.0).length() > 0.03
            })
        {
            self.first_step = Some(t);
        }
        if matches!(ctl.mode(), Mode::Walk(_)) {
            self.dev.0 += off_path(pts, w.positions[self.pelvis].with_y(0.0));
            self.dev.1 += 1;
        }
    }

    /// The row of a walk along `path` (`length_m` long), the pelvis
    /// ending `arrival` from its end, with the layered action's row.
    fn row(
        self,
        path: &WalkPath,
        length_m: f64,
        arrival: f64,
        layered: Option<LayerRow>,
    ) -> WalkRow {
        let (dev_sum, dev_n) = self.dev;
        let m = self.meter.finish();
        let speed_mps = path.speed_mps;
        let speed = match (self.speed_from, self.speed_until) {
            (Some((t0, a0)), Some((t1, a1))) if t1 - t0 >= SPEED_OVER_S => {
                Some((a1 - a0) / (t1 - t0))
            }
            _ => None,
        };
        WalkRow {
            family: String::new(),
            length_m: (length_m * 1000.0).round() / 1000.0,
            speed_mps,
            followed: arrival <= FOLLOWED_M,
            arrival_cm: arrival * 100.0,
            deviation_cm: if dev_n > 0 {
                dev_sum / dev_n as f64 * 100.0
            } else {
                0.0
            },
            skate_mm: m.foot_skate_mm_per_frame,
            skate_max_mm: m.foot_skate_max_mm,
            pops: m.pops,
            pop_list: m.pop_list.into_iter().take(5).collect(),
            worst_skate: m.worst_skate,
            start_s: match (self.left_reach, self.first_step) {
                (Some(a), Some(b)) => (b - a).max(0.0),
                _ => -1.0,
            },
            speed_ratio: speed
                .filter(|_| path.pauses.is_empty())
                .map(|v| (v / speed_mps * 1000.0).round() / 1000.0),
            in_gait: false,
            stood: (self.stops.0 > 0).then(|| self.stops.1 as f64 / self.stops.0 as f64),
            layered,
        }
    }
}
