//! Authoring the default motion library: editable scores (keyframes per
//! body part with timing and easing) compiled to BVH on marionette's own
//! rig. See [`score`] for the format.

pub mod compile;
pub mod rig;
pub mod score;

pub use compile::{author_library, compile};
