//! Driving a figure from the library's postures (retargeting): each mapped
//! joint turns as its library joint turns from its rest, after its bone
//! is laid along the library's rest bone (an A-pose figure under a T-pose
//! library); unmapped joints (fingers, tails, helpers) keep their rest
//! pose on their parents; the pelvis goes where the library's goes, its
//! height over the ankles and its travel scaled by leg length, then as
//! high as its standing legs reach bent as the library's are; the
//! figure's own legs then reach where the library puts the feet, a foot
//! coming down where the figure's leg, shaped as the library's, puts it
//! and moving from there as the library's does (two-bone IK; a one-bone
//! leg pointed along the library's, the pelvis as high as such a leg
//! needs to reach), its arms keep the library's turns and are
//! bent to reach only where a hand must be lifted off the floor (a
//! one-bone arm pointed along the library's and swung up by the least
//! turn that keeps its hand off it); a joint the rig hangs elsewhere (feet from the root) is
//! hung on its limb; nothing it carries low (a cape, a tail, a shin) goes
//! under the floor, nor its head: a bow deeper than its head allows (a
//! chibi's), a lean that would put what the trunk carries low under the
//! floor (a knight's cape on its chest) is turned back up about the
//! pelvis (`upright`).

mod floor;
mod rest;

use glam::{DMat4, DQuat, DVec3};

use self::rest::{follow_and_hang, hang_order, hip_wide, planted_feet, standing};
use super::Figure;
use super::limbs::{Carried, end_points, foot_points, low_points, near_points, toward, two_bone};
use super::upright::Upright;
use crate::character::body::{facing, leg_length_posed};
use crate::character::library::Library;
use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::{Skeleton, WorldPose, forward_kinematics};

/// The role a role's bone points to, and the role above it on its limb.
const CHAIN: [(Role, Option<Role>, Option<Role>); 16] = [
    (Role::Pelvis, Some(Role::Chest), None),
    (Role::Chest, Some(Role::Neck), Some(Role::Pelvis)),
    (Role::Neck, Some(Role::Head), Some(Role::Chest)),
    (Role::Head, None, Some(Role::Neck)),
    (Role::LeftShoulder, Some(Role::LeftElbow), Some(Role::Chest)),
    (
        Role::LeftElbow,
        Some(Role::LeftHand),
        Some(Role::LeftShoulder),
    ),
    (Role::LeftHand, None, Some(Role::LeftElbow)),
    (
        Role::RightShoulder,
        Some(Role::RightElbow),
        Some(Role::Chest),
    ),
    (
        Role::RightElbow,
        Some(Role::RightHand),
        Some(Role::RightShoulder),
    ),
    (Role::RightHand, None, Some(Role::RightElbow)),
    (Role::LeftHip, Some(Role::LeftKnee), Some(Role::Pelvis)),
    (Role::LeftKnee, Some(Role::LeftFoot), Some(Role::LeftHip)),
    (Role::LeftFoot, None, Some(Role::LeftKnee)),
    (Role::RightHip, Some(Role::RightKnee), Some(Role::Pelvis)),
    (Role::RightKnee, Some(Role::RightFoot), Some(Role::RightHip)),
    (Role::RightFoot, None, Some(Role::RightKnee)),
];

/// The limbs IK puts on the library's ends: (upper, middle, end) roles.
const LIMBS: [(Role, Role, Role); 4] = [
    (Role::LeftHip, Role::LeftKnee, Role::LeftFoot),
    (Role::RightHip, Role::RightKnee, Role::RightFoot),
    (Role::LeftShoulder, Role::LeftElbow, Role::LeftHand),
    (Role::RightShoulder, Role::RightElbow, Role::RightHand),
];

/// How high a foot rises over its standing height (library metres) before
/// its offset from the library's turns with the hips alone (a one-bone
/// leg's), or is no longer held where it came down (see `Drive::offset`).
const HEADING_BLEND_M: f64 = 0.1;

/// How high a foot rises over its standing height (library metres)
/// before it goes where the library's goes from the hip rather than
/// where it stands (see `Drive::foot_goal`).
const RAISED_BLEND_M: f64 = 0.3;

/// How near its standing height (library metres) the library's ankle is
/// for the figure's foot on that side to stand (see `Drive::stand`).
const STANDING_M: f64 = 0.02;

