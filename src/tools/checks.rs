//! Does a clip move like a person? Measurements on a clip's postures: feet
//! sliding while planted, anything below the floor, joints beyond human
//! limits. Pure; used by the default library's tests and by evaluations.

use glam::DVec3;
use serde::Serialize;

use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::{Pose, Skeleton, WorldPose, forward_kinematics};

/// What [`check`] measured.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ClipReport {
    /// Largest horizontal move of a planted foot between two frames (mm).
    pub max_slide_mm: f64,
    /// Where that was: joint name and frame.
    pub worst_slide: String,
    /// Frames in which some foot was planted.
    pub planted_frames: usize,
    /// Lowest point of any joint or End Site below the floor, as a positive
    /// depth (mm); 0 when nothing goes below.
    pub max_penetration_mm: f64,
    /// Joint-limit violations, one line each (first few).
    pub violations: Vec<String>,
}

/// Human joint limits, in degrees.
pub struct Limits {
    pub knee_flexion: f64,
    pub elbow_flexion: f64,
    pub hip_flexion: f64,
    pub hip_extension: f64,
    pub hip_abduction: f64,
    pub head_turn: f64,
    pub spine_turn: f64,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            knee_flexion: 155.0,
            elbow_flexion: 155.0,
            hip_flexion: 125.0,
            hip_extension: 35.0,
            hip_abduction: 45.0,
            head_turn: 80.0,
            spine_turn: 95.0,
        }
    }
}

fn angle(a: DVec3, b: DVec3) -> f64 {
    a.angle_between(b).to_degrees()
}

/// Measure a clip against a floor at `floor_y`.
#[must_use]
pub fn check(
    skeleton: &Skeleton,
    roles: &RoleMap,
    frames: &[Pose],
    floor_y: f64,
    limits: &Limits,
) -> ClipReport {
    let worlds: Vec<WorldPose> = frames
        .iter()
        .map(|p| forward_kinematics(skeleton, p))
        .collect();
    let mut r = ClipReport::default();
    slides(skeleton, roles, &worlds, &mut r);
    for w in &worlds {
        for i in 0..skeleton.len() {
            let y = w
                .end_site(skeleton, i)
                .map_or(w.positions[i].y, |e| e.y.min(w.positions[i].y));
            r.max_penetration_mm = r.max_penetration_mm.max((floor_y - y) * 1e3);
        }
    }
    for (n, w) in worlds.iter().enumerate() {
        let violations = &mut r.violations;
        beyond_limits(roles, w, limits, &mut |what| {
            if violations.len() < 8 {
                violations.push(format!("frame {n}: {what}"));
            }
        });
    }
    r
}

/// The planted feet's slides into `r`: the largest, where, and the frames
/// with a foot planted.
fn slides(skeleton: &Skeleton, roles: &RoleMap, worlds: &[WorldPose], r: &mut ClipReport) {
    let feet = [Role::LeftFoot, Role::RightFoot].map(|f| {
        let ankle = roles.get(f);
        // The foot's lowest descendant (toe or End Site) is its sole.
        let toes: Vec<usize> = (0..skeleton.len())
            .filter(|&i| i != ankle && skeleton.is_ancestor(ankle, i))
            .collect();
        (ankle, toes)
    });
    let low = |w: &WorldPose, (ankle, toes): &(usize, Vec<usize>)| {
        toes.iter()
            .map(|&t| w.positions[t].y)
            .fold(w.positions[*ankle].y, f64::min)
    };
    let planted_refs: Vec<(f64, f64)> = feet
        .iter()
        .map(|f| {
            let sole = worlds
                .iter()
                .map(|w| low(w, f))
                .fold(f64::INFINITY, f64::min);
            let ankle = worlds
                .iter()
                .map(|w| w.positions[f.0].y)
                .fold(f64::INFINITY, f64::min);
            (sole, ankle)
        })
        .collect();
    // The toes are on the floor while the sole is within 1.5 cm of its
    // lowest; the heel (ankle) only while it is within 5 mm of its lowest. A
    // heel rising over planted toes moves the ankle without sliding.
    let toes_down = |w: &WorldPose, k: usize| low(w, &feet[k]) <= planted_refs[k].0 + 0.015;
    let heel_down = |w: &WorldPose, k: usize| w.positions[feet[k].0].y <= planted_refs[k].1 + 0.005;
    for (n, pair) in worlds.windows(2).enumerate() {
        let mut any = false;
        for (k, f) in feet.iter().enumerate() {
            if toes_down(&pair[0], k) && toes_down(&pair[1], k) {
                any = true;
                let heel = heel_down(&pair[0], k) && heel_down(&pair[1], k);
                let points: Vec<usize> = if heel {
                    std::iter::once(f.0).chain(f.1.iter().copied()).collect()
                } else {
                    f.1.clone()
                };
                for &p in &points {
                    let d = pair[1].positions[p] - pair[0].positions[p];
                    let mm = d.x.hypot(d.z) * 1e3;
                    if mm > r.max_slide_mm {
                        r.max_slide_mm = mm;
                        r.worst_slide = format!("{} at frame {}", skeleton.joints[p].name, n + 1);
                    }
                }
            }
        }
        r.planted_frames += usize::from(any);
    }
}

