//! `marionette library check`: what a drag can start in a library, told to
//! the person who recorded it. Each clip in turn is left out and replayed
//! as drags from the two trial views (the calibration of the template
//! recogniser, [`crate::control::action::calibrate`]); the report says,
//! for each action, how often its drags start it, start nothing or start
//! another action, and what to do about it: record more takes of an action
//! that has one, merge two actions a drag cannot tell apart from a view (or
//! lead one with another part), and which actions the default camera cannot
//! see drawn.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::character::body::{Anchor, Placement};
use crate::character::camera::Camera;
use crate::character::library::Library;
use crate::control::action::calibrate::{
    Calibration, SEED, SLOW_BUDGET, calibrate, left_out_tests,
};
use crate::control::action::model::{ActionModel, ClipPath};
use crate::control::action::recogniser::{DragMatch, Recogniser, TemplateRule, Thresholds};
use crate::control::action::trials::each_drag;
use crate::tools::eval::actions::{TrialExplained, explain_drag};

/// A drag from one view confused with another action this often is a pair
/// the builder should hear about.
const CONFUSED_SHARE: f64 = 0.25;
/// An action's takes whose drags differ in size by more than this are told.
const SIZE_RATIO: f64 = 1.5;
/// ...where its left-out drags start it less than this share of the time.
const SIZES_TOLD_UNDER: f64 = 0.8;
/// A take whose drag goes more than this far from the way its action's
/// other takes go is told (degrees).
const OTHER_WAY_DEG: f64 = 90.0;
/// An action whose drag shows less than this share of its takes' path...
const SHOWN_SHARE: f64 = 0.35;
/// ...where its left-out drags start it less than this share of the time
/// is told: it travels on far past what a drag can show of it.
const SHOWN_TOLD_UNDER: f64 = 0.5;

/// The whole report.
#[derive(Clone, Debug, Serialize)]
pub struct LibraryReport {
    /// The thresholds calibrated for the library.
    pub thresholds: Thresholds,
    /// Whether slow posing drags stay within half the budget.
    pub within_budget: bool,
    pub drags: usize,
    pub correct: f64,
    pub wrong_action: f64,
    pub missed: f64,
    pub false_trigger_slow: f64,
    pub decided_at: f64,
    pub actions: Vec<ActionReport>,
    /// What to do, one line each.
    pub advice: Vec<String>,
}

/// One action's rows.
#[derive(Clone, Debug, Serialize)]
pub struct ActionReport {
    pub action: String,
    pub primary: String,
    /// Source files its clips come from (cuts and mirror images of one take
    /// count once).
    pub takes: usize,
    pub clips: usize,
    pub views: Vec<ViewReport>,
    pub false_trigger_slow: f64,
    /// Clips whose drag can be drawn from the default camera.
    pub drawable_from_default_camera: usize,
    /// Its take drawn longest from the default camera, dragged there as
    /// recorded (as `demo --library` drags it): what it started, and the
    /// action nearest to it.
    pub home_view: HomeView,
}

/// What a drag of an action's own take from the default camera does.
#[derive(Clone, Debug, Serialize)]
pub struct HomeView {
    /// The action it started (none: nothing).
    pub started: Option<String>,
    /// The other action costing least along the drag.
    pub nearest_other: Option<String>,
}

/// One action's left-out drags from one view.
#[derive(Clone, Debug, Serialize)]
pub struct ViewReport {
    pub view_deg: f64,
    pub drags: usize,
    pub correct: f64,
    pub missed: f64,
    pub wrong_action: f64,
    /// The actions its drags started instead, with how many.
    pub confused_with: BTreeMap<String, usize>,
}

fn share(a: usize, b: usize) -> f64 {
    if b == 0 {
        0.0
    } else {
        (a as f64 / b as f64 * 1000.0).round() / 1000.0
    }
}

/// The take a clip comes from: its file, without a frame range or mirror
/// mark.
fn take_of(clip: &str) -> &str {
    let end = clip.find(['#', '~']).unwrap_or(clip.len());
    &clip[..end]
}

