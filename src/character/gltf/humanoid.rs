//! Which joint of an exhibit's rig plays which role, role by role, from
//! the best evidence there is: the file's own humanoid map (VRM), the
//! configuration, joint names (a table of the conventions exhibit builders
//! meet), the hierarchy (limbs are chains that leave the trunk; the joint
//! above a hand is the forearm's), and where joints stand once the body
//! is upright (left and right, high and low). Each piece is checked
//! against the others: a name the hierarchy or the places contradict is
//! overruled, and said.

use std::collections::BTreeMap;

use glam::DVec3;
use serde::Serialize;

use crate::character::roles::Role;

/// Where a role's joint came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Evidence {
    /// The file's own humanoid map (VRM's `humanBones`).
    File,
    /// `[character.mesh_roles]` (or a library's `[roles]`).
    Configuration,
    /// The joint's name says the part.
    Name,
    /// Its place in the hierarchy (the joint above a named hand, where
    /// the legs branch, ...).
    Hierarchy,
    /// Where it stands in the bind pose.
    Place,
    /// Made up where the rig has no joint: the end of the last bone's
    /// mesh (a forearm with no hand, a one-bone limb).
    MadeUp,
}

impl Evidence {
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Evidence::File => "file",
            Evidence::Configuration => "configuration",
            Evidence::Name => "name",
            Evidence::Hierarchy => "hierarchy",
            Evidence::Place => "place",
            Evidence::MadeUp => "made up",
        }
    }
}

pub(super) use super::names::{LIMBS, Seg, Side, classify, limb_roles};
pub use super::vrm::Credit;
pub(super) use super::vrm::{VRM_BONES, vrm_bones, vrm_credit};

/// The joints as role finding sees them: names, parents, places.
pub(super) struct Rig<'a> {
    pub names: &'a [String],
    pub parents: &'a [Option<usize>],
    pub places: &'a [DVec3],
    pub classes: Vec<(Option<Side>, Seg)>,
    pub depth: Vec<usize>,
    children: Vec<Vec<usize>>,
    /// Joints under each joint, itself included.
    size: Vec<usize>,
}

impl<'a> Rig<'a> {
    pub(super) fn new(
        names: &'a [String],
        parents: &'a [Option<usize>],
        places: &'a [DVec3],
    ) -> Self {
        let n = names.len();
        let mut children = vec![Vec::new(); n];
        let mut depth = vec![0; n];
        // Parents come first in the order joints are given.
        for j in 0..n {
            if let Some(p) = parents[j] {
                children[p].push(j);
                depth[j] = depth[p] + 1;
            }
        }
        let mut size = vec![1usize; n];
        for j in (0..n).rev() {
            if let Some(p) = parents[j] {
                size[p] += size[j];
            }
        }
        Self {
            names,
            parents,
            places,
            classes: names.iter().map(|s| classify(s)).collect(),
            depth,
            children,
            size,
        }
    }

    fn seg(&self, j: usize) -> Seg {
        self.classes[j].1
    }

    fn side(&self, j: usize) -> Option<Side> {
        self.classes[j].0
    }

    fn is_helper(&self, j: usize) -> bool {
        matches!(self.seg(j), Seg::Helper)
    }

    pub(super) fn is_ancestor(&self, a: usize, mut j: usize) -> bool {
        loop {
            if j == a {
                return true;
            }
            match self.parents[j] {
                Some(p) => j = p,
                None => return false,
            }
        }
    }

    fn common_ancestor(&self, a: usize, b: usize) -> usize {
        let mut x = a;
        loop {
            if self.is_ancestor(x, b) {
                return x;
            }
            match self.parents[x] {
                Some(p) => x = p,
                None => return x,
            }
        }
    }

    /// The first joint above `j` that is not a helper.
    fn limb_parent(&self, j: usize) -> Option<usize> {
        let mut p = self.parents[j]?;
        while self.is_helper(p) {
            p = self.parents[p]?;
        }
        Some(p)
    }

    /// The child of `j` a limb goes on through: not a helper, finger or
    /// face joint, the one with most joints under it.
    fn limb_child(&self, j: usize) -> Option<usize> {
        let mut best: Option<usize> = None;
        let mut stack: Vec<usize> = self.children[j].clone();
        while let Some(c) = stack.pop() {
            match self.seg(c) {
                // Through a helper to what hangs under it.
                Seg::Helper => stack.extend(self.children[c].iter().copied()),
                Seg::Finger | Seg::Face | Seg::Toe => {}
                _ => {
                    if best.is_none_or(|b| self.size[c] > self.size[b]) {
                        best = Some(c);
                    }
                }
            }
        }
        best
    }

