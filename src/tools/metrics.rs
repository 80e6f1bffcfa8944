//! Motion quality of a replay (`marionette replay --metrics`): NaNs, pops
//! (jumps in joint angular speed between consecutive frames, which show on
//! mode switches), planted feet sliding, the body going into the floor.

use serde::Serialize;

use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::{Pose, Skeleton, WorldPose, foot_points, forward_kinematics};

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

/// Motion quality of postures stepped every `dt` seconds, one posture at a
/// time, in bounded memory: it keeps the last
/// posture and its joints' speeds only, so a replay of hours is measured
/// as it runs.
pub struct Meter<'a> {
    skeleton: &'a Skeleton,
    feet: [usize; 2],
    dt: f64,
    m: Metrics,
    /// The last posture (when finite), its world pose and its joints'
    /// angular speeds since the one before (when both were finite).
    last: Option<(Pose, WorldPose)>,
    speeds: Option<Vec<f64>>,
    skate_sum: f64,
    skate_n: usize,
}

impl<'a> Meter<'a> {
    #[must_use]
    pub fn new(skeleton: &'a Skeleton, roles: &RoleMap, dt: f64) -> Self {
        Self {
            skeleton,
            feet: [roles.get(Role::LeftFoot), roles.get(Role::RightFoot)],
            dt,
            m: Metrics::default(),
            last: None,
            speeds: None,
            skate_sum: 0.0,
            skate_n: 0,
        }
    }

    /// The next posture, `held` the parts fingers hold: a foot a finger
    /// drags along the floor is the visitor's doing, not skating.
    pub fn push(&mut self, pose: &Pose, held: &[Role]) {
        let k = self.m.frames;
        self.m.frames += 1;
        if !finite(pose) {
            self.m.nan_frames += 1;
            self.last = None;
            self.speeds = None;
            return;
        }
        let world = forward_kinematics(self.skeleton, pose);
        let time_s = (k + 1) as f64 * self.dt;
        if let Some((prev, prev_world)) = self.last.take() {
            self.jumps(&prev, pose, time_s);
            self.skates(&prev_world, &world, held, time_s);
        }
        self.penetration(&world, time_s);
        self.last = Some((pose.clone(), world));
    }

    /// Angular speed of every joint's local rotation since `prev`, and its
    /// jump from the frame before: the largest, and the frames where one
    /// pops.
    fn jumps(&mut self, prev: &Pose, pose: &Pose, time_s: f64) {
        let (skeleton, dt, m) = (self.skeleton, self.dt, &mut self.m);
        let speeds: Vec<f64> = prev
            .rotations
            .iter()
            .zip(&pose.rotations)
            .map(|(a, b)| a.angle_between(*b) / dt)
            .collect();
        if let Some(before) = &self.speeds {
            let mut frame_max = (0.0f64, 0usize);
            for (j, (x, y)) in before.iter().zip(&speeds).enumerate() {
                let jump = (y - x).abs();
                if jump > frame_max.0 {
                    frame_max = (jump, j);
                }
                if jump > m.max_joint_speed_jump_rad_s {
                    m.max_joint_speed_jump_rad_s = jump;
                    m.worst_jump = format!("{} at {time_s:.2} s", skeleton.joints[j].name);
                }
            }
            if frame_max.0 > POP_RAD_S {
                m.pops += 1;
                if m.pop_list.len() < MAX_LISTED {
                    m.pop_list.push(format!(
                        "{time_s:.2} s {} {:.1} rad/s",
                        skeleton.joints[frame_max.1].name, frame_max.0
                    ));
                }
            }
        }
        self.speeds = Some(speeds);
    }

    /// Feet: a point of the foot (ankle, toes, their End Sites) within 2 cm
    /// of the floor in both frames is planted, and its horizontal slide is
    /// skating; a foot's slide in a step is its planted points' largest.
    /// The same point is followed from frame to frame: a foot that rolls
    /// from heel to toes does not skate, though its lowest point moves. A
    /// held foot is not counted.
    fn skates(&mut self, prev_world: &WorldPose, world: &WorldPose, held: &[Role], time_s: f64) {
        let skeleton = self.skeleton;
        for (&f, role) in self.feet.iter().zip([Role::LeftFoot, Role::RightFoot]) {
            if held.contains(&role) {
                continue;
            }
            let planted: Vec<f64> = foot_points(skeleton, prev_world, f)
                .zip(foot_points(skeleton, world, f))
                .filter(|(a, b)| a.y < 0.02 && b.y < 0.02)
                .map(|(a, b)| (b - a).with_y(0.0).length() * 1e3)
                .collect();
            if let Some(mm) = planted.into_iter().reduce(f64::max) {
                tracing::trace!(
                    time_s,
                    foot = %skeleton.joints[f].name,
                    mm,
                    "planted foot slid"
                );
                self.skate_sum += mm;
                self.skate_n += 1;
                if mm > self.m.foot_skate_max_mm {
                    self.m.foot_skate_max_mm = mm;
                    self.m.worst_skate = format!("{} at {time_s:.2} s", skeleton.joints[f].name);
                }
            }
        }
    }

    /// The deepest any joint or End Site goes under the floor.
    fn penetration(&mut self, world: &WorldPose, time_s: f64) {
        let (skeleton, m) = (self.skeleton, &mut self.m);
        for i in 0..skeleton.len() {
            let y = world
                .end_site(skeleton, i)
                .map_or(world.positions[i].y, |e| e.y.min(world.positions[i].y));
            if -y * 1e3 > m.ground_penetration_mm {
                m.ground_penetration_mm = -y * 1e3;
                m.worst_penetration = format!("{} at {time_s:.2} s", skeleton.joints[i].name);
            }
        }
    }

