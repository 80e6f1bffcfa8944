//! After the target posture: the ragdoll's physical effects on the regions
//! no finger holds (eq. 5-7), and a push from another character's body
//! that fades as the body recovers. [`Physical`] owns the ragdoll, the
//! effects taken from it and the push under way.

use glam::DVec3;

use super::feet::GROUND_CONTACT_M;
use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::{Pose, Skeleton, WorldPose, forward_kinematics};
use crate::physics::body::Region;
use crate::physics::effects::{Attenuation, Effects, free_regions};
use crate::physics::ragdoll::{Capsule, Ragdoll, RagdollSettings};

/// A push from another character fades with this time constant (s): the
/// body is back where it stood within about a second.
const SHOVE_RECOVERY_S: f64 = 0.3;

/// The body as physics sees it.
#[derive(Clone)]
pub(super) struct Physical {
    /// The ragdoll pulled towards the target, and the effects taken from
    /// it.
    ragdoll: Ragdoll,
    effects: Effects,
    /// How far another character's body pushed this one (m, on the
    /// floor): added to the pelvis, fading as the body recovers.
    shove: DVec3,
}

impl Physical {
    /// The ragdoll of a body standing in `world`.
    pub(super) fn new(
        sk: &Skeleton,
        roles: &RoleMap,
        world: &WorldPose,
        attenuation: Attenuation,
    ) -> Self {
        Self {
            ragdoll: Ragdoll::new(sk, roles, world, world, RagdollSettings::default()),
            effects: Effects::new(attenuation),
            shove: DVec3::ZERO,
        }
    }

    /// Physics-based tracking: step the ragdoll towards `target` and add
    /// its physical effects to the regions of `output` no finger holds
    /// (`held`) and that do not touch the floor (a foot `planted` does)
    /// (eq. 5–7).
    #[allow(clippy::too_many_arguments, reason = "one step's inputs, each named")]
    pub(super) fn effects(
        &mut self,
        sk: &Skeleton,
        roles: &RoleMap,
        target: &Pose,
        output: &mut Pose,
        held: &[Role],
        planted: [bool; 2],
        dt: f64,
    ) {
        let target = forward_kinematics(sk, target);
        let shown = forward_kinematics(sk, output);
        let resets = self.ragdoll.resets();
        self.ragdoll.step(&target, &shown, dt);
        if self.ragdoll.resets() != resets {
            self.effects.forget();
        }
        self.effects
            .update(self.ragdoll.segments(), &self.ragdoll.states(), dt);
        let held_regions: Vec<Region> = held.iter().copied().map(Region::of).collect();
        let mut touching = Vec::new();
        for (k, (role, region)) in [
            (Role::LeftFoot, Region::LeftLeg),
            (Role::RightFoot, Region::RightLeg),
        ]
        .into_iter()
        .enumerate()
        {
            let sole = crate::character::skeleton::sole(sk, &shown, roles.get(role)).y;
            if planted[k] || sole < GROUND_CONTACT_M {
                touching.push(region);
            }
        }
        for (role, region) in [
            (Role::LeftHand, Region::LeftArm),
            (Role::RightHand, Region::RightArm),
            (Role::Head, Region::Torso),
            (Role::Chest, Region::Torso),
        ] {
            if shown.positions[roles.get(role)].y < GROUND_CONTACT_M * 2.0 {
                touching.push(region);
            }
        }
        let pelvis_free = !held.contains(&Role::Pelvis);
        self.effects
            .set_active(free_regions(&held_regions, &touching), pelvis_free, dt);
        self.effects
            .apply(sk, self.ragdoll.segments(), output, &shown);
    }

    /// The push under way added to `output`'s pelvis, fading.
    pub(super) fn recover(&mut self, output: &mut Pose, dt: f64) {
        if self.shove != DVec3::ZERO {
            output.translations[0] += self.shove;
            self.shove *= (-dt / SHOVE_RECOVERY_S).exp();
            if self.shove.length() < 1e-4 {
                self.shove = DVec3::ZERO;
            }
        }
    }