    /// Whether a joint's name says the same part as its parent's, as
    /// segments of one bone do (`upper_arm.L`, `upper_arm.L.001`).
    fn same_bone(&self, j: usize, other: usize) -> bool {
        let (a, b) = (&self.names[j], &self.names[other]);
        let (short, long) = if a.len() <= b.len() { (a, b) } else { (b, a) };
        // Blender numbers the segments of one bone `.001`, `.002`.
        self.classes[j] == self.classes[other]
            && long.strip_prefix(short.as_str()).is_some_and(|rest| {
                rest.len() == 4
                    && rest.starts_with(['.', '_'])
                    && rest[1..].chars().all(|c| c.is_ascii_digit())
            })
    }

    /// The top of the run of joints named as `j` is, up from it.
    fn run_top(&self, mut j: usize) -> usize {
        while let Some(p) = self.limb_parent(j).filter(|&p| self.same_bone(p, j)) {
            j = p;
        }
        j
    }

    /// The bottom of the run of joints named as `j` is, down from it.
    fn run_bottom(&self, mut j: usize) -> usize {
        while let Some(c) = self.limb_child(j).filter(|&c| self.same_bone(c, j)) {
            j = c;
        }
        j
    }

    /// The joints down a limb from `j` (its limb children, in turn), at
    /// most eight.
    fn chain_below(&self, mut j: usize) -> Vec<usize> {
        let mut out = Vec::new();
        while let Some(c) = self.limb_child(j) {
            out.push(c);
            if out.len() == 8 {
                break;
            }
            j = c;
        }
        out
    }

    /// The shallowest joint on `side` whose name says one of `segs`.
    fn named(&self, side: Option<Side>, segs: &[Seg]) -> Option<usize> {
        (0..self.names.len())
            .filter(|&j| self.side(j) == side && segs.contains(&self.seg(j)))
            .min_by_key(|&j| (self.depth[j], j))
    }
}

/// A limb found: its root (upper arm or thigh), middle (forearm or shin)
/// and end (hand or foot), each with its evidence.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Limb {
    pub upper: Option<(usize, Evidence)>,
    pub middle: Option<(usize, Evidence)>,
    pub end: Option<(usize, Evidence)>,
}

/// The arm or leg on `side` from names, filled in by the hierarchy.
pub(super) fn limb_by_names(rig: &Rig<'_>, side: Side, arm: bool) -> Limb {
    let (upper_segs, middle_segs, end_segs): (&[Seg], &[Seg], &[Seg]) = if arm {
        (&[Seg::UpperArm], &[Seg::Forearm], &[Seg::Hand])
    } else {
        (
            &[Seg::Thigh, Seg::Leg],
            &[Seg::Shin, Seg::Leg],
            &[Seg::Foot],
        )
    };
    let side = Some(side);
    // From the end up: the end by name, or the joint above a named toe.
    let end = rig
        .named(side, end_segs)
        .map(|j| (j, Evidence::Name))
        .or_else(|| {
            (!arm)
                .then(|| rig.named(side, &[Seg::Toe]))
                .flatten()
                .and_then(|t| rig.limb_parent(t))
                .filter(|&f| rig.side(f) == side || rig.side(f).is_none())
                .map(|f| (f, Evidence::Hierarchy))
        });
    match end {
        Some(end) => limb_up_from(rig, side, (upper_segs, middle_segs), end),
        None => limb_down_from_root(rig, side, arm, (upper_segs, middle_segs, end_segs)),
    }
}