/// Every left-out drag of `lib`'s calibration, explained point by point
/// with the thresholds [`check`] calibrated, as `eval actions --explain`
/// explains held-out ones: `file` names the clip left out.
#[must_use]
pub fn explain(
    lib: &Library,
    actions: &[ActionModel],
    thresholds: Thresholds,
) -> Vec<TrialExplained> {
    let recogniser = &Recogniser {
        rule: TemplateRule::default(),
        thresholds,
    };
    let (which, tests) = left_out_tests(lib, actions);
    let mut out = Vec::new();
    each_drag(&tests, SEED, &mut |d| {
        let (ai, ci) = which[d.test];
        let m = DragMatch::new(recogniser, actions, d.role, d.camera, d.at, Some((ai, ci)));
        let (points, started) = explain_drag(m, actions, &recogniser.thresholds, d.trail);
        out.push(TrialExplained {
            action: actions[ai].def.name.clone(),
            file: actions[ai].templates[ci].clip.clone(),
            view_deg: d.angle_deg,
            slow: d.slow,
            started: started.map(|(a, _)| a),
            points,
        });
    });
    out
}

/// Check `lib`: calibrate its recogniser and report on the left-out drags.
/// `camera` is the kiosk's default view of a character at the origin.
#[must_use]
pub fn check(lib: &Library, actions: &[ActionModel], camera: &Camera) -> LibraryReport {
    let c = calibrate(lib, actions, TemplateRule::default());
    report(actions, &c, camera)
}

fn report(actions: &[ActionModel], c: &Calibration, camera: &Camera) -> LibraryReport {
    let mut advice = Vec::new();
    let rows = (0..actions.len())
        .map(|ai| action_row(actions, ai, c, camera, &mut advice))
        .collect();
    if !c.within_budget {
        advice.push(format!(
            "no threshold keeps slow posing drags under {:.0}% of trials: the strictest is used, and fewer drags start their action",
            SLOW_BUDGET / 2.0 * 100.0
        ));
    }
    let drags: Vec<_> = c.outcomes.iter().filter(|o| !o.slow).collect();
    let n = drags.len();
    let right: Vec<f64> = drags
        .iter()
        .filter(|o| o.started.as_deref() == Some(o.action.as_str()))
        .filter_map(|o| o.decided_at)
        .collect();
    let wrong = drags
        .iter()
        .filter(|o| o.started.as_ref().is_some_and(|s| s != &o.action))
        .count();
    let slow: Vec<_> = c.outcomes.iter().filter(|o| o.slow).collect();
    LibraryReport {
        thresholds: c.recogniser.thresholds,
        within_budget: c.within_budget,
        drags: n,
        correct: share(right.len(), n),
        wrong_action: share(wrong, n),
        missed: share(n - right.len() - wrong, n),
        false_trigger_slow: share(
            slow.iter().filter(|o| o.started.is_some()).count(),
            slow.len(),
        ),
        decided_at: if right.is_empty() {
            0.0
        } else {
            (right.iter().sum::<f64>() / right.len() as f64 * 1000.0).round() / 1000.0
        },
        actions: rows,
        advice,
    }
}

/// Drags of one action by the view they were made from: how many, how
/// many started it, how many started nothing, and what else they started.
type ByView = BTreeMap<i64, (usize, usize, usize, BTreeMap<String, usize>)>;

