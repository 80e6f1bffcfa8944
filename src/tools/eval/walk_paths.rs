//! The paths `eval walk` drags the pelvis along: read from a file and
//! checked, or drawn at random by family (the kinds of drag a visitor
//! makes: curves, turn-backs, loops, zig-zags, stops on the way, slow and
//! fast fingers).

use std::path::Path;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::control::action::trials::Lcg;
use crate::control::locomotion::walker::path_length;

/// The most paths a file may hold, and points a path.
const MAX_PATHS: usize = 1000;
const MAX_POINTS: usize = 10_000;
/// The longest path (m): a table shows a few metres of floor.
const MAX_PATH_M: f64 = 100.0;
/// The most walking all paths may take together (s, each at its speed).
const MAX_WALKING_S: f64 = 600.0;

/// A path to walk: floor points in metres in the character's frame (x to
/// its right, z ahead), from its pelvis, and the finger's speed along it;
/// where the finger stops on the way, and the kind of path it is.
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct WalkPath {
    pub points: Vec<[f64; 2]>,
    pub speed_mps: f64,
    /// Where the finger stands still on the way: `[metres along the
    /// path, seconds]`, in order along it.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub pauses: Vec<[f64; 2]>,
    /// The family the path is of (see [`FAMILIES`]); a row per family is
    /// printed.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub family: String,
}

/// The families of random paths, each the kind of drag a visitor makes:
/// smooth curves at a walk, turning back on themselves, looping, zig-
/// zagging, stopping on the way (1.5 to 3 s), slow (0.3-0.6 m/s) and fast (1.5-2 m/s)
/// curves.
pub const FAMILIES: [&str; 7] = [
    "curve",
    "turn_back",
    "loop",
    "zig_zag",
    "stop_and_go",
    "slow",
    "fast",
];

/// The most pauses a path may have, and the longest (s).
const MAX_PAUSES: usize = 100;
const MAX_PAUSE_S: f64 = 10.0;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PathsFile {
    paths: Vec<WalkPath>,
}

/// Read a paths file: `{"paths": [{"points": [[x, z], ...], "speed_mps": v,
/// "pauses": [[m, s], ...], "family": "..."}]}` (pauses and family may be
/// left out).
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
        check_pauses(p, n, length)?;
        walking_s += length / p.speed_mps + p.pauses.iter().map(|q| q[1]).sum::<f64>();
    }
    if walking_s > MAX_WALKING_S {
        return Err(format!(
            "the paths take {walking_s:.0} s to walk; at most {MAX_WALKING_S} s in all"
        ));
    }
    Ok(())
}

/// Random smooth curves over the floor in view of the home camera, setting
/// off across it, with finger speeds from a slow drag to a quick one (the
/// `curve` family); the same for a seed.
#[must_use]
pub fn random_curves(seed: u64, n: usize) -> Vec<WalkPath> {
    let across = home_across();
    let mut rng = Lcg(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ 0x5851_f42d_4c95_7f2d);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let points = curve(&mut rng, across);
        if in_view(&points) {
            let speed_mps = rng.range(0.6, 1.4);
            out.push(WalkPath {
                points,
                speed_mps,
                family: FAMILIES[0].into(),
                ..WalkPath::default()
            });
        }
    }
    out
}

/// Random paths of `families` (of [`FAMILIES`]) in turn (path `i` of
/// `families[i % families.len()]`), each in view of the home camera and
/// setting off across it; the same for a seed.
#[must_use]
pub fn random_paths(seed: u64, n: usize, families: &[&str]) -> Vec<WalkPath> {
    let families = if families.is_empty() {
        &FAMILIES[..]
    } else {
        families
    };
    let across = home_across();
    let mut rng = Lcg(seed.wrapping_mul(0xd1b5_4a32_d192_ed03) ^ 0x2545_f491_4f6c_dd1d);
    (0..n)
        .map(|i| {
            let family = families[i % families.len()];
            let mut path = of_family(&mut rng, across, family);
            // Drawn again until it stays in view (a few tries at most:
            // most do).
            for _ in 0..MAX_TRIES {
                if in_view(&path.points) {
                    break;
                }
                path = of_family(&mut rng, across, family);
            }
            path
        })
        .collect()
}

/// How many times a random path is drawn again to keep it in view.
const MAX_TRIES: usize = 1000;

/// Floor points kept in view of the home camera: across the floor, not
/// behind the camera.
fn in_view(points: &[[f64; 2]]) -> bool {
    points
        .iter()
        .all(|q| q[0].abs() <= 2.0 && (-2.5..=1.5).contains(&q[1]))
}

/// A smooth curve setting off across the view (to the screen's right or
/// left, within 35 degrees: a drag up or down the screen from the home
/// view moves the pelvis up or down rather than walking), 1.2 to 3 m.
fn curve(rng: &mut Lcg, across: f64) -> Vec<[f64; 2]> {
    let mut heading = across + side(rng) + rng.range(-0.6, 0.6);
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
    points
}

