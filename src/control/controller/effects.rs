//! After the target posture: the ragdoll's physical effects on the regions
//! no finger holds (eq. 5-7), and the feet that carry the body kept where
//! they came down.

use glam::DVec3;

use super::{Controller, FOOT_CREEP_M_S, GROUND_CONTACT_M};
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
            if self.feet[k].anchor.is_some() || sole < GROUND_CONTACT_M {
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

    /// Foot contact and foot IK: a foot of the target posture that is near
    /// the floor and nearly still carries the body; it is held where it was
    /// when it came down while tracking moves the pelvis. Feet held by a
    /// finger are the finger's. No sole goes below the floor.
    pub(super) fn fix_feet(&mut self, dt: f64) {
        let sk = &self.ch.lib.skeleton;
        let roles = &self.ch.roles;
        let target = forward_kinematics(sk, &self.target);
        let shown = forward_kinematics(sk, &self.output);
        let held = self.held();
        // A held foot whose target slid away (more than 2 cm) follows it at
        // a walking foot's creep at most, so that a planted foot never
        // skates visibly; a released foot returns to the tracked posture
        // within about 0.1 s, never in one jump.
        let creep = FOOT_CREEP_M_S * dt;
        let fade = (-dt / 0.04).exp();
        let settle = 1.0 - (-dt / 0.06).exp();
        let switched = std::mem::take(&mut self.switched);
        let mut goals = [None; 2];
        let feet = [Role::LeftFoot, Role::RightFoot];
        for (k, role) in feet.into_iter().enumerate() {
            let p = target.positions[roles.get(role)];
            // Across a switch of controller the target's feet jump: that
            // is not the foot moving.
            let speed = if dt > 0.0 && !switched {
                (p - self.last_feet[k]).length() / dt
            } else {
                0.0
            };
            self.last_feet[k] = p;
            let support = p.y <= self.ankle_rest + 0.03 && speed < 0.3 && !held.contains(&role);
            let tracked = shown.positions[roles.get(role)];
            let foot = &mut self.feet[k];
            if support {
                let a = match foot.anchor {
                    Some(a) => {
                        let off = (p - a).with_y(0.0);
                        if off.length() > 0.02 {
                            a + off.clamp_length_max(creep)
                        } else {
                            a
                        }
                    }
                    // Where the foot is shown now: no jump.
                    None => foot
                        .release
                        .map_or(tracked, |(r, w)| tracked + (r - tracked) * w),
                };
                // Height from the target (a heel may rise over planted
                // toes), reached smoothly from where the foot came down.
                foot.anchor = Some(a.with_y(a.y + (p.y - a.y) * settle));
                foot.release = None;
                goals[k] = foot.anchor;
            } else {
                if let Some(a) = foot.anchor.take() {
                    foot.release = Some((a, 1.0));
                }
                foot.release = foot
                    .release
                    .map(|(r, w)| (r, w * fade))
                    .filter(|(_, w)| *w > 0.02);
                goals[k] = foot.release.map(|(r, w)| tracked + (r - tracked) * w);
            }
        }
        if goals.iter().any(Option::is_some) {
            crate::control::posing::ik::plant_feet(sk, roles, &mut self.output, goals);
        }
        // The floor: a sole below it (tracking straightens a leg before the
        // pelvis rises, toes tip down) is lifted onto it: the leg bends,
        // then the foot turns at the ankle so that its lowest point rests
        // on the floor, as toes flatten on the ground.
        let mut lifted = false;
        let ankle_min = self.ankle_rest * 0.5;
        let w = forward_kinematics(sk, &self.output);
        for (k, role) in feet.into_iter().enumerate() {
            let ankle = w.positions[roles.get(role)];
            goals[k] = if ankle.y < ankle_min {
                lifted = true;
                Some(ankle.with_y(ankle_min))
            } else {
                goals[k].map(|_| ankle)
            };
        }
        if lifted {
            crate::control::posing::ik::plant_feet(sk, roles, &mut self.output, goals);
        }
        for _ in 0..2 {
            let w = forward_kinematics(sk, &self.output);
            let mut turned = false;
            for role in feet {
                let j = roles.get(role);
                let ankle = w.positions[j];
                let v = crate::character::skeleton::sole(sk, &w, j) - ankle;
                let len = v.length();
                if ankle.y + v.y >= -1e-4 || len < 1e-6 || v.with_y(0.0).length() < 1e-6 {
                    continue;
                }
                let want = (-ankle.y / len).clamp(-1.0, 1.0).asin();
                let turn = glam::DQuat::from_axis_angle(
                    v.cross(DVec3::Y).normalize(),
                    want - (v.y / len).asin(),
                );
                let parent = sk.joints[j]
                    .parent
                    .map_or(glam::DQuat::IDENTITY, |p| w.rotations[p]);
                self.output.rotations[j] = (parent.inverse() * turn * w.rotations[j]).normalize();
                turned = true;
            }
            if !turned {
                break;
            }
        }
    }
}
