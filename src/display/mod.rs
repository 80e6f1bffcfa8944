//! Display outputs: which output and mode, and the presenters to try
//! ([`output`]), and the presenters that show frames on them: [`direct`]
//! (Vulkan drives the display) and the copy presenter in [`present`] (into
//! gbm's scanout buffers, [`gbm`], or dumb buffers), behind one interface
//! in [`screen`]. The headless presenter is `render::headless`.

pub mod config;
pub mod direct;
pub mod error;
pub mod gbm;
pub mod output;
pub mod present;
pub mod screen;
