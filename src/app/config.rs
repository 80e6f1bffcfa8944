//! The configuration file (TOML), validated as a whole at start.
//!
//! The sections belong to the subsystems that read them
//! (`InputConfig`, `DisplayConfig`, `ActionConfig`,
//! `CharacterConfig`, `TrackingConfig`); this module composes them with
//! the application's own (`[kiosk]`, `[log]`) and validates the whole.
//!
//! Every key is documented in `config/marionette.toml`. An unknown key, a
//! value of the wrong type or out of range is a [`ConfigError`] that names
//! the file, the key and what is allowed; the binary exits with
//! `exit::CONFIG` (78) on it.

use crate::reading::quote;
use std::path::{Path, PathBuf};

use serde::Deserialize;
use thiserror::Error;

use crate::control::config::{
    ActionConfig, CharacterConfig, Characters, MAX_CHARACTERS, TrackingConfig,
};
use crate::control::controller::Settings;
use crate::display::config::DisplayConfig;
use crate::input::config::{InputConfig, parse_usb_id};
use crate::screen::Rotation;

/// Where `run` looks for its configuration when none is given.
pub const DEFAULT_PATH: &str = "/etc/marionette/marionette.toml";

/// Errors loading the configuration.
#[derive(Debug, Error)]
pub enum ConfigError {
    /// The file could not be read.
    #[error("cannot read configuration {path}: {source}")]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// Not TOML, an unknown key or a wrong type (the message shows where).
    #[error("configuration {path}: {message}")]
    Parse { path: PathBuf, message: String },
    /// A value out of its allowed range.
    #[error("configuration {path}: `{key}` {message}")]
    Invalid {
        path: PathBuf,
        key: String,
        message: String,
    },
}

/// Floor distance between the duel scene's characters (m): a punch or a
/// kick reaches the other.
pub const DUEL_SPACING_M: f64 = 0.9;

/// The whole configuration.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Config {
    /// The file this configuration was read from (empty: built-in
    /// defaults): relative paths in it are resolved from its folder, and
    /// errors name it.
    #[serde(skip)]
    pub source: PathBuf,
    pub display: DisplayConfig,
    pub input: InputConfig,
    pub action: ActionConfig,
    pub character: Characters,
    pub tracking: TrackingConfig,
    pub kiosk: KioskConfig,
    pub log: LogConfig,
}

/// `[kiosk]`: what `marionette run` does when nobody touches the table.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct KioskConfig {
    /// After this long without a touch the character returns to its rest
    /// posture (s).
    pub idle_after_s: f64,
    /// An evemu recording the character then performs in a loop until
    /// someone touches; empty for none.
    pub attract: PathBuf,
    /// When `run` cannot start (configuration, library), the reason stays
    /// on the display this long (s) before the process exits; 0: none.
    pub error_screen_s: f64,
    /// Where to write the vital signs every minute in Prometheus text
    /// format (node_exporter's textfile collector); empty: nowhere.
    pub metrics_textfile: PathBuf,
    /// The record of what visitors do (SQLite); empty: none.
    pub visits: PathBuf,
    /// Days of visits kept, and the most the record may take (MB).
    pub visits_keep_days: f64,
    pub visits_max_mb: f64,
}

impl Default for KioskConfig {
    fn default() -> Self {
        Self {
            idle_after_s: 45.0,
            attract: PathBuf::new(),
            error_screen_s: 60.0,
            metrics_textfile: PathBuf::new(),
            visits: PathBuf::from("/var/lib/marionette/visits.db"),
            visits_keep_days: 365.0,
            visits_max_mb: 256.0,
        }
    }
}

/// `[log]`
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LogConfig {
    /// Default level: error, warn, info, debug or trace (`RUST_LOG`
    /// overrides it).
    pub level: String,
}

impl Default for LogConfig {
    fn default() -> Self {
        Self {
            level: "info".to_owned(),
        }
    }
}

