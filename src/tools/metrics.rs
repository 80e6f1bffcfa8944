//! Motion quality of a replay (`marionette replay --metrics`): NaNs, pops
//! (jumps in joint angular speed between consecutive frames, which show on
//! mode switches), planted feet sliding, the body going into the floor.

use serde::Serialize;

use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::{Pose, Skeleton, WorldPose, forward_kinematics, sole};

/// A jump in a joint's angular speed larger than this between two frames
/// (rad/s) counts as a pop: 10 rad/s in one 1/30 s frame is 300 rad/s²,
/// about three times what the library's own quickest motions (punches,
/// kicks) reach.
pub const POP_RAD_S: f64 = 10.0;

/// Pops listed by name at most.
const MAX_LISTED: usize = 40;

/// What `--metrics` writes (plus the actions, added by the caller).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Metrics {
    pub frames: usize,
    pub nan_frames: usize,
    /// Largest change of any joint's angular speed between consecutive
    /// frames (rad/s).
    pub max_joint_speed_jump_rad_s: f64,
    /// Where it was: joint and time (s).
    pub worst_jump: String,
    /// Frames whose speed jump exceeds [`POP_RAD_S`]...
    pub pops: usize,
    /// ...the first of them: time (s), joint and jump (rad/s).
    pub pop_list: Vec<String>,
    /// Mean horizontal slide of planted feet per frame (mm)...
    pub foot_skate_mm_per_frame: f64,
    /// ...and the largest (mm), with the foot and time.
    pub foot_skate_max_mm: f64,
    pub worst_skate: String,
    /// Deepest point of the body below the floor (mm; 0 if none), with the
    /// joint and time.
    pub ground_penetration_mm: f64,
    pub worst_penetration: String,
}

fn finite(p: &Pose) -> bool {
    p.rotations
        .iter()
        .all(|q| q.to_array().iter().all(|v| v.is_finite()))
        && p.translations.iter().all(|t| t.is_finite())
}

/// Measure postures stepped every `dt` seconds.
#[must_use]
pub fn measure(skeleton: &Skeleton, roles: &RoleMap, poses: &[Pose], dt: f64) -> Metrics {
    let mut m = Metrics {
        frames: poses.len(),
        ..Metrics::default()
    };
    let good: Vec<bool> = poses.iter().map(finite).collect();
    m.nan_frames = good.iter().filter(|g| !**g).count();
    // Angular speed of every joint's local rotation.
    let speeds: Vec<Option<Vec<f64>>> = poses
        .windows(2)
        .zip(good.windows(2))
        .map(|(p, g)| {
            (g[0] && g[1]).then(|| {
                p[0].rotations
                    .iter()
                    .zip(&p[1].rotations)
                    .map(|(a, b)| a.angle_between(*b) / dt)
                    .collect()
            })
        })
        .collect();
    for (k, w) in speeds.windows(2).enumerate() {
        let (Some(a), Some(b)) = (&w[0], &w[1]) else {
            continue;
        };
        let mut frame_max = (0.0f64, 0usize);
        for (j, (x, y)) in a.iter().zip(b).enumerate() {
            let jump = (y - x).abs();
            if jump > frame_max.0 {
                frame_max = (jump, j);
            }
            if jump > m.max_joint_speed_jump_rad_s {
                m.max_joint_speed_jump_rad_s = jump;
                m.worst_jump = format!(
                    "{} at {:.2} s",
                    skeleton.joints[j].name,
                    (k + 2) as f64 * dt
                );
            }
        }
        if frame_max.0 > POP_RAD_S {
            m.pops += 1;
            if m.pop_list.len() < MAX_LISTED {
                m.pop_list.push(format!(
                    "{:.2} s {} {:.1} rad/s",
                    (k + 2) as f64 * dt,
                    skeleton.joints[frame_max.1].name,
                    frame_max.0
                ));
            }
        }
    }
    // Feet: planted while the sole is within 2 cm of the floor in both
    // frames; the floor is at 0.
    let worlds: Vec<Option<WorldPose>> = poses
        .iter()
        .zip(&good)
        .map(|(p, g)| g.then(|| forward_kinematics(skeleton, p)))
        .collect();
    let feet = [roles.get(Role::LeftFoot), roles.get(Role::RightFoot)];
    let (mut sum, mut n) = (0.0, 0usize);
    for (k, pair) in worlds.windows(2).enumerate() {
        let (Some(a), Some(b)) = (&pair[0], &pair[1]) else {
            continue;
        };
        for &f in &feet {
            let (sa, sb) = (sole(skeleton, a, f), sole(skeleton, b, f));
            if sa.y < 0.02 && sb.y < 0.02 {
                let mm = (sb - sa).with_y(0.0).length() * 1e3;
                sum += mm;
                n += 1;
                if mm > m.foot_skate_max_mm {
                    m.foot_skate_max_mm = mm;
                    m.worst_skate = format!(
                        "{} at {:.2} s",
                        skeleton.joints[f].name,
                        (k + 2) as f64 * dt
                    );
                }
            }
        }
    }
    m.foot_skate_mm_per_frame = if n == 0 { 0.0 } else { sum / n as f64 };
    for (k, w) in worlds.iter().enumerate() {
        let Some(w) = w else { continue };
        for i in 0..skeleton.len() {
            let y = w
                .end_site(skeleton, i)
                .map_or(w.positions[i].y, |e| e.y.min(w.positions[i].y));
            if -y * 1e3 > m.ground_penetration_mm {
                m.ground_penetration_mm = -y * 1e3;
                m.worst_penetration = format!(
                    "{} at {:.2} s",
                    skeleton.joints[i].name,
                    (k + 1) as f64 * dt
                );
            }
        }
    }
    let r = |v: f64| (v * 1000.0).round() / 1000.0;
    m.max_joint_speed_jump_rad_s = r(m.max_joint_speed_jump_rad_s);
    m.foot_skate_mm_per_frame = r(m.foot_skate_mm_per_frame);
    m.foot_skate_max_mm = r(m.foot_skate_max_mm);
    m.ground_penetration_mm = r(m.ground_penetration_mm);
    m
}
