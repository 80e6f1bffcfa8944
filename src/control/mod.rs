//! Control: turning touches into the character's motion and the view.
//! [`controller`] routes fingers to body parts or the camera and runs the
//! paper's posing, action and tracking control; [`rig`] is the camera.

pub mod controller;
pub mod demo;
pub mod metrics;
pub mod rig;
pub mod ticker;
