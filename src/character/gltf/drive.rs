//! Driving a figure from the library's postures (retargeting): each mapped
//! joint turns as its library joint turns from its rest, after its bone
//! is laid along the library's rest bone (an A-pose figure under a T-pose
//! library); unmapped joints (fingers, tails, helpers) keep their rest
//! pose on their parents; the pelvis goes where the library's goes, its
//! height over the ankles and its travel scaled by leg length; the
//! figure's own legs then reach where the library puts the feet (two-bone
//! IK; a one-bone leg pointed along the library's, the pelvis as high as
//! such a leg needs to reach), its arms keep the library's turns and are
//! bent to reach only where a hand must be lifted off the floor (a
//! one-bone arm pointed along the library's and swung up by the least
//! turn that keeps its hand off it); a joint the rig hangs elsewhere (feet from the root) is
//! hung on its limb; nothing it carries low (a cape, a tail, a shin) goes
//! under the floor, nor its head: a bow deeper than its head allows (a
//! chibi's) is turned back up about the pelvis (`upright`).

use glam::{DMat4, DQuat, DVec3};

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
/// its offset from the library's turns with the hips alone.
const HEADING_BLEND_M: f64 = 0.1;

/// Turns tried, up to [`FLATTEN_MAX`], to bring a foot's sole off the
/// floor.
const FLATTEN_STEPS: u8 = 8;

/// The most a foot is turned flatter to keep its sole off the floor
/// before it is lifted (rad, about 23 degrees).
const FLATTEN_MAX: f64 = 0.4;

/// The most a hand is turned about its wrist to keep what it holds off
/// the floor before it is lifted (rad, a quarter turn: a sword hanging
/// from it held level).
const HAND_TURN_MAX: f64 = std::f64::consts::FRAC_PI_2;

/// How high a foot rises over its standing height (library metres)
/// before it goes where the library's goes from the hip rather than
/// where it stands (see `Drive::foot_goal`).
const RAISED_BLEND_M: f64 = 0.3;

/// How near the floor (m) a hand's points come before all it carries is
/// looked at (`limbs::near_points`): more than the points kept for it
/// miss by (7.7 mm, a knight's shield rim).
const NEAR_M: f64 = 0.05;

