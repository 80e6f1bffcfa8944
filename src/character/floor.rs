//! Where the floor is under a library's feet. Capture floors are not
//! always at zero under the skeleton's feet: a studio's rig may end its
//! toes 10 cm above the floor it recorded on and place the floor
//! elsewhere. The character would then stand (and be judged planted) on
//! air. A library whose feet stand off the floor is moved onto it.

use std::collections::BTreeMap;

use super::motion::Clip;
use super::roles::Role;
use super::skeleton::{forward_kinematics, sole};

/// A library whose standing sole lies within this band (m) is left where
/// it is: feet on the floor, the sole point (a toe's or the ankle's End
/// Site) a little above it (the default library's stands at 2.0 cm, CMU's
/// takes within it too).
pub const STANDING_BAND_M: (f64, f64) = (-0.005, 0.025);

/// Where a library out of the band is moved to: its standing sole this far
/// above the floor (m), the toes' bone line over the sole of a shoe.
pub const STANDING_SOLE_M: f64 = 0.01;

/// The height (m) at which the library's feet stand: over every frame of
/// every clip, the lower foot's lowest point (ankle, toes, End Sites),
/// the median of those. `None` for no frames.
#[must_use]
pub fn standing_sole(clips: &BTreeMap<String, Clip>) -> Option<f64> {
    let mut lows = Vec::new();
    for clip in clips.values() {
        let feet = [Role::LeftFoot, Role::RightFoot].map(|r| clip.roles.get(r));
        for pose in &clip.frames {
            let w = forward_kinematics(&clip.skeleton, pose);
            let low = feet
                .iter()
                .map(|&f| sole(&clip.skeleton, &w, f).y)
                .fold(f64::INFINITY, f64::min);
            if low.is_finite() {
                lows.push(low);
            }
        }
    }
    if lows.is_empty() {
        return None;
    }
    let mid = lows.len() / 2;
    let (_, m, _) = lows.select_nth_unstable_by(mid, f64::total_cmp);
    Some(*m)
}

/// Moves every clip up or down so that the library stands on the floor,
/// when its standing sole is outside [`STANDING_BAND_M`], and says so;
/// returns the shift made (m, 0 when none).
pub fn settle(clips: &mut BTreeMap<String, Clip>) -> f64 {
    let Some(h) = standing_sole(clips) else {
        return 0.0;
    };
    let (lo, hi) = STANDING_BAND_M;
    if (lo..=hi).contains(&h) {
        return 0.0;
    }
    let dy = STANDING_SOLE_M - h;
    for clip in clips.values_mut() {
        shift(clip, dy);
    }
    tracing::info!(
        standing_sole_m = h,
        moved_m = dy,
        "the takes' feet stand {:.1} cm {} their floor: the clips are moved onto it",
        h.abs() * 100.0,
        if h > 0.0 { "above" } else { "below" }
    );
    dy
}

/// Moves a clip up by `dy` metres (down if negative).
pub fn shift(clip: &mut Clip, dy: f64) {
    for pose in &mut clip.frames {
        pose.translations[0].y += dy;
    }
}
