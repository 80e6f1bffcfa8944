//! What a take's parts do: each part's path and speed over the clip, the
//! bursts of movement in it, where a long take is cut between them, and
//! the span in which it moves at all.

use glam::{DQuat, DVec3};

use super::CANDIDATES;
use crate::character::body::facing_yaw;
use crate::character::motion::Clip;
use crate::character::roles::Role;
use crate::character::skeleton::forward_kinematics;

/// A part moving faster than this share of its peak speed is in motion.
const ACTIVE_SHARE: f64 = 0.25;

/// Speeds are averaged over this long (s) before they are judged.
const SMOOTHING_S: f64 = 0.2;

/// Bursts of motion closer than this (s) are one movement.
const MERGE_GAP_S: f64 = 0.25;

/// A burst shorter than this (s) is a twitch, not an action.
const MIN_BURST_S: f64 = 0.15;

/// A take is cut only where its part is back this near (a share of its
/// range) to where it started.
const RETURNED: f64 = 0.3;

/// One part's movement over a clip.
#[derive(Clone, Debug, PartialEq)]
pub struct PartMotion {
    pub role: Role,
    /// The diagonal of the box its path fills (m): hands, feet and head
    /// relative to the pelvis and the body's facing, the pelvis in the
    /// room.
    pub range_m: f64,
    /// Its speed at each frame (m/s), smoothed.
    pub speed: Vec<f64>,
    /// Its path (m), as `range_m` measures it.
    pub path: Vec<DVec3>,
}

/// How each candidate part moves in `clip`.
#[must_use]
pub fn part_motion(clip: &Clip) -> Vec<PartMotion> {
    let worlds: Vec<_> = clip
        .frames
        .iter()
        .map(|f| forward_kinematics(&clip.skeleton, f))
        .collect();
    let pelvis = clip.roles.get(Role::Pelvis);
    let dt = clip.frame_time.max(1e-6);
    CANDIDATES
        .iter()
        .map(|&role| {
            let j = clip.roles.get(role);
            let path: Vec<DVec3> = worlds
                .iter()
                .map(|w| {
                    if role == Role::Pelvis {
                        w.positions[pelvis] - worlds[0].positions[pelvis]
                    } else {
                        let unyaw = DQuat::from_rotation_y(-facing_yaw(w, &clip.roles));
                        unyaw * (w.positions[j] - w.positions[pelvis])
                    }
                })
                .collect();
            let (lo, hi) = path.iter().fold(
                (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
                |(lo, hi), p| (lo.min(*p), hi.max(*p)),
            );
            let raw: Vec<f64> = (0..path.len())
                .map(|k| {
                    let (a, b) = (k.saturating_sub(1), (k + 1).min(path.len() - 1));
                    if b > a {
                        (path[b] - path[a]).length() / ((b - a) as f64 * dt)
                    } else {
                        0.0
                    }
                })
                .collect();
            PartMotion {
                role,
                range_m: (hi - lo).length(),
                speed: smooth(&raw, ((SMOOTHING_S / dt / 2.0).round() as usize).max(1)),
                path,
            }
        })
        .collect()
}

/// A centred moving average `half` frames either side.
pub(super) fn smooth(v: &[f64], half: usize) -> Vec<f64> {
    (0..v.len())
        .map(|k| {
            let (a, b) = (k.saturating_sub(half), (k + half).min(v.len() - 1));
            v[a..=b].iter().sum::<f64>() / (b - a + 1) as f64
        })
        .collect()
}

/// The runs of frames (first, last) where `speed` is over `ACTIVE_SHARE` of
/// its peak, runs closer than `MERGE_GAP_S` merged, twitches dropped.
#[must_use]
pub fn bursts(speed: &[f64], frame_time: f64) -> Vec<(usize, usize)> {
    let peak = speed.iter().copied().fold(0.0, f64::max);
    if peak <= 0.0 {
        return Vec::new();
    }
    let frames = |s: f64| (s / frame_time.max(1e-6)).round() as usize;
    let mut runs: Vec<(usize, usize)> = Vec::new();
    for (k, s) in speed.iter().enumerate() {
        if *s <= ACTIVE_SHARE * peak {
            continue;
        }
        match runs.last_mut() {
            Some((_, last)) if k - *last <= frames(MERGE_GAP_S) => *last = k,
            _ => runs.push((k, k)),
        }
    }
    runs.retain(|(a, b)| b - a >= frames(MIN_BURST_S));
    runs
}

/// Where a take of several movements is cut: at the slowest frame between
/// two bursts, where the part is back near where the take started (within
/// `RETURNED` of its range): five punches from a guard are cut, a bow's
/// pause with the head down is not. Empty when it holds one movement.
#[must_use]
pub fn cuts(motion: &PartMotion, bursts: &[(usize, usize)]) -> Vec<usize> {
    let speed = &motion.speed;
    bursts
        .windows(2)
        .map(|w| {
            let (from, to) = (w[0].1, w[1].0);
            (from..=to)
                .min_by(|a, b| speed[*a].total_cmp(&speed[*b]))
                .unwrap_or(from)
        })
        .filter(|&c| (motion.path[c] - motion.path[0]).length() <= RETURNED * motion.range_m)
        .collect()
}

/// The first and last frames where a piece's speed is over
/// `ACTIVE_SHARE` of its own peak.
pub(super) fn active_span(speed: &[f64]) -> Option<(usize, usize)> {
    let peak = speed.iter().copied().fold(0.0, f64::max);
    if peak <= 0.0 {
        return None;
    }
    let active = |s: &f64| *s > ACTIVE_SHARE * peak;
    Some((
        speed.iter().position(active)?,
        speed.iter().rposition(active)?,
    ))
}

pub(super) fn median(v: &mut [f64]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(v[v.len() / 2])
}
