//! The template recogniser: a drag is compared with every clip of every
//! action its part can start (one template per clip, not the average
//! trajectory, which blurs clips of different timing into a path nobody
//! draws), and an action starts as soon as it leads every other action by
//! a margin.
//!
//! What it keeps of the paper's eq. 1, and what it adds:
//! - Each template is the clip's own path of the primary part, projected
//!   with the current camera; its still lead-in (the part standing within
//!   [`TemplateRule::still_m`] of where it began) is trimmed, and so is the
//!   drag's, so a kick that stands still for half its clip is matched from
//!   where the foot starts to move.
//! - Costs are in metres at the character: screen distances over the
//!   pixels a metre spans at the part's depth, so one threshold serves
//!   every view and distance.
//! - Corresponding points by dynamic programming, as eq. 1, with time
//!   counted only outside a tempo band ([`TemplateRule::tempo`]); a drag
//!   more than [`Thresholds::max_slow`] times slower than the template's
//!   part it covers is no match at all (this is what refuses slow posing
//!   drags).
//! - A template whose part drifts and pauses before its movement (a bow's
//!   head before it goes down) is matched from the pause too, as a drag
//!   that rests begins anew.
//! - Coverage is measured along the template's path (a share of its
//!   length), and must reach the calibrated floor.
//! - The paper's 45° view rule becomes what it stands for: a template whose
//!   projected path is too short, or too foreshortened, to be drawn from
//!   this view is left out.
//!
//! The matching is incremental: [`DragMatch::push`] costs one row of the
//! dynamic programme per template, so recognition per drag point does not
//! grow with the drag's length.

use glam::{DVec2, DVec3};

mod explain;
mod template;

pub use self::explain::{Explained, Held, Leading};

use self::template::{Seen, see};
use super::model::ActionModel;
use super::trail::TrailPoint;
use super::trail::tempo_gap;
use crate::character::body::Placement;
use crate::character::camera::Camera;
use crate::character::roles::Role;

/// The fixed parts of the template rule (the thresholds that depend on the
/// library are in [`Thresholds`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TemplateRule {
    /// Time's weight against position (m per second outside the band).
    pub h: f64,
    /// A drag may be up to this many times faster or slower than a template
    /// at no cost.
    pub tempo: f64,
    /// The drag must be at least this share of the length of the
    /// template's part it is matched with.
    pub min_drawn: f64,
    /// The still lead-in: a part within this distance of where it began
    /// has not started moving (m at the character; at least `still_px`).
    pub still_m: f64,
    pub still_px: f64,
    /// A drag that moves less than `rest_speed` (m/s at the character)
    /// over `rest_window_s` is resting: what it draws next is matched from
    /// there, as a clip is matched from the end of its still lead-in.
    pub rest_speed: f64,
    pub rest_window_s: f64,
    /// A template that rests this much longer than `rest_window_s` on its
    /// way is matched from there too (s).
    pub min_pause_s: f64,
    /// ...if the part drifted less than this before the pause (m).
    pub max_drift_m: f64,
    /// Templates keep this much of their clip once the part moves (s):
    /// what a drag shows before the action should have started.
    pub horizon_s: f64,
    /// A template whose projected path is shorter than this is not drawn
    /// from this view (px)...
    pub min_path_px: f64,
    /// ...nor one shorter than this at the character (m): a drag that
    /// small is posing.
    pub min_path_m: f64,
    /// A clip whose part never moves faster than this (m/s) cannot be told
    /// from posing: it is no template.
    pub min_peak_speed: f64,
    /// ...nor one whose peak speed is under this share of the median of
    /// its action's clips.
    pub min_peak_share: f64,
    /// ...or whose projected length is under this share of its length in
    /// space (seen end-on).
    pub min_foreshortening: f64,
}

