//! The template recogniser on synthetic actions: left-out takes, slow
//! drags, rests and turns, views.
use super::*;
use crate::character::body::Anchor;
use crate::character::library::{ActionDef, Release, Segment};
use crate::control::action::model::{ClipPath, lead_in};
use crate::control::posing::model::LearnedModel;
use crate::screen::ScreenPoint;

/// An action of the right hand whose clips follow `path(s, k)` for
/// s in 0..1 over `seconds`, after `still` seconds of standing.
fn action(
    name: &str,
    clips: usize,
    seconds: f64,
    still: f64,
    path: &dyn Fn(f64, usize) -> DVec3,
) -> ActionModel {
    let dt = 1.0 / 30.0;
    let templates = (0..clips)
        .map(|k| {
            let n = ((still + seconds) / dt) as usize;
            let points: Vec<DVec3> = (0..=n)
                .map(|i| {
                    let t = i as f64 * dt - still;
                    path((t / seconds).clamp(0.0, 1.0), k)
                })
                .collect();
            ClipPath {
                clip: format!("{name}_{k}.bvh"),
                lead_in: lead_in(&points),
                peak_speed: points
                    .windows(3)
                    .map(|w| w[0].distance(w[2]) / (2.0 * dt))
                    .fold(0.0, f64::max),
                points,
                dt,
            }
        })
        .collect();
    ActionModel {
        def: ActionDef {
            name: name.into(),
            clips: vec![],
            primary: Role::RightHand,
            segments: vec![Segment {
                until: 1.0,
                still: false,
                release: Release::Forward,
            }],
            threshold_m: None,
        },
        model: LearnedModel::with_coords(vec![], vec![]),
        trajectory: vec![],
        direction: DVec3::X,
        duration: seconds + still,
        templates,
    }
}

fn side_camera() -> Camera {
    Camera {
        eye: DVec3::new(3.0, 1.2, 0.0),
        target: DVec3::new(0.0, 1.2, 0.0),
        fov_y_deg: 45.0,
        width: 1280.0,
        height: 720.0,
    }
}

fn origin() -> Placement {
    Placement {
        position: DVec3::ZERO,
        yaw: 0.0,
        anchor: Anchor::ClipStart,
    }
}

/// A punch forward (+Z) and a swipe up (+Y), each three takes a little
/// apart; the hand starts at chest height.
fn two_actions() -> Vec<ActionModel> {
    let ease = |s: f64| s * s * (3.0 - 2.0 * s);
    vec![
        action("punch", 3, 0.4, 0.5, &|s, k| {
            DVec3::new(0.0, 1.2, 0.5 * ease(s) * (1.0 + 0.05 * k as f64))
        }),
        action("swipe", 3, 0.5, 0.3, &|s, k| {
            DVec3::new(
                0.0,
                1.2 + 0.5 * ease(s) * (1.0 + 0.05 * k as f64),
                0.1 * ease(s),
            )
        }),
    ]
}

/// The screen trail of `action`'s clip `clip` (a held-out variant:
/// `scale` times as far), at `pace` times its speed.
fn drag(a: &ActionModel, clip: usize, scale: f64, pace: f64) -> Vec<TrailPoint> {
    let cam = side_camera();
    let tpl = &a.templates[clip];
    let start = tpl.points[0];
    tpl.points
        .iter()
        .enumerate()
        .map(|(i, p)| TrailPoint {
            at: cam.project(start + (*p - start) * scale).unwrap(),
            t: i as f64 * tpl.dt / pace,
        })
        .collect()
}

fn first_start(actions: &[ActionModel], trail: &[TrailPoint]) -> Option<(Decision, usize)> {
    let r = Recogniser::default();
    let mut m = DragMatch::new(
        &r,
        actions,
        Role::RightHand,
        &side_camera(),
        &origin(),
        Some((0, 0)),
    );
    trail.iter().enumerate().find_map(|(k, p)| {
        m.push(*p);
        m.decide(actions, &r.thresholds).map(|d| (d, k))
    })
}

#[test]
fn a_left_out_take_starts_its_own_action_early_at_its_own_pace() {
    let actions = two_actions();
    for pace in [0.7, 1.0, 1.4] {
        let trail = drag(&actions[0], 0, 1.1, pace);
        let (d, k) = first_start(&actions, &trail).expect("the punch starts");
        assert_eq!(d.action, 0, "{d:?}");
        assert_ne!(d.clip, "punch_0.bvh", "the left-out take is no template");
        // Decided before the punch is over, and after its still lead-in.
        let still = 15;
        assert!(k > still && k < trail.len() - 3, "{k} of {}", trail.len());
        assert!(d.cost_m < 0.05 && d.coverage >= 0.35, "{d:?}");
        assert!((d.tempo / pace - 1.0).abs() < 0.4, "{d:?} at pace {pace}");
    }
    let trail = drag(&actions[1], 1, 0.95, 1.0);
    let mut m = DragMatch::new(
        &Recogniser::default(),
        &actions,
        Role::RightHand,
        &side_camera(),
        &origin(),
        None,
    );
    let started = trail.iter().find_map(|p| {
        m.push(*p);
        m.decide(&actions, &Thresholds::default())
    });
    assert_eq!(started.map(|d| d.action), Some(1));
}

