//! One frame's picture from the controller's state: the character as the
//! rig's camera sees it, with the marks the controller asks for. The kiosk
//! and headless replays draw through it alike.

use crate::control::controller::Controller;
use crate::control::marks::Marks;
use crate::render::renderer::DrawList;
use crate::render::scene::{self, View};
use crate::screen::Rotation;

/// The draw list for the controller's current posture and view.
#[must_use]
pub fn compose(ctl: &Controller, rotation: Rotation, marks: &Marks) -> DrawList {
    let view = View {
        camera: ctl.rig.camera(),
        rotation,
    };
    let c = ctl.character();
    scene::compose(
        &view,
        &c.lib.skeleton,
        &c.roles,
        ctl.world(),
        &ctl.held(),
        marks,
    )
}