/// How near its standing height (library metres) the library's ankle is
/// for the figure's foot on that side to stand (see `Drive::stand`).
const STANDING_M: f64 = 0.02;

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
    /// figure's less the library's scaled. A foot stands that much aside
    /// of the library's (turned with the foot), so that a figure with
    /// wider hips stands with its feet under them.
    hip_wide: [DVec3; 2],
    /// How each library foot lies planted, facing +Z (inverted).
    planted_inv: [DQuat; 2],
    /// Each limb of [`LIMBS`]: the figure's length over the library's.
    limb_scale: [f64; 4],
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
    /// would go under the floor.
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
        Self {
            follow,
            hang,
            order,
            scale,
            ankles: (stand, fpos[fig.roles.get(Role::LeftFoot)].y),
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
            hip_wide: [Role::LeftHip, Role::RightHip].map(|h| {
                hip_wide(
                    h,
                    (&fpos, &fig.roles),
                    (&standing, &rest_lib, lib_roles),
                    scale,
                )
            }),
            planted_inv: planted.map(|q| q.map_or(DQuat::IDENTITY, DQuat::inverse)),
            near: LIMBS.map(|(_, _, r)| {
                Carried::new(if matches!(r, Role::LeftHand | Role::RightHand) {
                    near_points(fig, fig.roles.get(r))
                } else {
                    Vec::new()
                })
            }),
            one_bone: LIMBS
                .map(|(_, b, _)| fig.made_up.get(fig.roles.get(b)).copied().unwrap_or(false)),
            low: Carried::new(low_points(fig)),
            upright: Upright::new(
                lib,
                lib_roles,
                Carried::new(end_points(fig, fig.roles.get(Role::Head))),
            ),
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
    #[must_use]
    pub fn pose(&self, fig: &Figure, lib: &WorldPose) -> Vec<DMat4> {
        let free = vec![None; fig.rest.len()];
        let w = self.place(fig, lib, &free, DVec3::ZERO);
        let raise = self.stand(lib, &w);
        let w = if raise == DVec3::ZERO {
            w
        } else {
            self.place(fig, lib, &free, raise)
        };
        let turned = self.turned_up(fig, lib, &w, raise);
        let (lib, w) = match &turned {
            Some(t) => (t, self.place(fig, t, &free, raise)),
            None => (lib, w),
        };
        let mut lift = [0.0f64; 4];
        let mut turn = [DQuat::IDENTITY; 4];
        let mut fixed = self.reach(fig, lib, &w, lift, turn);
        let mut posed = self.place(fig, lib, &fixed, raise);
        // No sole under the floor: a foot whose lowest point went under is
        // first turned flatter about its ankle (a longer foot than the
        // library's, pointed as steeply, reaches lower), by at most
        // `FLATTEN_MAX`; what is left under lifts it by as much (the leg
        // bends), once more if need be. A hand under the floor (long arms
        // in a crouch, a sword it holds) is first turned about its wrist
        // by at most `HAND_TURN_MAX` as a foot is, then lifted by what is
        // left under.
        for pass in 0..3 {
            let mut under = false;
            let skin = self.skinning(&posed);
            for (k, (_, _, f)) in LIMBS.into_iter().enumerate() {
                let j = self.fig_roles.get(f);
                if self.end_clear(&skin, k) {
                    continue;
                }
                if pass > 0 && !self.one_bone[k] {
                    // Only how far it is under is wanted now.
                    let low = self.end_lowest(&skin, k);
                    if low < -1e-4 {
                        under = true;
                        lift[k] -= low;
                    }
                    continue;
                }
                let points = self.end_now(&skin, k);
                let lowest =
                    |ps: &mut dyn Iterator<Item = DVec3>| ps.min_by(|a, b| a.y.total_cmp(&b.y));
                let Some(low) = lowest(&mut points.iter().copied()) else {
                    continue;
                };
                if low.y >= -1e-4 {
                    continue;
                }
                under = true;
                let ankle = posed[j].w_axis.truncate();
                let axis = (low - ankle).cross(DVec3::Y);
                if k >= 2 && self.one_bone[k] {
                    // A one-bone arm too long to hang where the library's
                    // does (a chibi's): swung up about its shoulder by
                    // the least turn that brings its hand onto the floor.
                    let shoulder = posed[self.fig_roles.get(LIMBS[k].0)].w_axis.truncate();
                    let chest = posed[self.fig_roles.get(Role::Chest)].w_axis.truncate();
                    turn[k] = swing_clear(&points, shoulder, ankle, chest) * turn[k];
                } else if pass == 0 && axis.length() > 1e-9 {
                    // Turned towards raising the lowest point: the least
                    // turn that brings every point onto the floor, else
                    // the one that leaves the lowest highest (raising the
                    // toes lowers the heel).
                    let axis = axis.normalize();
                    let most = if k < 2 { FLATTEN_MAX } else { HAND_TURN_MAX };
                    let angle = flatter(&points, (ankle, axis), low.y, most);
                    turn[k] = DQuat::from_axis_angle(axis, angle) * turn[k];
                } else {
                    lift[k] -= low.y;
                }
            }
            if !under {
                break;
            }
            fixed = self.reach(fig, lib, &w, lift, turn);
            posed = self.place(fig, lib, &fixed, raise);
        }
        // A limb too short to reach where it is lifted to (a stride longer
        // than the legs, scaled), a head no turn of the trunk lifts: the
        // whole figure rises by what is left.
        let skin = self.skinning(&posed);
        let low = (0..LIMBS.len())
            .map(|k| self.end_lowest(&skin, k))
            .chain([
                self.low.lowest_below(&skin, 0.0),
                self.upright.points.lowest_below(&skin, 0.0),
            ])
            .fold(0.0f64, f64::min);
        if low < -1e-4 {
            for m in &mut posed {
                m.w_axis.y -= low;
            }
        }
        posed
    }

    /// A bow that would put the head under the floor (the figure placed
    /// by `w`, standing `raise` off the library's): the library's posture
    /// with the trunk turned back up, the legs as they were (so `raise`
    /// holds).
    fn turned_up(
        &self,
        fig: &Figure,
        lib: &WorldPose,
        w: &[DMat4],
        raise: DVec3,
    ) -> Option<WorldPose> {
        let head_lowest = |w: &[DMat4]| self.upright.points.lowest_below(&self.skinning(w), 0.0);
        if head_lowest(w) >= 0.0 {
            return None;
        }
        let free = vec![None; fig.rest.len()];
        self.upright
            .turned(lib, |l| head_lowest(&self.place(fig, l, &free, raise)))
    }

    /// The height of foot `k`'s lowest mesh point (0 left, 1 right) in
    /// the posture `posed` (joint transforms from [`Self::pose`]).
    #[must_use]
    pub fn foot_lowest(&self, posed: &[DMat4], k: usize) -> Option<f64> {
        self.end_now(&self.skinning(posed), k.min(1))
            .into_iter()
            .map(|p| p.y)
            .min_by(f64::total_cmp)
    }

    /// Where limb `k`'s end's mesh points are for skinning matrices
    /// `skin` (from [`Self::skinning`] of a posture, made once for all
    /// four limbs): a hand near the floor by all it carries.
    fn end_now(&self, skin: &[DMat4], k: usize) -> Vec<DVec3> {
        let kept = self.ends[k].now(skin);
        if !self.near[k].is_empty() && kept.iter().any(|p| p.y < NEAR_M) {
            return self.near[k].now(skin);
        }
        kept
    }

    /// The height of limb `k`'s end's lowest mesh point
    /// ([`Self::end_now`]), or 0 where none is under the floor.
    fn end_lowest(&self, skin: &[DMat4], k: usize) -> f64 {
        if self.near[k].is_empty() || self.ends[k].lowest_below(skin, NEAR_M) >= NEAR_M {
            self.ends[k].lowest_below(skin, 0.0)
        } else {
            self.near[k].lowest_below(skin, 0.0)
        }
    }

    /// Whether none of limb `k`'s end's mesh points ([`Self::end_now`])
    /// can be under the floor for skinning matrices `skin`.
    fn end_clear(&self, skin: &[DMat4], k: usize) -> bool {
        self.ends[k].floor_bound(skin) >= -1e-4
            && (self.near[k].is_empty() || self.near[k].floor_bound(skin) >= -1e-4)
    }

    /// The joint turns that put each limb's end where the library has it
    /// (raised by `lift`, the ends turned by `turn`, world turns about
    /// the ankles and wrists; a one-bone arm's about its shoulder), from
    /// the posture `w` turned as the library's.
    fn reach(
        &self,
        fig: &Figure,
        lib: &WorldPose,
        w: &[DMat4],
        lift: [f64; 4],
        turn: [DQuat; 4],
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
                self.foot_goal(lib, k, root) + DVec3::Y * lift[k]
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
    /// `hip`): one on the floor scaled as the pelvis is, so that a planted
    /// foot stays planted whatever the hips do.
    fn foot_goal(&self, lib: &WorldPose, k: usize, hip: DVec3) -> DVec3 {
        let (a, _, c) = LIMBS[k];
        let l = lib.positions[self.lib_roles.get(c)];
        let planted = DVec3::new(
            l.x * self.scale,
            self.ankles.1 + (l.y - self.ankles.0) * self.scale,
            l.z * self.scale,
        ) + self.heading(lib, k) * self.hip_wide[k];
        // A foot raised `RAISED_BLEND_M` or more goes where the library's
        // is from its hip, the leg's length scaled (a kick points as the
        // library's does).
        let raised = hip + (l - lib.positions[self.lib_roles.get(a)]) * self.limb_scale[k];
        let up = ((l.y - self.ankles.0) / RAISED_BLEND_M).clamp(0.0, 1.0);
        planted.lerp(raised, up)
    }

    /// How much higher than the library's (scaled) the pelvis stands so
    /// that the legs reach where the library puts the feet (`w`, the
    /// posture turned as the library's). A one-bone leg, which cannot
    /// bend, reaches no further: the pelvis as high as the one that needs
    /// it most, so that the standing foot reaches the floor and a lifted
    /// one stays above its place. Legs that bend: lowered as much as a
    /// standing foot needs to reach its place (a figure whose hips stand
    /// wider or lower for its legs than the library's, on straight legs),
    /// else where it is.
    fn stand(&self, lib: &WorldPose, w: &[DMat4]) -> DVec3 {
        let mut one_bone: Option<f64> = None;
        let mut lower = 0.0f64;
        for (k, &(a, b, c)) in LIMBS.iter().enumerate().take(2) {
            let at = |r: Role| w[self.fig_roles.get(r)].w_axis.truncate();
            let hip = at(a);
            let length = if self.one_bone[k] {
                (at(c) - hip).length()
            } else {
                (at(b) - hip).length() + (at(c) - at(b)).length()
            };
            let v = self.foot_goal(lib, k, hip) - hip;
            let across = v.with_y(0.0).length().min(length);
            let need = v.y + (length * length - across * across).sqrt();
            if self.one_bone[k] {
                one_bone = Some(one_bone.map_or(need, |r: f64| r.max(need)));
            } else if lib.positions[self.lib_roles.get(c)].y < self.ankles.0 + STANDING_M {
                lower = lower.min(need);
            }
        }
        DVec3::Y * one_bone.unwrap_or(lower)
    }

    /// The turn about the vertical that carries foot `k`'s offset from the
    /// library's ([`Self::hip_wide`]): a foot on the floor turns it with
    /// itself (from how it lies planted facing +Z), so that it stays
    /// planted as the hips swing; one raised by `HEADING_BLEND_M` or more
    /// with the hips, as the hip it hangs from does.
    fn heading(&self, lib: &WorldPose, k: usize) -> DQuat {
        let foot = self.lib_roles.get([Role::LeftFoot, Role::RightFoot][k]);
        let hips = facing(lib, &self.lib_roles);
        let ahead = (lib.rotations[foot] * self.planted_inv[k]) * DVec3::Z;
        if ahead.with_y(0.0).length() < 0.5 {
            // Pointing nearly straight down or up: no heading of its own.
            return hips;
        }
        let own = DQuat::from_rotation_y(ahead.x.atan2(ahead.z));
        let up = ((lib.positions[foot].y - self.ankles.0) / HEADING_BLEND_M).clamp(0.0, 1.0);
        own.slerp(hips, up)
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

/// Every fifth posture of the library's clips (world), and how high its
/// ankles stand: the lower one's median over them (a rest pose may stand
/// otherwise).
fn standing(library: &Library, lib_roles: &RoleMap) -> (Vec<WorldPose>, f64) {
    let lib = &library.skeleton;
    let feet = [Role::LeftFoot, Role::RightFoot].map(|r| lib_roles.get(r));
    let standing: Vec<WorldPose> = library
        .clips
        .values()
        .flat_map(|c| c.frames.iter().step_by(5))
        .map(|p| forward_kinematics(lib, p))
        .filter(|w| w.positions.iter().all(|p| p.is_finite()))
        .collect();
    let mut lows: Vec<f64> = standing
        .iter()
        .map(|w| w.positions[feet[0]].y.min(w.positions[feet[1]].y))
        .collect();
    lows.sort_by(f64::total_cmp);
    let stand = lows.get(lows.len() / 2).copied().unwrap_or(0.08);
    (standing, stand)
}

/// How a planted foot lies, facing +Z: each foot's turn where it stands
/// within 1 cm of `stand`, the body's facing taken out, averaged. A
/// figure's rest foot lies flat; the library's rest pose need not (a
/// studio's T-pose may point the toes).
fn planted_feet(standing: &[WorldPose], stand: f64, lib_roles: &RoleMap) -> [Option<DQuat>; 2] {
    [Role::LeftFoot, Role::RightFoot].map(|r| {
        let f = lib_roles.get(r);
        let mut sum = glam::DVec4::ZERO;
        for w in standing {
            if (w.positions[f].y - stand).abs() > 0.01 {
                continue;
            }
            let q = facing(w, lib_roles).inverse() * w.rotations[f];
            let v = glam::DVec4::from(q);
            sum += if v.dot(sum) < 0.0 { -v } else { v };
        }
        (sum.length() > 1e-9).then(|| DQuat::from_vec4(sum.normalize()))
    })
}

/// Per figure joint, the library joint it turns with and the turn from
/// that joint's to the figure's rest (see `Drive::follow`), and the joint
/// it hangs from (see `Drive::hang`).
fn follow_and_hang(
    fig: &Figure,
    rest_lib: &WorldPose,
    lib_roles: &RoleMap,
    planted: &[Option<DQuat>; 2],
) -> (Vec<Follow>, Vec<Option<usize>>) {
    let fpos: Vec<DVec3> = fig.rest.iter().map(|m| m.w_axis.truncate()).collect();
    let mut follow = vec![None; fig.rest.len()];
    let mut hang: Vec<Option<usize>> = fig.skeleton.joints.iter().map(|j| j.parent).collect();
    let dir = |p: &[DVec3], roles: &RoleMap, a: Role, b: Role| p[roles.get(b)] - p[roles.get(a)];
    // Rest alignment per role, an end role taking its limb's.
    let mut align = std::collections::BTreeMap::new();
    for (role, to, _) in CHAIN {
        if let Some(to) = to {
            let (f, l) = (
                dir(&fpos, &fig.roles, role, to),
                dir(&rest_lib.positions, lib_roles, role, to),
            );
            let c = if f.length() > 1e-9 && l.length() > 1e-9 {
                DQuat::from_rotation_arc(f.normalize(), l.normalize())
            } else {
                DQuat::IDENTITY
            };
            align.insert(role, c);
        }
    }
    for (role, _, up) in CHAIN {
        let c = align
            .get(&role)
            .or_else(|| up.and_then(|u| align.get(&u)))
            .copied()
            .unwrap_or(DQuat::IDENTITY);
        let m = fig.roles.get(role);
        let l = lib_roles.get(role);
        // A made-up joint goes where the joint above it takes it.
        if fig.made_up.get(m).copied().unwrap_or(false) {
            continue;
        }
        // From the library's rest, the bone laid along it; a foot from
        // how the library's planted foot lies.
        let from = match role {
            Role::LeftFoot => planted[0].map(|q| q.inverse()),
            Role::RightFoot => planted[1].map(|q| q.inverse()),
            _ => None,
        };
        follow[m] = Some((
            l,
            from.unwrap_or_else(|| rest_lib.rotations[l].inverse() * c),
        ));
        // Hung elsewhere by the rig: hang it on its limb.
        if let Some(up) = up {
            let u = fig.roles.get(up);
            if u != m && !fig.skeleton.is_ancestor(u, m) && !fig.skeleton.is_ancestor(m, u) {
                hang[m] = Some(u);
            }
        }
    }
    (follow, hang)
}

/// The figure's joints, each after the one it hangs from; anything left in
/// a loop of hangings keeps its own parent.
fn hang_order(fig: &Figure, hang: &mut [Option<usize>]) -> Vec<usize> {
    let n = hang.len();
    let mut order = Vec::with_capacity(n);
    let mut done = vec![false; n];
    let mut stack: Vec<usize> = (0..n).filter(|&j| hang[j].is_none()).collect();
    stack.reverse();
    while let Some(j) = stack.pop() {
        if done[j] {
            continue;
        }
        done[j] = true;
        order.push(j);
        for c in (0..n).rev() {
            if hang[c] == Some(j) && !done[c] {
                stack.push(c);
            }
        }
    }
    for j in 0..n {
        if !done[j] {
            hang[j] = fig.skeleton.joints[j].parent;
            order.push(j);
        }
    }
    order
}

/// A hip's place under the pelvis along the floor, the figure's (from its
/// rest) less the library's scaled (from its clips facing +Z: its rest
/// pose need not stand; the Bandai hips sit 9 cm apart in height there).
/// Across only: a figure's hips forward or back of its pelvis joint do not
/// move its feet.
fn hip_wide(
    hip: Role,
    (fpos, fig_roles): (&[DVec3], &RoleMap),
    (standing, rest_lib, lib_roles): (&[WorldPose], &WorldPose, &RoleMap),
    scale: f64,
) -> DVec3 {
    let (mut sum, mut n) = (DVec3::ZERO, 0.0);
    for w in standing {
        sum += facing(w, lib_roles).inverse()
            * (w.positions[lib_roles.get(hip)] - w.positions[lib_roles.get(Role::Pelvis)]);
        n += 1.0;
    }
    let lib_under = if n > 0.0 {
        sum / n
    } else {
        rest_lib.positions[lib_roles.get(hip)] - rest_lib.positions[lib_roles.get(Role::Pelvis)]
    };
    let d = fpos[fig_roles.get(hip)] - fpos[fig_roles.get(Role::Pelvis)] - lib_under * scale;
    DVec3::new(d.x, 0.0, 0.0)
}

/// How far to turn a foot's or hand's `points` about its `ankle` and
/// `axis` (up to `most`, in [`FLATTEN_STEPS`]) to raise the lowest, now
/// at `low_y`: the least turn that brings every point onto the floor,
/// else the one that leaves the lowest highest (raising the toes lowers
/// the heel).
fn flatter(points: &[DVec3], (ankle, axis): (DVec3, DVec3), low_y: f64, most: f64) -> f64 {
    let low_after = |angle: f64| {
        // Only the height is wanted: the turn's row that gives it.
        let up = glam::DMat3::from_quat(DQuat::from_axis_angle(axis, angle)).row(1);
        points
            .iter()
            .map(|p| ankle.y + up.dot(*p - ankle))
            .min_by(f64::total_cmp)
            .unwrap_or(f64::NEG_INFINITY)
    };
    let mut best = (0.0, low_y);
    for step in 1..=FLATTEN_STEPS {
        let angle = most * f64::from(step) / f64::from(FLATTEN_STEPS);
        let y = low_after(angle);
        if y > best.1 + 1e-6 {
            best = (angle, y);
        }
        if y >= 0.0 {
            break;
        }
    }
    best.0
}

/// The least turn about `shoulder` that brings every point of `points`
/// (a one-bone arm's hand, posed) onto the floor: the arm swung up
/// towards where it reaches along the floor, or out from the chest where
/// it hangs straight down; at most to the horizontal.
fn swing_clear(points: &[DVec3], shoulder: DVec3, hand: DVec3, chest: DVec3) -> DQuat {
    let arm = hand - shoulder;
    let along = arm.with_y(0.0);
    let out = if along.length() > 0.2 * arm.length() {
        along
    } else {
        (shoulder - chest).with_y(0.0)
    };
    let axis = arm.cross(out);
    if arm.length() < 1e-9 || axis.length() < 1e-9 {
        return DQuat::IDENTITY;
    }
    let axis = axis.normalize();
    let lowest = |angle: f64| {
        let q = DQuat::from_axis_angle(axis, angle);
        points
            .iter()
            .map(|p| (shoulder + q * (*p - shoulder)).y)
            .fold(f64::INFINITY, f64::min)
    };
    let most = arm.angle_between(out);
    if lowest(most) < 0.0 {
        return DQuat::from_axis_angle(axis, most);
    }
    let (mut lo, mut hi) = (0.0, most);
    for _ in 0..24 {
        let mid = (lo + hi) / 2.0;
        if lowest(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    DQuat::from_axis_angle(axis, hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_long_arm_is_swung_out_by_the_least_turn_that_clears_the_floor() {
        // A shoulder 0.6 m up, an arm hanging 0.9 m straight down: its
        // hand 0.3 m under the floor, the chest to its right.
        let shoulder = DVec3::new(0.2, 0.6, 0.0);
        let hand = DVec3::new(0.2, -0.3, 0.0);
        let points = [hand, hand + DVec3::new(0.0, -0.05, 0.0)];
        let q = swing_clear(&points, shoulder, hand, DVec3::new(0.0, 0.6, 0.0));
        let moved: Vec<DVec3> = points
            .iter()
            .map(|p| shoulder + q * (*p - shoulder))
            .collect();
        let low = moved.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
        assert!(low.abs() < 1e-6, "{moved:?}");
        // Out to the side, away from the chest; the least turn: the
        // arm's 0.95 m reach meets the floor at acos(0.6 / 0.95).
        assert!(moved[0].x > 0.2, "{moved:?}");
        let angle = q.to_axis_angle().1;
        assert!((angle - (0.6f64 / 0.95).acos()).abs() < 1e-4, "{angle}");
        // An arm already clear is not turned.
        let up = [DVec3::new(0.2, 0.1, 0.0)];
        let q = swing_clear(&up, shoulder, up[0], DVec3::new(0.0, 0.6, 0.0));
        assert!(q.to_axis_angle().1.abs() < 1e-6);
    }
}
