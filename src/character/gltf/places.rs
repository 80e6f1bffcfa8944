//! The roles settled in the upright figure: names the places contradict
//! overruled (a hand above the head, a foot above its knee, left and
//! right crossed), limbs the names missed found by where the joints
//! stand, the trunk from the limbs, and the ends a reduced rig lacks (a
//! forearm with no hand, a one-bone limb) made up at the end of the last
//! bone's mesh. What a character cannot do without is named, with the
//! joints that were found.

use crate::reading::quote;
use std::collections::BTreeMap;

use glam::{DMat4, DVec3};

use super::humanoid::{self, Evidence, Found, LIMBS, Rig, limb_roles};
use super::read::File;
use super::{GltfError, Part};
use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::{Joint, Skeleton, forward_kinematics};

/// What the skeleton, its rest transforms and the made-up flags become
/// as ends are added.
pub(super) struct Body<'a> {
    pub skeleton: &'a mut Skeleton,
    pub rest: &'a mut Vec<DMat4>,
    pub made_up: &'a mut Vec<bool>,
}

/// Every role settled, with its evidence; `notes` gains what was
/// overruled.
pub(super) fn settle(
    file: &File,
    mut body: Body<'_>,
    parts: &[Part],
    h: f64,
    mut found: Found,
    notes: &mut Vec<String>,
) -> Result<(RoleMap, BTreeMap<Role, Evidence>), GltfError> {
    let p: Vec<DVec3> = forward_kinematics(body.skeleton, &body.skeleton.rest_pose()).positions;
    overrule(body.skeleton, &p, h, &mut found, notes);
    let by_place = by_places(body.skeleton, h);
    for (side, arm) in LIMBS {
        let roles = limb_roles(side, arm);
        let have = roles.iter().filter(|r| found.contains_key(r)).count();
        if have < 3 && roles.iter().all(|r| by_place.contains_key(r)) {
            for r in roles {
                found.insert(r, (by_place[&r], Evidence::Place));
            }
        }
    }
    // The trunk again from the limbs as settled.
    found.retain(|r, (_, e)| {
        !matches!(r, Role::Pelvis | Role::Chest | Role::Neck)
            || matches!(e, Evidence::File | Evidence::Configuration)
    });
    let names: Vec<String> = body
        .skeleton
        .joints
        .iter()
        .map(|j| j.name.clone())
        .collect();
    let parents: Vec<Option<usize>> = body.skeleton.joints.iter().map(|j| j.parent).collect();
    {
        let rig = Rig::new(&names, &parents, &p);
        humanoid::trunk(&rig, &mut found);
    }
    if let (std::collections::btree_map::Entry::Vacant(head), Some(&j)) =
        (found.entry(Role::Head), by_place.get(&Role::Head))
    {
        head.insert((j, Evidence::Place));
        found.entry(Role::Neck).or_insert((j, Evidence::Place));
    }
    let missing = |found: &Found| -> Vec<Role> {
        [
            Role::Pelvis,
            Role::Chest,
            Role::Head,
            Role::LeftShoulder,
            Role::RightShoulder,
            Role::LeftHip,
            Role::RightHip,
        ]
        .into_iter()
        .filter(|r| !found.contains_key(r))
        .collect()
    };
    let lacking = missing(&found);
    if !lacking.is_empty() {
        return Err(refusal(file, body.skeleton, &found, &lacking));
    }
    make_up_ends(&mut body, parts, h, &mut found);
    let head = found[&Role::Head];
    found.entry(Role::Neck).or_insert(head);
    let map: BTreeMap<Role, usize> = found.iter().map(|(r, (j, _))| (*r, *j)).collect();
    let evidence: BTreeMap<Role, Evidence> = found.iter().map(|(r, (_, e))| (*r, *e)).collect();
    Ok((RoleMap(map), evidence))
}

/// Each limb without an end (a hand or foot the rig lacks) given one made
/// up along its last bone, as far as the mesh it carries reaches (and a
/// middle where the limb is one bone), added to the skeleton.
fn make_up_ends(body: &mut Body<'_>, parts: &[Part], h: f64, found: &mut Found) {
    for (side, arm) in LIMBS {
        let [u, m, e] = limb_roles(side, arm);
        let upper = found[&u].0;
        let middle = found.get(&m).map(|x| x.0);
        if found.contains_key(&e) {
            continue;
        }
        let (mid, end) = made_up_end(body, parts, upper, middle, h);
        let last = body.skeleton.joints[middle.unwrap_or(upper)].name.clone();
        let (mid, end) = add_ends(
            body.skeleton,
            body.rest,
            body.made_up,
            &last,
            mid,
            end,
            upper,
            middle,
        );
        if middle.is_none() {
            found.insert(m, (mid, Evidence::MadeUp));
        }
        found.insert(e, (end, Evidence::MadeUp));
    }
}