/// A limb up from its end (`end`): the middle the nearest joint above
/// whose name says it (within two steps), else the joint above; the upper
/// likewise above the middle.
fn limb_up_from(
    rig: &Rig<'_>,
    side: Option<Side>,
    (upper_segs, middle_segs): (&[Seg], &[Seg]),
    end: (usize, Evidence),
) -> Limb {
    let e = end.0;
    let mut limb = Limb {
        end: Some(end),
        ..Limb::default()
    };
    // The middle: the nearest joint above whose name says it (within
    // two steps), else the joint above.
    let above = |j: usize, segs: &[Seg]| -> Option<(usize, Evidence)> {
        let first = rig.limb_parent(j)?;
        let second = rig.limb_parent(first);
        if segs.contains(&rig.seg(first)) {
            Some((rig.run_top(first), Evidence::Name))
        } else if let Some(s) = second.filter(|&s| segs.contains(&rig.seg(s))) {
            Some((rig.run_top(s), Evidence::Name))
        } else {
            Some((first, Evidence::Hierarchy))
        }
    };
    // A foot the rig hangs from its root (IK style) says nothing of
    // the leg above it: the leg by its names.
    limb.middle = above(e, middle_segs)
        .filter(|&(m, _)| rig.side(m) == side)
        .or_else(|| {
            rig.named(side, &middle_segs[..1])
                .or_else(|| {
                    (0..rig.names.len()).find(|&j| {
                        rig.side(j) == side
                            && rig.seg(j) == Seg::Leg
                            && rig.limb_parent(j).is_some_and(|p| rig.seg(p) == Seg::Thigh)
                    })
                })
                .map(|m| (m, Evidence::Name))
        });
    if let Some((m, _)) = limb.middle {
        limb.upper = above(m, upper_segs);
    }
    limb
}

/// A limb down from its upper part, named, along the chain; for an arm
/// without a named upper, from a named forearm.
fn limb_down_from_root(
    rig: &Rig<'_>,
    side: Option<Side>,
    arm: bool,
    (upper_segs, middle_segs, end_segs): (&[Seg], &[Seg], &[Seg]),
) -> Limb {
    let mut limb = Limb::default();
    // From the root down: the upper by name, the rest along the chain.
    let upper = if arm {
        rig.named(side, upper_segs)
    } else {
        rig.named(side, &[Seg::Thigh])
            .or_else(|| rig.named(side, &[Seg::Leg]))
    };
    if let Some(u) = upper {
        limb.upper = Some((u, Evidence::Name));
        // Down the chain: the first joint named as the next part, else the
        // first that is not a segment of the same bone.
        let next = |from: usize, segs: &[Seg]| -> Option<(usize, Evidence)> {
            let chain = rig.chain_below(from);
            chain
                .iter()
                .find(|&&c| segs.contains(&rig.seg(c)) && rig.seg(c) != rig.seg(from))
                .map(|&c| (c, Evidence::Name))
                .or_else(|| {
                    chain
                        .iter()
                        .find(|&&c| !rig.same_bone(c, from))
                        .map(|&c| (c, Evidence::Hierarchy))
                })
        };
        limb.middle = next(u, middle_segs);
        if let Some((m, _)) = limb.middle {
            limb.end = next(m, end_segs).or_else(|| {
                // A forearm that ends in several palms or fingers: the one
                // nearest their middle is the hand.
                arm.then(|| middle_child(rig, rig.run_bottom(m)))
                    .flatten()
                    .map(|h| (h, Evidence::Hierarchy))
            });
        }
    } else if arm {
        // A forearm named, the rest by the hierarchy.
        if let Some(m) = rig.named(side, middle_segs) {
            limb.middle = Some((m, Evidence::Name));
            limb.upper = rig.limb_parent(m).map(|u| (u, Evidence::Hierarchy));
            limb.end = rig
                .limb_child(m)
                .or_else(|| middle_child(rig, m))
                .map(|h| (h, Evidence::Hierarchy));
        }
    }
    limb
}

/// Of a joint's finger or palm children, the one nearest their middle.
fn middle_child(rig: &Rig<'_>, j: usize) -> Option<usize> {
    let kids: Vec<usize> = rig.children[j]
        .iter()
        .copied()
        .filter(|&k| rig.seg(k) == Seg::Finger)
        .collect();
    if kids.len() < 2 {
        return None;
    }
    let mid = kids.iter().map(|&k| rig.places[k]).sum::<DVec3>() / kids.len() as f64;
    kids.into_iter().min_by(|&a, &b| {
        (rig.places[a] - mid)
            .length()
            .total_cmp(&(rig.places[b] - mid).length())
    })
}

/// The roles found so far, each with its evidence.
pub(super) type Found = BTreeMap<Role, (usize, Evidence)>;