    /// The figures over every posture pushed.
    #[must_use]
    pub fn finish(self) -> Metrics {
        let mut m = self.m;
        m.foot_skate_mm_per_frame = if self.skate_n == 0 {
            0.0
        } else {
            self.skate_sum / self.skate_n as f64
        };
        let r = |v: f64| (v * 1000.0).round() / 1000.0;
        m.max_joint_speed_jump_rad_s = r(m.max_joint_speed_jump_rad_s);
        m.foot_skate_mm_per_frame = r(m.foot_skate_mm_per_frame);
        m.foot_skate_max_mm = r(m.foot_skate_max_mm);
        m.ground_penetration_mm = r(m.ground_penetration_mm);
        m
    }
}

#[cfg(test)]
mod tests {
    use glam::{DQuat, DVec3};

    use super::*;
    use crate::character::skeleton::Joint;

    #[test]
    fn a_foot_that_rolls_onto_its_toes_does_not_skate_one_that_slides_does() {
        // An ankle 8 cm up, the toe joint 12 cm ahead and 1 cm off the
        // floor, the toe tip 5 cm further and 3 mm higher (a flat foot's
        // lowest point is the toe joint); the foot turns about the tip.
        let joint = |name: &str, parent, offset: DVec3| Joint {
            name: name.to_owned(),
            parent,
            offset,
            end_site: None,
        };
        let mut skeleton = Skeleton {
            joints: vec![
                joint("LeftFoot", None, DVec3::ZERO),
                joint("LeftToe", Some(0), DVec3::new(0.0, -0.07, 0.12)),
            ],
        };
        skeleton.joints[1].end_site = Some(DVec3::new(0.0, 0.003, 0.05));
        let mut roles = RoleMap::default();
        for r in Role::ALL {
            roles.0.insert(r, 0);
        }
        let tip = DVec3::new(0.0, 0.013, 0.17);
        let pose = |pitch: f64, slide: f64| {
            // Turned about the toe tip, then slid along x.
            let q = DQuat::from_rotation_x(pitch);
            let ankle = tip + q * (DVec3::new(0.0, 0.08, 0.0) - tip) + DVec3::X * slide;
            Pose {
                translations: vec![ankle, DVec3::new(0.0, -0.07, 0.12)],
                rotations: vec![q, DQuat::IDENTITY],
            }
        };
        let skate = |poses: &[Pose]| {
            let mut m = Meter::new(&skeleton, &roles, 1.0 / 30.0);
            for p in poses {
                m.push(p, &[]);
            }
            m.finish().foot_skate_max_mm
        };
        // Rolling: the lowest point jumps 5 cm from the toe joint to the
        // tip, but the tip stays where it is.
        let low = |p: &Pose| {
            crate::character::skeleton::sole(&skeleton, &forward_kinematics(&skeleton, p), 0)
        };
        let jumped = (low(&pose(0.2, 0.0)) - low(&pose(0.0, 0.0)))
            .with_y(0.0)
            .length();
        assert!(jumped > 0.04, "{jumped}");
        let roll = skate(&[pose(0.0, 0.0), pose(0.2, 0.0), pose(0.4, 0.0)]);
        assert!(roll < 0.5, "{roll} mm");
        let slide = skate(&[pose(0.0, 0.0), pose(0.0, 0.03)]);
        assert!((slide - 30.0).abs() < 0.5, "{slide} mm");
    }

    #[test]
    fn a_sudden_turn_is_a_pop_and_a_nan_frame_breaks_the_chain() {
        let joint = |name: &str, parent, y| Joint {
            name: name.to_owned(),
            parent,
            offset: DVec3::new(0.0, y, 0.0),
            end_site: None,
        };
        let skeleton = Skeleton {
            joints: vec![joint("Hips", None, 1.0), joint("Spine", Some(0), 0.3)],
        };
        let mut roles = RoleMap::default();
        for r in Role::ALL {
            roles.0.insert(r, 1);
        }
        roles.0.insert(Role::Pelvis, 0);
        let pose = |angle: f64| Pose {
            translations: vec![DVec3::new(0.0, 1.0, 0.0), DVec3::new(0.0, 0.3, 0.0)],
            rotations: vec![DQuat::IDENTITY, DQuat::from_rotation_x(angle)],
        };
        let dt = 1.0 / 30.0;
        let mut m = Meter::new(&skeleton, &roles, dt);
        // Still, still, then 0.5 rad in one frame: 15 rad/s at once.
        for a in [0.0, 0.0, 0.5, 0.5] {
            m.push(&pose(a), &[]);
        }
        let mut nan = pose(0.5);
        nan.rotations[1] = DQuat::from_xyzw(f64::NAN, 0.0, 0.0, 1.0);
        m.push(&nan, &[]);
        // After the NaN, speeds start afresh: no jump from the bad frame.
        m.push(&pose(1.5), &[]);
        let r = m.finish();
        assert_eq!(r.frames, 6);
        assert_eq!(r.nan_frames, 1);
        assert_eq!(r.pops, 2, "{r:?}");
        assert!((r.max_joint_speed_jump_rad_s - 15.0).abs() < 1e-3, "{r:?}");
        assert_eq!(r.worst_jump, "Spine at 0.10 s");
    }
}