/// The largest configuration file read (bytes).
pub const MAX_CONFIG_BYTES: u64 = 1 << 20;

impl Config {
    /// Read and validate a configuration file.
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        let text =
            crate::reading::read_text(path, MAX_CONFIG_BYTES).map_err(|e| ConfigError::Read {
                path: path.to_owned(),
                source: e.into(),
            })?;
        Self::parse(&text, path)
    }

    /// Parse and validate configuration text; `path` is for messages.
    pub fn parse(text: &str, path: &Path) -> Result<Self, ConfigError> {
        let mut config: Config = toml::from_str(text).map_err(|e| ConfigError::Parse {
            path: path.to_owned(),
            message: crate::reading::toml_error(text, &e),
        })?;
        config.validate(path)?;
        // A relative library folder is the configuration file's neighbour,
        // wherever the program was started from.
        let base = std::path::absolute(path)
            .ok()
            .and_then(|p| p.parent().map(Path::to_path_buf));
        for c in &mut config.character.0 {
            for p in [&mut c.library, &mut c.mesh] {
                if !p.as_os_str().is_empty()
                    && p.is_relative()
                    && let Some(base) = &base
                {
                    *p = base.join(&*p);
                }
            }
        }
        config.source = path.to_owned();
        Ok(config)
    }

    fn validate(&self, path: &Path) -> Result<(), ConfigError> {
        let invalid = |key: &str, message: String| ConfigError::Invalid {
            path: path.to_owned(),
            key: key.to_owned(),
            message,
        };
        // Every number within its range (inclusive), or the error for the
        // first that is not: `(key, value, lowest, highest)`.
        let in_ranges = |checks: &[(&str, f64, f64, f64)]| {
            for &(key, v, lo, hi) in checks {
                if !(v.is_finite() && (lo..=hi).contains(&v)) {
                    return Err(invalid(
                        key,
                        format!("must be between {lo} and {hi}, found {v}"),
                    ));
                }
            }
            Ok(())
        };
        self.validate_display(&invalid)?;
        self.validate_characters(&invalid)?;
        in_ranges(&[
            ("kiosk.idle_after_s", self.kiosk.idle_after_s, 1.0, 86_400.0),
            (
                "kiosk.error_screen_s",
                self.kiosk.error_screen_s,
                0.0,
                3_600.0,
            ),
            (
                "kiosk.visits_keep_days",
                self.kiosk.visits_keep_days,
                1.0,
                36_500.0,
            ),
            (
                "kiosk.visits_max_mb",
                self.kiosk.visits_max_mb,
                1.0,
                1_000_000.0,
            ),
        ])?;
        for (key, path, e_g) in [
            (
                "kiosk.metrics_textfile",
                &self.kiosk.metrics_textfile,
                "node_exporter's textfile directory, e.g. \"/var/lib/prometheus/node-exporter/marionette.prom\"",
            ),
            (
                "kiosk.visits",
                &self.kiosk.visits,
                "e.g. \"/var/lib/marionette/visits.db\"",
            ),
        ] {
            if !path.as_os_str().is_empty() && !path.is_absolute() {
                return Err(invalid(
                    key,
                    format!(
                        "must be an absolute path ({e_g}) or empty, found {}",
                        quote(&path.display().to_string())
                    ),
                ));
            }
        }
        let t = &self.tracking;
        in_ranges(&[
            ("tracking.settle_s", t.settle_s, 0.0, 2.0),
            ("tracking.s1", t.s1, 0.0, 0.95),
            ("tracking.s2", t.s2, 0.0, 2.0),
        ])?;
        if !(50..=60_000).contains(&self.input.rescan_interval_ms) {
            return Err(invalid(
                "input.rescan_interval_ms",
                format!(
                    "must be between 50 and 60000, found {}",
                    self.input.rescan_interval_ms
                ),
            ));
        }
        self.validate_devices(&invalid)?;
        let a = &self.action;
        in_ranges(&[
            ("action.h", a.h, 0.0, 10_000.0),
            ("action.tempo_tolerance", a.tempo_tolerance, 1.0, 10.0),
            ("action.threshold_px", a.threshold_px, 0.0, 1_000.0),
            (
                "action.threshold_per_speed",
                a.threshold_per_speed,
                0.0,
                10.0,
            ),
            ("action.min_trail_px", a.min_trail_px, 0.0, 2_000.0),
            ("action.min_coverage", a.min_coverage, 0.0, 1.0),
            ("action.min_view_angle_deg", a.min_view_angle_deg, 0.0, 90.0),
        ])?;
        if !["error", "warn", "info", "debug", "trace"].contains(&self.log.level.as_str()) {
            return Err(invalid(
                "log.level",
                format!(
                    "must be one of error, warn, info, debug, trace, found {}",
                    quote(&self.log.level)
                ),
            ));
        }
        Ok(())
    }
}

