//! Measuring the controllers on held-out motion capture.
//!
//! - [`posing`]: postures reconstructed from constrained parts.
//! - [`actions`]: drags replayed as finger trails, recognised or not.
//! - [`live`]: the same drags through a whole controller.
//! - [`separation`]: how far apart the actions are, next to the drags' spread.
//! - [`character`]: a skinned figure playing a library's clips.
//! - [`walk`]: the pelvis dragged along floor paths, walked.
//! - [`walk_paths`]: those paths, read from a file or drawn by family.
//! - [`layer`]: a second finger's action laid over those walks.

pub mod actions;
pub mod character;
pub mod layer;
pub mod live;
pub mod posing;
pub mod separation;
pub mod walk;
pub mod walk_paths;