#[test]
fn a_drag_far_slower_than_every_take_starts_nothing() {
    let actions = two_actions();
    // The punch's own path at a quarter of its pace.
    let trail = drag(&actions[0], 0, 1.0, 0.25);
    assert_eq!(first_start(&actions, &trail).map(|(d, _)| d.action), None);
    // And a drag the other way starts nothing either.
    let back: Vec<TrailPoint> = drag(&actions[0], 0, -1.0, 1.0);
    assert_eq!(first_start(&actions, &back).map(|(d, _)| d.action), None);
}

#[test]
fn a_rest_begins_the_drag_anew_but_a_turn_does_not() {
    let actions = two_actions();
    let mut trail = drag(&actions[0], 1, 1.0, 1.0);
    // Half a second of the finger wandering slowly first: trimmed as
    // the rest it is (a still lead-in of another length).
    let first = trail[0];
    let mut wandering: Vec<TrailPoint> = (0..15)
        .map(|i| TrailPoint {
            at: ScreenPoint::new(
                first.at.x + f64::from(i) * 0.6,
                first.at.y - f64::from(i) * 0.4,
            ),
            t: f64::from(i) / 30.0,
        })
        .collect();
    let shift = wandering.last().unwrap();
    let (dx, dy, dt) = (
        shift.at.x - first.at.x,
        shift.at.y - first.at.y,
        shift.t + 1.0 / 30.0,
    );
    for p in &mut trail {
        p.at = ScreenPoint::new(p.at.x + dx, p.at.y + dy);
        p.t += dt;
    }
    wandering.extend(trail);
    let (d, _) = first_start(&actions, &wandering).expect("starts after the wander");
    assert_eq!(d.action, 0);
    // A quick out-and-back within the rest window is movement.
    let r = Recogniser::default();
    let mut m = DragMatch::new(
        &r,
        &actions,
        Role::RightHand,
        &side_camera(),
        &origin(),
        None,
    );
    for i in 0..12 {
        let x = 600.0 + 40.0 * (f64::from(i) * std::f64::consts::PI / 6.0).sin();
        m.push(TrailPoint {
            at: ScreenPoint::new(x, 300.0),
            t: f64::from(i) / 60.0,
        });
    }
    assert!(m.origin.is_some(), "a wave's turn is no rest");
}

#[test]
fn templates_too_short_to_draw_from_a_view_are_left_out() {
    let actions = two_actions();
    // From the side both are drawn; from in front the punch comes
    // straight at the camera.
    let r = Recogniser::default();
    let side = DragMatch::new(
        &r,
        &actions,
        Role::RightHand,
        &side_camera(),
        &origin(),
        None,
    );
    assert_eq!((side.drawable(0), side.drawable(1)), (3, 3));
    let front = Camera {
        eye: DVec3::new(0.0, 1.2, 3.0),
        ..side_camera()
    };
    let m = DragMatch::new(&r, &actions, Role::RightHand, &front, &origin(), None);
    assert_eq!((m.drawable(0), m.drawable(1)), (0, 3));
}

#[test]
fn time_counts_only_outside_the_band() {
    assert_eq!(tempo_gap(1.0, 1.5, 1.6), 0.0);
    assert_eq!(tempo_gap(1.0, 0.7, 1.6), 0.0);
    assert!((tempo_gap(1.0, 2.0, 1.6) - 0.4).abs() < 1e-12);
    assert!((tempo_gap(1.0, 0.5, 1.6) - (1.0 / 1.6 - 0.5)).abs() < 1e-12);
}

#[test]
fn a_take_that_drifts_and_pauses_is_matched_from_its_pause() {
    // A bow's head: a quick 6 cm nod (too quick for the still lead-in to
    // leave out), a 0.5 s pause, then 0.45 m down and forward in 0.6 s. A
    // drag that pauses there too rests, and what it draws next is matched
    // afresh: against the template from the pause.
    let ease = |s: f64| s * s * (3.0 - 2.0 * s);
    let bow = |s: f64, k: usize| {
        let t = s * 1.25;
        let nod = 0.06 * ease((t / 0.15).min(1.0));
        let down = ease(((t - 0.65) / 0.6).clamp(0.0, 1.0)) * (1.0 + 0.05 * k as f64);
        DVec3::new(0.0, 1.5 - 0.36 * down, nod + 0.27 * down)
    };
    let actions = vec![action("bow", 3, 1.25, 0.3, &bow)];
    let trail = drag(&actions[0], 0, 1.05, 1.0);
    let starts = |rule: TemplateRule| {
        let r = Recogniser {
            rule,
            thresholds: Thresholds::default(),
        };
        let mut m = DragMatch::new(
            &r,
            &actions,
            Role::RightHand,
            &side_camera(),
            &origin(),
            Some((0, 0)),
        );
        trail.iter().find_map(|p| {
            m.push(*p);
            m.decide(&actions, &r.thresholds)
        })
    };
    let d = starts(TemplateRule::default()).expect("the bow starts");
    assert_eq!(d.action, 0);
    // Matched from the pause: well into the clip.
    assert!(d.generalized > 0.5, "{d:?}");
    // Without templates from pauses it does not.
    let none = starts(TemplateRule {
        min_pause_s: 99.0,
        ..TemplateRule::default()
    });
    assert!(none.is_none(), "{none:?}");
}