impl Config {
    /// `[display]`: the picture's size, rotation and samples, the mode,
    /// the body and the presenter.
    fn validate_display(
        &self,
        invalid: &dyn Fn(&str, String) -> ConfigError,
    ) -> Result<(), ConfigError> {
        let d = &self.display;
        for (key, v) in [("display.width", d.width), ("display.height", d.height)] {
            if !(16..=16384).contains(&v) {
                return Err(invalid(
                    key,
                    format!("must be between 16 and 16384 pixels, found {v}"),
                ));
            }
        }
        if Rotation::from_degrees(i64::from(d.rotation)).is_none() {
            return Err(invalid(
                "display.rotation",
                format!(
                    "must be one of 0, 90, 180, 270 (degrees clockwise), found {}",
                    d.rotation
                ),
            ));
        }
        if ![0, 1, 2, 4, 8].contains(&d.samples) {
            return Err(invalid(
                "display.samples",
                format!("must be 0 (automatic), 1, 2, 4 or 8, found {}", d.samples),
            ));
        }
        if !d.mode.is_empty()
            && crate::display::present::OutputChoice::parse_mode(&d.mode).is_none()
        {
            return Err(invalid(
                "display.mode",
                format!(
                    "must be WIDTHxHEIGHT or WIDTHxHEIGHT@HZ, each above 0 (e.g. \"1920x1080@60\"; see `marionette list-outputs`), or empty for the preferred mode, found {}",
                    quote(&d.mode)
                ),
            ));
        }
        if ![
            crate::display::config::BODY_SKINNED,
            crate::display::config::BODY_CAPSULES,
        ]
        .contains(&d.body.as_str())
        {
            return Err(invalid(
                "display.body",
                format!(
                    "must be \"skinned\" (one smooth skinned body) or \"capsules\" (the mannequin of capsules), found {}",
                    quote(&d.body)
                ),
            ));
        }
        if crate::display::present::PresenterKind::parse(&d.presenter).is_none() {
            return Err(invalid(
                "display.presenter",
                format!(
                    "must be \"auto\", \"direct\" (Vulkan drives the display: real GPU drivers), \"gbm\" (gbm's scanout buffers, rendered into where the Vulkan driver imports them, else written into: drivers Mesa's gbm opens) or \"copy\" (frames copied into dumb buffers: any driver), found {}",
                    quote(&d.presenter)
                ),
            ));
        }
        Ok(())
    }

