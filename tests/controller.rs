//! The character controller driven by touch frames, as the kiosk and the
//! headless presenter drive it: grabbing, pinning, camera gestures, and a
//! touch's effect showing at the next step (the next rendered frame).

#![allow(
    clippy::print_stdout,
    clippy::print_stderr,
    reason = "measurements are printed for the reader of the run"
)]

mod common;

use common::contact;
use marionette::character::roles::Role;
use marionette::control::controller::{Controller, Settings};
use marionette::control::stage::Stage;
use marionette::input::touch::Phase;
use marionette::input::touch::{ScreenContact, ScreenFrame};
use marionette::screen::ScreenPoint;

fn frame(t: f64, contacts: Vec<ScreenContact>) -> ScreenFrame {
    ScreenFrame { t, contacts }
}

fn controller() -> Stage {
    Stage::single(
        Controller::new(common::character(), Settings::default(), 0.0),
        1280.0,
        720.0,
    )
}

fn screen_of(ctl: &Stage, role: Role) -> ScreenPoint {
    let p = ctl.ctl().world().positions[ctl.ctl().character().roles.get(role)];
    ctl.rig().camera().project(p).unwrap()
}

#[test]
fn a_touch_shows_at_the_next_step() {
    let mut ctl = controller();
    ctl.advance(1.0 / 30.0);
    let hand = screen_of(&ctl, Role::LeftHand);
    let before = ctl.ctl().world().positions[ctl.ctl().character().roles.get(Role::LeftHand)];
    // The finger goes down between two steps and moves in the next frame.
    ctl.touch(&frame(0.04, vec![contact(1, Phase::Down, hand)]));
    ctl.advance(2.0 / 30.0);
    assert_eq!(ctl.held(), vec![Role::LeftHand], "held at the next step");
    assert_eq!(ctl.marks(true).fingers.len(), 1);
    let up = ScreenPoint::new(hand.x + 40.0, hand.y - 120.0);
    ctl.touch(&frame(0.07, vec![contact(1, Phase::Move, up)]));
    ctl.advance(3.0 / 30.0);
    let after = ctl.ctl().world().positions[ctl.ctl().character().roles.get(Role::LeftHand)];
    assert!(
        (after - before).length() > 0.01,
        "the hand moved by {:.3} m at the next step",
        (after - before).length()
    );
}

#[test]
fn a_held_part_stays_pinned_while_another_finger_poses() {
    let mut ctl = controller();
    ctl.advance(1.0 / 30.0);
    let foot = screen_of(&ctl, Role::LeftFoot);
    ctl.touch(&frame(0.04, vec![contact(1, Phase::Down, foot)]));
    for k in 2..20 {
        ctl.touch(&frame(
            f64::from(k) / 30.0,
            vec![contact(1, Phase::Hold, foot)],
        ));
        ctl.advance(f64::from(k) / 30.0);
    }
    let hand = screen_of(&ctl, Role::RightHand);
    ctl.touch(&frame(
        0.7,
        vec![contact(1, Phase::Hold, foot), contact(2, Phase::Down, hand)],
    ));
    let mut held_at = Vec::new();
    for k in 22..80 {
        let t = f64::from(k) / 30.0;
        let s = f64::from(k - 22) / 58.0;
        // A slow drag (posing, not an action).
        let p = ScreenPoint::new(hand.x - 60.0 * s, hand.y - 120.0 * s);
        ctl.touch(&frame(
            t,
            vec![contact(1, Phase::Hold, foot), contact(2, Phase::Move, p)],
        ));
        ctl.advance(t);
        held_at.push(screen_of(&ctl, Role::LeftFoot));
    }
    assert!(ctl.action().is_none(), "a slow drag poses");
    let mut held = ctl.held();
    held.sort();
    assert_eq!(held, vec![Role::RightHand, Role::LeftFoot]);
    for p in &held_at[20..] {
        assert!(
            p.distance(foot) < 12.0,
            "the pinned foot drifted {:.1} px from the finger",
            p.distance(foot)
        );
    }
}

