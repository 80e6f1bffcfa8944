//! `[action]`, `[character]` and `[tracking]`: how drags start actions,
//! how fingers and the camera behave, and how the shown motion follows the
//! synthesised one. The application composes these sections into its
//! configuration and validates them; [`Settings::from_sections`] turns them
//! into the controller's settings.

use std::path::PathBuf;

use serde::Deserialize;

use super::controller::Settings;
use crate::control::action::trail::StartRule;

/// `[tracking]`: how the shown motion follows the synthesised one (the
/// paper's section 6).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TrackingConfig {
    /// Acceleration-based tracking settles in about this long (s); 0 shows
    /// the synthesised postures as they are.
    pub settle_s: f64,
    /// Add the ragdoll's physical effects to the untouched limbs.
    pub physics: bool,
    /// Attenuation of the accumulated effect per frame of 1/30 s (eq. 6).
    pub s1: f64,
    /// Share of the ragdoll's motion per frame of 1/30 s (eq. 6).
    pub s2: f64,
}

impl Default for TrackingConfig {
    fn default() -> Self {
        let s = Settings::default();
        Self {
            settle_s: s.settle_s,
            physics: s.physics,
            s1: s.attenuation.s1,
            s2: s.attenuation.s2,
        }
    }
}

/// `[character]`: the motion library and how fingers and the camera behave.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CharacterConfig {
    /// Folder of the motion library (with its `library.toml`); empty for
    /// the default library shipped with marionette.
    pub library: PathBuf,
    /// A finger within this distance of a body part grabs it (px).
    pub pick_radius_px: f64,
    /// The camera eases back to its home view after this long without a
    /// touch (s).
    pub camera_home_after_s: f64,
}

impl Default for CharacterConfig {
    fn default() -> Self {
        let s = Settings::default();
        Self {
            library: PathBuf::new(),
            pick_radius_px: s.pick_radius_px,
            camera_home_after_s: s.home_after_s,
        }
    }
}

/// `[action]`: when a drag starts an action (the paper's section 5).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ActionConfig {
    /// Weight of time against position in the trail match (px per second).
    pub h: f64,
    /// A drag may run this many times faster or slower than the action
    /// before time counts in the match (1 = exact timing).
    pub tempo_tolerance: f64,
    /// Match cost under which a drag at rest starts an action (px).
    pub threshold_px: f64,
    /// How much the threshold grows per px/s of drag speed.
    pub threshold_per_speed: f64,
    /// Shortest drag that can start an action (px).
    pub min_trail_px: f64,
    /// Part of the action's trajectory the drag must cover (0..1).
    pub min_coverage: f64,
    /// Actions moving within this angle of the line of sight are not
    /// started from this view (degrees).
    pub min_view_angle_deg: f64,
}

impl Default for ActionConfig {
    fn default() -> Self {
        let r = StartRule::default();
        Self {
            h: r.h,
            tempo_tolerance: r.tempo,
            threshold_px: r.base_threshold_px,
            threshold_per_speed: r.speed_gain,
            min_trail_px: r.min_trail_px,
            min_coverage: r.min_coverage,
            min_view_angle_deg: r.min_view_angle_deg,
        }
    }
}

impl ActionConfig {
    /// The start rule these settings make.
    #[must_use]
    pub fn rule(&self) -> StartRule {
        StartRule {
            h: self.h,
            tempo: self.tempo_tolerance,
            base_threshold_px: self.threshold_px,
            speed_gain: self.threshold_per_speed,
            min_trail_px: self.min_trail_px,
            min_coverage: self.min_coverage,
            min_view_angle_deg: self.min_view_angle_deg,
        }
    }
}

impl Settings {
    /// The settings these configuration sections give.
    #[must_use]
    pub fn from_sections(
        action: &ActionConfig,
        character: &CharacterConfig,
        tracking: &TrackingConfig,
    ) -> Self {
        Self {
            rule: action.rule(),
            pick_radius_px: character.pick_radius_px,
            home_after_s: character.camera_home_after_s,
            settle_s: tracking.settle_s,
            physics: tracking.physics,
            attenuation: crate::physics::effects::Attenuation {
                s1: tracking.s1,
                s2: tracking.s2,
            },
            ..Self::default()
        }
    }
}
