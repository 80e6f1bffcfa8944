//! Inverse kinematics after the blend (the paper's section 4): two-bone IK
//! that keeps a limb's bend plane, CCD for what it cannot reach, at most
//! 0.2 m of movement, and planted feet put back where they stood.

use glam::{DQuat, DVec3};

use super::constraint::Constraint;
use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::{Pose, Skeleton, forward_kinematics, two_bone_turns};

/// The joints CCD turns to move a body part: the limb's own joints (elbow
/// and shoulder for a hand, knee and hip for a foot, neck and chest for the
/// head), never twist or helper bones.
pub(crate) fn chain(skeleton: &Skeleton, roles: &RoleMap, role: Role) -> Vec<usize> {
    let r = |roles_: &[Role]| roles_.iter().map(|x| roles.get(*x)).collect::<Vec<_>>();
    // The joint between the shoulder and the chest (a clavicle), if any.
    let clavicle = |shoulder: Role| {
        let p = skeleton.joints[roles.get(shoulder)].parent;
        p.filter(|&p| p != roles.get(Role::Chest))
            .into_iter()
            .collect::<Vec<_>>()
    };
    match role {
        Role::LeftHand => [
            r(&[Role::LeftElbow, Role::LeftShoulder]),
            clavicle(Role::LeftShoulder),
        ]
        .concat(),
        Role::RightHand => [
            r(&[Role::RightElbow, Role::RightShoulder]),
            clavicle(Role::RightShoulder),
        ]
        .concat(),
        Role::LeftFoot => r(&[Role::LeftKnee, Role::LeftHip]),
        Role::RightFoot => r(&[Role::RightKnee, Role::RightHip]),
        Role::LeftElbow => r(&[Role::LeftShoulder]),
        Role::RightElbow => r(&[Role::RightShoulder]),
        Role::LeftKnee => r(&[Role::LeftHip]),
        Role::RightKnee => r(&[Role::RightHip]),
        Role::Head => r(&[Role::Neck, Role::Chest]),
        Role::Neck => r(&[Role::Chest]),
        _ => Vec::new(),
    }
}

/// Foot IK: keep each foot given a position there, turning only knee and
/// hip (the feet that carry the body stay put when the pelvis moves).
pub fn plant_feet(skeleton: &Skeleton, roles: &RoleMap, pose: &mut Pose, at: [Option<DVec3>; 2]) {
    let goals: Vec<(usize, Vec<usize>, DVec3)> =
        [(Role::LeftFoot, at[0]), (Role::RightFoot, at[1])]
            .into_iter()
            .filter_map(|(r, p)| p.map(|p| (roles.get(r), chain(skeleton, roles, r), p)))
            .collect();
    if !goals.is_empty() {
        ccd(skeleton, pose, &goals, 12);
    }
}

/// CCD IK: move each effector towards its goal, turning the joints of its
/// chain, nearest first. Turning a chain joint moves neither its ancestors
/// nor their rotations, so one pass of forward kinematics down the path
/// from the root to the effector per goal and sweep suffices; sweeps stop
/// once every goal is within 0.1 mm.
pub fn ccd(
    skeleton: &Skeleton,
    pose: &mut Pose,
    goals: &[(usize, Vec<usize>, DVec3)],
    sweeps: usize,
) {
    ccd_within(skeleton, pose, goals, sweeps, |_, q| q);
}

