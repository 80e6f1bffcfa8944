//! The application edge: configuration, exit codes, logging.

pub mod cache;
pub mod calibrate;
pub mod cli;
pub mod config;
pub mod exit;
pub mod headless;
pub mod logging;
pub mod run;
