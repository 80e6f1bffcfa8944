//! Action control (the paper's section 5): recognising an action from a
//! drag and playing it under the finger.
//!
//! - [`timeline`]: the generalized time of a playing action, its condition
//!   segments, and the event stream (started, stopped, finished,
//!   cancelled).
//! - [`model`]: action models (learned model, average trajectory,
//!   direction, duration) and recognition among them.
//! - [`player`]: playing an action under the fingers.
//! - [`layer`]: an arm or head action laid over the upper body of a walk
//!   (or of an action led by the legs), region by region.
//! - [`trail`]: matching a finger's trail against an action's projected
//!   trajectory by dynamic programming (eq. 1), and the paper's start
//!   conditions.
//! - [`recogniser`]: the default recogniser: one template per clip, costs
//!   in metres at the character, an action started once it leads the
//!   others by a margin.
//! - [`calibrate`]: that recogniser's thresholds chosen per library by
//!   leave-one-clip-out on its own clips.
//! - [`trials`]: the drags a recogniser is judged by (held-out capture or
//!   the library's own clips left out in turn).

pub mod calibrate;
pub mod layer;
pub mod model;
pub mod player;
pub mod recogniser;
pub mod timeline;
pub mod trail;
pub mod trials;