/// A figure placed and kept off the floor: its joint transforms, how
/// much each standing foot was lifted off its place (its sole under the
/// floor) and how much the whole figure rose (what it carries under it).
pub(super) struct Settled {
    posed: Vec<DMat4>,
    lift: [f64; 2],
    rise: f64,
}

/// What a figure carries from one posture to the next (see
/// [`Drive::pose_held`]): where each standing foot came down, off the
/// library's (scaled), and the library's foot's heading then.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Hold {
    feet: [Option<(DVec3, Option<DQuat>)>; 2],
}

/// A figure joint's library joint and turn (see `Drive::follow`).
type Follow = Option<(usize, DQuat)>;

/// How one figure follows one library's skeleton.
#[derive(Clone, Debug)]
pub struct Drive {
    /// Per figure joint: the library joint it turns with, and the inverse
    /// of that joint's reference turn with the turn that lays the figure's
    /// rest bone along the library's (`lib_now * this * figure_rest`).
    follow: Vec<Follow>,
    /// Per figure joint: the joint it hangs from (its parent, or the joint
    /// of the role above it on its limb where the rig hangs it elsewhere).
    hang: Vec<Option<usize>>,
    /// Figure joints, each after the one it hangs from.
    order: Vec<usize>,
    /// Figure leg length over the library's.
    pub scale: f64,
    /// Each figure joint's rest turn and place, and the inverse of its
    /// rest transform (taken apart once, not every frame).
    rest: Vec<(DQuat, DVec3)>,
    rest_inv: Vec<DMat4>,
    /// Ankle heights standing at rest: the library's and the figure's.
    ankles: (f64, f64),
    /// How far below the pelvis the hips are at rest: the figure's less
    /// the library's scaled (the pelvis is raised by it, so that the legs
    /// stand as straight as the library's).
    hip_drop: f64,
    /// Each hip's place under the pelvis at rest (along the floor): the
    /// figure's less the library's scaled. A one-bone leg's foot stands
    /// that much aside of the library's (turned with the foot), so that
    /// a figure with wider hips stands with its feet under them (a leg
    /// that bends stands where its own shape puts it, see
    /// `Drive::offset`).
    hip_wide: [DVec3; 2],
    /// How each library foot lies planted, facing +Z (inverted).
    planted_inv: [DQuat; 2],
    /// Each limb of [`LIMBS`]: the figure's length over the library's.
    limb_scale: [f64; 4],
    /// Each leg's thigh and shin lengths (the figure's, metres).
    leg_lengths: [(f64, f64); 2],
    /// Each limb end's mesh points (rest pose; feet, then hands, as
    /// [`LIMBS`]) with the joint carrying each (see `limbs::end_points`).
    ends: [Carried; 4],
    /// The hands' points looked at where one comes within [`NEAR_M`] of
    /// the floor (see `limbs::near_points`; none for the feet).
    near: [Carried; 4],
    /// Each limb of [`LIMBS`]: one bone from its root to its end (its
    /// middle made up).
    one_bone: [bool; 4],
    /// Mesh points the figure carries low at rest off its legs (a cape, a
    /// skirt, a tail), each with its joint: none goes under the floor.
    low: Carried,
    /// The library's upper body turned back up where the figure's head
    /// or what its trunk carries low (see `trunk_points`) would go under
    /// the floor.
    upright: Upright,
    fig_roles: RoleMap,
    lib_roles: RoleMap,
}

