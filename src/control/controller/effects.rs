//! After the target posture: the ragdoll's physical effects on the regions
//! no finger holds (eq. 5-7).

use super::{Controller, GROUND_CONTACT_M};
use crate::character::roles::Role;
use crate::character::skeleton::forward_kinematics;
use crate::physics::body::Region;
use crate::physics::effects::free_regions;

impl Controller {
    /// Physics-based tracking: step the ragdoll towards the target and add
    /// its physical effects to the regions no finger holds and that do not
    /// touch the floor (eq. 5–7).
    pub(super) fn physical_effects(&mut self, dt: f64) {
        let sk = &self.ch.lib.skeleton;
        let roles = &self.ch.roles;
        let target = forward_kinematics(sk, &self.target);
        let shown = forward_kinematics(sk, &self.output);
        let resets = self.ragdoll.resets();
        self.ragdoll.step(&target, &shown, dt);
        if self.ragdoll.resets() != resets {
            self.effects.forget();
        }
        self.effects
            .update(self.ragdoll.segments(), &self.ragdoll.states(), dt);
        let held: Vec<Region> = self.held().into_iter().map(Region::of).collect();
        let mut touching = Vec::new();
        for (k, (role, region)) in [
            (Role::LeftFoot, Region::LeftLeg),
            (Role::RightFoot, Region::RightLeg),
        ]
        .into_iter()
        .enumerate()
        {
            let sole = crate::character::skeleton::sole(sk, &shown, roles.get(role)).y;
            if self.feet.planted(k) || sole < GROUND_CONTACT_M {
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
        let pelvis_free = !self.held().contains(&Role::Pelvis);
        self.effects
            .set_active(free_regions(&held, &touching), pelvis_free, dt);
        self.effects
            .apply(sk, self.ragdoll.segments(), &mut self.output, &shown);
    }
}
