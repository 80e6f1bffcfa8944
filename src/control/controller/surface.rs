//! The figure shown over the body: a touch on its skinned surface grabs
//! the part nearest it.

use std::sync::Arc;

use super::Controller;
use crate::character::gltf::Skin;

impl Controller {
    /// The glTF figure shown over the body (`None`: none): a touch on its
    /// skinned surface grabs the part nearest it.
    pub fn set_surface(&mut self, figure: Option<Arc<Skin>>) {
        self.fingers.surface = figure;
    }
}
