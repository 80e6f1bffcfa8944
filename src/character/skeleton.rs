//! Skeletons and poses, and forward kinematics.
//!
//! Conventions, stated once for all character code: Y up, right-handed,
//! metres, radians, column vectors; a joint's rotation is local to its
//! parent; the root's translation is in world space. Motion data is kept in
//! `f64` so that import and export round-trip to well under a millimetre.

use glam::{DQuat, DVec3};

/// One joint of a hierarchy.
#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    pub name: String,
    /// Index of the parent joint; `None` for the root.
    pub parent: Option<usize>,
    /// Rest offset from the parent, in metres.
    pub offset: DVec3,
    /// Offset of the BVH `End Site` below this joint, if it has one.
    pub end_site: Option<DVec3>,
}

/// A joint hierarchy; parents come before their children.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Skeleton {
    pub joints: Vec<Joint>,
}

/// A posture: each joint's local translation and rotation.
///
/// `translations[i]` is the joint's position in its parent's frame (the rest
/// offset unless the data animates it); for the root it is the world
/// position.
#[derive(Clone, Debug, PartialEq)]
pub struct Pose {
    pub translations: Vec<DVec3>,
    pub rotations: Vec<DQuat>,
}

impl Skeleton {
    #[must_use]
    pub fn len(&self) -> usize {
        self.joints.len()
    }

    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.joints.is_empty()
    }

    /// The index of a joint by exact name.
    #[must_use]
    pub fn find(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// The rest pose: offsets, no rotation.
    #[must_use]
    pub fn rest_pose(&self) -> Pose {
        Pose {
            translations: self.joints.iter().map(|j| j.offset).collect(),
            rotations: vec![DQuat::IDENTITY; self.joints.len()],
        }
    }

    /// Children of a joint.
    pub fn children(&self, joint: usize) -> impl Iterator<Item = usize> + '_ {
        self.joints
            .iter()
            .enumerate()
            .filter(move |(_, j)| j.parent == Some(joint))
            .map(|(i, _)| i)
    }

    /// Depth of a joint (root = 0).
    #[must_use]
    pub fn depth(&self, mut joint: usize) -> usize {
        let mut d = 0;
        while let Some(p) = self.joints[joint].parent {
            joint = p;
            d += 1;
        }
        d
    }

    /// Whether `ancestor` is `joint` or above it.
    #[must_use]
    pub fn is_ancestor(&self, ancestor: usize, mut joint: usize) -> bool {
        loop {
            if joint == ancestor {
                return true;
            }
            match self.joints[joint].parent {
                Some(p) => joint = p,
                None => return false,
            }
        }
    }

    /// The lowest joint above (or at) both `a` and `b`.
    #[must_use]
    pub fn common_ancestor(&self, a: usize, b: usize) -> usize {
        let mut x = a;
        loop {
            if self.is_ancestor(x, b) {
                return x;
            }
            match self.joints[x].parent {
                Some(p) => x = p,
                None => return x,
            }
        }
    }

    /// Scale every offset (units to metres).
    pub fn scale(&mut self, s: f64) {
        for j in &mut self.joints {
            j.offset *= s;
            if let Some(e) = &mut j.end_site {
                *e *= s;
            }
        }
    }
}

/// World transforms of every joint of a pose.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WorldPose {
    pub positions: Vec<DVec3>,
    pub rotations: Vec<DQuat>,
}

impl WorldPose {
    /// World position of joint `i`'s End Site, if it has one.
    #[must_use]
    pub fn end_site(&self, skeleton: &Skeleton, i: usize) -> Option<DVec3> {
        skeleton.joints[i]
            .end_site
            .map(|e| self.positions[i] + self.rotations[i] * e)
    }
}

/// Forward kinematics: world positions and rotations of every joint.
#[must_use]
pub fn forward_kinematics(skeleton: &Skeleton, pose: &Pose) -> WorldPose {
    let n = skeleton.len();
    let mut w = WorldPose {
        positions: Vec::with_capacity(n),
        rotations: Vec::with_capacity(n),
    };
    for (i, j) in skeleton.joints.iter().enumerate() {
        let (p, r) = match j.parent {
            None => (pose.translations[i], pose.rotations[i]),
            Some(parent) => {
                let pr = w.rotations[parent];
                (
                    w.positions[parent] + pr * pose.translations[i],
                    pr * pose.rotations[i],
                )
            }
        };
        w.positions.push(p);
        w.rotations.push(r.normalize());
    }
    w
}