/// Every limb the names and the hierarchy give, into `found` (roles
/// already there kept).
pub(super) fn limbs_by_names(rig: &Rig<'_>, found: &mut Found) {
    for (side, arm) in LIMBS {
        let roles = limb_roles(side, arm);
        if roles.iter().any(|r| found.contains_key(r)) {
            continue;
        }
        let limb = limb_by_names(rig, side, arm);
        for (r, j) in roles.into_iter().zip([limb.upper, limb.middle, limb.end]) {
            if let Some(j) = j {
                found.insert(r, j);
            }
        }
    }
}

/// The trunk from the limbs: the pelvis where the legs meet (a joint
/// named for it just above, where the rig puts one there), the chest where
/// the arms meet, the head by name under the chest or else the top of the
/// chain that leaves the chest upwards, the neck on the way to it (the
/// head where there is none).
pub(super) fn trunk(rig: &Rig<'_>, found: &mut Found) {
    let get = |f: &Found, r: Role| f.get(&r).map(|x| x.0);
    if !found.contains_key(&Role::Pelvis) {
        if let (Some(l), Some(r)) = (get(found, Role::LeftHip), get(found, Role::RightHip)) {
            let p = rig.common_ancestor(l, r);
            let ev = if rig.seg(p) == Seg::Pelvis {
                Evidence::Name
            } else {
                Evidence::Hierarchy
            };
            found.insert(Role::Pelvis, (p, ev));
        }
    }
    if !found.contains_key(&Role::Chest) {
        if let (Some(l), Some(r)) = (
            get(found, Role::LeftShoulder),
            get(found, Role::RightShoulder),
        ) {
            let c = rig.common_ancestor(l, r);
            let ev = if rig.seg(c) == Seg::Chest {
                Evidence::Name
            } else {
                Evidence::Hierarchy
            };
            found.insert(Role::Chest, (c, ev));
        }
    }
    let Some(chest) = get(found, Role::Chest) else {
        return;
    };
    if !found.contains_key(&Role::Head) {
        let head = head_below(rig, chest, found);
        if let Some(h) = head {
            found.insert(Role::Head, h);
        }
    }
    if !found.contains_key(&Role::Neck) {
        if let Some(head) = get(found, Role::Head) {
            // The chest's child on the way to the head.
            let mut j = head;
            while let Some(p) = rig.parents[j] {
                if p == chest {
                    break;
                }
                j = p;
            }
            let neck = if j != head && rig.is_ancestor(chest, j) {
                let ev = if rig.seg(j) == Seg::Neck {
                    Evidence::Name
                } else {
                    Evidence::Hierarchy
                };
                (j, ev)
            } else {
                // No neck: the head rides on the chest.
                (head, Evidence::Hierarchy)
            };
            found.insert(Role::Neck, neck);
        }
    }
}

