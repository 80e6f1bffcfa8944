//! The device edges: everything that opens a device node or talks to the
//! kernel or the service manager lives here, behind small interfaces the
//! rest of the crate can test without devices.
//!
//! - [`evdev`]: touch panels (`/dev/input/event*`) for the input hub.
//! - [`uinput`]: virtual panels that replay recordings (`play`).
//! - [`record`]: a panel's events into an evemu file (`record`).
//! - [`kms`]: DRM cards, connectors and modes.
//! - [`signals`]: SIGTERM/SIGINT as a stop flag.
//! - [`notify`]: systemd's `sd_notify` (READY, WATCHDOG, STOPPING).
//! - [`clock`]: the monotonic clock the kiosk steps by.
//!
//! Nothing in `input`, `character`, `control`, `physics` or `render`
//! imports this module.

#![allow(
    clippy::disallowed_methods,
    reason = "the application, the device edges and the tools measure and wait in real time"
)]

pub mod clock;
pub mod evdev;
pub mod kms;
pub mod notify;
pub mod record;
pub mod signals;
pub mod uinput;