/// The rotation from `from` to `to` as a rotation vector (axis × angle),
/// the shorter way round: the paper's "difference between two rotations".
#[must_use]
pub fn rotation_difference(from: DQuat, to: DQuat) -> DVec3 {
    let mut q = to * from.inverse();
    if q.w < 0.0 {
        q = -q;
    }
    let (axis, angle) = q.normalize().to_axis_angle();
    if angle.abs() < 1e-12 {
        DVec3::ZERO
    } else {
        axis * angle
    }
}

/// The points of a foot: the ankle, the joints below it and their End
/// Sites, always in the same order.
pub fn foot_points<'a>(
    skeleton: &'a Skeleton,
    w: &'a WorldPose,
    ankle: usize,
) -> impl Iterator<Item = DVec3> + 'a {
    (0..skeleton.len())
        .filter(move |&i| i == ankle || skeleton.is_ancestor(ankle, i))
        .flat_map(move |i| std::iter::once(w.positions[i]).chain(w.end_site(skeleton, i)))
}

/// The sole of a foot: its lowest point (ankle, toes, End Sites).
#[must_use]
pub fn sole(skeleton: &Skeleton, w: &WorldPose, ankle: usize) -> DVec3 {
    foot_points(skeleton, w, ankle).fold(
        w.positions[ankle],
        |best, p| if p.y < best.y { p } else { best },
    )
}

/// Two-bone IK on world positions, the turns only: for the limb `a`-`b`-`c`
/// to reach `goal` (as near as its lengths allow) in the plane it bends
/// in, the bend at `a` and at `b` (world, about one axis across the limb)
/// and then the swing about `a` onto the goal. `None` for a limb with a
/// bone of no length.
#[must_use]
pub fn two_bone_turns(a: DVec3, b: DVec3, c: DVec3, goal: DVec3) -> Option<(DQuat, DQuat, DQuat)> {
    let (lab, lbc) = ((b - a).length(), (c - b).length());
    if lab < 1e-9 || lbc < 1e-9 {
        return None;
    }
    let reach = (goal - a)
        .length()
        .clamp((lab - lbc).abs() + 1e-6, lab + lbc - 1e-6);
    let angle = |u: DVec3, v: DVec3| u.normalize().dot(v.normalize()).clamp(-1.0, 1.0).acos();
    // Interior angles now and wanted (law of cosines).
    let at_a = angle(c - a, b - a);
    let at_b = angle(a - b, c - b);
    let cos = |x: f64| x.clamp(-1.0, 1.0).acos();
    let want_a = cos((lbc * lbc - lab * lab - reach * reach) / (-2.0 * lab * reach));
    let want_b = cos((reach * reach - lab * lab - lbc * lbc) / (-2.0 * lab * lbc));
    let mut axis = (c - a).cross(b - a);
    if axis.length() < 1e-9 {
        // A straight limb bends about any axis across it; take one across
        // the goal too.
        axis = (c - a).cross(goal - a);
        if axis.length() < 1e-9 {
            axis = (c - a).any_orthonormal_vector();
        }
    }
    let axis = axis.normalize();
    let bend_b = DQuat::from_axis_angle(axis, want_b - at_b);
    let bend_a = DQuat::from_axis_angle(axis, want_a - at_a);
    // Where the end lies after both bends, then the swing onto the goal.
    let bent = a + bend_a * ((b - a) + bend_b * (c - b));
    let (from, to) = (bent - a, goal - a);
    let swing = if from.length() > 1e-9 && to.length() > 1e-9 {
        DQuat::from_rotation_arc(from.normalize(), to.normalize())
    } else {
        DQuat::IDENTITY
    };
    Some((bend_a, bend_b, swing))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chain() -> Skeleton {
        Skeleton {
            joints: vec![
                Joint {
                    name: "root".into(),
                    parent: None,
                    offset: DVec3::ZERO,
                    end_site: None,
                },
                Joint {
                    name: "a".into(),
                    parent: Some(0),
                    offset: DVec3::Y,
                    end_site: None,
                },
                Joint {
                    name: "b".into(),
                    parent: Some(1),
                    offset: DVec3::Y,
                    end_site: Some(DVec3::X),
                },
            ],
        }
    }

    #[test]
    fn fk_composes_rotations_down_the_chain() {
        let s = chain();
        let mut p = s.rest_pose();
        p.rotations[1] = DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2);
        let w = forward_kinematics(&s, &p);
        assert!((w.positions[2] - DVec3::new(-1.0, 1.0, 0.0)).length() < 1e-12);
        assert!((w.end_site(&s, 2).unwrap() - DVec3::new(-1.0, 2.0, 0.0)).length() < 1e-12);
        assert_eq!(s.common_ancestor(2, 1), 1);
        assert_eq!(s.depth(2), 2);
    }
}
