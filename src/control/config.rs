//! `[action]`, `[character]` (or `[[character]]`) and `[tracking]`: how drags start actions,
//! how fingers and the camera behave, and how the shown motion follows the
//! synthesised one. The application composes these sections into its
//! configuration and validates them; [`Settings::from_sections`] turns them
//! into the controller's settings.

use std::path::PathBuf;

use serde::Deserialize;

use super::controller::{RecogniserKind, Settings};
use crate::control::action::trail::StartRule;
use crate::input::config::exactly_some;

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
    /// Where the character stands on the floor, `[x, z]` in metres; unset:
    /// see [`Characters::placements`].
    #[serde(deserialize_with = "exactly_some")]
    pub place: Option<[f64; 2]>,
    /// Which way it faces (degrees from +Z, the camera's home side,
    /// positive towards +X); unset: see [`Characters::placements`].
    pub facing_deg: Option<f64>,
    /// Colour of its clothes, linear RGB 0..1; unset: the default shirt
    /// for a lone character, else one of [`TINTS`].
    #[serde(deserialize_with = "exactly_some")]
    pub tint: Option<[f64; 3]>,
    /// A skinned glTF character (`.glb`, `.gltf`) the library drives;
    /// empty: the project's own body (`[display] body`).
    pub mesh: PathBuf,
    /// The mesh's joints for roles its names and places do not find, or
    /// find wrongly: role → joint name (`left_hand = "Wrist.L"`), as a
    /// library's `[roles]` table.
    pub mesh_roles: std::collections::BTreeMap<String, String>,
}

impl Default for CharacterConfig {
    fn default() -> Self {
        let s = Settings::default();
        Self {
            library: PathBuf::new(),
            pick_radius_px: s.pick_radius_px,
            camera_home_after_s: s.home_after_s,
            place: None,
            facing_deg: None,
            tint: None,
            mesh: PathBuf::new(),
            mesh_roles: std::collections::BTreeMap::new(),
        }
    }
}

/// The most characters a table holds.
pub const MAX_CHARACTERS: usize = 4;

/// Tints of characters that share the table and set none, in order.
pub const TINTS: [[f64; 3]; MAX_CHARACTERS] = [
    [0.62, 0.1, 0.07],
    [0.09, 0.26, 0.55],
    [0.75, 0.5, 0.05],
    [0.12, 0.45, 0.2],
];

/// Spacing of characters placed by default (m).
pub const DEFAULT_SPACING_M: f64 = 1.2;

/// The characters: `[character]` (one table, one character) or
/// `[[character]]` (one table each, up to [`MAX_CHARACTERS`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Characters(pub Vec<CharacterConfig>);

impl Default for Characters {
    fn default() -> Self {
        Self(vec![CharacterConfig::default()])
    }
}

impl Characters {
    /// The first character's table: the one whose `pick_radius_px` and
    /// `camera_home_after_s` hold for the whole table.
    #[must_use]
    pub fn first(&self) -> &CharacterConfig {
        // Never empty: parsing refuses an empty list.
        &self.0[0]
    }

    #[must_use]
    pub fn len(&self) -> usize {
        self.0.len()
    }

    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    pub fn iter(&self) -> std::slice::Iter<'_, CharacterConfig> {
        self.0.iter()
    }

    /// Where each character stands and faces: `(x, z, yaw radians)`.
    /// Unset places spread the characters along X, [`DEFAULT_SPACING_M`]
    /// apart around the origin (a lone character at the origin); unset
    /// facings turn two characters towards each other, and otherwise face
    /// the camera's home side (+Z).
    #[must_use]
    pub fn placements(&self) -> Vec<(f64, f64, f64)> {
        let n = self.0.len();
        self.0
            .iter()
            .enumerate()
            .map(|(k, c)| {
                let [x, z] = c
                    .place
                    .unwrap_or([(k as f64 - (n as f64 - 1.0) / 2.0) * DEFAULT_SPACING_M, 0.0]);
                let facing = c.facing_deg.map_or_else(
                    || match (n, k) {
                        (2, 0) => std::f64::consts::FRAC_PI_2,
                        (2, _) => -std::f64::consts::FRAC_PI_2,
                        _ => 0.0,
                    },
                    f64::to_radians,
                );
                (x, z, facing)
            })
            .collect()
    }

    /// Each character's tint (`None`: the default clothes).
    #[must_use]
    pub fn tints(&self) -> Vec<Option<[f32; 3]>> {
        let n = self.0.len();
        self.0
            .iter()
            .enumerate()
            .map(|(k, c)| {
                c.tint
                    .or_else(|| (n > 1).then(|| TINTS[k % TINTS.len()]))
                    .map(|t| t.map(|v| v as f32))
            })
            .collect()
    }
}

impl<'de> Deserialize<'de> for Characters {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct OneOrMany;
        impl<'de> serde::de::Visitor<'de> for OneOrMany {
            type Value = Characters;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a [character] table or [[character]] tables")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> Result<Characters, A::Error> {
                CharacterConfig::deserialize(serde::de::value::MapAccessDeserializer::new(map))
                    .map(|c| Characters(vec![c]))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<Characters, A::Error> {
                let mut all = Vec::new();
                while let Some(c) = seq.next_element::<CharacterConfig>()? {
                    all.push(c);
                }
                if all.is_empty() {
                    return Err(serde::de::Error::custom(
                        "no character: give at least one [[character]] table",
                    ));
                }
                Ok(Characters(all))
            }
        }
        d.deserialize_any(OneOrMany)
    }
}

/// `[action]`: when a drag starts an action (the paper's section 5).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ActionConfig {
    /// Which recogniser: `"templates"` (each clip's own path, thresholds
    /// calibrated for the library) or `"paper"` (the average trajectory
    /// and the start rule below, for comparison).
    pub recogniser: RecogniserKind,
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
            recogniser: RecogniserKind::default(),
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
            recogniser: action.recogniser,
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