/// The refusal: what is missing, and every role that was found.
fn refusal(file: &File, skeleton: &Skeleton, found: &Found, lacking: &[Role]) -> GltfError {
    let seen: Vec<String> = found
        .iter()
        .map(|(r, (j, e))| format!("{r} = {} ({})", quote(&skeleton.joints[*j].name), e.name()))
        .collect();
    GltfError::NotHumanoid {
        path: file.path.clone(),
        missing: lacking
            .iter()
            .map(|r| r.name())
            .collect::<Vec<_>>()
            .join(", "),
        found: if seen.is_empty() {
            "none".to_owned()
        } else {
            seen.join(", ")
        },
    }
}

/// Names and hierarchy the places contradict, dropped (and said): a
/// hand above the head, a foot above its knee or a knee above its hip,
/// a left limb standing on the right while the right one stands on the
/// left (its sides swapped).
fn overrule(skeleton: &Skeleton, p: &[DVec3], h: f64, found: &mut Found, notes: &mut Vec<String>) {
    let soft = |e: Evidence| matches!(e, Evidence::Name | Evidence::Hierarchy);
    let head_y = found.get(&Role::Head).map(|&(j, _)| p[j].y);
    let name = |j: usize| quote(&skeleton.joints[j].name);
    for (side, arm) in LIMBS {
        let roles = limb_roles(side, arm);
        let Some(&(end, e)) = found.get(&roles[2]) else {
            continue;
        };
        let wrong = if arm {
            head_y
                .is_some_and(|y| p[end].y > y + 0.05 * h)
                .then(|| format!("{} stands above the head", name(end)))
        } else {
            let above = |a: Role, b: Role| match (found.get(&a), found.get(&b)) {
                (Some(&(x, _)), Some(&(y, _))) => p[x].y > p[y].y + 0.05 * h,
                _ => false,
            };
            (above(roles[2], roles[1]) || above(roles[1], roles[0]))
                .then(|| format!("{} stands above its knee or hip", name(end)))
        };
        if let (Some(why), true) = (wrong, soft(e)) {
            notes.push(format!(
                "{why}: not taken as the {}; found by where joints stand instead",
                roles[2]
            ));
            for r in roles {
                found.remove(&r);
            }
        }
    }
    // Sides: each limb's upper joint should stand on its own side.
    for arm in [true, false] {
        let [l, ..] = limb_roles(humanoid::Side::Left, arm);
        let [r, ..] = limb_roles(humanoid::Side::Right, arm);
        if let (Some(&(a, ea)), Some(&(b, eb))) = (found.get(&l), found.get(&r)) {
            if soft(ea) && soft(eb) && p[a].x < -0.02 * h && p[b].x > 0.02 * h {
                notes.push(format!(
                    "{} and {} are named for the other side from where they stand: swapped",
                    name(a),
                    name(b)
                ));
                let roles = [
                    limb_roles(humanoid::Side::Left, arm),
                    limb_roles(humanoid::Side::Right, arm),
                ];
                let taken: Vec<Option<(usize, Evidence)>> =
                    roles.iter().flatten().map(|r| found.remove(r)).collect();
                for (k, v) in taken.into_iter().enumerate() {
                    if let Some(v) = v {
                        found.insert(roles[1 - k / 3][k % 3], v);
                    }
                }
            }
        }
    }
}

/// Where a limb's missing end (and middle, for a one-bone limb) would be:
/// along the last bone, as far as the mesh it carries reaches.
fn made_up_end(
    body: &Body<'_>,
    parts: &[Part],
    upper: usize,
    middle: Option<usize>,
    h: f64,
) -> (DVec3, DVec3) {
    let at = |j: usize| body.rest[j].w_axis.truncate();
    let last = middle.unwrap_or(upper);
    let carried = carried_points(body.skeleton, parts, last);
    let centre = if carried.is_empty() {
        None
    } else {
        Some(carried.iter().sum::<DVec3>() / carried.len() as f64)
    };
    let dir = match (middle, centre) {
        (Some(m), _) => at(m) - at(upper),
        (None, Some(c)) => c - at(upper),
        (None, None) => DVec3::NEG_Y,
    };
    let dir = if dir.length() > 1e-9 {
        dir.normalize()
    } else {
        DVec3::NEG_Y
    };
    let reach = carried
        .iter()
        .map(|v| (*v - at(last)).dot(dir))
        .fold(0.0f64, f64::max);
    let reach = if reach > 1e-3 * h { reach } else { 0.1 * h };
    let end = at(last) + dir * reach;
    tracing::debug!(
        joint = %body.skeleton.joints[last].name,
        points = carried.len(),
        ?dir,
        reach,
        "a made-up end along the last bone's mesh"
    );
    ((at(upper) + end) / 2.0, end)
}