/// Action `ai`'s row of the report, its advice added to `advice`.
fn action_row(
    actions: &[ActionModel],
    ai: usize,
    c: &Calibration,
    camera: &Camera,
    advice: &mut Vec<String>,
) -> ActionReport {
    let origin = Placement {
        position: glam::DVec3::ZERO,
        yaw: 0.0,
        anchor: Anchor::ClipStart,
    };
    let a = &actions[ai];
    let name = &a.def.name;
    let mut views = ByView::new();
    let (mut slow, mut slow_n) = (0, 0);
    for o in c.outcomes.iter().filter(|o| &o.action == name) {
        if o.slow {
            slow_n += 1;
            slow += usize::from(o.started.is_some());
            continue;
        }
        let v = views.entry(o.view_deg.round() as i64).or_default();
        v.0 += 1;
        match &o.started {
            Some(s) if s == name => v.1 += 1,
            Some(s) => *v.3.entry(s.clone()).or_default() += 1,
            None => v.2 += 1,
        }
    }
    let takes: std::collections::BTreeSet<&str> =
        a.templates.iter().map(|t| take_of(&t.clip)).collect();
    let drawable = DragMatch::new(
        &Recogniser::default(),
        actions,
        a.def.primary,
        camera,
        &origin,
        None,
    )
    .drawable(ai);
    if takes.len() == 1 {
        advice.push(format!(
            "`{name}` has one take ({}): a drag by another performer is judged against that one alone; record two or three more takes",
            takes.iter().next().copied().unwrap_or("")
        ));
    }
    let (n, right) = views.values().fold((0, 0), |(n, r), v| (n + v.0, r + v.1));
    let started = share(right, n);
    shape_advice(name, &a.templates, started, advice);
    shown_advice(name, &a.templates, started, &c.recogniser.rule, advice);
    let home = home_view(actions, ai, &c.recogniser, camera, &origin);
    home_advice(a, &home, drawable, advice);
    let views = view_reports(name, views, advice);
    if slow > 1 && share(slow, slow_n) > 2.0 * SLOW_BUDGET {
        advice.push(format!(
            "slow posing drags of the {} start `{name}` ({slow} of {slow_n}): its start is slow and small, so posing that part can start it",
            a.def.primary.name()
        ));
    }
    ActionReport {
        action: name.clone(),
        primary: a.def.primary.name().to_owned(),
        takes: takes.len(),
        clips: a.templates.len(),
        views,
        false_trigger_slow: share(slow, slow_n),
        drawable_from_default_camera: drawable,
        home_view: home,
    }
}

/// The first clip of each take among `paths` (cuts and mirror images of a
/// take are one take).
fn one_per_take(paths: &[ClipPath]) -> impl Iterator<Item = &ClipPath> {
    let mut seen = std::collections::BTreeSet::new();
    paths.iter().filter(move |p| seen.insert(take_of(&p.clip)))
}

/// How far a clip's part goes from where it starts moving (m), and which
/// way (a unit vector in the character's frame) to the point it goes
/// farthest.
fn shape_of(p: &ClipPath) -> Option<(f64, glam::DVec3)> {
    let start = *p.points.get(p.lead_in)?;
    let (far, reach) = p.points[p.lead_in..]
        .iter()
        .map(|q| (*q, (*q - start).length()))
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    (reach > 1e-3).then(|| (reach, (far - start) / reach))
}