    /// `[[input.device]]`: each matched by name or USB id, its axes and
    /// its calibration.
    fn validate_devices(
        &self,
        invalid: &dyn Fn(&str, String) -> ConfigError,
    ) -> Result<(), ConfigError> {
        for (i, dev) in self.input.device.iter().enumerate() {
            let key = |k: &str| format!("input.device[{i}].{k}");
            if dev.match_name.is_none() && dev.match_usb.is_none() {
                return Err(invalid(
                    &format!("input.device[{i}]"),
                    "needs `match_name` (the device name, see `marionette list-devices`) or `match_usb` (\"vendor:product\" in hex)".to_owned(),
                ));
            }
            if let Some(u) = &dev.match_usb {
                if parse_usb_id(u).is_none() {
                    return Err(invalid(
                        &key("match_usb"),
                        format!(
                            "must be \"vendor:product\" in hex, like \"0eef:72a1\", found {}",
                            quote(u)
                        ),
                    ));
                }
            }
            if let Some(axes) = &dev.axes {
                for (k, name) in [("x", &axes.x), ("y", &axes.y)] {
                    if crate::input::remap::axis_code(name).is_none() {
                        return Err(invalid(
                            &key(&format!("axes.{k}")),
                            format!(
                                "{} is not an axis marionette knows; one of {}",
                                quote(name),
                                crate::input::remap::AXIS_NAMES.map(|(n, _)| n).join(", ")
                            ),
                        ));
                    }
                }
                if axes.x.eq_ignore_ascii_case(&axes.y) {
                    return Err(invalid(
                        &key("axes"),
                        format!(
                            "x and y must be two axes, found {} for both",
                            quote(&axes.x)
                        ),
                    ));
                }
            }
            if !dev.matrix().is_usable() {
                return Err(invalid(
                    &key("calibration"),
                    format!(
                        "must be 6 numbers [a, b, c, d, e, f] within ±10 with |a·e − b·d| between 0.01 and 100, mapping the panel onto the screen within a factor of 10 (identity is [1, 0, 0, 0, 1, 0]), found {:?}",
                        dev.calibration
                    ),
                ));
            }
        }
        Ok(())
    }

