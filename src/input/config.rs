//! `[input]` and `[[input.device]]`: where the panels are and how each is
//! read (its calibration matrix, or not at all). The application composes
//! this section into its configuration and validates it.

use std::path::PathBuf;

use serde::Deserialize;

use super::calibration::Matrix;
use super::device::DeviceDescription;
use super::remap::{Remap, RemapError, axis_code};

/// `[input]`
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct InputConfig {
    /// Where the event devices are.
    pub dev_dir: PathBuf,
    /// Grab touchscreens (EVIOCGRAB) so no other program sees their touches.
    pub grab: bool,
    /// How often to look for panels that appeared, in milliseconds.
    pub rescan_interval_ms: u64,
    /// Per-device settings; the first entry that matches a device applies.
    pub device: Vec<DeviceConfig>,
}

impl Default for InputConfig {
    fn default() -> Self {
        Self {
            dev_dir: PathBuf::from("/dev/input"),
            grab: true,
            rescan_interval_ms: 1000,
            device: Vec::new(),
        }
    }
}

/// A list of `N` numbers in the configuration, exactly: a longer list is
/// refused rather than cut short (a fixed-size array would drop what is
/// past `N` without a word).
pub fn exactly<'de, D, const N: usize>(d: D) -> Result<[f64; N], D::Error>
where
    D: serde::Deserializer<'de>,
{
    let v = Vec::<f64>::deserialize(d)?;
    let n = v.len();
    v.try_into()
        .map_err(|_| serde::de::Error::custom(format!("expected {N} numbers, found {n}")))
}

/// [`exactly`], for a list that may be left out.
pub fn exactly_some<'de, D, const N: usize>(d: D) -> Result<Option<[f64; N]>, D::Error>
where
    D: serde::Deserializer<'de>,
{
    exactly(d).map(Some)
}

/// `[[input.device]]`
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DeviceConfig {
    /// Match the device's name exactly.
    #[serde(default)]
    pub match_name: Option<String>,
    /// Match the device's `vendor:product` (hex, as `lsusb` prints it).
    #[serde(default)]
    pub match_usb: Option<String>,
    /// libinput calibration matrix `[a, b, c, d, e, f]`.
    #[serde(default = "identity", deserialize_with = "exactly")]
    pub calibration: [f64; 6],
    /// Do not read this device at all.
    #[serde(default)]
    pub ignore: bool,
    /// The axes that carry the position, when not the usual ones:
    /// `{ x = "ABS_Z", y = "ABS_RX" }` (kernel names).
    #[serde(default)]
    pub axes: Option<AxesConfig>,
    /// What the device's contacts are, whatever it announces: `"finger"`
    /// makes a panel that says `BTN_TOOL_PEN` for fingers usable.
    #[serde(default)]
    pub tool: Option<ToolOverride>,
}

/// `axes = { x = "...", y = "..." }`
#[derive(Clone, Debug, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxesConfig {
    pub x: String,
    pub y: String,
}

/// `tool = "finger"`
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ToolOverride {
    Finger,
}

fn identity() -> [f64; 6] {
    Matrix::IDENTITY.0
}

impl DeviceConfig {
    /// Whether this entry applies to a device.
    #[must_use]
    pub fn matches(&self, d: &DeviceDescription) -> bool {
        let name_ok = self.match_name.as_ref().is_none_or(|n| *n == d.name);
        let usb_ok = self.match_usb.as_ref().is_none_or(|u| {
            parse_usb_id(u).is_some_and(|(v, p)| v == d.id.vendor && p == d.id.product)
        });
        name_ok && usb_ok
    }

    #[must_use]
    pub fn matrix(&self) -> Matrix {
        Matrix(self.calibration)
    }

    /// The axis codes `axes` names, `None` when unset or a name is unknown
    /// (the configuration's validation refuses those).
    #[must_use]
    pub fn axis_codes(&self) -> Option<(u16, u16)> {
        let a = self.axes.as_ref()?;
        Some((axis_code(&a.x)?, axis_code(&a.y)?))
    }

    /// What this entry changes of a device's reports.
    pub fn remap(&self, d: &DeviceDescription) -> Result<Option<Remap>, RemapError> {
        Remap::new(
            d,
            self.axis_codes(),
            self.tool == Some(ToolOverride::Finger),
        )
    }
}

/// `vendor:product` in hex, as `lsusb` prints it.
#[must_use]
pub fn parse_usb_id(s: &str) -> Option<(u16, u16)> {
    let (v, p) = s.split_once(':')?;
    Some((
        u16::from_str_radix(v, 16).ok()?,
        u16::from_str_radix(p, 16).ok()?,
    ))
}

impl InputConfig {
    /// The settings for a device: the first matching `[[input.device]]`.
    #[must_use]
    pub fn device_for(&self, d: &DeviceDescription) -> Option<&DeviceConfig> {
        self.device.iter().find(|c| c.matches(d))
    }

    /// What the configuration changes of a device's reports, if anything.
    pub fn remap_for(&self, d: &DeviceDescription) -> Result<Option<Remap>, RemapError> {
        self.device_for(d).map_or(Ok(None), |c| c.remap(d))
    }
}
