//! marionette: a kiosk program for touch tables. Visitors drag a 3-D
//! character's body parts with their fingers; it takes natural poses and
//! performs whole actions, following Oshita's example-based posture
//! synthesis.
//!
//! # How the pieces fit
//!
//! ```text
//! input ──────────> control ─────────────────────> render ────> display
//! evdev / evemu     posing | action | tracking     wgpu         KMS | headless
//! tracker,          (learned models from           (scene,
//! calibration        character data; physics)       overlays)
//! ```
//!
//! - [`screen`]: screen-space types every stage shares.
//! - [`input`] turns panels (live devices through the hub, or evemu
//!   recordings) into touch frames in picture pixels. Pure.
//! - [`character`] holds the data the method learns from: skeletons, BVH,
//!   body-part roles, motion libraries, the camera's projection. Pure.
//! - [`physics`] is the ragdoll of physics-based tracking. Pure.
//! - [`control`] turns touches into the character's motion and the view:
//!   the paper's posing, action and tracking control. Pure.
//! - [`render`] draws the character and the overlays with wgpu.
//! - `display` shows frames on DRM/KMS outputs; `platform` holds the
//!   device edges (evdev, uinput, DRM, signals, sd_notify, the clock).
//! - [`tools`]: evaluation, authoring, sheets and metrics, apart from what
//!   the kiosk runs.
//! - [`app`] is the application at the top: configuration, the kiosk, the
//!   commands.
//!
//! ARCHITECTURE.md in the repository says what each module may import.
//!
//! Conventions, stated once: time is in seconds (or microseconds) from the
//! events' own clock or an injected one (never `Instant::now()` in core
//! code, which clippy refuses); screen pixels have their origin top left
//! with y down; the world is Y-up, right-handed, in metres and radians.

pub mod app;
pub mod character;
pub mod control;
pub(crate) mod display;
pub mod input;
pub mod output;
pub mod physics;
pub(crate) mod platform;
pub mod reading;
pub mod render;
pub mod screen;
pub mod tools;
