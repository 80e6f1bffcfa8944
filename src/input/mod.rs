//! Input: from touch panels (or recordings of them) to "these fingers are at
//! these screen pixels".
//!
//! ```text
//! evdev device ─┐
//!               ├─> RawEvent ─> ContactTracker ─> TouchFrame ─> Calibration ─> ScreenTouch
//! evemu file ───┘   (event)     (tracker)         (raw units)   (calibration)  (pixels)
//! ```
//!
//! - [`event`]: kernel event numbers and [`event::RawEvent`].
//! - [`device`]: what a device is and how marionette classifies it.
//! - [`evemu`]: recordings, read and written.
//! - [`tracker`]: protocol A/B/single-touch state machine, SYN_DROPPED;
//!   [`touch`]: the touch frames it reports.
//! - [`calibration`]: typed coordinate spaces and the calibration solver.
//! - [`remap`]: per-device overrides (axes, pen bits as a finger), applied
//!   before the tracker.
//! - [`pipeline`]: recordings through the stack (inspect, replay, demo);
//!   `synth`: authoring recordings.
//! - `live`: real devices (evdev, hotplug, resync ioctls) behind an
//!   injected opener; `record`: devices to evemu files; `uinput`:
//!   virtual devices for `play`.
//!
//! Everything but `live`, `record` and `uinput` is pure and runs without
//! devices.

pub mod calibration;
pub(crate) mod config;
pub mod device;
pub mod evemu;
pub mod event;
pub mod hub;
pub mod pipeline;
pub mod remap;
pub mod touch;
pub mod tracker;