/// The head below `chest`: a joint named as one (an IK target named
/// `HEAD` elsewhere in the rig is not it), else the top of the chain
/// leaving the chest that holds no arm.
fn head_below(rig: &Rig<'_>, chest: usize, found: &Found) -> Option<(usize, Evidence)> {
    // A head by name below the chest (an IK target named `HEAD`
    // elsewhere in the rig is not it).
    let named = (0..rig.names.len())
        .filter(|&j| rig.seg(j) == Seg::Head && j != chest && rig.is_ancestor(chest, j))
        .min_by_key(|&j| (rig.depth[j], j));
    named.map(|h| (h, Evidence::Name)).or_else(|| {
        // The top of the chain leaving the chest that holds no arm.
        let arms: Vec<usize> = [Role::LeftShoulder, Role::RightShoulder]
            .iter()
            .filter_map(|r| found.get(r).map(|x| x.0))
            .collect();
        let mut j = rig.children[chest]
            .iter()
            .copied()
            .filter(|&c| {
                !rig.is_helper(c)
                    && !matches!(rig.seg(c), Seg::Face | Seg::Finger)
                    && !arms.iter().any(|&a| rig.is_ancestor(c, a))
                    && rig.side(c).is_none()
            })
            .max_by_key(|&c| rig.size[c])?;
        while let Some(c) = rig.limb_child(j) {
            if rig.side(c).is_some() {
                break;
            }
            j = c;
        }
        Some((j, Evidence::Hierarchy))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A made-up rig: (name, parent) in order, each joint a step below
    /// and beside its parent.
    fn roles_of(joints: &[(&str, Option<usize>)]) -> BTreeMap<Role, String> {
        let names: Vec<String> = joints.iter().map(|j| j.0.to_owned()).collect();
        let parents: Vec<Option<usize>> = joints.iter().map(|j| j.1).collect();
        let places: Vec<DVec3> = (0..joints.len()).map(|k| DVec3::splat(k as f64)).collect();
        let rig = Rig::new(&names, &parents, &places);
        let mut found = Found::new();
        limbs_by_names(&rig, &mut found);
        trunk(&rig, &mut found);
        found
            .into_iter()
            .map(|(r, (j, _))| (r, names[j].clone()))
            .collect()
    }

    #[test]
    fn segments_of_one_bone_helpers_and_feet_hung_from_the_root_are_seen_through() {
        let rig = [
            ("root", None),               // 0
            ("DEF-hips", Some(0)),        // 1
            ("DEF-spine.001", Some(1)),   // 2
            ("DEF-spine.003", Some(2)),   // 3
            ("DEF-neck", Some(3)),        // 4
            ("DEF-head", Some(4)),        // 5
            ("DEF-upper_arm.L", Some(3)), // 6
            ("DEF-upper_arm.L.001", Some(6)),
            ("DEF-forearm.L", Some(7)), // 8
            ("DEF-forearm.L.001", Some(8)),
            ("DEF-hand.L", Some(9)),      // 10
            ("DEF-upper_arm.R", Some(3)), // 11
            ("DEF-forearm.R", Some(11)),  // 12
            ("DEF-hand.R", Some(12)),     // 13
            ("DEF-thigh.L", Some(1)),     // 14
            ("DEF-shin.L", Some(14)),     // 15
            ("thigh_twist_01_l", Some(15)),
            ("DEF-thigh.R", Some(1)), // 17
            ("DEF-shin.R", Some(17)), // 18
            ("DEF-foot.L", Some(0)),  // 19: hung from the root
            ("IK-foot.R", Some(0)),   // 20
            ("DEF-foot.R", Some(18)), // 21
        ];
        let r = roles_of(&rig);
        assert_eq!(r[&Role::LeftShoulder], "DEF-upper_arm.L");
        assert_eq!(r[&Role::LeftElbow], "DEF-forearm.L");
        assert_eq!(r[&Role::LeftHand], "DEF-hand.L");
        assert_eq!(r[&Role::LeftKnee], "DEF-shin.L");
        assert_eq!(r[&Role::LeftHip], "DEF-thigh.L");
        assert_eq!(r[&Role::LeftFoot], "DEF-foot.L");
        assert_eq!(r[&Role::RightFoot], "DEF-foot.R");
        assert_eq!(r[&Role::Pelvis], "DEF-hips");
        assert_eq!(r[&Role::Chest], "DEF-spine.003");
        assert_eq!(
            (r[&Role::Neck].as_str(), r[&Role::Head].as_str()),
            ("DEF-neck", "DEF-head")
        );
    }

    #[test]
    fn a_rig_without_neck_hands_or_head_names_is_read_from_its_hierarchy() {
        let rig = [
            ("hip", None),          // 0
            ("waist", Some(0)),     // 1
            ("chest", Some(1)),     // 2
            ("skull", Some(2)),     // 3: the head, by the hierarchy
            ("l-arm", Some(2)),     // 4
            ("l-forearm", Some(4)), // 5: no hand
            ("r-arm", Some(2)),
            ("r-forearm", Some(6)),
            ("l-thigh", Some(0)), // 8
            ("l-leg", Some(8)),   // 9: the shin under a thigh
            ("l-foot", Some(9)),
            ("r-thigh", Some(0)),
            ("r-leg", Some(11)),
            ("r-foot", Some(12)),
            ("HEAD", None), // an IK target named for the head
        ];
        let r = roles_of(&rig);
        assert_eq!(r[&Role::LeftKnee], "l-leg");
        assert_eq!(r[&Role::LeftHip], "l-thigh");
        assert_eq!(r[&Role::LeftElbow], "l-forearm");
        assert!(!r.contains_key(&Role::LeftHand), "{r:?}");
        assert_eq!(r[&Role::Pelvis], "hip");
        assert_eq!(r[&Role::Head], "skull");
        assert_eq!(r[&Role::Neck], "skull");
    }
}
