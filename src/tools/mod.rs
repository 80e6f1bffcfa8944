//! Tools around the product, apart from what the kiosk runs: evaluation
//! of the controllers on held-out motion capture, authoring of the
//! default library and of recordings, contact sheets, motion checks and
//! quality metrics. The kiosk's path (`app::run`) uses none of it.
//!
//! - [`eval`]: posing and action control measured on held-out clips.
//! - [`author`]: the default library's scores compiled into BVH;
//!   [`init`]: a library planned from a folder of an exhibit's takes;
//!   [`libcheck`]: what a drag can start in a library, told to its builder.
//! - [`synth`]: recordings authored from gestures; [`demo`]: the demo
//!   recording, authored against the character; [`abuse`]: random
//!   multi-finger abuse of the table.
//! - `sheet`, [`checks`], `metrics`: stick-figure sheets, foot sliding
//!   and joint limits of clips, and motion quality of a replay.

#![allow(
    clippy::disallowed_methods,
    reason = "the application, the device edges and the tools measure and wait in real time"
)]

pub mod abuse;
pub mod author;
pub mod checks;
pub mod demo;
pub mod eval;
pub mod init;
pub mod libcheck;
pub(crate) mod metrics;
pub(crate) mod sheet;
pub mod synth;
