//! `[display]`: the output, its mode and presenter, and what the picture
//! shows. The application composes this section into its configuration
//! and validates it.

use serde::Deserialize;

use crate::screen::{Picture, Rotation};

/// `[display]`
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DisplayConfig {
    /// Picture width in pixels for headless output (the demo, replays); on
    /// KMS the output's mode decides.
    pub width: u32,
    /// Picture height in pixels, as `width`.
    pub height: u32,
    /// Clockwise turn of the picture on the panel: 0, 90, 180 or 270.
    pub rotation: u32,
    /// Samples per pixel for anti-aliasing: 1, 2, 4 or 8 (fewer when the
    /// adapter cannot); 0 chooses: 4 on a GPU, 1 on a CPU renderer.
    pub samples: u32,
    /// Show the trajectories of the actions a held part can start.
    pub trajectories: bool,
    /// Show a status line (mode, action, frame time).
    pub status_line: bool,
    /// Show the service view from the start (touchscreens, fingers'
    /// calibrated points and trails, frame rate, latency); five fingers
    /// held three seconds toggle it either way.
    pub service_view: bool,
    /// The KMS output to drive, by connector name (`HDMI-A-1`; see
    /// `marionette list-outputs`); empty: the first connected one.
    pub output: String,
    /// Its mode, `WIDTHxHEIGHT` or `WIDTHxHEIGHT@HZ`; empty: the preferred.
    pub mode: String,
    /// How frames reach the output: `auto` (direct where the Vulkan driver
    /// can drive the display, else gbm, else copy), `direct`, `gbm` or
    /// `copy`.
    pub presenter: String,
    /// How the character looks: `skinned` (one smooth skinned body, the
    /// default) or `capsules` (the mannequin of capsules). A configured
    /// `[character] mesh` is shown instead of either.
    pub body: String,
}

/// `[display] body` for the project's own skinned body.
pub const BODY_SKINNED: &str = "skinned";
/// `[display] body` for the mannequin of capsules.
pub const BODY_CAPSULES: &str = "capsules";

impl Default for DisplayConfig {
    fn default() -> Self {
        Self {
            width: 1280,
            height: 720,
            rotation: 0,
            samples: 0,
            trajectories: true,
            status_line: true,
            service_view: false,
            output: String::new(),
            mode: String::new(),
            presenter: "auto".to_owned(),
            body: BODY_SKINNED.to_owned(),
        }
    }
}

impl DisplayConfig {
    #[must_use]
    pub fn rotation(&self) -> Rotation {
        Rotation::from_degrees(i64::from(self.rotation)).unwrap_or_default()
    }

    /// The picture: the output's size and the rotation.
    #[must_use]
    pub fn picture(&self) -> Picture {
        Picture {
            output: self.output_size(),
            rotation: self.rotation(),
        }
    }

    /// Picture size in pixels: the output's, turned by the rotation.
    #[must_use]
    pub fn size(&self) -> (u32, u32) {
        self.picture().size()
    }

    /// Output size in pixels (before rotation).
    #[must_use]
    pub fn output_size(&self) -> (u32, u32) {
        (self.width, self.height)
    }
}
