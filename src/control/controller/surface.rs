//! What a finger grabs: the body part under it, on the figure shown over
//! the body where one is.

use std::sync::Arc;

use super::Controller;
use crate::character::camera::Camera;
use crate::character::gltf::Skin;
use crate::character::roles::Role;
use crate::control::posing::pick::pick_with;
use crate::screen::ScreenPoint;

impl Controller {
    /// The glTF figure shown over the body (`None`: none): a touch on its
    /// skinned surface grabs the part nearest it.
    pub fn set_surface(&mut self, figure: Option<Arc<Skin>>) {
        self.surface = figure;
    }

    /// The part a finger at `p` grabs, seen through `camera`.
    pub(super) fn pick_part(&self, camera: &Camera, p: ScreenPoint) -> Option<Role> {
        pick_with(
            camera,
            &self.ch.lib.skeleton,
            &self.ch.roles,
            &self.world,
            self.surface.as_deref(),
            p,
            self.settings.pick_radius_px,
        )
    }
}
