//! The character as data: skeleton, motion clips, body-part roles, the
//! motion library the paper's learned models are built from, and the
//! camera that shows it. Pure: no control, no devices, no caches.
//!
//! - [`skeleton`]: joints, poses, forward kinematics (the conventions).
//! - [`body`]: where the character stands, its facing, its legs' lengths.
//! - [`bvh`]: BVH files in and out.
//! - [`motion`]: a clip in metres, with units and T-pose frame resolved.
//! - [`roles`]: which joint is the head, a hand, a foot...
//! - [`library`]: a folder of clips and its `library.toml`; [`clip_ref`]:
//!   the clip names in it, kept inside the clips folder.
//! - [`camera`]: projection to screen pixels and rays back from them.

pub mod body;
pub mod bvh;
pub mod camera;
pub mod clip_ref;
pub mod digest;
pub mod floor;
pub mod gltf;
pub mod library;
pub mod mirror;
pub mod motion;
pub mod roles;
pub mod skeleton;
