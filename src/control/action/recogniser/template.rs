//! A clip's template seen from the drag's view: projected, its still
//! lead-in left out, cut to what a drag shows before the action should
//! start, in metres at the character; and the tempo band.

use glam::DVec2;

use super::TemplateRule;
use crate::character::body::Placement;
use crate::character::camera::Camera;
use crate::control::action::model::ClipPath;

/// A template seen from the drag's view.
#[derive(Clone, Debug)]
pub(super) struct Seen {
    pub(super) action: usize,
    pub(super) clip: usize,
    /// Relative to the trimmed start, on the screen, in metres.
    pub(super) at: Vec<DVec2>,
    /// Seconds from the trimmed start.
    pub(super) t: Vec<f64>,
    /// Share of the path's length up to each point.
    pub(super) along: Vec<f64>,
    /// Its length up to each point (m at the character, on the screen).
    pub(super) arc_m: Vec<f64>,
    /// Generalized time of each point in its clip.
    pub(super) generalized: Vec<f64>,
    /// The last row of the dynamic programme: least summed cost to each
    /// point, and its number of pairs.
    pub(super) row: Vec<(f64, u32)>,
}

impl Seen {
    /// The time the template's path takes to reach length `arc` (m), past
    /// its end at its mean speed.
    pub(super) fn time_to_cover(&self, arc: f64) -> f64 {
        let total = self.arc_m.last().copied().unwrap_or(0.0);
        let end = self.t.last().copied().unwrap_or(0.0);
        if arc >= total {
            return if total > 0.0 { end * arc / total } else { end };
        }
        let k = self.arc_m.partition_point(|a| *a < arc);
        if k == 0 {
            return 0.0;
        }
        let (a0, a1) = (self.arc_m[k - 1], self.arc_m[k]);
        let f = if a1 > a0 { (arc - a0) / (a1 - a0) } else { 0.0 };
        self.t[k - 1] + f * (self.t[k] - self.t[k - 1])
    }
}

/// A clip's path seen from `camera`: one template from the end of its
/// still lead-in, and one more from each place it rests on the way (as a
/// drag that rests begins anew, so does its template: a bow whose head
/// pauses before it goes down is matched from the pause too). None where
/// the path cannot be drawn from this view.
#[allow(clippy::too_many_arguments)]
pub(super) fn see(
    tpl: &ClipPath,
    action: usize,
    clip: usize,
    camera: &Camera,
    at: &Placement,
    scale: f64,
    still_px: f64,
    rule: &TemplateRule,
) -> Vec<Seen> {
    let Some(screen) = tpl
        .points
        .iter()
        .map(|p| camera.project(at.place(*p)).map(|s| DVec2::new(s.x, s.y)))
        .collect::<Option<Vec<_>>>()
    else {
        return Vec::new();
    };
    let from = |start: usize| seen_from(tpl, &screen, start, action, clip, scale, still_px, rule);
    let mut out: Vec<Seen> = from(tpl.lead_in).into_iter().collect();
    // Where the part pauses within what a drag shows (resting by the rule a
    // drag rests by, for at least `min_pause_s` more): the last resting
    // point of each stretch begins a template, where the part had only
    // drifted before it (less than `max_drift_m`): the slow start a still
    // lead-in leaves in. (A pause after a movement of its own, the crouch
    // before a jump, would only add look-alikes: a squat rises too.)
    let window = (rule.rest_window_s / tpl.dt).round().max(1.0) as usize;
    let end = (tpl.lead_in + (rule.horizon_s / tpl.dt).ceil() as usize + 1).min(screen.len());
    let resting = |k: usize| {
        k >= window && {
            let old = screen[k - window];
            let radius = rule.rest_speed * window as f64 * tpl.dt * scale;
            screen[k - window..=k]
                .iter()
                .all(|q| q.distance(old) < radius)
        }
    };
    let mut k = tpl.lead_in + 1;
    while k < end {
        if resting(k) {
            let first = k;
            while k + 1 < end && resting(k + 1) {
                k += 1;
            }
            let drift: f64 = screen[tpl.lead_in..=first]
                .windows(2)
                .map(|w| w[0].distance(w[1]))
                .sum::<f64>()
                / scale;
            if (k - first) as f64 * tpl.dt >= rule.min_pause_s && drift < rule.max_drift_m {
                out.extend(from(k));
            }
        }
        k += 1;
    }
    out
}

/// The template of `tpl` from point `start` (its still lead-in from there
/// trimmed), if it can be drawn from this view.
#[allow(clippy::too_many_arguments)]
fn seen_from(
    tpl: &ClipPath,
    screen: &[DVec2],
    start: usize,
    action: usize,
    clip: usize,
    scale: f64,
    still_px: f64,
    rule: &TemplateRule,
) -> Option<Seen> {
    // The clip's still lead-in is left out (where the part starts its
    // movement), and so is what little it moves before that from here.
    let first = *screen.get(start)?;
    let moved = start
        + screen[start..]
            .iter()
            .position(|s| s.distance(first) > still_px)?;
    let start = moved.saturating_sub(1).max(start);
    // What a drag can show before the action should have started: the
    // first `horizon_s` of movement (a whole punch; two steps of a walk).
    let end = (start + (rule.horizon_s / tpl.dt).ceil() as usize + 1).min(screen.len());
    let screen = &screen[start..end];
    let space = &tpl.points[start..end];
    let px: f64 = screen.windows(2).map(|w| w[0].distance(w[1])).sum();
    let metres: f64 = space.windows(2).map(|w| w[0].distance(w[1])).sum();
    if px < rule.min_path_px
        || px / scale < rule.min_path_m
        || px / scale < rule.min_foreshortening * metres
    {
        return None;
    }
    let mut along = Vec::with_capacity(screen.len());
    let mut run = 0.0;
    for (k, s) in screen.iter().enumerate() {
        if k > 0 {
            run += s.distance(screen[k - 1]);
        }
        along.push(run / px);
    }
    let n = tpl.points.len().max(2) - 1;
    Some(Seen {
        action,
        clip,
        at: screen.iter().map(|s| (*s - screen[0]) / scale).collect(),
        t: (0..screen.len()).map(|k| k as f64 * tpl.dt).collect(),
        arc_m: along.iter().map(|a| a * px / scale).collect(),
        along,
        generalized: (0..screen.len())
            .map(|k| (start + k) as f64 / n as f64)
            .collect(),
        row: Vec::new(),
    })
}