/// To the screen's right (0) or left (a half turn), as likely.
fn side(rng: &mut Lcg) -> f64 {
    if rng.unit() < 0.5 {
        0.0
    } else {
        std::f64::consts::PI
    }
}

/// Left (-1) or right (1), as likely.
fn sign(rng: &mut Lcg) -> f64 {
    if rng.unit() < 0.5 { -1.0 } else { 1.0 }
}

/// One random path of `family`.
fn of_family(rng: &mut Lcg, across: f64, family: &str) -> WalkPath {
    let heading = across + side(rng) + rng.range(-0.5, 0.5);
    let mut pen = Pen::new(heading);
    let mut pauses = Vec::new();
    let speed_mps = match family {
        "turn_back" => {
            // Out, round a U-turn from on the spot to a 35 cm radius,
            // and back.
            pen.line(rng.range(0.8, 1.6));
            pen.arc(rng.range(0.05, 0.35), sign(rng) * std::f64::consts::PI);
            pen.line(rng.range(0.6, 1.4));
            rng.range(0.3, 2.0)
        }
        "loop" => {
            pen.line(rng.range(0.3, 0.6));
            pen.arc(rng.range(0.4, 0.75), sign(rng) * std::f64::consts::TAU);
            pen.line(rng.range(0.3, 0.8));
            rng.range(0.3, 2.0)
        }
        "zig_zag" => {
            // Three to six legs, each turned 35 to 65 degrees off the
            // way the zig-zag goes, to one side then the other.
            let legs = 3 + (rng.unit() * 4.0) as usize;
            let off = rng.range(0.6, 1.1);
            let first = sign(rng);
            for k in 0..legs {
                let s = if k % 2 == 0 { first } else { -first };
                pen.heading = heading + s * off;
                pen.line(rng.range(0.4, 0.8));
            }
            rng.range(0.3, 2.0)
        }
        "stop_and_go" => {
            // A curve with one or two stops of 1.5 to 3 s on the way.
            pen.points = curve(rng, across);
            let length = planar_length(&pen.points);
            pauses.push([length * rng.range(0.3, 0.45), rng.range(1.5, 3.0)]);
            if rng.unit() < 0.5 {
                pauses.push([length * rng.range(0.6, 0.75), rng.range(1.5, 3.0)]);
            }
            rng.range(0.6, 1.4)
        }
        _ => {
            pen.points = curve(rng, across);
            match family {
                "slow" => rng.range(0.3, 0.6),
                "fast" => rng.range(1.5, 2.0),
                _ => rng.range(0.6, 1.4),
            }
        }
    };
    WalkPath {
        points: pen.points,
        speed_mps,
        pauses,
        family: family.into(),
    }
}

/// The length of a path of floor points (m).
fn planar_length(points: &[[f64; 2]]) -> f64 {
    points
        .windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum()
}

/// Draws a path a piece at a time: straight lines and arcs, a point every
/// 10 cm or less; headings in radians from ahead (+z) towards the right
/// (+x).
struct Pen {
    heading: f64,
    points: Vec<[f64; 2]>,
}

impl Pen {
    /// The longest step between points (m).
    const STEP_M: f64 = 0.1;

    fn new(heading: f64) -> Self {
        Self {
            heading,
            points: vec![[0.0, 0.0]],
        }
    }

    fn step(&mut self, l: f64) {
        let p = *self.points.last().unwrap_or(&[0.0, 0.0]);
        self.points
            .push([p[0] + l * self.heading.sin(), p[1] + l * self.heading.cos()]);
    }

    /// Straight on for `length` m.
    fn line(&mut self, length: f64) {
        let n = (length / Self::STEP_M).ceil().max(1.0);
        for _ in 0..n as usize {
            self.step(length / n);
        }
    }

    /// Round an arc of `radius` m, turning by `turn` radians (positive to
    /// the right).
    fn arc(&mut self, radius: f64, turn: f64) {
        let length = radius * turn.abs();
        let n = (length / Self::STEP_M).ceil().max(1.0);
        let d = turn / n;
        // Each chord leaves at half its turn: the points lie on the arc.
        for _ in 0..n as usize {
            self.heading += d / 2.0;
            self.step(2.0 * radius * (d.abs() / 2.0).sin());
            self.heading += d / 2.0;
        }
    }
}

impl WalkPath {
    /// How far along the path the finger is `t` seconds after it set off
    /// (m), and whether it stands still there (a pause).
    #[must_use]
    pub fn finger_at(&self, t: f64) -> (f64, bool) {
        let mut left = t.max(0.0);
        let mut from = 0.0;
        for &[at, seconds] in &self.pauses {
            let travel = (at - from).max(0.0) / self.speed_mps;
            if left < travel {
                return (from + left * self.speed_mps, false);
            }
            left -= travel;
            from = at.max(from);
            if left < seconds {
                return (from, true);
            }
            left -= seconds;
        }
        (from + left * self.speed_mps, false)
    }
}