/// [`ccd`] with each joint's turn kept within what `limit` allows: it
/// maps joint `j`'s new local rotation to the nearest it may take.
pub fn ccd_within(
    skeleton: &Skeleton,
    pose: &mut Pose,
    goals: &[(usize, Vec<usize>, DVec3)],
    sweeps: usize,
    limit: impl Fn(usize, DQuat) -> DQuat,
) {
    // Per goal: the path from the root down to the effector, and where each
    // chain joint lies on it (a chain joint off the path cannot move it).
    let paths: Vec<(Vec<usize>, Vec<usize>)> = goals
        .iter()
        .map(|(effector, chain, _)| {
            let mut path = vec![*effector];
            while let Some(p) = skeleton.joints[*path.last().unwrap_or(effector)].parent {
                path.push(p);
            }
            path.reverse();
            let on_path = chain
                .iter()
                .filter_map(|j| path.iter().position(|p| p == j))
                .collect();
            (path, on_path)
        })
        .collect();
    let mut positions = Vec::new();
    let mut rotations = Vec::new();
    for _ in 0..sweeps {
        let mut worst = 0.0f64;
        for ((_, _, goal), (path, on_path)) in goals.iter().zip(&paths) {
            positions.clear();
            rotations.clear();
            for (k, &j) in path.iter().enumerate() {
                let (p, r) = if k == 0 {
                    (pose.translations[j], pose.rotations[j])
                } else {
                    let pr: DQuat = rotations[k - 1];
                    (
                        positions[k - 1] + pr * pose.translations[j],
                        pr * pose.rotations[j],
                    )
                };
                positions.push(p);
                rotations.push(r.normalize());
            }
            let Some(mut end) = positions.last().copied() else {
                continue;
            };
            worst = worst.max((end - *goal).length());
            for &k in on_path {
                let j = path[k];
                let pivot = positions[k];
                let (a, b) = (end - pivot, *goal - pivot);
                if a.length() < 1e-9 || b.length() < 1e-9 {
                    continue;
                }
                let turn = DQuat::from_rotation_arc(a.normalize(), b.normalize());
                let parent_rot = if k == 0 {
                    DQuat::IDENTITY
                } else {
                    rotations[k - 1]
                };
                // This joint's world rotation now, after the turns of the
                // joints below it (which do not change it).
                let current = parent_rot * pose.rotations[j];
                let local = limit(j, (parent_rot.inverse() * (turn * current)).normalize());
                pose.rotations[j] = local;
                // Where the effector went with the turn the limit allowed.
                let turn = parent_rot * local * current.inverse();
                end = pivot + turn * a;
            }
        }
        if worst < 1e-4 {
            break;
        }
    }
}

/// The limb of a hand or foot: its upper joint (shoulder or hip) and its
/// middle joint (elbow or knee).
pub(crate) fn limb(roles: &RoleMap, role: Role) -> Option<(usize, usize)> {
    let (upper, middle) = match role {
        Role::LeftHand => (Role::LeftShoulder, Role::LeftElbow),
        Role::RightHand => (Role::RightShoulder, Role::RightElbow),
        Role::LeftFoot => (Role::LeftHip, Role::LeftKnee),
        Role::RightFoot => (Role::RightHip, Role::RightKnee),
        _ => return None,
    };
    Some((roles.get(upper), roles.get(middle)))
}

/// Turn joint `j` of `pose` by the world rotation `turn`, `world` being the
/// pose's world rotations before the turn.
pub(crate) fn turn_joint(
    skeleton: &Skeleton,
    pose: &mut Pose,
    world: &[DQuat],
    j: usize,
    turn: DQuat,
) {
    let parent = skeleton.joints[j]
        .parent
        .map_or(DQuat::IDENTITY, |p| world[p]);
    pose.rotations[j] = (parent.inverse() * (turn * world[j])).normalize();
}

/// Two-bone IK: bend the middle joint so that the limb spans the distance
/// to the goal, then swing the upper joint onto it; the limb keeps the plane
/// it bends in (the least turn that reaches).
pub fn two_bone(
    skeleton: &Skeleton,
    pose: &mut Pose,
    (upper, middle, end): (usize, usize, usize),
    goal: DVec3,
) {
    let w = forward_kinematics(skeleton, pose);
    let (a, b, c) = (w.positions[upper], w.positions[middle], w.positions[end]);
    let Some((bend_a, bend_b, swing)) = two_bone_turns(a, b, c, goal) else {
        return;
    };
    turn_joint(skeleton, pose, &w.rotations, middle, bend_b);
    turn_joint(skeleton, pose, &w.rotations, upper, swing * bend_a);
}