impl Default for TemplateRule {
    fn default() -> Self {
        Self {
            h: 0.5,
            tempo: 1.6,
            min_drawn: 0.5,
            horizon_s: 1.5,
            rest_speed: 0.15,
            rest_window_s: 0.2,
            min_pause_s: 0.15,
            max_drift_m: 0.15,
            still_m: 0.025,
            still_px: 8.0,
            min_path_px: 40.0,
            min_path_m: 0.35,
            min_peak_speed: 0.6,
            min_peak_share: 0.45,
            min_foreshortening: 0.3,
        }
    }
}

/// The thresholds of one library, chosen by [`super::calibrate`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Thresholds {
    /// The leading action's cost must be under this (m).
    pub cost_m: f64,
    /// ...and every other action's at least this much more (m).
    pub margin_m: f64,
    /// ...and its path covered at least this far (share of its length).
    pub coverage: f64,
    /// A drag more than this many times slower than the part of the
    /// template it covers matches nothing.
    pub max_slow: f64,
}

impl Default for Thresholds {
    fn default() -> Self {
        Self {
            cost_m: 0.08,
            margin_m: 0.02,
            coverage: 0.35,
            max_slow: 1.8,
        }
    }
}

/// The recogniser of a library: the fixed rule and the thresholds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Recogniser {
    pub rule: TemplateRule,
    pub thresholds: Thresholds,
}

/// A decision and why it was taken (logged at debug level).
#[derive(Clone, Debug, PartialEq)]
pub struct Decision {
    /// Index into the action models.
    pub action: usize,
    /// The template that matched best (its clip).
    pub clip: String,
    pub cost_m: f64,
    /// How much more the next action costs (m; infinite when no other
    /// action of this part matches).
    pub margin_m: f64,
    /// Share of the template's path the drag covers.
    pub coverage: f64,
    /// The template's time over the drag's (above 1: the drag is quicker).
    pub tempo: f64,
    /// Generalized time of the action where the drag is.
    pub generalized: f64,
}

/// What the drag's latest point says of one template.
#[derive(Clone, Copy, Debug, PartialEq)]
struct TemplateCost {
    pub action: usize,
    pub clip: usize,
    /// Least mean cost over the template's points the drag may have reached
    /// (m), and the same among points covering at least each of
    /// [`COVERAGE_FLOORS`].
    any: [f64; CAPS],
    covered: [f64; GATES],
    /// The template's point where each covered match ends.
    covered_j: [usize; GATES],
}

/// How many coverage floors a drag is judged for at once (calibration
/// tries them all in one pass).
pub const FLOORS: usize = 4;

/// The coverage floors calibration chooses among.
pub const COVERAGE_FLOORS: [f64; FLOORS] = [0.25, 0.35, 0.45, 0.55];

/// How many caps on slowness a drag is judged for at once.
pub const CAPS: usize = 3;

/// The caps on slowness calibration chooses among.
pub const SLOW_CAPS: [f64; CAPS] = [1.5, 1.8, 2.2];

/// A coverage floor and a cap together: `floor * CAPS + cap`.
pub const GATES: usize = FLOORS * CAPS;

/// One drag being matched: the templates its part can start, seen from the
/// drag's camera, and the drag so far.
#[derive(Clone, Debug)]
pub struct DragMatch {
    rule: TemplateRule,
    seen: Vec<Seen>,
    /// Pixels a metre spans at the part's depth.
    px_per_m: f64,
    /// A drag within this of where it began has not started moving (px).
    still_px: f64,
    /// The first point, and the last one still within the lead-in radius.
    anchor: Option<TrailPoint>,
    last_still: Option<TrailPoint>,
    /// Where the drag began moving (its trimmed start), once it has.
    origin: Option<TrailPoint>,
    /// The drag's length since its trimmed start (m at the character),
    /// jitter left out, and the point it was last measured from.
    drawn: f64,
    drawn_from: Option<TrailPoint>,
    /// The latest point's costs, one per template (in `seen` order).
    costs: Vec<TemplateCost>,
    /// The latest point's time from the trimmed start (s).
    u: f64,
    /// The drag's points over the last `rest_window_s` (and one before).
    recent: std::collections::VecDeque<TrailPoint>,
    /// The leading template that came closest to starting its action
    /// (least cost) while none started: what a drag that started nothing
    /// was nearest to.
    closest: Option<Decision>,
}