/// The rest-pose mesh points that `joint`, or the joints below it, carry
/// most.
fn carried_points(skeleton: &Skeleton, parts: &[Part], joint: usize) -> Vec<DVec3> {
    let n = skeleton.len();
    let mut ours = vec![false; n];
    ours[joint] = true;
    for j in 0..n {
        if let Some(p) = skeleton.joints[j].parent {
            if ours[p] {
                ours[j] = true;
            }
        }
    }
    super::carried(parts)
        .filter(|(j, _)| ours.get(*j).copied().unwrap_or(false))
        .map(|(_, v)| v)
        .collect()
}

/// The made-up joints added to the skeleton: an end on the last joint,
/// and for a one-bone limb a middle between: (middle, end) indices (the
/// middle is the limb's own where it has one).
#[allow(clippy::too_many_arguments)]
fn add_ends(
    skeleton: &mut Skeleton,
    rest: &mut Vec<DMat4>,
    made_up: &mut Vec<bool>,
    limb: &str,
    mid: DVec3,
    end: DVec3,
    upper: usize,
    middle: Option<usize>,
) -> (usize, usize) {
    let mut push = |name: String, parent: usize, at: DVec3| {
        let (_, r, _) = rest[parent].to_scale_rotation_translation();
        skeleton.joints.push(Joint {
            name,
            parent: Some(parent),
            offset: at - rest[parent].w_axis.truncate(),
            end_site: None,
        });
        rest.push(DMat4::from_rotation_translation(r, at));
        made_up.push(true);
        skeleton.len() - 1
    };
    let m = match middle {
        Some(m) => m,
        None => push(format!("({limb} middle)"), upper, mid),
    };
    let e = push(format!("({limb} end)"), m, end);
    (m, e)
}
/// Roles from where the joints stand in the upright figure (`h` tall,
/// facing +Z, its left at +X): each side's lowest joint and the low ones
/// above it are the foot, the joint above them (or beside, for a rig whose
/// feet hang from its root) the knee and its parent the hip; the chains
/// that leave the trunk sideways high up are the arms, the first long bone
/// along them the upper arm; the highest joint on the middle line the head.
/// What is missing is named.
pub(super) fn by_places(skeleton: &Skeleton, h: f64) -> BTreeMap<Role, usize> {
    let p: Vec<DVec3> = forward_kinematics(skeleton, &skeleton.rest_pose()).positions;
    let n = skeleton.len();
    let floor = p.iter().map(|q| q.y).fold(f64::INFINITY, f64::min);
    let rest = AtRest {
        skeleton,
        p,
        floor,
        h,
    };
    let (y, parent) = (|j: usize| rest.y(j), |j: usize| skeleton.joints[j].parent);
    let middle = |j: usize| rest.p[j].x.abs() < 0.03 * h;
    let mut size = vec![1usize; n];
    for j in (0..n).rev() {
        if let Some(q) = parent(j) {
            size[q] += size[j];
        }
    }
    for (joint, at) in skeleton.joints.iter().zip(&rest.p) {
        tracing::debug!(
            joint = %joint.name,
            x = at.x / h,
            y = (at.y - floor) / h,
            z = at.z / h,
            "where a joint stands (shares of the height)"
        );
    }
    let mut map = BTreeMap::new();
    if let Some(head) = (0..n)
        .filter(|&j| middle(j))
        .max_by(|&a, &b| y(a).total_cmp(&y(b)))
    {
        map.insert(Role::Head, head);
    }
    for (sign, roles) in [
        (
            1.0,
            [
                Role::LeftFoot,
                Role::LeftKnee,
                Role::LeftHip,
                Role::LeftHand,
                Role::LeftElbow,
                Role::LeftShoulder,
            ],
        ),
        (
            -1.0,
            [
                Role::RightFoot,
                Role::RightKnee,
                Role::RightHip,
                Role::RightHand,
                Role::RightElbow,
                Role::RightShoulder,
            ],
        ),
    ] {
        let side = |j: usize| rest.side(j, sign);
        // The arm: the largest chain leaving the trunk sideways, high.
        let arm_root = (0..n)
            .filter(|&j| side(j) && y(j) > 0.5 * h && parent(j).is_some_and(|q| !side(q)))
            .max_by_key(|&j| size[j]);
        let in_arm = |j: usize| arm_root.is_some_and(|a| skeleton.is_ancestor(a, j));
        let [foot, knee, hip] = rest.leg(sign, &in_arm);
        let [hand, elbow, shoulder] = arm_root.map_or([None; 3], |root| rest.arm(root));
        for (role, j) in roles
            .into_iter()
            .zip([foot, knee, hip, hand, elbow, shoulder])
        {
            if let Some(j) = j {
                map.insert(role, j);
            }
        }
    }
    map
}

