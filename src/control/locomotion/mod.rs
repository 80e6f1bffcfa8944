//! Walking where a finger leads (the paper's future work: a walk steered
//! along a path rather than played as a cycle): the library's locomotion
//! clips made ready for matching (`gait`) and a walk along a finger's path
//! with them (`walker`). Foot contacts are the controller's: a foot of the
//! walking posture that comes down stays where it landed.

pub mod gait;
pub mod walker;