/// Say each joint of one posture past its human limit.
fn beyond_limits(roles: &RoleMap, w: &WorldPose, limits: &Limits, bad: &mut dyn FnMut(String)) {
    let g = |role: Role| w.positions[roles.get(role)];
    let pelvis_rot = w.rotations[roles.get(Role::Pelvis)];
    // The pelvis's frame from where the body is, not from its joint's
    // axes (a rig whose rest pose lies along X has other axes): its
    // side from hip to hip, up towards the chest, forward across both.
    let (up, forward) = frame(
        g(Role::LeftHip) - g(Role::RightHip),
        g(Role::Chest) - g(Role::Pelvis),
    )
    .unwrap_or((pelvis_rot * DVec3::Y, pelvis_rot * DVec3::Z));
    for (hip, knee, foot) in [
        (Role::LeftHip, Role::LeftKnee, Role::LeftFoot),
        (Role::RightHip, Role::RightKnee, Role::RightFoot),
    ] {
        let leg = [(hip, g(hip)), (knee, g(knee)), (foot, g(foot))];
        leg_beyond_limits(leg, (up, forward), limits, bad);
    }
    for (shoulder, elbow, hand) in [
        (Role::LeftShoulder, Role::LeftElbow, Role::LeftHand),
        (Role::RightShoulder, Role::RightElbow, Role::RightHand),
    ] {
        let flex = angle(g(elbow) - g(shoulder), g(hand) - g(elbow));
        if flex > limits.elbow_flexion {
            bad(format!(
                "{elbow} bent {flex:.0}° (limit {})",
                limits.elbow_flexion
            ));
        }
    }
    let chest_rot = w.rotations[roles.get(Role::Chest)];
    let head_rot = w.rotations[roles.get(Role::Head)];
    let head = (chest_rot.inverse() * head_rot)
        .angle_between(glam::DQuat::IDENTITY)
        .to_degrees();
    if head > limits.head_turn {
        bad(format!(
            "head turned {head:.0}° from the chest (limit {})",
            limits.head_turn
        ));
    }
    // The chest's frame against the pelvis's, both from positions
    // (shoulder to shoulder, up the neck), where the rig has them.
    let chest_frame = frame(
        g(Role::LeftShoulder) - g(Role::RightShoulder),
        g(Role::Neck) - g(Role::Chest),
    );
    let spine = match chest_frame {
        Some((c_up, c_forward)) => {
            let m = |u: DVec3, f: DVec3| glam::DMat3::from_cols(u.cross(f), u, f);
            glam::DQuat::from_mat3(&(m(up, forward).transpose() * m(c_up, c_forward)))
                .angle_between(glam::DQuat::IDENTITY)
                .to_degrees()
        }
        None => (pelvis_rot.inverse() * chest_rot)
            .angle_between(glam::DQuat::IDENTITY)
            .to_degrees(),
    };
    if spine > limits.spine_turn {
        bad(format!(
            "chest turned {spine:.0}° from the pelvis (limit {})",
            limits.spine_turn
        ));
    }
}

/// Say a leg's knee and hip past their limits: the knee bent too far or
/// backwards, the thigh flexed, extended or spread too far in the pelvis's
/// frame (`up`, `forward`).
fn leg_beyond_limits(
    [(hip, h), (knee, k), (_, f)]: [(Role, DVec3); 3],
    (up, forward): (DVec3, DVec3),
    limits: &Limits,
    bad: &mut dyn FnMut(String),
) {
    let flex = angle(k - h, f - k);
    if flex > limits.knee_flexion {
        bad(format!(
            "{knee} bent {flex:.0}° (limit {})",
            limits.knee_flexion
        ));
    }
    // The knee may not bend backwards: it lies in front of the
    // hip–ankle line whenever it is bent.
    let line = (f - h).normalize();
    let bulge = (k - h) - line * (k - h).dot(line);
    if flex > 10.0 && bulge.dot(forward) < -0.01 {
        bad(format!("{knee} bends backwards"));
    }
    // Flexion and extension in the pelvis's sagittal plane,
    // abduction across it.
    let thigh = (k - h).normalize();
    let side = up.cross(forward);
    let sagittal = thigh.dot(-up).atan2(thigh.dot(forward));
    let pitch_from_down = 90.0 - sagittal.to_degrees();
    let abduction = thigh.dot(side).abs().asin().to_degrees();
    if pitch_from_down > limits.hip_flexion {
        bad(format!(
            "{hip} flexed {pitch_from_down:.0}° (limit {})",
            limits.hip_flexion
        ));
    }
    if -pitch_from_down > limits.hip_extension {
        bad(format!(
            "{hip} extended {:.0}° backwards (limit {})",
            -pitch_from_down, limits.hip_extension
        ));
    }
    if abduction > limits.hip_abduction {
        bad(format!(
            "{hip} spread {abduction:.0}° sideways (limit {})",
            limits.hip_abduction
        ));
    }
}

/// A body frame from a side-to-side vector (right to left) and one
/// roughly up: its up and forward, orthonormal; `None` where either is
/// degenerate.
fn frame(side: DVec3, towards_up: DVec3) -> Option<(DVec3, DVec3)> {
    let up = towards_up - side * (towards_up.dot(side) / side.length_squared().max(1e-12));
    if side.length() < 1e-6 || up.length() < 1e-6 {
        return None;
    }
    let (side, up) = (side.normalize(), up.normalize());
    Some((up, side.cross(up)))
}