impl Drive {
    /// How `fig` follows the postures of `library` (whose roles are
    /// `lib_roles`).
    #[must_use]
    pub fn new(fig: &Figure, library: &Library, lib_roles: &RoleMap) -> Self {
        let lib = &library.skeleton;
        let rest_lib = forward_kinematics(lib, &lib.rest_pose());
        let (standing, stand) = standing(library, lib_roles);
        let planted = planted_feet(&standing, stand, lib_roles);
        let fpos: Vec<DVec3> = fig.rest.iter().map(|m| m.w_axis.truncate()).collect();
        let scale = Self::leg_ratio(fig, lib, lib_roles);
        let (follow, mut hang) = follow_and_hang(fig, &rest_lib, lib_roles, &planted);
        let order = hang_order(fig, &mut hang);
        let one_bone =
            LIMBS.map(|(_, b, _)| fig.made_up.get(fig.roles.get(b)).copied().unwrap_or(false));
        Self {
            follow,
            hang,
            order,
            scale,
            ankles: (stand, fpos[fig.roles.get(Role::LeftFoot)].y),
            leg_lengths: [0, 1].map(|k| {
                let (a, b, c) = LIMBS[k];
                let at = |r: Role| fpos[fig.roles.get(r)];
                ((at(b) - at(a)).length(), (at(c) - at(b)).length())
            }),
            limb_scale: LIMBS.map(|(a, b, c)| {
                let len = |p: &[DVec3], r: &RoleMap| {
                    (p[r.get(b)] - p[r.get(a)]).length() + (p[r.get(c)] - p[r.get(b)]).length()
                };
                len(&fpos, &fig.roles) / len(&rest_lib.positions, lib_roles).max(1e-9)
            }),
            ends: LIMBS.map(|(_, m, r)| {
                Carried::new(if matches!(r, Role::LeftFoot | Role::RightFoot) {
                    foot_points(fig, fig.roles.get(r), fig.roles.get(m))
                } else {
                    end_points(fig, fig.roles.get(r))
                })
            }),
            hip_drop: {
                let drop = |p: &[DVec3], r: &RoleMap| {
                    p[r.get(Role::Pelvis)].y
                        - (p[r.get(Role::LeftHip)].y + p[r.get(Role::RightHip)].y) / 2.0
                };
                drop(&fpos, &fig.roles) - drop(&rest_lib.positions, lib_roles) * scale
            },
            hip_wide: [0, 1].map(|k| {
                let wide = hip_wide(
                    LIMBS[k].0,
                    (&fpos, &fig.roles),
                    (&standing, &rest_lib, lib_roles),
                    scale,
                );
                // A one-bone leg, which cannot bend, leans to the
                // library's foot from where its hip is: moved back under
                // the hip it rolls onto its sole's edge in a bow and the
                // figure floats.
                if one_bone[k] { wide.with_z(0.0) } else { wide }
            }),
            planted_inv: planted.map(|q| q.map_or(DQuat::IDENTITY, DQuat::inverse)),
            near: LIMBS.map(|(_, _, r)| {
                Carried::new(if matches!(r, Role::LeftHand | Role::RightHand) {
                    near_points(fig, fig.roles.get(r))
                } else {
                    Vec::new()
                })
            }),
            one_bone,
            low: Carried::new(low_points(fig)),
            upright: Upright::new(lib, lib_roles, Carried::new(trunk_points(fig))),
            fig_roles: fig.roles.clone(),
            lib_roles: lib_roles.clone(),
            rest: fig
                .rest
                .iter()
                .map(|m| {
                    let (_, r, t) = m.to_scale_rotation_translation();
                    (r, t)
                })
                .collect(),
            rest_inv: fig.rest.iter().map(DMat4::inverse).collect(),
        }
    }

    /// The figure's leg length over the library's (`lib_roles` naming the
    /// library skeleton's joints).
    #[must_use]
    pub fn leg_ratio(fig: &Figure, lib: &Skeleton, lib_roles: &RoleMap) -> f64 {
        let fpos: Vec<DVec3> = fig.rest.iter().map(|m| m.w_axis.truncate()).collect();
        let rest_lib = forward_kinematics(lib, &lib.rest_pose());
        leg_length_posed(&fpos, &fig.roles)
            / leg_length_posed(&rest_lib.positions, lib_roles).max(1e-9)
    }

    /// The figure's joint transforms for a library posture (world), with
    /// `fixed[j]` overriding a joint's world rotation.
    /// The pelvis stands `raise` off the library's, scaled.
    fn place(
        &self,
        fig: &Figure,
        lib: &WorldPose,
        fixed: &[Option<DQuat>],
        raise: DVec3,
    ) -> Vec<DMat4> {
        let n = fig.rest.len();
        let mut w = vec![DMat4::IDENTITY; n];
        for &j in &self.order {
            let (rest_rot, rest_pos) = self.rest[j];
            let rot = if let Some(q) = fixed[j] {
                q
            } else if let Some((l, from)) = self.follow[j] {
                (lib.rotations[l] * from * rest_rot).normalize()
            } else if let Some(p) = self.hang[j] {
                let p_rest = self.rest[p].0;
                let (_, p_now, _) = w[p].to_scale_rotation_translation();
                (p_now * p_rest.inverse() * rest_rot).normalize()
            } else {
                rest_rot
            };
            let pos = match self.hang[j] {
                Some(p) => w[p].transform_point3(self.rest_inv[p].transform_point3(rest_pos)),
                None => rest_pos,
            };
            w[j] = DMat4::from_rotation_translation(rot, pos);
        }
        // The pelvis where the library's is, scaled by leg length.
        let pelvis = self.fig_roles.get(Role::Pelvis);
        // Its height over the ankles scaled, not over the floor: a figure
        // whose ankles stand higher for its legs (big feet) stands as
        // straight as the library's.
        let lp = lib.positions[self.lib_roles.get(Role::Pelvis)];
        let want = DVec3::new(
            lp.x * self.scale,
            self.ankles.1 + (lp.y - self.ankles.0) * self.scale,
            lp.z * self.scale,
        ) + DVec3::Y * self.hip_drop
            + raise;
        let shift = want - w[pelvis].w_axis.truncate();
        for m in &mut w {
            m.w_axis += shift.extend(0.0);
        }
        w
    }