/// A skeleton standing at rest: its joints' places, its floor (the lowest
/// joint) and its height.
struct AtRest<'a> {
    skeleton: &'a Skeleton,
    p: Vec<DVec3>,
    floor: f64,
    h: f64,
}

impl AtRest<'_> {
    /// How high joint `j` stands over the floor.
    fn y(&self, j: usize) -> f64 {
        self.p[j].y - self.floor
    }

    fn parent(&self, j: usize) -> Option<usize> {
        self.skeleton.joints[j].parent
    }

    /// Whether joint `j` stands out to the side `sign` (+1 left, -1 right).
    fn side(&self, j: usize, sign: f64) -> bool {
        self.p[j].x * sign > 0.03 * self.h
    }

    /// The leg on side `sign` (not in the arm): foot, knee, hip. The foot
    /// is up from the side's lowest joint while still low; the knee is
    /// its parent, knee-high.
    fn leg(&self, sign: f64, in_arm: &dyn Fn(usize) -> bool) -> [Option<usize>; 3] {
        let (p, h, n) = (&self.p, self.h, self.p.len());
        let (y, parent, side) = (
            |j: usize| self.y(j),
            |j: usize| self.parent(j),
            |j: usize| self.side(j, sign),
        );
        let lowest = (0..n)
            .filter(|&j| side(j) && !in_arm(j))
            .min_by(|&a, &b| y(a).total_cmp(&y(b)))
            .filter(|&j| y(j) < 0.12 * h);
        let foot = lowest.map(|mut j| {
            while let Some(q) = parent(j).filter(|&q| side(q) && y(q) < 0.12 * h) {
                j = q;
            }
            j
        });
        let knee_band = |j: usize| side(j) && !in_arm(j) && (0.12 * h..0.45 * h).contains(&y(j));
        let knee = foot.and_then(|f| {
            parent(f).filter(|&q| knee_band(q)).or_else(|| {
                // Feet that hang from the root: the knee-high joint nearest
                // above the foot that hangs from a hip-high one.
                (0..n)
                    .filter(|&j| knee_band(j) && parent(j).is_some_and(|q| side(q) && y(q) > y(j)))
                    .min_by(|&a, &b| {
                        let d = |j: usize| (p[j] - p[f]).with_y(0.0).length();
                        d(a).total_cmp(&d(b))
                    })
            })
        });
        let hip = knee.and_then(parent).filter(|&q| parent(q).is_some());
        [foot, knee, hip]
    }

    /// The arm from its `root`: hand, elbow, shoulder. Down its chain of
    /// single children, the shoulder starts the first bone a tenth of the
    /// height long.
    fn arm(&self, root: usize) -> [Option<usize>; 3] {
        let (p, skeleton) = (&self.p, self.skeleton);
        let mut chain = vec![root];
        loop {
            let last = *chain.last().unwrap_or(&root);
            let kids: Vec<usize> = skeleton.children(last).collect();
            if kids.len() != 1 {
                break;
            }
            chain.push(kids[0]);
        }
        let Some(i) = (0..chain.len().saturating_sub(1))
            .find(|&i| (p[chain[i + 1]] - p[chain[i]]).length() >= 0.1 * self.h)
        else {
            return [None; 3];
        };
        let hand = chain.get(i + 2).copied().or_else(|| {
            // The forearm ends in several fingers or palms: the one
            // nearest their middle.
            let kids: Vec<usize> = skeleton.children(chain[i + 1]).collect();
            let mid = kids.iter().map(|&k| p[k]).sum::<DVec3>() / kids.len().max(1) as f64;
            kids.into_iter()
                .min_by(|&a, &b| (p[a] - mid).length().total_cmp(&(p[b] - mid).length()))
        });
        [hand, Some(chain[i + 1]), Some(chain[i])]
    }
}
