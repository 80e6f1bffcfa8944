//! The posing part: where posing places its samples (moved when an action
//! or a walk moved the character), and the feet kept where they stood
//! while fingers pose the body (the paper's section 4).

use glam::DVec3;

use crate::character::body::Placement;
use crate::character::skeleton::Pose;
use crate::control::character::Character;
use crate::control::posing::constraint::{Constraint, SynthOptions};
use crate::control::posing::synth::synthesize;

/// Where posing places its samples, and the feet it keeps.
#[derive(Clone, Debug)]
pub(super) struct Posing {
    at: Placement,
    /// Foot positions kept while posing (none: no finger poses the body).
    planted: Option<[DVec3; 2]>,
}

impl Posing {
    /// Posing at `at`, no finger on the body.
    pub fn new(at: Placement) -> Self {
        Self { at, planted: None }
    }

    /// A finger took the body: the feet are kept where they stand
    /// (`feet`, left and right).
    pub fn begin(&mut self, feet: [DVec3; 2]) {
        self.planted = Some(feet);
    }

    /// The character stands at `at` now (an action or a walk moved it):
    /// posing's samples are placed there.
    pub fn place(&mut self, at: Placement) {
        self.at = at;
    }

    /// The character stands at `at` now and no finger poses it.
    pub fn rest(&mut self, at: Placement) {
        self.at = at;
        self.planted = None;
    }

    /// The last finger on the body lifted: whether one was posing it.
    pub fn end(&mut self) -> bool {
        self.planted.take().is_some()
    }

    /// The posture that meets `constraints` (the paper's posture
    /// synthesis), the feet kept where posing began.
    pub fn aim(&self, ch: &Character, constraints: &[Constraint]) -> Pose {
        synthesize(
            &ch.lib.skeleton,
            &ch.roles,
            &ch.posing,
            constraints,
            &self.at,
            self.planted,
            &SynthOptions::default(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::character::body::Anchor;

    #[test]
    fn posing_ends_once_for_each_time_it_began_and_rest_forgets_the_feet() {
        let at = Placement {
            position: DVec3::ZERO,
            yaw: 0.0,
            anchor: Anchor::ClipStart,
        };
        let mut p = Posing::new(at);
        assert!(!p.end(), "nothing to end before a finger took the body");
        p.begin([DVec3::X, -DVec3::X]);
        assert!(p.end());
        assert!(!p.end(), "ended once");
        p.begin([DVec3::X, -DVec3::X]);
        p.place(Placement {
            position: DVec3::Z,
            ..at
        });
        assert!(p.end(), "a new place keeps the feet");
        p.begin([DVec3::X, -DVec3::X]);
        p.rest(at);
        assert!(!p.end(), "at rest no feet are kept");
    }
}
