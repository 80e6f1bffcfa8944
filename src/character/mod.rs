//! The character: skeleton, motion data, body-part roles and the motion
//! library that the paper's learned models are built from.
//!
//! - [`skeleton`]: joints, poses, forward kinematics (the conventions).
//! - [`bvh`]: BVH files in and out.
//! - [`motion`]: a clip in metres, with units and T-pose frame resolved.
//! - [`roles`]: which joint is the head, a hand, a foot...
//! - [`library`]: a folder of clips and its `library.toml`.

pub mod action;
pub mod author;
pub mod bvh;
pub mod camera;
pub mod checks;
pub mod library;
pub mod motion;
pub mod posing;
pub mod roles;
pub mod sheet;
pub mod skeleton;
pub mod tracking;