#[test]
fn fingers_on_empty_space_turn_and_zoom_the_camera_within_limits() {
    let mut ctl = controller();
    ctl.advance(1.0 / 30.0);
    let home = ctl.rig().orbit;
    let a = ScreenPoint::new(100.0, 650.0);
    ctl.touch(&frame(0.1, vec![contact(1, Phase::Down, a)]));
    for k in 1..30 {
        let p = ScreenPoint::new(100.0 + 20.0 * f64::from(k), 650.0 - 30.0 * f64::from(k));
        ctl.touch(&frame(
            0.1 + f64::from(k) / 60.0,
            vec![contact(1, Phase::Move, p)],
        ));
    }
    ctl.advance(0.7);
    assert!(ctl.held().is_empty());
    assert!((ctl.rig().orbit.yaw - home.yaw).abs() > 1.0, "turned");
    // Dragging up tilts the view down to the horizon, and no further.
    assert_eq!(
        ctl.rig().orbit.pitch,
        ctl.rig().limits.min_pitch,
        "tilt stops at its limit"
    );
    ctl.touch(&frame(0.8, vec![contact(1, Phase::Up, a)]));
    // Two fingers spread far apart: zoom in, stopping at the limit.
    let (l, r) = (
        ScreenPoint::new(100.0, 600.0),
        ScreenPoint::new(200.0, 600.0),
    );
    ctl.touch(&frame(
        1.0,
        vec![contact(2, Phase::Down, l), contact(3, Phase::Down, r)],
    ));
    ctl.touch(&frame(
        1.1,
        vec![
            contact(2, Phase::Move, ScreenPoint::new(10.0, 600.0)),
            contact(3, Phase::Move, ScreenPoint::new(1200.0, 600.0)),
        ],
    ));
    ctl.advance(1.1);
    assert_eq!(ctl.rig().orbit.distance, ctl.rig().limits.min_distance);
    // The whole character stays in view.
    for role in [Role::Head, Role::LeftFoot, Role::RightFoot] {
        let p = screen_of(&ctl, role);
        assert!(
            p.x > 0.0 && p.x < 1280.0 && p.y > 0.0 && p.y < 720.0,
            "{role:?} at {p:?}"
        );
    }
    ctl.touch(&frame(
        1.2,
        vec![
            contact(2, Phase::Up, ScreenPoint::new(10.0, 600.0)),
            contact(3, Phase::Up, ScreenPoint::new(1200.0, 600.0)),
        ],
    ));
    // Idle: the camera eases home.
    let mut t = 1.2;
    while t < 1.2 + ctl.ctl().settings.home_after_s + 4.0 {
        t += 1.0 / 30.0;
        ctl.advance(t);
    }
    assert!((ctl.rig().orbit.distance - home.distance).abs() < 0.05);
    assert!((ctl.rig().orbit.pitch - home.pitch).abs() < 0.02);
}