    /// `[character]` / `[[character]]`: how many, where they stand, their
    /// tints and the table-wide settings of the first.
    fn validate_characters(
        &self,
        invalid: &dyn Fn(&str, String) -> ConfigError,
    ) -> Result<(), ConfigError> {
        let all = &self.character;
        let many = all.len() > 1;
        let key = |k: usize, name: &str| {
            if many {
                format!("character[{k}].{name}")
            } else {
                format!("character.{name}")
            }
        };
        if all.len() > MAX_CHARACTERS {
            return Err(invalid(
                "character",
                format!(
                    "{} [[character]] tables: a table holds at most {MAX_CHARACTERS} characters",
                    all.len()
                ),
            ));
        }
        let first = all.first();
        for (k, c) in all.iter().enumerate() {
            check_character(c, (k > 0).then_some(first), &|name| key(k, name), invalid)?;
        }
        let places = all.placements();
        for (i, a) in places.iter().enumerate() {
            for (j, b) in places.iter().enumerate().skip(i + 1) {
                let apart = (a.0 - b.0).hypot(a.1 - b.1);
                if apart < 0.6 {
                    return Err(invalid(
                        &key(j, "place"),
                        format!(
                            "stands {apart:.2} m from character {i}: give each its own `place`, at least 0.6 m apart (e.g. place = [{:.1}, 0.0])",
                            a.0 + 1.2
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The duel scene's table: two characters [`DUEL_SPACING_M`] apart on
    /// the X axis, facing each other (the first on the left of the home
    /// view, in red; the second, in blue), of this configuration's first two
    /// libraries (the first's twice when it has one character).
    #[must_use]
    pub fn duel(&self) -> Config {
        let mut c = self.clone();
        let first = self.character.first().clone();
        let second = self
            .character
            .iter()
            .nth(1)
            .cloned()
            .unwrap_or_else(|| first.clone());
        let half = DUEL_SPACING_M / 2.0;
        c.character = Characters(vec![
            CharacterConfig {
                place: Some([-half, 0.0]),
                facing_deg: Some(90.0),
                tint: None,
                ..first
            },
            CharacterConfig {
                place: Some([half, 0.0]),
                facing_deg: Some(-90.0),
                tint: None,
                ..second
            },
        ]);
        c
    }

    /// The configuration with `mesh` as every character's figure (its
    /// roles found from the file alone).
    #[must_use]
    pub fn with_mesh(&self, mesh: &Path) -> Config {
        let mut c = self.clone();
        for ch in &mut c.character.0 {
            ch.mesh = mesh.to_owned();
            ch.mesh_roles.clear();
        }
        c
    }

    /// This configuration with every character's library set to `dir`
    /// (`--library` given to a command that replays).
    #[must_use]
    pub fn with_library(&self, dir: &Path) -> Config {
        let mut c = self.clone();
        for ch in &mut c.character.0 {
            ch.library = dir.to_owned();
        }
        c
    }

    /// The controller's settings from `[action]`, `[character]` and
    /// `[tracking]`.
    #[must_use]
    pub fn control_settings(&self) -> Settings {
        Settings::from_sections(&self.action, self.character.first(), &self.tracking)
    }

    /// Where the library is: the configured folder, else the shipped
    /// default library (installed, else next to the source tree).
    #[must_use]
    pub fn library_dir(&self) -> PathBuf {
        Self::library_dir_of(self.character.first())
    }

    /// Where each character's library is, in `[[character]]` order.
    #[must_use]
    pub fn library_dirs(&self) -> Vec<PathBuf> {
        self.character.iter().map(Self::library_dir_of).collect()
    }

    fn library_dir_of(character: &CharacterConfig) -> PathBuf {
        let configured = &character.library;
        if !configured.as_os_str().is_empty() {
            return configured.clone();
        }
        let installed = Path::new("/usr/share/marionette/library");
        if installed.join("library.toml").exists() {
            return installed.to_owned();
        }
        let here = Path::new("assets/library");
        if here.join("library.toml").exists() {
            return here.to_owned();
        }
        Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/library")
    }
}

/// One `[[character]]` table's values in range (`key` names a value in
/// errors); the table-wide ones as the first table (`first`, for the
/// others) sets them.
fn check_character(
    c: &CharacterConfig,
    first: Option<&CharacterConfig>,
    key: &dyn Fn(&str) -> String,
    invalid: &dyn Fn(&str, String) -> ConfigError,
) -> Result<(), ConfigError> {
    let range = |name: &str, v: f64, lo: f64, hi: f64| {
        if (lo..=hi).contains(&v) {
            Ok(())
        } else {
            Err(invalid(
                &key(name),
                format!("must be between {lo} and {hi}, found {v}"),
            ))
        }
    };
    range("pick_radius_px", c.pick_radius_px, 1.0, 500.0)?;
    range("camera_home_after_s", c.camera_home_after_s, 0.0, 3600.0)?;
    if first.is_some_and(|f| {
        c.pick_radius_px != f.pick_radius_px || c.camera_home_after_s != f.camera_home_after_s
    }) {
        return Err(invalid(
            &key("pick_radius_px"),
            "and camera_home_after_s hold for the whole table: set them in the first [[character]] only".to_owned(),
        ));
    }
    if let Some([x, z]) = c.place {
        range("place", x, -5.0, 5.0)?;
        range("place", z, -5.0, 5.0)?;
    }
    if let Some(f) = c.facing_deg {
        range("facing_deg", f, -360.0, 360.0)?;
    }
    if let Some(t) = c.tint {
        for v in t {
            range("tint", v, 0.0, 1.0)?;
        }
    }
    for role in c.mesh_roles.keys() {
        if crate::character::roles::Role::from_name(role).is_none() {
            let all: Vec<&str> = crate::character::roles::Role::ALL
                .iter()
                .map(|r| r.name())
                .collect();
            return Err(invalid(
                &key(&format!("mesh_roles.{role}")),
                format!("is not a role; roles are {}", all.join(", ")),
            ));
        }
    }
    if !c.mesh_roles.is_empty() && c.mesh.as_os_str().is_empty() {
        return Err(invalid(
            &key("mesh_roles"),
            "names joints of a mesh, but no `mesh` is set".to_owned(),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests;
