//! marionette: a kiosk program for touch tables. Visitors drag a 3-D
//! character's body parts with their fingers; it takes natural poses and
//! performs whole actions, following Oshita's example-based posture
//! synthesis.
//!
//! # How the pieces fit
//!
//! ```text
//! input ─────────────> character ───────────> physics ──────> render ──────> display
//! evdev / evemu        posing | action        tracking        wgpu           KMS | headless
//! tracker, calibration  (learned models)      (PD + ragdoll)
//! ```
//!
//! - [`input`] turns panels (live evdev devices or evemu recordings) into
//!   touch frames in screen pixels. Pure except [`input::live`] and
//!   [`input::uinput`], which touch devices.
//! - [`character`] holds the motion data the method learns from: skeletons,
//!   BVH, body-part roles, motion libraries and the authoring of the default
//!   library. Pure.
//! - [`control`] turns touches into the character's motion and the view
//!   (posing, action and tracking control; the camera rig). Pure.
//! - [`display`] talks to DRM/KMS outputs.
//! - [`render`] draws the character and the overlays with wgpu, into
//!   offscreen images (headless) or onto the display.
//! - [`app`] is the application edge: configuration, exit codes, logging.
//!
//! Conventions, stated once: time is in microseconds from the events' own
//! clock (never `Instant::now()` in core code); screen pixels have their
//! origin top left with y down.

pub mod app;
pub mod character;
pub mod control;
pub(crate) mod display;
pub mod input;
pub mod physics;
pub(crate) mod platform;
pub mod render;
pub mod screen;
pub mod tools;