    /// The figure's joint transforms (world, metres) for the library's
    /// posture `lib`: turned as the library's joints, then each limb put
    /// on the library's hand or foot, relative to the hip or shoulder.
    /// Where a standing foot had to be lifted (its sole under the floor)
    /// or the whole figure raised (a cape under it), it is placed again
    /// with its pelvis that much higher, as far as its legs reach, so
    /// that its legs keep the library's shape rather than bend or float.
    #[must_use]
    pub fn pose(&self, fig: &Figure, lib: &WorldPose) -> Vec<DMat4> {
        self.pose_held(fig, lib, &mut Hold::default())
    }

    /// As [`Self::pose`], for one of a sequence of postures (`hold`
    /// carried from each to the next): a foot that comes down stands
    /// where the figure's own leg, shaped as the library's, puts it, and
    /// stays there, moving and turning only as the library's foot does,
    /// until it rises again (see [`Self::offset`]). Alone, a posture's
    /// feet stand where its legs put them.
    #[must_use]
    pub fn pose_held(&self, fig: &Figure, lib: &WorldPose, hold: &mut Hold) -> Vec<DMat4> {
        let free = vec![None; fig.rest.len()];
        let w = self.place(fig, lib, &free, DVec3::ZERO);
        let offsets = [0, 1].map(|k| self.offset(lib, k, &w, &mut hold.feet[k]));
        let first = self.settle(fig, lib, &w, ([0.0; 2], 0.0), offsets);
        if first.rise > 1e-4 || first.lift.iter().any(|&l| l > 1e-3) {
            return self
                .settle(fig, lib, &w, (first.lift, first.rise), offsets)
                .posed;
        }
        first.posed
    }

    /// The figure placed for `lib` (see [`Self::pose`]; `placed`, turned
    /// as the library's where the library's pelvis is), its standing
    /// feet's places raised by `lifted` and its pelvis by `rise` as far
    /// as its legs reach.
    fn settle(
        &self,
        fig: &Figure,
        lib: &WorldPose,
        placed: &[DMat4],
        (lifted, rise): ([f64; 2], f64),
        offsets: [DVec3; 2],
    ) -> Settled {
        let free = vec![None; fig.rest.len()];
        let (want, most) = self.stand(lib, placed, lifted, offsets);
        let raise = DVec3::Y * (want + rise).min(most);
        let w = if raise == DVec3::ZERO {
            placed.to_vec()
        } else {
            self.place(fig, lib, &free, raise)
        };
        let turned = self.turned_up(fig, lib, &w, raise);
        let (lib, w) = match &turned {
            Some(t) => (t, self.place(fig, t, &free, raise)),
            None => (lib, w),
        };
        self.off_the_floor(fig, lib, &w, raise, offsets)
    }