/// Advice on action `name`'s takes (its templates, one shape a take: the
/// take's first clip) whose drags differ in size by more than
/// [`SIZE_RATIO`] where its left-out drags start it less than
/// [`SIZES_TOLD_UNDER`] of the time (`started`), or one that goes another
/// way than the others.
fn shape_advice(name: &str, paths: &[ClipPath], started: f64, advice: &mut Vec<String>) {
    let takes: Vec<(&str, f64, glam::DVec3)> = one_per_take(paths)
        .filter_map(|p| shape_of(p).map(|(r, w)| (take_of(&p.clip), r, w)))
        .collect();
    if takes.len() < 2 {
        return;
    }
    let by_size =
        |a: &&(&str, f64, glam::DVec3), b: &&(&str, f64, glam::DVec3)| a.1.total_cmp(&b.1);
    if let (Some(small), Some(big)) = (takes.iter().min_by(by_size), takes.iter().max_by(by_size))
        && big.1 > SIZE_RATIO * small.1
        && started < SIZES_TOLD_UNDER
    {
        advice.push(format!(
            "`{name}`'s takes differ in size: {} goes {:.2} m, {} {:.2} m ({:.1}x), and left out in turn its drags start it {:.0}% of the time: a take left out is far from the others; record takes of the sizes in between (and of the sizes visitors drag), or leave the odd one out",
            big.0,
            big.1,
            small.0,
            small.1,
            big.1 / small.1,
            started * 100.0
        ));
    }
    for (k, (take, _, way)) in takes.iter().enumerate() {
        let others: glam::DVec3 = takes
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != k)
            .map(|(_, t)| t.2)
            .sum();
        if others.length() < 1e-6 {
            continue;
        }
        let deg = way
            .dot(others.normalize())
            .clamp(-1.0, 1.0)
            .acos()
            .to_degrees();
        if deg > OTHER_WAY_DEG && (takes.len() > 2 || k == 0) {
            advice.push(format!(
                "{take}, a take of `{name}`, goes another way than {} ({deg:.0} degrees from them): a drag like it starts another action or nothing; check it is the same action (a mirror image belongs to the mirrored action), or leave it out",
                if takes.len() > 2 {
                    "its other takes"
                } else {
                    "its other take"
                }
            ));
        }
    }
}

/// How long a clip's part path is from where it starts moving (m), and how
/// much of that the first `horizon_s` of its movement goes.
fn shown_of(p: &ClipPath, horizon_s: f64) -> Option<(f64, f64)> {
    let moving = p.points.get(p.lead_in..)?;
    let length = |pts: &[glam::DVec3]| -> f64 { pts.windows(2).map(|w| w[0].distance(w[1])).sum() };
    let k = ((horizon_s / p.dt).ceil() as usize + 1).min(moving.len());
    Some((length(moving), length(&moving[..k])))
}

/// Advice on action `name` whose takes go on far past what a drag shows
/// of them (the first [`TemplateRule::horizon_s`] of movement: a walk of
/// several metres, of which a drag shows two steps), where its left-out
/// drags start it less than [`SHOWN_TOLD_UNDER`] of the time (`started`):
/// in that much, actions that differ in pace or in where they go later
/// (a walk, a run, a dash) are drawn alike.
fn shown_advice(
    name: &str,
    paths: &[ClipPath],
    started: f64,
    rule: &TemplateRule,
    advice: &mut Vec<String>,
) {
    let mut takes: Vec<(f64, f64)> = one_per_take(paths)
        .filter_map(|p| shown_of(p, rule.horizon_s))
        .filter(|(all, _)| *all > 0.0)
        .collect();
    if takes.is_empty() || started >= SHOWN_TOLD_UNDER {
        return;
    }
    takes.sort_by(|a, b| (a.1 / a.0).total_cmp(&(b.1 / b.0)));
    let (all, shown) = takes[takes.len() / 2];
    if shown < SHOWN_SHARE * all {
        advice.push(format!(
            "`{name}`: a drag shows the first {:.1} s of its takes' movement, {shown:.2} m of {all:.2} m (half its takes show less), and left out in turn its drags start it {:.0}% of the time: in that much it is drawn like actions that differ from it in pace or later on; cut its takes to the part that tells it (its start), or let walking carry it (list its takes under [locomotion]: a finger dragged out of posing's reach walks)",
            rule.horizon_s,
            started * 100.0
        ));
    }
}

/// What to do where an action dragged from the default camera starts
/// another or nothing, or cannot be drawn from there.
fn home_advice(a: &ActionModel, home: &HomeView, drawable: usize, advice: &mut Vec<String>) {
    let name = &a.def.name;
    match (&home.started, &home.nearest_other) {
        (Some(s), _) if s == name => {}
        (Some(other), _) => advice.push(format!(
            "`{name}` dragged from the default camera as its take was recorded starts `{other}`: from there the two are drawn alike; merge them, or give one another primary part"
        )),
        (None, Some(other)) if drawable > 0 => advice.push(format!(
            "`{name}` dragged from the default camera as its take was recorded starts nothing: `{other}` is drawn as near to it from there; merge them, give one another primary part, or record takes that differ more"
        )),
        _ => {}
    }
    if drawable == 0 {
        advice.push(format!(
            "`{name}`: from the default camera its {} moves too little on the screen (or straight towards the camera) to be drawn; a visitor must turn the view, or lead it with another part",
            a.def.primary.name()
        ));
    }
}

