//! What the controller asks to be drawn over the picture: a mark under
//! every finger, the trajectories of the actions a held part can start (the
//! paper's Fig. 4), a status line and the service view. The renderer draws
//! them.

use crate::character::roles::Role;
use crate::screen::ScreenPoint;

/// What a finger is doing, for its mark.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FingerUse {
    /// Holds a body part.
    Part(Role),
    /// Turns, tilts or zooms the camera.
    Camera,
}

/// A mark under a finger.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FingerMark {
    pub at: ScreenPoint,
    pub usage: FingerUse,
    /// The tint of the character the finger holds (several characters).
    pub tint: Option<[f32; 3]>,
}

/// An action's trajectory as seen from the camera (the paper's Fig. 4).
#[derive(Clone, Debug, PartialEq)]
pub struct TrajectoryMark {
    pub points: Vec<ScreenPoint>,
    /// Whether a drag along it can start the action from this view.
    pub executable: bool,
    /// The tint of the character whose action it is (several characters).
    pub tint: Option<[f32; 3]>,
}

/// The service view: lines of text in a panel, and every finger's recent
/// path (its calibrated points, oldest first).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ServiceMarks {
    pub lines: Vec<String>,
    pub trails: Vec<Vec<ScreenPoint>>,
}

/// Everything drawn over the picture.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Marks {
    pub fingers: Vec<FingerMark>,
    pub trajectories: Vec<TrajectoryMark>,
    pub status: Option<String>,
    pub service: Option<ServiceMarks>,
}