    /// The joint turns that put each limb's end where the library has it
    /// (raised by `lift`, the ends turned by `turn`, world turns about
    /// the ankles and wrists; a one-bone arm's about its shoulder), from
    /// the posture `w` turned as the library's, its pelvis standing
    /// `raise` off the library's (a raised foot's place does not move
    /// with it: a foot lifting off the floor rises as the library's;
    /// each foot `offsets` along the floor off the library's, see
    /// [`Self::offset`]).
    fn reach(
        &self,
        fig: &Figure,
        lib: &WorldPose,
        w: &[DMat4],
        (lift, turn): ([f64; 4], [DQuat; 4]),
        raise: DVec3,
        offsets: [DVec3; 2],
    ) -> Vec<Option<DQuat>> {
        let mut fixed = vec![None; fig.rest.len()];
        for (k, (a, b, c)) in LIMBS.into_iter().enumerate() {
            let (fa, fb, fc) = (
                self.fig_roles.get(a),
                self.fig_roles.get(b),
                self.fig_roles.get(c),
            );
            let (la, lc) = (self.lib_roles.get(a), self.lib_roles.get(c));
            // A hand where the library has it from the shoulder, scaled
            // by the arm's length; an ankle as high above its standing
            // height as the library's.
            let root = w[fa].w_axis.truncate();
            let goal = if k < 2 {
                self.foot_goal(lib, k, root - raise, offsets[k]) + DVec3::Y * lift[k]
            } else {
                root + (lib.positions[lc] - lib.positions[la]) * self.limb_scale[k]
                    + DVec3::Y * lift[k]
            };
            let (pa, pb, pc) = (root, w[fb].w_axis.truncate(), w[fc].w_axis.truncate());
            // An arm keeps the library's turns (its upper arm and forearm
            // point as the library's, whatever their proportions) unless
            // its hand must be lifted off the floor.
            if k >= 2 && lift[k] <= 0.0 && !self.one_bone[k] {
                // Only turned about its wrist, if at all.
                if turn[k] != DQuat::IDENTITY {
                    let (_, r, _) = w[fc].to_scale_rotation_translation();
                    fixed[fc] = Some((turn[k] * r).normalize());
                }
                continue;
            }
            if self.one_bone[k] {
                // One bone from shoulder to hand or hip to foot: pointed
                // where the library's limb points.
                let (from, to) = (pc - pa, goal - pa);
                if from.length() > 1e-9 && to.length() > 1e-9 {
                    // Then swung off the floor (`turn`, an arm's).
                    let arc = DQuat::from_rotation_arc(from.normalize(), to.normalize());
                    let rot = |m: &DMat4| m.to_scale_rotation_translation().1;
                    fixed[fa] = Some((turn[k] * arc * rot(&w[fa])).normalize());
                }
                continue;
            }
            if let Some((ta, tb)) = two_bone(pa, pb, pc, goal) {
                // The knee or elbow turned about the limb's line towards
                // where the library bends it (from the limb's root).
                let lb = self.lib_roles.get(b);
                let pole = pa + (lib.positions[lb] - lib.positions[la]) * self.limb_scale[k];
                let twist = toward(pa, pa + ta * (pb - pa), goal, pole);
                let ta = twist * ta;
                let tb = twist * tb * twist.inverse();
                let rot = |m: &DMat4| m.to_scale_rotation_translation().1;
                fixed[fa] = Some((ta * rot(&w[fa])).normalize());
                fixed[fb] = Some((tb * ta * rot(&w[fb])).normalize());
                // The end keeps the turn the library gave it (a foot or
                // hand turned by `turn` off the floor).
                fixed[fc] = Some((turn[k] * rot(&w[fc])).normalize());
            }
        }
        fixed
    }

    /// Where the library puts foot `k`'s ankle for the figure (its hip at
    /// `hip`): one on the floor scaled as the pelvis is, `offset` along
    /// the floor (see [`Self::offset`]), so that a planted foot stays
    /// planted whatever the hips do.
    fn foot_goal(&self, lib: &WorldPose, k: usize, hip: DVec3, offset: DVec3) -> DVec3 {
        let (a, _, c) = LIMBS[k];
        let l = lib.positions[self.lib_roles.get(c)];
        let planted = self.scaled(lib, k) + offset;
        // A foot raised `RAISED_BLEND_M` or more goes where the figure's
        // leg, pointed as the library's, puts it from its hip (a kick
        // points as the library's does).
        let raised = match self.shaped(lib, k) {
            Some(v) => hip + v,
            None => hip + (l - lib.positions[self.lib_roles.get(a)]) * self.limb_scale[k],
        };
        planted.lerp(raised, self.risen(lib, k, RAISED_BLEND_M))
    }

    /// Where the library's ankle `k` is, scaled as the pelvis is.
    fn scaled(&self, lib: &WorldPose, k: usize) -> DVec3 {
        let l = lib.positions[self.lib_roles.get(LIMBS[k].2)];
        DVec3::new(
            l.x * self.scale,
            self.ankles.1 + (l.y - self.ankles.0) * self.scale,
            l.z * self.scale,
        )
    }

