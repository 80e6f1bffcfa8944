//! Another character's body: the capsules this one offers to collision
//! tests, and how a blow from outside reaches it.

use glam::DVec3;

use super::Controller;

impl Controller {
    /// The body's capsules in the posture shown, one per ragdoll segment,
    /// with the name of the joint each carries.
    #[must_use]
    pub fn capsules(&self) -> Vec<(crate::physics::ragdoll::Capsule, &str)> {
        self.physical
            .capsules(self.shown.world())
            .into_iter()
            .map(|(c, j)| (c, self.ch.lib.skeleton.joints[j].name.as_str()))
            .collect()
    }

    /// Whether each ragdoll segment is the trunk's (pelvis, spine, chest,
    /// neck, head), in [`Self::capsules`]' order.
    #[must_use]
    pub fn trunk_segments(&self) -> Vec<bool> {
        self.physical.trunk_segments()
    }

    /// Mass of each ragdoll segment (kg), in [`Self::capsules`]' order.
    #[must_use]
    pub fn segment_masses(&self) -> Vec<f64> {
        self.physical.segment_masses()
    }

    /// A blow from outside: `impulse` (N·s) on segment `k` of the ragdoll,
    /// which shows through the physical effects on the regions no finger
    /// holds (eq. 5-7), and the body moved by `shove` (m, on the floor)
    /// at once, fading back as it recovers; feet that carry the body stay
    /// where they stand.
    pub fn hit(&mut self, k: usize, impulse: DVec3, shove: DVec3) {
        if let Some(shove) = self.physical.hit(k, impulse, shove) {
            self.shown.shove(shove);
        }
    }
}
