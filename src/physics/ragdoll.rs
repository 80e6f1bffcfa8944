//! The ragdoll of physics-based tracking (the paper's section 6, eq. 5): a
//! rigid capsule per body segment, sized from the skeleton's bones, with
//! masses from an anthropometric table, joined by joints with human limits,
//! standing under gravity on a floor with friction. Each frame a PD force
//! pulls every segment's centre of mass towards where the target posture
//! puts it. The ragdoll is only read for its motion (see `effects`); it
//! never explodes: forces are bounded, and it is put back on the posture
//! shown whenever a segment drifts away or a value stops being finite.
//!
//! Conventions: a body's rotation is the rotation of its segment *from the
//! rest posture* (identity at rest), so joint frames and limits are the
//! same for every posture the ragdoll is (re)built in; rest-posture axes
//! are the character's: X to its left, Y up, Z forward.

use glam::{DQuat, DVec3, Quat, Vec3};
use rapier3d::prelude::*;

use super::body::{Hinge, Region, SegmentDef, segment_defs};
use crate::character::roles::RoleMap;
use crate::character::skeleton::{Skeleton, WorldPose};

/// How the ragdoll follows the target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RagdollSettings {
    /// The PD pull (eq. 5) settles in about this long (s): softer than
    /// acceleration-based tracking, so that the ragdoll's limbs lag, swing
    /// and carry momentum.
    pub settle_s: f64,
    /// Damping ratio of the pull (1 = critical); under 1 a released limb
    /// swings past its target a few times before it settles.
    pub damping_ratio: f64,
    /// The pull's acceleration is bounded (m/s²).
    pub max_accel: f64,
    /// A segment this far from its target (m) puts the ragdoll back on
    /// the posture shown.
    pub drift_m: f64,
    /// Longest simulation step (s).
    pub max_step_s: f64,
}

impl Default for RagdollSettings {
    fn default() -> Self {
        Self {
            settle_s: 0.4,
            damping_ratio: 0.5,
            max_accel: 100.0,
            drift_m: 0.8,
            max_step_s: 1.0 / 60.0,
        }
    }
}

/// One simulated segment.
#[derive(Clone, Debug)]
pub struct Segment {
    def: SegmentDef,
    body: RigidBodyHandle,
    /// World rotation of `joint` at rest.
    rest_rot: DQuat,
    /// Centre of mass minus the joint's position, at rest (world axes).
    com_off: DVec3,
}

impl Segment {
    /// The skeleton joint whose rotation this segment carries.
    #[must_use]
    pub fn joint(&self) -> usize {
        self.def.joint
    }

    /// The parent segment, if any.
    #[must_use]
    pub fn parent(&self) -> Option<usize> {
        self.def.parent.map(|(p, _)| p)
    }

    #[must_use]
    pub fn region(&self) -> Region {
        self.def.region
    }

    /// The segment's rotation from rest, for a posture's world transforms.
    #[must_use]
    pub fn rotation_in(&self, w: &WorldPose) -> DQuat {
        w.rotations[self.def.joint] * self.rest_rot.inverse()
    }

    /// Where a posture puts the segment's centre of mass.
    #[must_use]
    pub fn com_in(&self, w: &WorldPose) -> DVec3 {
        w.positions[self.def.joint] + self.rotation_in(w) * self.com_off
    }

    /// The segment's capsule where a posture puts it.
    #[must_use]
    pub fn capsule_in(&self, w: &WorldPose) -> Capsule {
        let rot = self.rotation_in(w);
        let com = self.com_in(w);
        let mid = (self.def.ends[0] + self.def.ends[1]) * 0.5;
        Capsule {
            a: com + rot * (self.def.ends[0] - mid),
            b: com + rot * (self.def.ends[1] - mid),
            radius: self.def.radius,
        }
    }

    /// The segment's mass (kg).
    #[must_use]
    pub fn mass(&self) -> f64 {
        self.def.mass
    }
}