/// Each view's shares, with advice where its drags start another action.
fn view_reports(name: &str, views: ByView, advice: &mut Vec<String>) -> Vec<ViewReport> {
    views
        .into_iter()
        .map(|(deg, (n, right, missed, confused))| {
            for (other, k) in &confused {
                if share(*k, n) >= CONFUSED_SHARE {
                    advice.push(format!(
                        "`{name}` drags from the {deg}° view start `{other}` ({k} of {n}): from there the two start alike; merge them, or give one another primary part"
                    ));
                }
            }
            ViewReport {
                view_deg: deg as f64,
                drags: n,
                correct: share(right, n),
                missed: share(missed, n),
                wrong_action: share(n - right - missed, n),
                confused_with: confused,
            }
        })
        .collect()
}

/// Action `ai`'s take drawn longest from `camera`, dragged as recorded
/// against every template (its own included) with the library's
/// thresholds.
fn home_view(
    actions: &[ActionModel],
    ai: usize,
    recogniser: &Recogniser,
    camera: &Camera,
    at: &Placement,
) -> HomeView {
    let a = &actions[ai];
    let mut m = DragMatch::new(recogniser, actions, a.def.primary, camera, at, None);
    let gate = crate::control::action::recogniser::gate_of(&recogniser.thresholds);
    let mut nearest = None;
    for p in a.most_drawn(camera, at) {
        m.push(p);
        if let Some(d) = m.decide(actions, &recogniser.thresholds) {
            return HomeView {
                started: Some(actions[d.action].def.name.clone()),
                nearest_other: m
                    .nearest_other(ai, gate)
                    .map(|o| actions[o].def.name.clone()),
            };
        }
        nearest = m.nearest_other(ai, gate).or(nearest);
    }
    HomeView {
        started: None,
        nearest_other: nearest.map(|o| actions[o].def.name.clone()),
    }
}