#[test]
fn many_fingers_on_empty_space_never_put_the_camera_overhead_or_far() {
    // Up to ten fingers on empty space, going down, wandering and lifting
    // at random for a minute: the view stays below 40° and near enough
    // that the character fills at least a quarter of the picture's height.
    let mut ctl = controller();
    let mut seed = 7u64;
    let mut unit = move || {
        seed = seed
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut fingers: Vec<(u64, ScreenPoint)> = Vec::new();
    let mut next_id = 1;
    let (mut lowest, mut steepest) = (f64::INFINITY, 0.0f64);
    for k in 1..=1800 {
        let t = f64::from(k) / 30.0;
        let mut contacts = Vec::new();
        if fingers.len() < 10 && unit() < 0.2 {
            // On empty space: the left or right edge strips.
            let x = if unit() < 0.5 { 60.0 } else { 1220.0 };
            let p = ScreenPoint::new(x, 100.0 + 520.0 * unit());
            contacts.push(contact(next_id, Phase::Down, p));
            fingers.push((next_id, p));
            next_id += 1;
        }
        let lift = if !fingers.is_empty() && unit() < 0.05 {
            Some((unit() * fingers.len() as f64) as usize % fingers.len())
        } else {
            None
        };
        for (i, (id, p)) in fingers.iter_mut().enumerate() {
            // Wandering, mostly downwards (tilting the view up over the
            // character) and together (zooming out).
            p.x = (p.x + (unit() - 0.5) * 80.0 + (640.0 - p.x) * 0.05).clamp(0.0, 1279.0);
            p.y = (p.y + (unit() - 0.3) * 80.0).clamp(0.0, 719.0);
            let phase = if Some(i) == lift {
                Phase::Up
            } else {
                Phase::Move
            };
            if !contacts.iter().any(|c| c.id == *id) {
                contacts.push(contact(*id, phase, *p));
            }
        }
        if let Some(i) = lift {
            fingers.remove(i);
        }
        ctl.touch(&frame(t, contacts));
        ctl.advance(t);
        let cam = ctl.rig().camera();
        let roles = &ctl.ctl().character().roles;
        let at = |r: Role| {
            cam.project(ctl.ctl().world().positions[roles.get(r)])
                .unwrap()
        };
        let feet = at(Role::LeftFoot).y.max(at(Role::RightFoot).y);
        lowest = lowest.min(feet - at(Role::Head).y);
        steepest = steepest.max(ctl.rig().orbit.pitch);
    }
    println!(
        "many camera fingers: figure at least {lowest:.0} px tall of 720, tilt at most {:.1}°",
        steepest.to_degrees()
    );
    assert!(next_id > 50, "{next_id} fingers went down");
    assert!(steepest <= 40f64.to_radians() + 1e-9);
    assert!(lowest >= 0.25 * 720.0, "{lowest} px");
}

#[test]
fn a_cancelled_contact_lets_go() {
    let mut ctl = controller();
    ctl.advance(1.0 / 30.0);
    let hand = screen_of(&ctl, Role::RightHand);
    ctl.touch(&frame(0.05, vec![contact(1, Phase::Down, hand)]));
    ctl.advance(0.1);
    assert_eq!(ctl.held().len(), 1);
    ctl.touch(&frame(0.12, vec![contact(1, Phase::Cancel, hand)]));
    ctl.advance(0.15);
    assert!(ctl.held().is_empty());
}

/// Drag the right hand quickly outwards and let go while it still moves;
/// the right shoulder's local rotation every step for `after_s` seconds
/// after the release, and the steps' time.
fn release_mid_swing(settings: Settings, after_s: f64) -> Vec<glam::DQuat> {
    let mut ctl = Stage::single(
        Controller::new(common::character(), settings, 0.0),
        1280.0,
        720.0,
    );
    ctl.advance(1.0 / 30.0);
    let hand = screen_of(&ctl, Role::RightHand);
    ctl.touch(&frame(0.04, vec![contact(1, Phase::Down, hand)]));
    ctl.advance(2.0 / 30.0);
    // Out to the side and up, about 260 px in 0.3 s; the finger lifts at
    // full speed.
    let steps = 9;
    for k in 1..=steps {
        let t = f64::from(2 + k) / 30.0;
        let s = f64::from(k) / f64::from(steps);
        let p = ScreenPoint::new(hand.x - 200.0 * s, hand.y - 170.0 * s);
        ctl.touch(&frame(t, vec![contact(1, Phase::Move, p)]));
        ctl.advance(t);
    }
    assert!(ctl.action().is_none(), "the drag poses: {:?}", ctl.action());
    let t_up = f64::from(3 + steps) / 30.0;
    ctl.touch(&frame(t_up, vec![contact(1, Phase::Up, hand)]));
    let shoulder = ctl.ctl().character().roles.get(Role::RightShoulder);
    let mut out = Vec::new();
    let mut k = 0;
    while f64::from(k) / 30.0 < after_s {
        ctl.advance(t_up + f64::from(k) / 30.0);
        out.push(ctl.pose().rotations[shoulder]);
        k += 1;
    }
    out
}

/// Per-step turns of a joint (rotation vectors, rad) over a run.
fn turns(r: &[glam::DQuat]) -> Vec<glam::DVec3> {
    r.windows(2)
        .map(|w| (w[1] * w[0].inverse()).to_scaled_axis())
        .collect()
}

#[test]
fn a_released_arm_keeps_swinging_and_settles() {
    let on = release_mid_swing(Settings::default(), 4.0);
    let off = release_mid_swing(
        Settings {
            physics: false,
            ..Settings::default()
        },
        4.0,
    );
    let path = |t: &[glam::DVec3]| t.iter().map(|v| v.length()).sum::<f64>();
    // From 0.3 s after the release (tracking alone has stopped by then).
    let (on_t, off_t) = (turns(&on), turns(&off));
    let (on_late, off_late) = (path(&on_t[9..]), path(&off_t[9..]));
    assert!(
        off_late < 0.01,
        "without physics the arm stops: {off_late:.4} rad"
    );
    assert!(
        on_late > 0.05,
        "with physics the arm keeps swinging: {on_late:.4} rad after 0.3 s"
    );
    // And it settles: still over the last half second.
    let last = on_t[on_t.len() - 15..]
        .iter()
        .map(|v| v.length() * 30.0)
        .fold(0.0, f64::max);
    assert!(last < 0.1, "still swinging at {last:.3} rad/s after 3.5 s");
    eprintln!(
        "after 0.3 s: {on_late:.3} rad with physics, {off_late:.4} without; last speed {last:.4} rad/s"
    );
}

#[test]
fn standing_still_stays_still() {
    // The ragdoll standing on the floor adds nothing: no tremor.
    let mut ctl = controller();
    let mut r = Vec::new();
    for k in 1..150 {
        ctl.advance(f64::from(k) / 30.0);
        r.push(ctl.pose().clone());
    }
    let first = &r[30];
    for p in &r[30..] {
        for (a, b) in p.rotations.iter().zip(&first.rotations) {
            assert!(a.angle_between(*b) < 1e-3, "the resting character moves");
        }
    }
}

#[test]
fn the_ragdoll_never_explodes() {
    use marionette::character::skeleton::forward_kinematics;
    use marionette::physics::ragdoll::{Ragdoll, RagdollSettings};
    let ch = common::character();
    let sk = &ch.lib.skeleton;
    let rest = ch.rest_pose(&marionette::character::body::Placement {
        position: glam::DVec3::ZERO,
        yaw: 0.0,
        anchor: marionette::character::body::Anchor::ClipStart,
    });
    let w = forward_kinematics(sk, &rest);
    let mut ragdoll = Ragdoll::new(sk, &ch.roles, &w, &w, RagdollSettings::default());
    assert!(ragdoll.segments().len() >= 14, "a segment per body part");
    // A target that teleports 3 m away: the ragdoll is put back on the
    // posture shown instead of being flung.
    let mut far = rest.clone();
    far.translations[0].x += 3.0;
    let far_w = forward_kinematics(sk, &far);
    ragdoll.step(&far_w, &w, 1.0 / 30.0);
    assert_eq!(ragdoll.resets(), 1);
    // A target that jumps between two postures every frame, with bad
    // frame times in between: everything stays finite and near.
    let mut bent = rest.clone();
    for q in bent.rotations.iter_mut().skip(1) {
        *q = glam::DQuat::from_rotation_x(1.2) * *q;
    }
    let bent_w = forward_kinematics(sk, &bent);
    for k in 0..600 {
        let target = if k % 2 == 0 { &bent_w } else { &w };
        let dt = match k % 97 {
            0 => f64::NAN,
            1 => 0.0,
            2 => 0.25,
            _ => 1.0 / 30.0,
        };
        ragdoll.step(target, &w, dt);
        for s in ragdoll.states() {
            assert!(s.position.is_finite() && s.rotation.is_finite());
            assert!(
                s.position.length() < 3.0,
                "a segment flew off: {:?}",
                s.position
            );
        }
    }
}

/// The library `library init` makes of the Bandai share's six styles
/// (walks, runs and dashes among its actions: clips that carry the pelvis
/// metres from where they began).
fn bandai_library() -> std::sync::Arc<marionette::control::character::Character> {
    let dir = tempfile::tempdir().unwrap();
    let lib = common::bandai::library(dir.path());
    let lib = marionette::character::library::Library::load(&lib).unwrap();
    std::sync::Arc::new(marionette::control::character::Character::from_library(lib))
}

#[test]
fn a_pelvis_dragged_far_leans_the_body_and_the_legs_stay_under_it() {
    // Posing samples are placed where their clip began; a walk's late
    // frames put the pelvis metres from there. Dragged far, the pelvis
    // went with them and IK pulled the feet back to where they stood: the
    // character lay in the air, legs stretched out behind it. Standing
    // feet now bound the search.
    let ch = bandai_library();
    let mut ctl = Stage::single(Controller::new(ch, Settings::default(), 0.0), 1280.0, 720.0);
    ctl.advance(1.0 / 30.0);
    let start = screen_of(&ctl, Role::Pelvis);
    ctl.touch(&frame(0.04, vec![contact(1, Phase::Down, start)]));
    let roles = ctl.ctl().character().roles.clone();
    let mut worst: f64 = 0.0;
    for k in 2..120 {
        let t = f64::from(k) / 30.0;
        let s = (f64::from(k - 2) / 90.0).min(1.0);
        let p = ScreenPoint::new(start.x + 560.0 * s, start.y + 40.0 * s);
        ctl.touch(&frame(t, vec![contact(1, Phase::Move, p)]));
        ctl.advance(t);
        let w = ctl.ctl().world();
        let pelvis = w.positions[roles.get(Role::Pelvis)];
        for foot in [Role::LeftFoot, Role::RightFoot] {
            // How far up the legs reach towards the pelvis.
            worst = worst.max(w.positions[roles.get(foot)].y / pelvis.y);
        }
    }
    eprintln!("highest foot: {:.2} of the pelvis's height", worst);
    assert!(
        worst < 0.35,
        "a foot rose to {worst:.2} of the pelvis's height"
    );
}

#[test]
fn a_foot_lifted_by_a_finger_comes_down_when_it_lets_go() {
    let mut ctl = controller();
    ctl.advance(1.0 / 30.0);
    let roles = ctl.ctl().character().roles.clone();
    let rest = ctl.ctl().world().positions[roles.get(Role::LeftFoot)].y;
    let foot = screen_of(&ctl, Role::LeftFoot);
    ctl.touch(&frame(0.04, vec![contact(1, Phase::Down, foot)]));
    for k in 2..60 {
        let t = f64::from(k) / 30.0;
        let s = f64::from(k - 2) / 58.0;
        let p = ScreenPoint::new(foot.x + 30.0 * s, foot.y - 120.0 * s);
        ctl.touch(&frame(t, vec![contact(1, Phase::Move, p)]));
        ctl.advance(t);
    }
    let raised = ctl.ctl().world().positions[roles.get(Role::LeftFoot)].y;
    assert!(raised > rest + 0.15, "raised {:.3} m", raised - rest);
    ctl.touch(&frame(2.0, vec![contact(1, Phase::Up, foot)]));
    for k in 61..120 {
        ctl.advance(f64::from(k) / 30.0);
    }
    let down = ctl.ctl().world().positions[roles.get(Role::LeftFoot)].y;
    let sole = marionette::character::skeleton::sole(
        &ctl.ctl().character().lib.skeleton,
        ctl.ctl().world(),
        roles.get(Role::LeftFoot),
    )
    .y;
    eprintln!(
        "ankle raised {:.3} m, {:.3} m after letting go, its lowest point {:.3} m above the floor",
        raised - rest,
        down - rest,
        sole
    );
    // The default character stands with its soles 2.0 cm up (the toe's
    // End Site); put down, within 1.5 cm of that.
    assert!(down - rest < 0.015 && sole < 0.035, "left at {sole:.3} m");
}