/// IK onto the constraints (each part moved at most `max_move`) and onto
/// planted foot positions: the head by CCD first (it turns the chest, which
/// carries the arms), then each limb by two-bone IK, then CCD for what is
/// left (a goal beyond a straight limb's reach, which the clavicle helps
/// with).
pub fn apply_ik(
    skeleton: &Skeleton,
    roles: &RoleMap,
    pose: &mut Pose,
    constraints: &[Constraint],
    planted: Option<[DVec3; 2]>,
    max_move: f64,
) {
    let w = forward_kinematics(skeleton, pose);
    let mut goals = Vec::new();
    for c in constraints {
        if c.role == Role::Pelvis {
            continue;
        }
        let e = roles.get(c.role);
        let from = w.positions[e];
        let to = c.target.nearest(from);
        let step = to - from;
        let goal = if step.length() > max_move {
            from + step * (max_move / step.length())
        } else {
            to
        };
        goals.push((c.role, goal));
    }
    if let Some(feet) = planted {
        for (role, at) in [(Role::LeftFoot, feet[0]), (Role::RightFoot, feet[1])] {
            if constraints.iter().all(|c| c.role != role) {
                goals.push((role, at));
            }
        }
    }
    let (limbs, others): (Vec<_>, Vec<_>) = goals
        .iter()
        .partition(|(role, _)| limb(roles, *role).is_some());
    let ccd_goals = |goals: &[&(Role, DVec3)]| -> Vec<(usize, Vec<usize>, DVec3)> {
        goals
            .iter()
            .map(|(role, goal)| (roles.get(*role), chain(skeleton, roles, *role), *goal))
            .collect()
    };
    if !others.is_empty() {
        ccd(skeleton, pose, &ccd_goals(&others), 30);
    }
    for (role, goal) in &limbs {
        if let Some((upper, middle)) = limb(roles, *role) {
            two_bone(skeleton, pose, (upper, middle, roles.get(*role)), *goal);
        }
    }
    let all: Vec<&(Role, DVec3)> = goals.iter().collect();
    if !all.is_empty() {
        ccd(skeleton, pose, &ccd_goals(&all), 30);
    }
    // The head keeps the way it looked (turning the neck and chest to move
    // it would turn its gaze).
    if goals.iter().any(|(role, _)| *role == Role::Head) {
        let j = roles.get(Role::Head);
        let now = forward_kinematics(skeleton, pose);
        let parent = skeleton.joints[j]
            .parent
            .map_or(DQuat::IDENTITY, |p| now.rotations[p]);
        pose.rotations[j] = (parent.inverse() * w.rotations[j]).normalize();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::character::skeleton::Joint;

    /// A leg hanging from a root: hip, knee, ankle.
    fn leg() -> Skeleton {
        let joint = |name: &str, parent, y| Joint {
            name: name.to_owned(),
            parent,
            offset: DVec3::new(0.0, y, 0.0),
            end_site: None,
        };
        Skeleton {
            joints: vec![
                joint("Root", None, 1.0),
                joint("Hip", Some(0), 0.0),
                joint("Knee", Some(1), -0.45),
                joint("Ankle", Some(2), -0.45),
            ],
        }
    }

    #[test]
    fn ccd_within_limits_turns_no_joint_past_its_limit_and_gets_as_near_as_that_allows() {
        let sk = leg();
        let rest = sk.rest_pose();
        let goal = DVec3::new(0.0, 0.5, 0.4);
        let goals = [(3, vec![2, 1], goal)];
        let dist = |p: &Pose| (forward_kinematics(&sk, p).positions[3] - goal).length();
        // Unlimited, the ankle reaches the goal.
        let mut free = rest.clone();
        ccd(&sk, &mut free, &goals, 12);
        assert!(dist(&free) < 1e-3, "{}", dist(&free));
        // Each joint turned at most 0.2 rad from rest: none turns further,
        // and the ankle comes nearer than it was.
        let most = 0.2;
        let limit = |j: usize, q: DQuat| {
            let from = rest.rotations[j];
            let d = q * from.inverse();
            let angle = d.to_scaled_axis().length();
            if angle > most {
                (DQuat::from_scaled_axis(d.to_scaled_axis() * (most / angle)) * from).normalize()
            } else {
                q
            }
        };
        let mut held = rest.clone();
        ccd_within(&sk, &mut held, &goals, 12, limit);
        for j in [1, 2] {
            let turned = (held.rotations[j] * rest.rotations[j].inverse()).to_scaled_axis();
            assert!(
                turned.length() <= most + 1e-9,
                "joint {j} turned {}",
                turned.length()
            );
        }
        assert!(
            dist(&held) < dist(&rest) - 0.1,
            "{} vs {}",
            dist(&held),
            dist(&rest)
        );
        assert!(dist(&held) > 0.05, "the limits keep it from the goal");
    }
}
