//! Recognising an action from a drag (the paper's section 5): the finger's
//! trail (screen points with times) is compared with the action's
//! trajectory projected to the screen, both taken relative to where they
//! begin. Corresponding points are found by dynamic programming, and the
//! cost is eq. 1 averaged over the corresponding pairs: position difference
//! plus `h` times relative-time difference. The input may correspond to the
//! beginning of the trajectory only: the action starts mid-drag.

use glam::DVec3;

use crate::screen::ScreenPoint;

/// A point of a trail or a projected trajectory: screen position and time
/// in seconds from its start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrailPoint {
    pub at: ScreenPoint,
    pub t: f64,
}

/// The best correspondence of a trail with a trajectory.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Match {
    /// Eq. 1 averaged over the corresponding pairs (px).
    pub cost: f64,
    /// Share of the trajectory's points that have a partner in the
    /// correspondence (0..1]: the paper's "S covers more than half the
    /// action trajectory".
    pub coverage: f64,
}

/// Match `trail` against the beginning of `trajectory` (both with at least
/// one point). `h` weighs time against position (px per second).
#[must_use]
pub fn match_trail(
    trail: &[TrailPoint],
    trajectory: &[TrailPoint],
    h: f64,
    tempo: f64,
) -> Option<Match> {
    let (n, m) = (trail.len(), trajectory.len());
    if n == 0 || m == 0 {
        return None;
    }
    let (p0, q0) = (trail[0], trajectory[0]);
    let cost = |i: usize, j: usize| {
        let a = trail[i];
        let b = trajectory[j];
        let dx = (a.at.x - p0.at.x) - (b.at.x - q0.at.x);
        let dy = (a.at.y - p0.at.y) - (b.at.y - q0.at.y);
        (dx * dx + dy * dy).sqrt() + h * tempo_gap(a.t - p0.t, b.t - q0.t, tempo)
    };
    // sum[i][j]: least summed cost of a path from (0, 0) to (i, j);
    // len[i][j]: its number of pairs.
    let mut sum = vec![f64::INFINITY; n * m];
    let mut len = vec![0u32; n * m];
    for i in 0..n {
        for j in 0..m {
            let c = cost(i, j);
            if i == 0 && j == 0 {
                sum[0] = c;
                len[0] = 1;
                continue;
            }
            let mut best = (f64::INFINITY, 0u32);
            for (pi, pj) in [
                (i.wrapping_sub(1), j),
                (i, j.wrapping_sub(1)),
                (i.wrapping_sub(1), j.wrapping_sub(1)),
            ] {
                if pi < n && pj < m && sum[pi * m + pj] < best.0 {
                    best = (sum[pi * m + pj], len[pi * m + pj]);
                }
            }
            sum[i * m + j] = best.0 + c;
            len[i * m + j] = best.1 + 1;
        }
    }
    // The whole trail against the trajectory's best prefix.
    let last = n - 1;
    (0..m)
        .map(|j| {
            let k = last * m + j;
            (j, sum[k] / f64::from(len[k].max(1)))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(j, avg)| Match {
            cost: avg,
            coverage: (j + 1) as f64 / m as f64,
        })
}

/// How far (s) the action's time `action_t` lies outside the band
/// `[input_t / tempo, input_t * tempo]`: the drag may run up to `tempo`
/// times faster or slower than the action at no cost.
pub(crate) fn tempo_gap(input_t: f64, action_t: f64, tempo: f64) -> f64 {
    let (lo, hi) = (input_t / tempo, input_t * tempo);
    if action_t > hi {
        action_t - hi
    } else if action_t < lo {
        lo - action_t
    } else {
        0.0
    }
}

/// Thresholds of recognition, all in the configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StartRule {
    /// Eq. 1's time weight (px per second).
    pub h: f64,
    /// The drag may be up to this many times faster or slower than the
    /// action before eq. 1's time term counts (1 = exact timing).
    pub tempo: f64,
    /// Cost threshold for a drag at rest (px)...
    pub base_threshold_px: f64,
    /// ...growing with drag speed (px of threshold per px/s of speed).
    pub speed_gain: f64,
    /// A trail shorter than this never starts an action (px).
    pub min_trail_px: f64,
    /// The trail must correspond to more than this part of the trajectory.
    pub min_coverage: f64,
    /// The action's direction must be more than this from the eye vector
    /// (degrees).
    pub min_view_angle_deg: f64,
}

