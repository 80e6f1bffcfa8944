//! Tracking control (the paper's section 6): the post-process that makes
//! motion continuous and physically plausible.
//!
//! - [`accel`]: acceleration-based tracking (eq. 2–4).

pub mod accel;
