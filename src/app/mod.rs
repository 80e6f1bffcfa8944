//! The application, at the top of the crate: it composes the
//! configuration from the subsystems' sections, builds the character,
//! and runs the commands.
//!
//! - [`cli`]: the command line, one file per command group.
//! - [`config`]: the configuration file, composed and validated.
//! - `kiosk`: `marionette run`, the kiosk loop on KMS.
//! - [`headless`]: recordings replayed through the whole pipeline into
//!   images (the demo, `replay --headless`).
//! - `calibrate`: on-screen calibration of a touchscreen.
//! - `frame`: one frame's picture from the controller's state.
//! - `character`: the configured library loaded into a character;
//!   [`cache`]: the posing model's cache on disk.
//! - `exit`: exit codes, and every error's mapping to one.
//! - `logging`: tracing to stderr (the journal under systemd).

#![allow(
    clippy::disallowed_methods,
    reason = "the application, the device edges and the tools measure and wait in real time"
)]

pub mod cache;
pub(crate) mod calibrate;
pub(crate) mod character;
pub mod cli;
pub mod config;
pub(crate) mod exit;
pub(crate) mod fault;
pub mod frame;
pub mod headless;
pub(crate) mod kiosk;
pub(crate) mod logging;
pub(crate) mod message;
pub mod report;
pub mod visits;
