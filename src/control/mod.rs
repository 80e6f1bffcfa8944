//! Control: turning touches into the character's motion and the view.
//! [`controller`] routes fingers to body parts or the camera and runs the
//! paper's posing, action and tracking control; [`rig`] is the camera;
//! [`live_eval`] judges drags through the controller.

pub mod config;
pub mod controller;
pub mod demo;
pub mod live_eval;
pub mod metrics;
pub mod rig;
pub mod ticker;