impl Default for StartRule {
    fn default() -> Self {
        Self {
            h: 100.0,
            tempo: 1.3,
            base_threshold_px: 10.0,
            speed_gain: 0.05,
            min_trail_px: 40.0,
            min_coverage: 0.5,
            min_view_angle_deg: 45.0,
        }
    }
}

/// Steps of a trail shorter than this are not counted as movement until
/// they add up to it (px): a panel's jitter of a couple of pixels per
/// report would otherwise make a slow, steady finger look fast and long.
pub const JITTER_PX: f64 = 6.0;

/// Length of a trail (px) and its mean speed (px/s), with jitter below
/// [`JITTER_PX`] left out: the path is followed from one point to the next
/// that lies at least that far from it.
#[must_use]
pub fn length_and_speed(trail: &[TrailPoint]) -> (f64, f64) {
    let mut len = 0.0;
    if let Some(first) = trail.first() {
        let mut anchor = first.at;
        for p in &trail[1..] {
            let d = anchor.distance(p.at);
            if d >= JITTER_PX {
                len += d;
                anchor = p.at;
            }
        }
    }
    let time = match (trail.first(), trail.last()) {
        (Some(a), Some(b)) => (b.t - a.t).max(1e-6),
        _ => 1.0,
    };
    (len, len / time)
}

/// The angle (degrees) between an action's representative direction and
/// the eye vector, as a line: 0 when the action moves straight along the
/// line of sight, 90 across it.
#[must_use]
pub fn view_angle_deg(direction: DVec3, eye: DVec3) -> f64 {
    let a = direction.angle_between(eye).to_degrees();
    a.min(180.0 - a)
}

