//! Physics-based tracking (the paper's section 6): a rapier3d ragdoll
//! pushed towards the target posture, and the physical effects taken
//! from it.

pub(crate) mod body;
pub(crate) mod effects;
pub mod ragdoll;
