//! What posture synthesis is asked for: constraints on body parts (a
//! half-line from the camera through a touch, or a 3-D point), the
//! synthesis options, and the constraints moved into a placement's frame.

use glam::{DQuat, DVec3};

use crate::character::body::Placement;
use crate::character::camera::HalfLine;
use crate::character::roles::Role;

/// Where a constrained body part should be.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Target {
    /// On the half-line from the camera through a touch.
    Ray(HalfLine),
    /// At a 3-D point (tests and other interfaces).
    Point(DVec3),
    /// Anywhere within `radius` of a point: a planted foot that the legs
    /// can still reach from where a sample puts it.
    Within { at: DVec3, radius: f64 },
}

impl Target {
    /// Distance of `p` to the target.
    #[must_use]
    pub fn distance(&self, p: DVec3) -> f64 {
        match self {
            Target::Ray(r) => r.distance(p),
            Target::Point(q) => (p - *q).length(),
            Target::Within { at, radius } => ((p - *at).length() - radius).max(0.0),
        }
    }

    /// The point of the target nearest to `p`.
    #[must_use]
    pub fn nearest(&self, p: DVec3) -> DVec3 {
        match self {
            Target::Ray(r) => r.closest(p),
            Target::Point(q) => *q,
            Target::Within { at, radius } => *at + (p - *at).clamp_length_max(*radius),
        }
    }

    /// The target shifted by `shift`, then turned by `turn` (about the
    /// origin), as a point would be.
    #[must_use]
    pub fn moved(&self, shift: DVec3, turn: DQuat) -> Self {
        match *self {
            Target::Point(q) => Target::Point(turn * (q + shift)),
            Target::Ray(r) => Target::Ray(HalfLine {
                origin: turn * (r.origin + shift),
                dir: turn * r.dir,
            }),
            Target::Within { at, radius } => Target::Within {
                at: turn * (at + shift),
                radius,
            },
        }
    }

    /// Whether this is a soft bound added by synthesis (a planted foot),
    /// not a finger's or a caller's constraint.
    #[must_use]
    pub fn is_bound(&self) -> bool {
        matches!(self, Target::Within { .. })
    }
}

/// A body part bound to a target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Constraint {
    pub role: Role,
    pub target: Target,
}

/// How to synthesise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SynthOptions {
    /// Find the region through the grid (the paper) or score every sample.
    pub use_grid: bool,
    /// Look into this many of the best cells.
    pub cells: usize,
    /// Search the cells of this many of the best blocks only (0: score
    /// every cell's representative).
    pub blocks: usize,
    /// Rank blocks by their representative's distance to each target less
    /// this share of the block's spread there (how far its samples lie from
    /// the representative, on average): a block of varied postures may hold
    /// samples much nearer than its representative.
    pub block_slack: f64,
    /// Blend at most this many samples.
    pub blend: usize,
    /// Apply CCD IK after blending.
    pub ik: bool,
    /// Furthest IK may move a constrained part (m).
    pub max_ik_m: f64,
    /// Refit the blend weights to meet the constraints, pulled towards the
    /// cost weights by this much (m², 0: no refit).
    pub fit: f64,
    /// Refit each constrained limb's own blend to reach its constraint,
    /// pulled towards the body's weights by this much (m², 0: the limbs
    /// keep the body's blend).
    pub limb_fit: f64,
    /// Samples a limb's blend may add to the body's: those whose limbs
    /// reach the constraint best.
    pub limb_extra: usize,
}

impl SynthOptions {
    /// For estimating an action's generalized time from the samples near
    /// the touches (section 5): a few nearest samples by their costs, no
    /// refit (a refit trades nearness for meeting the touches).
    pub const ACTION: Self = Self {
        use_grid: true,
        cells: 20,
        blocks: 8,
        block_slack: 0.0,
        blend: 12,
        ik: true,
        max_ik_m: 0.2,
        fit: 0.0,
        limb_fit: 0.0,
        limb_extra: 0,
    };
}

impl Default for SynthOptions {
    fn default() -> Self {
        Self {
            use_grid: true,
            cells: 16,
            blocks: 16,
            block_slack: 0.5,
            blend: 64,
            ik: true,
            max_ik_m: 0.2,
            fit: 0.03,
            limb_fit: 0.1,
            limb_extra: 16,
        }
    }
}

/// The constraints in a placement's frame (the frame of
/// [`Sample::local`]), each with its joint: scoring a sample then needs no
/// placing.
pub(crate) struct Local {
    pub(crate) role: Role,
    pub(crate) target: Target,
}

pub(crate) fn localize(constraints: &[Constraint], at: &Placement) -> Vec<Local> {
    let unturn = DQuat::from_rotation_y(-at.yaw);
    let floor = DVec3::new(at.position.x, 0.0, at.position.z);
    constraints
        .iter()
        .map(|c| Local {
            role: c.role,
            target: c.target.moved(-floor, unturn),
        })
        .collect()
}
