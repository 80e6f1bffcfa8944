//! What the character is made of: the library, its posing model and its
//! action models, built once and shared by every controller.

use crate::character::library::Library;
use crate::character::roles::RoleMap;
use crate::character::skeleton::Pose;
use crate::control::action::model::ActionModel;
use crate::control::posing::model::{LearnedModel, posing_samples};
use crate::control::posing::sample::{Placement, pose_of, samples_of};

/// What the character is made of: the library, its posing model and its
/// action models. Built once, shared by controllers.
#[derive(Debug)]
pub struct Character {
    pub lib: Library,
    pub roles: RoleMap,
    pub posing: LearnedModel,
    pub actions: Vec<ActionModel>,
}

impl Character {
    /// The character of a library with its posing model baked here, in
    /// memory (no cache): for tests, benches and tools.
    #[must_use]
    pub fn from_library(lib: Library) -> Self {
        let (_, samples) = posing_samples(&lib);
        let posing = LearnedModel::build(samples);
        Self::new(lib, posing)
    }

    /// Build the action models of `lib`; `posing` is its posing model.
    #[must_use]
    pub fn new(lib: Library, posing: LearnedModel) -> Self {
        let actions = lib
            .actions
            .iter()
            .map(|def| ActionModel::build(&lib, def))
            .collect();
        let roles = lib
            .posing
            .first()
            .or_else(|| lib.clips.keys().next())
            .and_then(|n| lib.clips.get(n))
            .map(|c| c.roles.clone())
            .unwrap_or_default();
        Self {
            lib,
            roles,
            posing,
            actions,
        }
    }

    /// The rest posture: the first frame of the first posing clip, standing
    /// at `at`.
    #[must_use]
    pub fn rest_pose(&self, at: &Placement) -> Pose {
        let clip = self.lib.posing.first().and_then(|n| self.lib.clips.get(n));
        match clip.and_then(|c| samples_of(0, c, std::iter::once(0)).pop()) {
            Some(s) => pose_of(&self.lib.skeleton, &s, at),
            None => self.lib.skeleton.rest_pose(),
        }
    }
}
