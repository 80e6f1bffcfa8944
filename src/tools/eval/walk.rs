//! Walking along a finger's path, measured (`marionette eval walk`): the
//! pelvis is dragged along floor paths through a whole controller, as live
//! touches are (the kiosk's home view; the finger put each frame over the
//! path's point at the pelvis's standing height, as the picture shows it
//! then), and the walk is judged: did it reach the path's end, how far
//! from it did it settle, how far did it stray from the path, did planted
//! feet slide, did joints pop, how soon did it step.

use std::path::Path;
use std::sync::Arc;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::character::roles::Role;
use crate::control::action::trials::Lcg;
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

/// The most paths a file may hold, and points a path.
const MAX_PATHS: usize = 1000;
const MAX_POINTS: usize = 10_000;
/// The longest path (m): a table shows a few metres of floor.
const MAX_PATH_M: f64 = 100.0;
/// The most walking all paths may take together (s, each at its speed).
const MAX_WALKING_S: f64 = 600.0;

/// A path to walk: floor points in metres in the character's frame (x to
/// its right, z ahead), from its pelvis, and the finger's speed along it.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct WalkPath {
    pub points: Vec<[f64; 2]>,
    pub speed_mps: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PathsFile {
    paths: Vec<WalkPath>,
}

/// One path's figures.
#[derive(Clone, Debug, Default, Serialize)]
pub struct WalkRow {
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
    /// The action a second finger laid over the walk, if one was asked.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub layered: Option<LayerRow>,
}

/// What `eval walk` prints.
#[derive(Clone, Debug, Default, Serialize)]
pub struct WalkReport {
    pub paths: usize,
    pub followed: f64,
    pub arrival_cm: f64,
    pub deviation_cm: f64,
    pub skate_mm: f64,
    pub skate_max_mm: f64,
    pub pops: usize,
    pub start_s: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub layered: Option<LayerReport>,
    pub rows: Vec<WalkRow>,
}

/// Read a paths file: `{"paths": [{"points": [[x, z], ...], "speed_mps": v}]}`.
/// The error names the file and, for a bad number, the path and point.
pub fn read_paths(file: &Path) -> Result<Vec<WalkPath>, String> {
    let text = crate::reading::read_text(file, 64 << 20).map_err(|e| match e {
        crate::reading::ReadError::TooLarge { said, .. } => format!(
            "{}: {said} bytes; a paths file holds at most 64 MB",
            file.display()
        ),
        e => format!("cannot read {}: {e}", file.display()),
    })?;
    let parsed: PathsFile = serde_json::from_str(&text).map_err(|e| {
        format!(
            "{}: not a paths file ({}); expected {{\"paths\": [{{\"points\": [[x, z], ...], \"speed_mps\": v}}]}}",
            file.display(),
            crate::reading::parser_message(&e.to_string())
        )
    })?;
    check_paths(&parsed.paths).map_err(|why| format!("{}: {why}", file.display()))?;
    Ok(parsed.paths)
}

/// Every path usable: some paths, each of 2 or more finite points that go
/// somewhere, at a speed a finger can drag.
pub fn check_paths(paths: &[WalkPath]) -> Result<(), String> {
    if paths.is_empty() {
        return Err("no paths: give at least one".into());
    }
    if paths.len() > MAX_PATHS {
        return Err(format!("{} paths; at most {MAX_PATHS}", paths.len()));
    }
    let mut walking_s = 0.0;
    for (i, p) in paths.iter().enumerate() {
        let n = i + 1;
        if !(p.speed_mps.is_finite() && p.speed_mps > 0.05 && p.speed_mps <= 5.0) {
            return Err(format!(
                "path {n}: speed_mps = {} must be above 0.05 and at most 5",
                p.speed_mps
            ));
        }
        if p.points.len() < 2 || p.points.len() > MAX_POINTS {
            return Err(format!(
                "path {n}: {} points; a path has 2 to {MAX_POINTS}",
                p.points.len()
            ));
        }
        if let Some((k, q)) = p
            .points
            .iter()
            .enumerate()
            .find(|(_, q)| !q.iter().all(|v| v.is_finite() && v.abs() <= 100.0))
        {
            return Err(format!(
                "path {n}, point {}: {q:?} is not a floor point in metres (finite, within 100 m)",
                k + 1
            ));
        }
        let length = path_length(&world_points(p));
        if length < 0.05 {
            return Err(format!("path {n}: its points do not go anywhere"));
        }
        if length > MAX_PATH_M {
            return Err(format!(
                "path {n}: {length:.0} m long; a path on the table is at most {MAX_PATH_M} m"
            ));
        }
        walking_s += length / p.speed_mps;
    }
    if walking_s > MAX_WALKING_S {
        return Err(format!(
            "the paths take {walking_s:.0} s to walk; at most {MAX_WALKING_S} s in all"
        ));
    }
    Ok(())
}