    /// A blow from outside: `impulse` (N·s) on segment `k` of the ragdoll,
    /// and the body pushed by `shove` (m, on the floor): what of the push
    /// moves the body at once, if anything.
    pub(super) fn hit(&mut self, k: usize, impulse: DVec3, shove: DVec3) -> Option<DVec3> {
        self.ragdoll.push(k, impulse);
        let shove = shove.with_y(0.0);
        (shove.is_finite() && shove != DVec3::ZERO).then(|| {
            self.shove += shove;
            shove
        })
    }

    /// The body's capsules in the posture `world`, one per ragdoll
    /// segment, with the joint each carries.
    pub(super) fn capsules(&self, world: &WorldPose) -> Vec<(Capsule, usize)> {
        self.ragdoll
            .segments()
            .iter()
            .map(|s| (s.capsule_in(world), s.joint()))
            .collect()
    }

    /// Whether each ragdoll segment is the trunk's, in
    /// [`Self::capsules`]' order.
    pub(super) fn trunk_segments(&self) -> Vec<bool> {
        self.ragdoll
            .segments()
            .iter()
            .map(|s| s.region() == Region::Torso)
            .collect()
    }

    /// Mass of each ragdoll segment (kg), in [`Self::capsules`]' order.
    pub(super) fn segment_masses(&self) -> Vec<f64> {
        self.ragdoll.segments().iter().map(|s| s.mass()).collect()
    }
}

#[cfg(test)]
mod tests {
    use glam::{DQuat, DVec3};

    use super::super::testbody::{body, crouched, moved, world};
    use super::Physical;
    use crate::character::roles::Role;
    use crate::physics::effects::Attenuation;

    const DT: f64 = 1.0 / 30.0;

    #[test]
    fn a_push_moves_the_body_at_once_and_fades_back_within_about_a_second() {
        let (sk, roles) = body();
        let still = crouched(&sk, &roles, 0.05);
        let mut physical = Physical::new(&sk, &roles, &world(&sk, &still), Attenuation::default());
        let push = DVec3::new(0.1, 0.3, 0.0);
        assert_eq!(
            physical.hit(0, DVec3::ZERO, push),
            Some(DVec3::X * 0.1),
            "on the floor only"
        );
        let mut offsets = Vec::new();
        for _ in 0..90 {
            let mut out = still.clone();
            physical.recover(&mut out, DT);
            offsets.push(out.translations[0].x - still.translations[0].x);
        }
        assert!((offsets[0] - 0.1).abs() < 1e-12);
        assert!(
            offsets[30] < 0.1 * (-1.0f64 / 0.3).exp() + 1e-9,
            "{:.4} m after a second",
            offsets[30]
        );
        assert!(offsets[30] > 0.0);
        assert_eq!(offsets[89], 0.0, "gone after three seconds");
        assert_eq!(physical.hit(0, DVec3::ZERO, DVec3::NAN), None);
    }

    #[test]
    fn the_effects_move_what_no_finger_holds_and_nothing_held() {
        let (sk, roles) = body();
        let still = crouched(&sk, &roles, 0.05);
        // The target swings both arms up and jumps: the ragdoll lags
        // behind it, and its effects show on the free regions.
        let mut jumped = moved(&still, DVec3::new(0.0, 0.1, 0.2));
        for r in [Role::LeftShoulder, Role::RightShoulder] {
            let j = roles.get(r);
            jumped.rotations[j] = DQuat::from_rotation_z(1.2) * jumped.rotations[j];
        }
        let run = |held: &[Role]| {
            let mut physical =
                Physical::new(&sk, &roles, &world(&sk, &still), Attenuation::default());
            let mut out = jumped.clone();
            for _ in 0..15 {
                out = jumped.clone();
                physical.effects(&sk, &roles, &jumped, &mut out, held, [false; 2], DT);
            }
            out
        };
        let free = run(&[]);
        let turned = |out: &crate::character::skeleton::Pose| {
            (0..sk.len())
                .map(|j| out.rotations[j].angle_between(jumped.rotations[j]))
                .fold(0.0, f64::max)
        };
        assert!(
            turned(&free) > 0.01,
            "free: the effects turned a joint {:.4} rad",
            turned(&free)
        );
        let all = Role::ALL;
        let held = run(&all);
        assert!(
            turned(&held) < 1e-9,
            "all held: a joint turned {:.4} rad",
            turned(&held)
        );
    }
}
