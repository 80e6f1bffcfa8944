//! Rendering with wgpu: the GPU and adapter choice ([`gpu`]), CPU geometry
//! (`mesh`, and bodies as solids of capsules in `solid`), composing a frame from the character and the overlays
//! ([`scene`]), the pipelines ([`renderer`], WGSL in `shaders/`) and
//! offscreen output read back as images ([`headless`]).

pub mod body;
pub(crate) mod contact;
pub(crate) mod damage;
pub(crate) mod figure;
pub mod gpu;
pub mod headless;
pub mod mesh;
pub mod renderer;
pub mod scene;
mod skinned;
pub mod solid;