/// Random smooth curves over the floor in view of the home camera, setting
/// off across it, with finger speeds from a slow drag to a quick one; the
/// same for a seed.
#[must_use]
pub fn random_paths(seed: u64, n: usize) -> Vec<WalkPath> {
    let across = home_across();
    let mut rng = Lcg(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ 0x5851_f42d_4c95_7f2d);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        // Setting off across the view (to the screen's right or left,
        // within 35 degrees): a drag up or down the screen from the home
        // view moves the pelvis up or down rather than walking.
        let side = if rng.unit() < 0.5 {
            0.0
        } else {
            std::f64::consts::PI
        };
        let mut heading = across + side + rng.range(-0.6, 0.6);
        let total = rng.range(1.2, 3.0);
        let bend = rng.range(-0.5, 0.5);
        let mut p = [0.0f64, 0.0];
        let mut points = vec![p];
        let mut s = 0.0;
        while s < total {
            heading += bend * 0.25 + rng.range(-0.15, 0.15);
            p = [p[0] + 0.25 * heading.sin(), p[1] + 0.25 * heading.cos()];
            points.push(p);
            s += 0.25;
        }
        // In view: across the floor, not behind the camera.
        if points
            .iter()
            .all(|q| q[0].abs() <= 2.0 && (-2.5..=1.5).contains(&q[1]))
        {
            let speed_mps = rng.range(0.6, 1.4);
            out.push(WalkPath { points, speed_mps });
        }
    }
    out
}

/// Which way the home view's screen right goes over the floor, as a
/// heading in the character's frame (radians from ahead, towards its
/// right), the character standing at the origin facing +Z.
fn home_across() -> f64 {
    let cam = crate::control::rig::Rig::new(1280.0, 720.0).camera();
    let ahead = (cam.target - cam.eye).with_y(0.0);
    let right = ahead.cross(glam::DVec3::Y);
    // World (dx, dz) is (-x, z) in the character's frame.
    (-right.x).atan2(right.z)
}

/// The path's points on the floor, the character at the origin facing +Z
/// (its right is -X).
fn world_points(p: &WalkPath) -> Vec<DVec3> {
    p.points
        .iter()
        .map(|q| DVec3::new(-(q[0] - p.points[0][0]), 0.0, q[1] - p.points[0][1]))
        .collect()
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
    let n = rows.len().max(1) as f64;
    let mean = |f: &dyn Fn(&WalkRow) -> f64| rows.iter().map(f).sum::<f64>() / n;
    let starts: Vec<f64> = rows
        .iter()
        .map(|r| r.start_s)
        .filter(|s| *s >= 0.0)
        .collect();
    let r3 = |v: f64| (v * 1000.0).round() / 1000.0;
    WalkReport {
        paths: rows.len(),
        followed: r3(rows.iter().filter(|r| r.followed).count() as f64 / n),
        arrival_cm: r3(mean(&|r| r.arrival_cm)),
        deviation_cm: r3(mean(&|r| r.deviation_cm)),
        skate_mm: r3(mean(&|r| r.skate_mm)),
        skate_max_mm: r3(rows.iter().map(|r| r.skate_max_mm).fold(0.0, f64::max)),
        pops: rows.iter().map(|r| r.pops).sum(),
        start_s: r3(starts.iter().sum::<f64>() / starts.len().max(1) as f64),
        layered: layer.map(|a| {
            let played: Vec<&LayerRow> = rows.iter().filter_map(|r| r.layered.as_ref()).collect();
            summarise(&ch.actions[a].def.name, &played)
        }),
        rows,
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
    let mut watch = Watch::new(ch, table.ctl(), dt);
    let total = path_length(&pts);
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
    loop {
        let t = f64::from(k + 1) * dt;
        let s = (t - start) * path.speed_mps;
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
            if watch.left_reach.is_none()
                && (p - table.ctl().world().positions[pelvis_j].with_y(0.0)).length()
                    > crate::control::controller::WALK_REACH_M
            {
                watch.left_reach = Some(t);
            }
            lifted = s >= total;
        }
        let frames = if contacts.is_empty() {
            None
        } else {
            Some(ScreenFrame { t, contacts })
        };
        step(&mut table, frames.as_slice(), &mut k);
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
    watch.row(path.speed_mps, total, arrival, layered)
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
}

impl<'a> Watch<'a> {
    fn new(ch: &'a Character, ctl: &Controller, dt: f64) -> Self {
        let feet = [Role::LeftFoot, Role::RightFoot].map(|r| ch.roles.get(r));
        Self {
            meter: Meter::new(&ch.lib.skeleton, &ch.roles, dt),
            pelvis: ch.roles.get(Role::Pelvis),
            feet,
            feet_rest: feet.map(|f| ctl.world().positions[f]),
            dev: (0.0, 0),
            left_reach: None,
            first_step: None,
        }
    }

    /// One frame at time `t` along path `pts`, the pelvis held until
    /// `lifted`.
    fn observe(&mut self, ctl: &Controller, t: f64, lifted: bool, pts: &[DVec3]) {
        let held = if lifted { vec![] } else { vec![Role::Pelvis] };
        self.meter.push(ctl.pose(), &held);
        let w = ctl.world();
        if self.first_step.is_none()
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

    /// The row of a walk at `speed_mps` along a path `length_m` long, the
    /// pelvis ending `arrival` from its end, with the layered action's row.
    fn row(
        self,
        speed_mps: f64,
        length_m: f64,
        arrival: f64,
        layered: Option<LayerRow>,
    ) -> WalkRow {
        let (dev_sum, dev_n) = self.dev;
        let m = self.meter.finish();
        WalkRow {
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
            layered,
        }
    }
}