/// Pixels a metre spans at `p` seen by `camera`.
fn px_per_m(camera: &Camera, p: DVec3) -> f64 {
    let depth = (p - camera.eye).dot(camera.eye_vector()).max(0.05);
    let focal = camera.height / 2.0 / (camera.fov_y_deg.to_radians() / 2.0).tan();
    focal / depth
}

impl DragMatch {
    /// Start matching a drag of `role` on `camera`'s screen, the character
    /// standing at `at`. `exclude` leaves one template out (an action and
    /// its clip index: leave-one-out calibration).
    #[must_use]
    pub fn new(
        recogniser: &Recogniser,
        actions: &[ActionModel],
        role: Role,
        camera: &Camera,
        at: &Placement,
        exclude: Option<(usize, usize)>,
    ) -> Self {
        let rule = recogniser.rule;
        let starts: Vec<DVec3> = actions
            .iter()
            .filter(|a| a.def.primary == role)
            .flat_map(|a| a.templates.iter().filter_map(|t| t.points.first()))
            .map(|p| at.place(*p))
            .collect();
        let scale = if starts.is_empty() {
            1.0
        } else {
            starts.iter().map(|p| px_per_m(camera, *p)).sum::<f64>() / starts.len() as f64
        };
        let still_px = (rule.still_m * scale).max(rule.still_px);
        let mut seen = Vec::new();
        for (ai, a) in actions.iter().enumerate() {
            if a.def.primary != role {
                continue;
            }
            // A take far gentler than the action's others is a style a
            // posing drag looks like: no template.
            let mut peaks: Vec<f64> = a.templates.iter().map(|t| t.peak_speed).collect();
            peaks.sort_by(f64::total_cmp);
            let floor = rule
                .min_peak_speed
                .max(rule.min_peak_share * peaks.get(peaks.len() / 2).copied().unwrap_or(0.0));
            for (ci, tpl) in a.templates.iter().enumerate() {
                if exclude == Some((ai, ci)) || tpl.peak_speed < floor {
                    continue;
                }
                seen.extend(see(tpl, ai, ci, camera, at, scale, still_px, &rule));
            }
        }
        Self {
            rule,
            seen,
            px_per_m: scale,
            still_px,
            anchor: None,
            last_still: None,
            origin: None,
            drawn: 0.0,
            drawn_from: None,
            costs: Vec::new(),
            u: 0.0,
            recent: std::collections::VecDeque::new(),
            closest: None,
        }
    }

    /// How many templates of action `action` can be drawn from this view.
    #[must_use]
    pub fn drawable(&self, action: usize) -> usize {
        let clips: std::collections::BTreeSet<usize> = self
            .seen
            .iter()
            .filter(|s| s.action == action)
            .map(|s| s.clip)
            .collect();
        clips.len()
    }

    /// Add the drag's next point (times in seconds, increasing).
    pub fn push(&mut self, p: TrailPoint) {
        self.recent.push_back(p);
        while self
            .recent
            .get(1)
            .is_some_and(|q| q.t <= p.t - self.rule.rest_window_s)
        {
            self.recent.pop_front();
        }
        // Resting: every point of the window within what `rest_speed`
        // covers in it of the first (a wave's turn goes out and back, and
        // is no rest).
        let resting = self.recent.front().is_some_and(|old| {
            let span = p.t - old.t;
            let radius = self.rule.rest_speed * span * self.px_per_m;
            span >= self.rule.rest_window_s
                && self.recent.iter().all(|q| q.at.distance(old.at) < radius)
        });
        if resting {
            // Resting: the drag begins anew from here.
            self.anchor = Some(p);
            self.last_still = Some(p);
            self.origin = None;
            self.drawn = 0.0;
            self.drawn_from = None;
            self.costs.clear();
            for s in &mut self.seen {
                s.row.clear();
            }
            return;
        }
        let Some(origin) = self.origin else {
            let Some(anchor) = self.anchor else {
                self.anchor = Some(p);
                self.last_still = Some(p);
                return;
            };
            if p.at.distance(anchor.at) <= self.still_px {
                self.last_still = Some(p);
                return;
            }
            // The drag leaves its lead-in: it begins at the last still point.
            let o = self.last_still.unwrap_or(anchor);
            self.origin = Some(o);
            self.row(o, o);
            self.row(o, p);
            return;
        };
        self.row(origin, p);
    }

