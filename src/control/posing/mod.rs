//! Posing control (the paper's section 4): a learned model of sample
//! postures in a 2-D latent space, and posture synthesis from touches.
//!
//! - [`sample`]: sample postures, the posture distance, placement.
//! - `mds`: landmark MDS to 2-D.
//! - [`model`]: the learned model and its grid.
//! - `limbs`: the limbs a blend can refit on their own.
//! - `reach`: the limbs' reaches in boxes, for the refit's search.
//! - [`synth`]: synthesis from half-line or point constraints, CCD IK.
//! - [`pick`]: the body part under a screen point.

pub mod constraint;
pub mod fit;
pub mod ik;
pub(crate) mod limbs;
pub(crate) mod mds;
pub mod model;
pub mod pick;
pub(crate) mod rank;
pub(crate) mod reach;
pub mod sample;
pub mod synth;