/// A capsule: the points within `radius` of the segment from `a` to `b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Capsule {
    pub a: DVec3,
    pub b: DVec3,
    pub radius: f64,
}

impl Capsule {
    /// Where two capsules overlap: the closest points of their segments
    /// (on `self`, on `other`) and how deep they sink into each other (m),
    /// if they do.
    #[must_use]
    pub fn overlap(&self, other: &Capsule) -> Option<(DVec3, DVec3, f64)> {
        let (p, q) = closest_points(self.a, self.b, other.a, other.b);
        let depth = self.radius + other.radius - p.distance(q);
        (depth > 0.0).then_some((p, q, depth))
    }

    /// The middle of the segment.
    #[must_use]
    pub fn centre(&self) -> DVec3 {
        (self.a + self.b) * 0.5
    }
}

/// The closest points of segments `p0-p1` and `q0-q1`.
#[must_use]
pub fn closest_points(p0: DVec3, p1: DVec3, q0: DVec3, q1: DVec3) -> (DVec3, DVec3) {
    let d1 = p1 - p0;
    let d2 = q1 - q0;
    let r = p0 - q0;
    let (a, e, f) = (d1.dot(d1), d2.dot(d2), d2.dot(r));
    const EPS: f64 = 1e-12;
    let (s, t) = if a <= EPS && e <= EPS {
        (0.0, 0.0)
    } else if a <= EPS {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(r);
        if e <= EPS {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(d2);
            let denom = a * e - b * b;
            let mut s = if denom > EPS {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    (p0 + d1 * s, q0 + d2 * t)
}

/// What the simulation gives for one segment this frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimState {
    /// Rotation from rest (world).
    pub rotation: DQuat,
    /// Centre of mass (world).
    pub position: DVec3,
}

/// The ragdoll and its world.
pub struct Ragdoll {
    world: PhysicsWorld,
    segments: Vec<Segment>,
    settings: RagdollSettings,
    resets: u64,
}

fn v32(v: DVec3) -> Vec3 {
    v.as_vec3()
}

fn q64(q: Quat) -> DQuat {
    q.as_dquat().normalize()
}

const GRAVITY: DVec3 = DVec3::new(0.0, -9.81, 0.0);

const RAGDOLL_GROUP: Group = Group::GROUP_1;
const FLOOR_GROUP: Group = Group::GROUP_2;

impl Ragdoll {
    /// Build the ragdoll of `skeleton` from its rest posture `rest`
    /// (world transforms, standing on the floor), standing in `now`.
    #[must_use]
    pub fn new(
        skeleton: &Skeleton,
        roles: &RoleMap,
        rest: &WorldPose,
        now: &WorldPose,
        settings: RagdollSettings,
    ) -> Self {
        let defs = segment_defs(skeleton, roles, rest);
        let mut ragdoll = Self::from_defs(&defs, rest, settings);
        ragdoll.reset(now, None);
        ragdoll.resets = 0;
        ragdoll
    }

    fn from_defs(defs: &[SegmentDef], rest: &WorldPose, settings: RagdollSettings) -> Self {
        let mut world = PhysicsWorld::new();
        world.gravity = v32(GRAVITY);
        let floor = world.bodies.insert(RigidBodyBuilder::fixed().build());
        world.colliders.insert_with_parent(
            ColliderBuilder::cuboid(50.0, 0.5, 50.0)
                .translation(Vec3::new(0.0, -0.5, 0.0))
                .friction(0.9)
                .collision_groups(InteractionGroups::new(
                    FLOOR_GROUP,
                    RAGDOLL_GROUP,
                    InteractionTestMode::And,
                ))
                .build(),
            floor,
            &mut world.bodies,
        );
        let mut segments: Vec<Segment> = Vec::with_capacity(defs.len());
        for def in defs {
            let joint_at = rest.positions[def.joint];
            let com = (def.ends[0] + def.ends[1]) * 0.5;
            let body = world.bodies.insert(
                RigidBodyBuilder::dynamic()
                    .translation(v32(com))
                    .angular_damping(2.0)
                    .can_sleep(false)
                    .build(),
            );
            world.colliders.insert_with_parent(
                ColliderBuilder::capsule_from_endpoints(
                    v32(def.ends[0] - com),
                    v32(def.ends[1] - com),
                    def.radius as f32,
                )
                .mass(def.mass as f32)
                .friction(0.9)
                .collision_groups(InteractionGroups::new(
                    RAGDOLL_GROUP,
                    FLOOR_GROUP,
                    InteractionTestMode::And,
                ))
                .build(),
                body,
                &mut world.bodies,
            );
            if let Some((p, hinge)) = def.parent {
                let parent: &Segment = &segments[p];
                let parent_com = rest.positions[parent.def.joint] + parent.com_off;
                let a1 = v32(joint_at - parent_com);
                let a2 = v32(joint_at - com);
                let joint = joint(hinge, a1, a2);
                world.impulse_joints.insert(parent.body, body, joint, true);
            }
            segments.push(Segment {
                def: def.clone(),
                body,
                rest_rot: rest.rotations[def.joint],
                com_off: com - joint_at,
            });
        }
        Self {
            world,
            segments,
            settings,
            resets: 0,
        }
    }

    /// The segments, parents before children.
    #[must_use]
    pub fn segments(&self) -> &[Segment] {
        &self.segments
    }

    /// How often the ragdoll was put back on the posture shown.
    #[must_use]
    pub fn resets(&self) -> u64 {
        self.resets
    }

    /// Put every segment where `w` puts it, moving with `velocity` (the
    /// posture's own motion, per segment), or still.
    pub fn reset(&mut self, w: &WorldPose, velocity: Option<&[DVec3]>) {
        self.resets += 1;
        for (k, s) in self.segments.iter().enumerate() {
            let rot = s.rotation_in(w);
            let com = s.com_in(w);
            if let Some(b) = self.world.bodies.get_mut(s.body) {
                b.set_position(Pose::from_parts(v32(com), rot.as_quat()), true);
                let v = velocity.and_then(|v| v.get(k)).copied().unwrap_or_default();
                b.set_linvel(v32(v), true);
                b.set_angvel(Vec3::ZERO, true);
            }
        }
    }

    /// One frame of `dt` seconds: pull every segment towards where the
    /// target posture (world transforms) puts it (eq. 5) and simulate;
    /// `shown` is the posture to start over from should the ragdoll drift.
    pub fn step(&mut self, target: &WorldPose, shown: &WorldPose, dt: f64) {
        if !(dt.is_finite() && dt > 0.0) {
            return;
        }
        let w = 4.0 / self.settings.settle_s.max(1e-3);
        let (k, d) = (w * w, 2.0 * self.settings.damping_ratio * w);
        let steps = (dt / self.settings.max_step_s).ceil().clamp(1.0, 16.0);
        self.world.integration_parameters.dt = (dt / steps) as f32;
        let goals: Vec<DVec3> = self.segments.iter().map(|s| s.com_in(target)).collect();
        for _ in 0..steps as usize {
            for (s, goal) in self.segments.iter().zip(&goals) {
                if let Some(b) = self.world.bodies.get_mut(s.body) {
                    let p = b.translation().as_dvec3();
                    let v = b.linvel().as_dvec3();
                    // The pull holds the segment up against gravity, as
                    // muscles do, then drives it (eq. 5).
                    let acc = ((*goal - p) * k - v * d).clamp_length_max(self.settings.max_accel)
                        - GRAVITY;
                    b.reset_forces(false);
                    b.add_force(v32(acc * s.def.mass), true);
                }
            }
            self.world.step();
        }
        let drifted = self.segments.iter().zip(&goals).any(|(s, goal)| {
            self.world.bodies.get(s.body).is_none_or(|b| {
                let p = b.translation().as_dvec3();
                !(p.is_finite() && b.rotation().is_finite())
                    || (p - *goal).length() > self.settings.drift_m
            })
        });
        if drifted {
            tracing::debug!("ragdoll drifted from the posture; put back on it");
            self.reset(shown, None);
        }
    }

    /// An impulse (N·s, world) on segment `k`'s centre of mass: a blow
    /// from outside the body, which the pull then brings back.
    pub fn push(&mut self, k: usize, impulse: DVec3) {
        if !impulse.is_finite() {
            return;
        }
        if let Some(b) = self
            .segments
            .get(k)
            .and_then(|s| self.world.bodies.get_mut(s.body))
        {
            b.apply_impulse(v32(impulse), true);
        }
    }

    /// Each segment's simulated state.
    #[must_use]
    pub fn states(&self) -> Vec<SimState> {
        self.segments
            .iter()
            .map(|s| {
                self.world.bodies.get(s.body).map_or(
                    SimState {
                        rotation: DQuat::IDENTITY,
                        position: DVec3::ZERO,
                    },
                    |b| SimState {
                        rotation: q64(*b.rotation()),
                        position: b.translation().as_dvec3(),
                    },
                )
            })
            .collect()
    }
}

impl Clone for Ragdoll {
    /// A ragdoll in the same state (bodies where they are, moving as they
    /// move); its contact caches start afresh.
    fn clone(&self) -> Self {
        let defs: Vec<SegmentDef> = self.segments.iter().map(|s| s.def.clone()).collect();
        // The rest transforms are rebuilt from what each segment keeps.
        let mut rest = WorldPose {
            positions: vec![
                DVec3::ZERO;
                self.segments
                    .iter()
                    .map(|s| s.def.joint + 1)
                    .max()
                    .unwrap_or(0)
            ],
            rotations: vec![
                DQuat::IDENTITY;
                self.segments
                    .iter()
                    .map(|s| s.def.joint + 1)
                    .max()
                    .unwrap_or(0)
            ],
        };
        for s in &self.segments {
            rest.positions[s.def.joint] = (s.def.ends[0] + s.def.ends[1]) * 0.5 - s.com_off;
            rest.rotations[s.def.joint] = s.rest_rot;
        }
        let mut copy = Self::from_defs(&defs, &rest, self.settings);
        for (a, b) in self.segments.iter().zip(&copy.segments) {
            if let (Some(from), Some(to)) = (
                self.world.bodies.get(a.body),
                copy.world.bodies.get_mut(b.body),
            ) {
                to.set_position(*from.position(), true);
                to.set_linvel(from.linvel(), true);
                to.set_angvel(from.angvel(), true);
            }
        }
        copy.resets = self.resets;
        copy
    }
}
/// The joint `hinge` makes between a segment and its parent, anchored at
/// `a1` on the parent and `a2` on the segment (from their centres).
fn joint(hinge: Hinge, a1: Vec3, a2: Vec3) -> GenericJoint {
    match hinge {
        Hinge::Ball(l) => SphericalJointBuilder::new()
            .local_anchor1(a1)
            .local_anchor2(a2)
            .limits(JointAxis::AngX, [-l[0] as f32, l[0] as f32])
            .limits(JointAxis::AngY, [-l[1] as f32, l[1] as f32])
            .limits(JointAxis::AngZ, [-l[2] as f32, l[2] as f32])
            .contacts_enabled(false)
            .build()
            .into(),
        Hinge::Hinge(axis, l) => RevoluteJointBuilder::new(v32(axis))
            .local_anchor1(a1)
            .local_anchor2(a2)
            .limits([l[0] as f32, l[1] as f32])
            .contacts_enabled(false)
            .build()
            .into(),
    }
}
