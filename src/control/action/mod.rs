//! Action control (the paper's section 5): recognising an action from a
//! drag and playing it under the finger.
//!
//! - [`timeline`]: the generalized time of a playing action, its condition
//!   segments, and the event stream (started, stopped, finished,
//!   cancelled).
//! - [`model`]: action models (learned model, average trajectory,
//!   direction, duration) and recognition among them.
//! - [`player`]: playing an action under the fingers.
//! - [`trail`]: matching a finger's trail against an action's projected
//!   trajectory by dynamic programming (eq. 1), and the start conditions.

pub mod model;
pub mod player;
pub mod timeline;
pub mod trail;