/// Each pause of path `n` (`length` m long) on it, in order, of a time a
/// finger rests.
fn check_pauses(p: &WalkPath, n: usize, length: f64) -> Result<(), String> {
    if p.pauses.len() > MAX_PAUSES {
        return Err(format!(
            "path {n}: {} pauses; at most {MAX_PAUSES}",
            p.pauses.len()
        ));
    }
    let mut last = 0.0;
    for (k, &[at, seconds]) in p.pauses.iter().enumerate() {
        if !(at.is_finite() && (last..=length + 1e-9).contains(&at)) {
            return Err(format!(
                "path {n}, pause {}: at {at} m; pauses lie along the path ({length:.2} m) in order, from {last:.2} m",
                k + 1
            ));
        }
        if !(seconds.is_finite() && seconds > 0.0 && seconds <= MAX_PAUSE_S) {
            return Err(format!(
                "path {n}, pause {}: {seconds} s; a pause lasts more than 0 and at most {MAX_PAUSE_S} s",
                k + 1
            ));
        }
        last = at;
    }
    Ok(())
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
pub(crate) fn world_points(p: &WalkPath) -> Vec<DVec3> {
    p.points
        .iter()
        .map(|q| DVec3::new(-(q[0] - p.points[0][0]), 0.0, q[1] - p.points[0][1]))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_finger_stops_where_its_pauses_say_and_goes_on_at_its_speed() {
        let path = WalkPath {
            points: vec![[0.0, 0.0], [2.0, 0.0]],
            speed_mps: 0.5,
            pauses: vec![[0.5, 2.0], [1.0, 1.0]],
            ..WalkPath::default()
        };
        let at = |t: f64| path.finger_at(t);
        assert_eq!(at(0.0), (0.0, false));
        assert_eq!(at(0.5), (0.25, false));
        // 1 s to the first pause, 2 s there, 1 s to the next, 1 s there.
        assert_eq!(at(1.5), (0.5, true));
        assert_eq!(at(2.99), (0.5, true));
        assert!((at(3.5).0 - 0.75).abs() < 1e-12 && !at(3.5).1);
        assert_eq!(at(4.5), (1.0, true));
        assert!((at(6.0).0 - 1.5).abs() < 1e-12 && !at(6.0).1);
    }

    #[test]
    fn pauses_off_the_path_out_of_order_or_endless_are_refused() {
        let with = |pauses: Vec<[f64; 2]>| {
            check_paths(&[WalkPath {
                points: vec![[0.0, 0.0], [1.0, 0.0]],
                speed_mps: 1.0,
                pauses,
                ..WalkPath::default()
            }])
        };
        assert!(with(vec![[0.5, 1.0]]).is_ok());
        let e = with(vec![[1.5, 1.0]]).unwrap_err();
        assert!(e.contains("path 1, pause 1") && e.contains("1.00 m"), "{e}");
        let e = with(vec![[0.6, 1.0], [0.4, 1.0]]).unwrap_err();
        assert!(e.contains("pause 2") && e.contains("in order"), "{e}");
        let e = with(vec![[0.5, f64::NAN]]).unwrap_err();
        assert!(e.contains("at most 10 s"), "{e}");
        let e = with(vec![[0.5, 11.0]]).unwrap_err();
        assert!(e.contains("at most 10 s"), "{e}");
    }

    #[test]
    fn random_paths_take_every_family_in_turn_in_view_and_the_same_for_a_seed() {
        let paths = random_paths(3, 2 * FAMILIES.len(), &FAMILIES);
        assert_eq!(paths, random_paths(3, 2 * FAMILIES.len(), &FAMILIES));
        assert!(check_paths(&paths).is_ok());
        for (i, p) in paths.iter().enumerate() {
            assert_eq!(p.family, FAMILIES[i % FAMILIES.len()]);
            assert!(in_view(&p.points), "{p:?}");
            let (lo, hi) = match p.family.as_str() {
                "slow" => (0.3, 0.6),
                "fast" => (1.5, 2.0),
                "turn_back" | "loop" | "zig_zag" => (0.3, 2.0),
                _ => (0.6, 1.4),
            };
            assert!((lo..=hi).contains(&p.speed_mps), "{p:?}");
            assert_eq!(p.pauses.is_empty(), p.family != "stop_and_go", "{p:?}");
        }
        // One family alone.
        assert!(
            random_paths(3, 4, &["loop"])
                .iter()
                .all(|p| p.family == "loop")
        );
    }

    #[test]
    fn a_loop_comes_back_round_and_a_turn_back_comes_back_alongside() {
        let mut pen = Pen::new(0.0);
        pen.arc(0.5, std::f64::consts::TAU);
        let end = pen.points.last().unwrap();
        assert!(end[0].hypot(end[1]) < 1e-9, "{end:?}");
        assert!((planar_length(&pen.points) - std::f64::consts::PI).abs() < 0.01);
        let mut pen = Pen::new(0.0);
        pen.line(1.0);
        pen.arc(0.2, std::f64::consts::PI);
        pen.line(1.0);
        let end = pen.points.last().unwrap();
        // Back where it began, 40 cm to the right.
        assert!(
            (end[0] - 0.4).abs() < 1e-9 && end[1].abs() < 1e-9,
            "{end:?}"
        );
    }
}