    /// One row of the dynamic programme for each template.
    fn row(&mut self, origin: TrailPoint, p: TrailPoint) {
        let q = DVec2::new(p.at.x - origin.at.x, p.at.y - origin.at.y) / self.px_per_m;
        let u = p.t - origin.t;
        self.u = u;
        match self.drawn_from {
            None => self.drawn_from = Some(origin),
            Some(from) => {
                let d = from.at.distance(p.at);
                if d >= super::trail::JITTER_PX {
                    self.drawn += d / self.px_per_m;
                    self.drawn_from = Some(p);
                }
            }
        }
        let drawn = self.drawn;
        let first = self.seen.first().is_some_and(|s| s.row.is_empty());
        let rule = self.rule;
        self.costs.clear();
        for s in &mut self.seen {
            s.advance(q, u, &rule, first);
            self.costs.push(s.cost(drawn, u, &rule));
        }
    }

    /// The leading action for gate `gate` (a coverage floor and a cap on
    /// slowness, see [`GATES`]): the template costing least among those the
    /// drag covers that far, its cost (m), and the least cost of any other
    /// action's templates (m; infinite when none).
    #[must_use]
    pub fn lead(&self, gate: usize) -> Option<(usize, f64, f64)> {
        let i = self.leader(gate)?;
        let lead = &self.costs[i];
        let next = self
            .costs
            .iter()
            .filter(|c| c.action != lead.action)
            .map(|c| c.any[gate % CAPS])
            .fold(f64::INFINITY, f64::min);
        Some((lead.action, lead.covered[gate], next))
    }

    /// The action other than `action` whose templates cost least now (for
    /// the slowness cap of `gate`): the one a drag of `action` is told
    /// from by the margin.
    #[must_use]
    pub fn nearest_other(&self, action: usize, gate: usize) -> Option<usize> {
        self.cheapest(gate, |a| a != action)
    }

    /// The action whose templates cost least now, at any coverage (for
    /// the slowness cap of `gate`), among those `keep` keeps.
    #[must_use]
    pub fn cheapest(&self, gate: usize, keep: impl Fn(usize) -> bool) -> Option<usize> {
        self.cheapest_template(gate, keep).map(|c| c.action)
    }

    /// The template costing least now, at any coverage (for the slowness
    /// cap of `gate`), among those of the actions `keep` keeps.
    fn cheapest_template(
        &self,
        gate: usize,
        keep: impl Fn(usize) -> bool,
    ) -> Option<&TemplateCost> {
        self.costs
            .iter()
            .filter(|c| keep(c.action) && c.any[gate % CAPS].is_finite())
            .min_by(|a, b| a.any[gate % CAPS].total_cmp(&b.any[gate % CAPS]))
    }

    fn leader(&self, gate: usize) -> Option<usize> {
        self.costs
            .iter()
            .enumerate()
            .filter(|(_, c)| c.covered[gate].is_finite())
            .min_by(|a, b| a.1.covered[gate].total_cmp(&b.1.covered[gate]))
            .map(|(i, _)| i)
    }