impl StartRule {
    /// Whether a drag with this match starts the action.
    #[must_use]
    pub fn starts(&self, m: &Match, trail: &[TrailPoint], view_angle_deg: f64) -> bool {
        let (len, speed) = length_and_speed(trail);
        len >= self.min_trail_px
            && m.coverage > self.min_coverage
            && view_angle_deg > self.min_view_angle_deg
            && m.cost < self.base_threshold_px + self.speed_gain * speed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(from: (f64, f64), to: (f64, f64), duration: f64, n: usize) -> Vec<TrailPoint> {
        (0..n)
            .map(|i| {
                let s = i as f64 / (n - 1) as f64;
                TrailPoint {
                    at: ScreenPoint::new(
                        from.0 + (to.0 - from.0) * s,
                        from.1 + (to.1 - from.1) * s,
                    ),
                    t: duration * s,
                }
            })
            .collect()
    }

    #[test]
    fn the_beginning_of_a_trajectory_matches_with_its_coverage() {
        // A punch: 300 px to the right in 0.5 s.
        let punch = line((100.0, 200.0), (400.0, 200.0), 0.5, 21);
        // The finger has done the first 60 % of it, somewhere else on screen.
        let drag = line((500.0, 100.0), (680.0, 100.0), 0.3, 10);
        let m = match_trail(&drag, &punch, 100.0, 1.0).unwrap();
        // Only the two samplings differ (20 px against 15 px steps).
        assert!(m.cost < 8.0, "{m:?}");
        assert!((m.coverage - 0.6).abs() < 0.06, "{m:?}");
        // The other way is far off.
        let back = line((500.0, 100.0), (320.0, 100.0), 0.3, 10);
        assert!(match_trail(&back, &punch, 100.0, 1.0).unwrap().cost > 50.0);
        // Same path at half the speed: the time term grows.
        let slow = line((500.0, 100.0), (680.0, 100.0), 0.6, 10);
        let ms = match_trail(&slow, &punch, 100.0, 1.0).unwrap();
        assert!(ms.cost > m.cost + 5.0, "{ms:?} vs {m:?}");
    }

    #[test]
    fn a_tempo_band_lets_the_drag_keep_its_own_pace() {
        let punch = line((100.0, 200.0), (400.0, 200.0), 0.5, 33);
        let exact = |d: f64| line((500.0, 100.0), (650.0, 100.0), d, 17);
        // Half the punch in 0.2 s instead of 0.25 s: 1.25 times faster.
        let quick = match_trail(&exact(0.2), &punch, 100.0, 1.3).unwrap();
        let on_time = match_trail(&exact(0.25), &punch, 100.0, 1.3).unwrap();
        assert!((quick.cost - on_time.cost).abs() < 1e-9, "{quick:?}");
        assert!(quick.coverage > 0.5, "{quick:?}");
        // Without the band the quicker drag pays for its pace.
        let strict = match_trail(&exact(0.2), &punch, 100.0, 1.0).unwrap();
        assert!(strict.cost > quick.cost + 1.0, "{strict:?} vs {quick:?}");
        // Three times slower is far outside the band: time still counts.
        let slow = match_trail(&exact(0.75), &punch, 100.0, 1.3).unwrap();
        assert!(slow.cost > on_time.cost + 5.0, "{slow:?} vs {on_time:?}");
        assert_eq!(tempo_gap(1.0, 1.2, 1.3), 0.0);
        assert!((tempo_gap(1.0, 0.5, 1.3) - (1.0 / 1.3 - 0.5)).abs() < 1e-12);
        assert!((tempo_gap(1.0, 2.0, 1.3) - 0.7).abs() < 1e-12);
    }

    #[test]
    fn jitter_is_not_movement() {
        // A finger resting for a second with ±2 px of jitter per report.
        let mut x = 7u32;
        let mut noise = || {
            x = x.wrapping_mul(1_103_515_245).wrapping_add(12_345);
            f64::from((x >> 16) % 401) / 100.0 - 2.0
        };
        let still: Vec<TrailPoint> = (0..60)
            .map(|i| TrailPoint {
                at: ScreenPoint::new(300.0 + noise(), 200.0 + noise()),
                t: f64::from(i) / 60.0,
            })
            .collect();
        let (len, speed) = length_and_speed(&still);
        assert!(len < 10.0 && speed < 10.0, "{len} px, {speed} px/s");
        // Summing every step would call it a drag of over 100 px.
        let raw: f64 = still.windows(2).map(|w| w[0].at.distance(w[1].at)).sum();
        assert!(raw > 100.0, "{raw}");
        // A steady drag keeps its length.
        let (len, speed) = length_and_speed(&line((0.0, 0.0), (300.0, 0.0), 0.5, 31));
        assert!((len - 300.0).abs() < 1e-9 && (speed - 600.0).abs() < 1e-6);
    }

    #[test]
    fn start_rule_checks_length_coverage_view_and_speed() {
        let rule = StartRule::default();
        let punch = line((100.0, 200.0), (400.0, 200.0), 0.5, 21);
        let drag = line((500.0, 100.0), (680.0, 100.0), 0.3, 10);
        let m = match_trail(&drag, &punch, rule.h, rule.tempo).unwrap();
        assert!(rule.starts(&m, &drag, 80.0));
        assert!(
            !rule.starts(&m, &drag, 30.0),
            "seen end-on, the action is excluded"
        );
        let short = line((500.0, 100.0), (520.0, 100.0), 0.05, 4);
        let ms = match_trail(&short, &punch, rule.h, rule.tempo).unwrap();
        assert!(
            !rule.starts(&ms, &short, 80.0),
            "too short and too little of the trajectory"
        );
        assert!((view_angle_deg(DVec3::Z, DVec3::NEG_Z) - 0.0).abs() < 1e-9);
        assert!((view_angle_deg(DVec3::X, DVec3::NEG_Z) - 90.0).abs() < 1e-9);
    }
}
