//! Display outputs: DRM/KMS connectors and modes ([`kms`]) and the two
//! presenters that show frames on them, [`direct`] (Vulkan drives the
//! display) and the copy presenter in [`present`], behind one interface in
//! [`screen`]. The headless presenter is `render::headless`.

pub mod config;
pub mod direct;
pub mod present;
pub mod screen;