    /// Where leg `k`'s ankle is from its hip with its thigh and shin
    /// pointed as the library's (none for a one-bone leg).
    fn shaped(&self, lib: &WorldPose, k: usize) -> Option<DVec3> {
        if self.one_bone[k] {
            return None;
        }
        let (a, b, c) = LIMBS[k];
        let at = |r: Role| lib.positions[self.lib_roles.get(r)];
        let (thigh, shin) = (at(b) - at(a), at(c) - at(b));
        let (l0, l1) = self.leg_lengths[k];
        Some(thigh.normalize_or_zero() * l0 + shin.normalize_or_zero() * l1)
    }

    /// Foot `k`'s place along the floor off the library's, scaled (`w`,
    /// the figure turned as the library's): where its leg, its thigh and
    /// shin pointed as the library's, puts it from its hip (a figure
    /// with wider hips, hips behind its pelvis joint, a shorter shin for
    /// its thigh stands on legs shaped as the library's, not leaning to
    /// the library's feet). Held while the foot stands (in `hold`, from
    /// when it came down, with the foot's heading then), so that it stays
    /// planted as the hips move, and let go as it rises
    /// [`HEADING_BLEND_M`]: the foot moves as the library's does, however
    /// the two legs' shapes part, and a foot pivoting on its ball (a
    /// kick's standing foot) turns its place with it. A one-bone
    /// leg's: its hip's offset ([`Self::hip_wide`]), turned with the
    /// foot.
    fn offset(
        &self,
        lib: &WorldPose,
        k: usize,
        w: &[DMat4],
        hold: &mut Option<(DVec3, Option<DQuat>)>,
    ) -> DVec3 {
        let up = self.risen(lib, k, HEADING_BLEND_M);
        let Some(v) = self.shaped(lib, k) else {
            return self.heading(lib, k) * self.hip_wide[k];
        };
        let hip = w[self.fig_roles.get(LIMBS[k].0)].w_axis.truncate();
        let live = (hip + v - self.scaled(lib, k)).with_y(0.0);
        let own = self.own_heading(lib, k);
        if up >= 1.0 {
            *hold = None;
        } else if self.stands(lib, k) && hold.is_none() {
            *hold = Some((live, own));
        }
        // A foot that turns as it stands (pivoting on its ball) turns
        // its place with it.
        let held = hold.map(|(c, then)| match (own, then) {
            (Some(now), Some(then)) => now * then.inverse() * c,
            _ => c,
        });
        held.map_or(live, |h| h.lerp(live, up))
    }

    /// How much higher than the library's (scaled) the pelvis stands so
    /// that the legs reach where the library puts the feet (`w`, the
    /// posture turned as the library's; a standing foot's place raised
    /// by `lifted`), and the most it may (the standing legs straight). A
    /// one-bone leg, which cannot bend, reaches no further: the pelvis as
    /// high as the one that needs it most, so that the standing foot
    /// reaches the floor and a lifted one stays above its place. Legs
    /// that bend: each standing leg as far above its foot as it reaches
    /// bent as the library's is (a short thigh on a long shin bends less
    /// for the same drop), the pelvis at the mean of the two, no higher
    /// than both reach; no leg standing, where it is.
    fn stand(
        &self,
        lib: &WorldPose,
        w: &[DMat4],
        lifted: [f64; 2],
        offsets: [DVec3; 2],
    ) -> (f64, f64) {
        let mut one_bone: Option<f64> = None;
        let mut standing: Option<(f64, f64, f64)> = None;
        for (k, &(a, b, c)) in LIMBS.iter().enumerate().take(2) {
            let at = |r: Role| w[self.fig_roles.get(r)].w_axis.truncate();
            let hip = at(a);
            let length = if self.one_bone[k] {
                (at(c) - hip).length()
            } else {
                (at(b) - hip).length() + (at(c) - at(b)).length()
            };
            let v = self.foot_goal(lib, k, hip, offsets[k]) - hip;
            let across = v.with_y(0.0).length().min(length);
            let straight = v.y + (length * length - across * across).sqrt();
            if self.one_bone[k] {
                let straight = straight + lifted[k];
                one_bone = Some(one_bone.map_or(straight, |r: f64| r.max(straight)));
            } else if self.stands(lib, k) {
                // (No higher than it reaches its place unlifted: placed
                // higher, it may not need the lift.)
                let shaped = v.y + lifted[k] - self.shaped(lib, k).map_or(0.0, |s| s.y);
                let (sum, n, most) = standing.unwrap_or((0.0, 0.0, f64::INFINITY));
                standing = Some((sum + shaped.min(straight), n + 1.0, most.min(straight)));
            }
        }
        match (one_bone, standing) {
            (Some(r), _) => (r, r),
            (None, Some((sum, n, most))) => ((sum / n).min(most), most),
            (None, None) => (0.0, 0.0),
        }
    }

