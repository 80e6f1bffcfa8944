//! Control: turning touches into the character's motion and the view,
//! after the paper's sections 4 to 6.
//!
//! - [`posing`]: the posing model and posture synthesis from touches.
//! - [`action`]: action models, recognising a drag, playing the action.
//! - `tracking`: acceleration-based tracking (eq. 2-4).
//! - [`controller`]: routes fingers to body parts or the camera and runs
//!   posing, action and tracking control with the ragdoll's effects.
//! - [`locomotion`]: walking along a finger's path with the library's
//!   locomotion clips.
//! - [`stage`]: the table: one character or several, the shared camera,
//!   which finger belongs to whom, and bodies meeting.
//! - [`marks`]: what is drawn over the picture for the fingers.
//! - `rig`: the camera; `ticker`: stepping a controller through
//!   touch frames at a fixed rate; `config`: its configuration sections.

pub mod action;
pub mod character;
pub(crate) mod config;
pub mod controller;
pub mod locomotion;
pub mod marks;
pub mod posing;
pub(crate) mod rig;
pub mod stage;
pub(crate) mod ticker;
pub(crate) mod tracking;