    /// Whether the drag so far starts an action: the action whose best
    /// template covering at least the coverage floor costs least, if that
    /// is under its threshold (the action's own `threshold_m`, else the
    /// library's) and every other action of this part costs the margin
    /// more.
    pub fn decide(&mut self, actions: &[ActionModel], thresholds: &Thresholds) -> Option<Decision> {
        let floor = gate_of(thresholds);
        let (action, cost, next) = self.lead(floor)?;
        let limit = actions[action].def.threshold_m.unwrap_or(thresholds.cost_m);
        let margin = next - cost;
        let starts = cost <= limit && margin >= thresholds.margin_m;
        // A refusal that comes no closer than one before needs no record.
        if !starts && self.closest.as_ref().is_some_and(|b| b.cost_m <= cost) {
            return None;
        }
        let i = self.leader(floor)?;
        let (s, c) = (&self.seen[i], &self.costs[i]);
        let j = c.covered_j[floor];
        let d = Decision {
            action,
            clip: actions[action].templates[c.clip].clip.clone(),
            cost_m: cost,
            margin_m: margin,
            coverage: s.along[j],
            tempo: if self.u > 0.0 { s.t[j] / self.u } else { 1.0 },
            generalized: s.generalized[j],
        };
        if !starts {
            self.closest = Some(d);
            return None;
        }
        Some(d)
    }

    /// The leading template that came closest to starting its action
    /// while none did (for the log of a drag that started nothing).
    #[must_use]
    pub fn closest(&self) -> Option<&Decision> {
        self.closest.as_ref()
    }
}

/// The gate of `thresholds`: the highest coverage floor at or under its
/// coverage, and the highest cap at or under its `max_slow`.
#[must_use]
pub fn gate_of(thresholds: &Thresholds) -> usize {
    let f = COVERAGE_FLOORS
        .iter()
        .rposition(|f| *f <= thresholds.coverage + 1e-9)
        .unwrap_or(0);
    let c = SLOW_CAPS
        .iter()
        .rposition(|c| *c <= thresholds.max_slow + 1e-9)
        .unwrap_or(0);
    f * CAPS + c
}

impl Seen {
    /// One more row of the dynamic programme: the drag's point `q` (m, from
    /// its start) at `u` s (`first`: its first row).
    fn advance(&mut self, q: DVec2, u: f64, rule: &TemplateRule, first: bool) {
        let m = self.at.len();
        let mut prev = std::mem::take(&mut self.row);
        let mut cur: Vec<(f64, u32)> = Vec::with_capacity(m);
        for j in 0..m {
            let c = (q - self.at[j]).length() + rule.h * tempo_gap(u, self.t[j], rule.tempo);
            let mut best = (f64::INFINITY, 0u32);
            if first {
                if j == 0 {
                    best = (0.0, 0);
                } else {
                    best = cur[j - 1];
                }
            } else {
                for cand in [
                    Some(prev[j]),
                    j.checked_sub(1).map(|k| prev[k]),
                    j.checked_sub(1).map(|k| cur[k]),
                ]
                .into_iter()
                .flatten()
                {
                    if cand.0 < best.0 {
                        best = cand;
                    }
                }
            }
            cur.push((best.0 + c, best.1 + 1));
        }
        prev.clear();
        self.row = cur;
    }

    /// What the template costs now, the drag having drawn `drawn` m in `u`
    /// s: its best end point (not one the drag is far too slow for) under
    /// every cap on slowness, and under every coverage floor too.
    fn cost(&self, drawn: f64, u: f64, rule: &TemplateRule) -> TemplateCost {
        let mut any = [f64::INFINITY; CAPS];
        let mut covered = [f64::INFINITY; GATES];
        let mut covered_j = [0; GATES];
        // How long the template took to go as far as the drag has.
        let took = self.time_to_cover(drawn);
        for (j, &(sum, len)) in self.row.iter().enumerate() {
            if drawn < rule.min_drawn * self.arc_m[j] {
                continue;
            }
            let mean = sum / f64::from(len.max(1));
            for (c, cap) in SLOW_CAPS.iter().enumerate() {
                if u > cap * took + 0.05 {
                    continue;
                }
                any[c] = any[c].min(mean);
                for (f, floor) in COVERAGE_FLOORS.iter().enumerate() {
                    let g = f * CAPS + c;
                    if self.along[j] >= *floor && mean < covered[g] {
                        covered[g] = mean;
                        covered_j[g] = j;
                    }
                }
            }
        }
        TemplateCost {
            action: self.action,
            clip: self.clip,
            any,
            covered,
            covered_j,
        }
    }
}

#[cfg(test)]
mod tests;
