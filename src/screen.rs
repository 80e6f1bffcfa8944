//! Screen space, shared by every stage: positions in the picture's pixels
//! ([`ScreenPoint`], origin top left, y down), positions normalised to
//! 0..1 ([`NormPoint`]), and how the picture is turned on the panel
//! ([`Rotation`]). Input produces these, the controller and the renderer
//! consume them; the module depends on nothing else in the crate.

use std::fmt;

use serde::{Deserialize, Serialize};

/// A position normalised to 0..1 over the panel (values outside 0..1 are
/// possible after a calibration matrix and are clamped to the screen).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct NormPoint {
    pub x: f64,
    pub y: f64,
}

/// A position in screen pixels (origin top left, y down).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ScreenPoint {
    pub x: f64,
    pub y: f64,
}

impl ScreenPoint {
    #[must_use]
    pub const fn new(x: f64, y: f64) -> Self {
        Self { x, y }
    }

    #[must_use]
    pub fn distance(self, o: ScreenPoint) -> f64 {
        (self.x - o.x).hypot(self.y - o.y)
    }
}

/// How the picture is turned on the panel, clockwise, for panels mounted
/// sideways or upside down.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Rotation {
    #[default]
    #[serde(rename = "0")]
    R0,
    #[serde(rename = "90")]
    R90,
    #[serde(rename = "180")]
    R180,
    #[serde(rename = "270")]
    R270,
}

impl Rotation {
    /// From degrees (0, 90, 180 or 270).
    #[must_use]
    pub fn from_degrees(d: i64) -> Option<Self> {
        match d {
            0 => Some(Self::R0),
            90 => Some(Self::R90),
            180 => Some(Self::R180),
            270 => Some(Self::R270),
            _ => None,
        }
    }

    #[must_use]
    pub fn degrees(self) -> u32 {
        match self {
            Self::R0 => 0,
            Self::R90 => 90,
            Self::R180 => 180,
            Self::R270 => 270,
        }
    }

    /// Panel-normalised → picture-normalised.
    #[must_use]
    pub fn apply(self, p: NormPoint) -> NormPoint {
        let (u, v) = (p.x, p.y);
        let (x, y) = match self {
            Self::R0 => (u, v),
            Self::R90 => (v, 1.0 - u),
            Self::R180 => (1.0 - u, 1.0 - v),
            Self::R270 => (1.0 - v, u),
        };
        NormPoint { x, y }
    }

    /// Picture-normalised → panel-normalised (inverse of [`Self::apply`]).
    #[must_use]
    pub fn invert(self, p: NormPoint) -> NormPoint {
        let (x, y) = (p.x, p.y);
        let (u, v) = match self {
            Self::R0 => (x, y),
            Self::R90 => (1.0 - y, x),
            Self::R180 => (1.0 - x, 1.0 - y),
            Self::R270 => (y, 1.0 - x),
        };
        NormPoint { x: u, y: v }
    }
}

impl fmt::Display for Rotation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}°", self.degrees())
    }
}

/// The picture on an output: the output's size in pixels and how the
/// picture is turned on it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Picture {
    /// The output's size in pixels (before rotation).
    pub output: (u32, u32),
    pub rotation: Rotation,
}

impl Picture {
    /// The picture's size in pixels: the output's, turned by the rotation.
    #[must_use]
    pub fn size(self) -> (u32, u32) {
        let (w, h) = self.output;
        match self.rotation {
            Rotation::R90 | Rotation::R270 => (h, w),
            Rotation::R0 | Rotation::R180 => (w, h),
        }
    }
}