impl LibraryReport {
    /// The report as lines of text: a table, then the advice.
    #[must_use]
    pub fn to_text(&self) -> Vec<String> {
        let t = self.thresholds;
        let mut out = vec![
            format!(
                "recogniser calibrated on the library's own clips: cost under {:.2} m, {:.3} m ahead of the next action, {:.0}% of the path covered, at most {:.1} times slower",
                t.cost_m,
                t.margin_m,
                t.coverage * 100.0,
                t.max_slow
            ),
            format!(
                "each clip left out in turn, {} drags from two views: correct {:.3}, wrong {:.3}, missed {:.3}, slow drags starting an action {:.3}, decided at {:.2} of the drag",
                self.drags,
                self.correct,
                self.wrong_action,
                self.missed,
                self.false_trigger_slow,
                self.decided_at
            ),
            String::new(),
            format!(
                "{:<28} {:<11} {:>5} {:>5}  {:>5} {:>8} {:>7} {:>7}  {}",
                "action",
                "primary",
                "takes",
                "view",
                "drags",
                "correct",
                "missed",
                "wrong",
                "started instead"
            ),
        ];
        for a in &self.actions {
            for (k, v) in a.views.iter().enumerate() {
                let (name, primary, takes) = if k == 0 {
                    (a.action.as_str(), a.primary.as_str(), a.takes.to_string())
                } else {
                    ("", "", String::new())
                };
                let instead: Vec<String> = v
                    .confused_with
                    .iter()
                    .map(|(o, n)| format!("{o} {n}"))
                    .collect();
                out.push(format!(
                    "{:<28} {:<11} {:>5} {:>4}°  {:>5} {:>8.2} {:>7.2} {:>7.2}  {}",
                    name,
                    primary,
                    takes,
                    v.view_deg,
                    v.drags,
                    v.correct,
                    v.missed,
                    v.wrong_action,
                    instead.join(", ")
                ));
            }
        }
        out.push(String::new());
        if self.advice.is_empty() {
            out.push("nothing to improve that a drag shows".to_owned());
        } else {
            out.extend(self.advice.iter().map(|a| format!("- {a}")));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn takes_are_files_without_cuts_or_mirrors() {
        assert_eq!(
            take_of("punch_normal_001.bvh#48-89~mirror"),
            "punch_normal_001.bvh"
        );
        assert_eq!(take_of("bow.bvh~mirror"), "bow.bvh");
        assert_eq!(take_of("bow.bvh"), "bow.bvh");
    }

    fn path(clip: &str, to: glam::DVec3) -> ClipPath {
        ClipPath {
            clip: clip.to_owned(),
            points: (0..=10).map(|k| to * (f64::from(k) / 10.0)).collect(),
            dt: 1.0 / 30.0,
            lead_in: 0,
            peak_speed: 1.0,
        }
    }

    #[test]
    fn a_take_that_goes_on_far_past_what_a_drag_shows_is_told() {
        // Straight on at 1 m/s for 6 s: a drag shows 1.5 m of 6 m.
        let walk = |clip: &str| ClipPath {
            clip: clip.to_owned(),
            points: (0..=180)
                .map(|k| glam::DVec3::new(0.0, 0.9, f64::from(k) / 30.0))
                .collect(),
            dt: 1.0 / 30.0,
            lead_in: 0,
            peak_speed: 1.0,
        };
        let rule = TemplateRule::default();
        let mut advice = Vec::new();
        shown_advice(
            "walk",
            &[walk("a.bvh"), walk("b.bvh")],
            0.2,
            &rule,
            &mut advice,
        );
        assert_eq!(advice.len(), 1, "{advice:?}");
        assert!(
            advice[0].contains("the first 1.5 s of its takes' movement, 1.50 m of 6.00 m"),
            "{advice:?}"
        );
        // Started often enough, or shown whole: nothing to tell.
        advice.clear();
        shown_advice("walk", &[walk("a.bvh")], 0.6, &rule, &mut advice);
        let mut punch = walk("p.bvh");
        punch.points.truncate(40);
        shown_advice("punch", &[punch], 0.1, &rule, &mut advice);
        assert!(advice.is_empty(), "{advice:?}");
    }

    #[test]
    fn takes_of_another_size_or_way_are_told() {
        let x = glam::DVec3::X;
        let alike = [
            path("a.bvh", x * 0.4),
            path("a.bvh#20-40", x * 0.9),
            path("b.bvh", x * 0.5),
            path("c.bvh", (x + glam::DVec3::Y * 0.2) * 0.45),
        ];
        let mut advice = Vec::new();
        shape_advice("punch", &alike, 0.5, &mut advice);
        assert!(advice.is_empty(), "{advice:?}");
        let odd = [
            path("a.bvh", x * 0.4),
            path("b.bvh", x * 0.5),
            path("c.bvh", -x * 0.45),
            path("d.bvh", x * 0.9),
        ];
        shape_advice("call", &odd, 0.9, &mut advice);
        assert_eq!(
            advice.len(),
            1,
            "sizes that cost nothing left out: {advice:?}"
        );
        advice.clear();
        shape_advice("call", &odd, 0.5, &mut advice);
        assert_eq!(advice.len(), 2, "{advice:?}");
        assert!(
            advice[0].contains("d.bvh goes 0.90 m, a.bvh 0.40 m (2.2x)"),
            "{advice:?}"
        );
        assert!(
            advice[1].starts_with("c.bvh, a take of `call`, goes another way"),
            "{advice:?}"
        );
        // One take: nothing to compare.
        let mut one = Vec::new();
        shape_advice("bow", &odd[..1], 0.0, &mut one);
        assert!(one.is_empty());
    }
}