    /// Whether the library stands on foot `k` (its ankle within
    /// [`STANDING_M`] of its standing height).
    fn stands(&self, lib: &WorldPose, k: usize) -> bool {
        lib.positions[self.lib_roles.get(LIMBS[k].2)].y < self.ankles.0 + STANDING_M
    }

    /// How far the library's foot `k` has risen over its standing height,
    /// as a share of `over` (library metres; 0 standing, 1 at `over` and
    /// above).
    fn risen(&self, lib: &WorldPose, k: usize, over: f64) -> f64 {
        let foot = lib.positions[self.lib_roles.get(LIMBS[k].2)];
        ((foot.y - self.ankles.0) / over).clamp(0.0, 1.0)
    }

    /// The turn about the vertical that carries foot `k`'s offset from the
    /// library's ([`Self::hip_wide`]): a foot on the floor turns it with
    /// itself (from how it lies planted facing +Z), so that it stays
    /// planted as the hips swing; one raised by `HEADING_BLEND_M` or more
    /// with the hips, as the hip it hangs from does.
    fn heading(&self, lib: &WorldPose, k: usize) -> DQuat {
        let hips = facing(lib, &self.lib_roles);
        let Some(own) = self.own_heading(lib, k) else {
            return hips;
        };
        own.slerp(hips, self.risen(lib, k, HEADING_BLEND_M))
    }

    /// The library's foot `k`'s turn about the vertical from how it lies
    /// planted facing +Z; none where it points nearly straight down or
    /// up.
    fn own_heading(&self, lib: &WorldPose, k: usize) -> Option<DQuat> {
        let foot = self.lib_roles.get(LIMBS[k].2);
        let ahead = (lib.rotations[foot] * self.planted_inv[k]) * DVec3::Z;
        (ahead.with_y(0.0).length() >= 0.5).then(|| DQuat::from_rotation_y(ahead.x.atan2(ahead.z)))
    }

    /// Skinning matrices (rest pose to posed) for joint transforms `w`.
    #[must_use]
    pub fn skinning(&self, w: &[DMat4]) -> Vec<DMat4> {
        w.iter()
            .zip(&self.rest_inv)
            .map(|(now, rest_inv)| *now * *rest_inv)
            .collect()
    }

    /// Skinned positions of every part for joint transforms `w`.
    #[must_use]
    pub fn skin(&self, fig: &Figure, w: &[DMat4]) -> Vec<Vec<DVec3>> {
        let skin = self.skinning(w);
        fig.parts
            .iter()
            .map(|p| {
                p.positions
                    .iter()
                    .zip(&p.joints)
                    .zip(&p.weights)
                    .map(|((v, j), wt)| {
                        let v = DVec3::new(v[0].into(), v[1].into(), v[2].into());
                        (0..4)
                            .filter(|&k| wt[k] > 0.0)
                            .map(|k| {
                                skin.get(usize::from(j[k]))
                                    .map_or(v, |m| m.transform_point3(v))
                                    * f64::from(wt[k])
                            })
                            .sum()
                    })
                    .collect()
            })
            .collect()
    }
}

/// The mesh points a bow or a lean may put under the floor that turning
/// the trunk back up lifts: the head's, and what the trunk alone carries
/// low (a cape on the chest); not what the pelvis or a limb carries.
fn trunk_points(fig: &Figure) -> Vec<super::Point> {
    let sk = &fig.skeleton;
    let pelvis = fig.roles.get(Role::Pelvis);
    let mut trunk = vec![false; sk.len()];
    let mut j = Some(fig.roles.get(Role::Head));
    while let Some(at) = j.filter(|&at| at != pelvis) {
        trunk[at] = true;
        j = sk.joints[at].parent;
    }
    let mut points = end_points(fig, fig.roles.get(Role::Head));
    points.extend(low_points(fig).into_iter().filter(|p| {
        (0..4).filter(|&k| p.weights[k] > 0.0).all(|k| {
            trunk
                .get(usize::from(p.joints[k]))
                .copied()
                .unwrap_or(false)
        })
    }));
    points
}
