//! Display outputs: which output and mode, and the presenters to try
//! ([`output`]), and the presenters that show frames on them: [`direct`]
//! (Vulkan drives the display) and the page-flipping presenter in
//! [`present`] over two scanout buffers ([`flips`]): gbm's ([`gbm`]),
//! rendered into without a copy where the Vulkan driver imports them
//! ([`zero_copy`], in a layout from [`modifiers`]) or written into, or
//! dumb buffers; behind one interface in [`screen`]. The headless
//! presenter is `render::headless`.

pub mod config;
pub mod direct;
pub mod error;
pub mod flips;
pub mod gbm;
pub mod modifiers;
pub mod output;
pub mod present;
pub mod screen;
pub mod zero_copy;
