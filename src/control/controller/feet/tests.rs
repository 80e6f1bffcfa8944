//! The feet on made-up postures of a made-up body.

use glam::DVec3;

use super::super::testbody::{at, body, crouched, foot_at, moved, standing, world};
use super::sweep::CLEARANCE_M;
use super::{Feet, FeetStep};
use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::{Pose, Skeleton, sole};
use crate::control::tracking::accel::AccelTracker;

const DT: f64 = 1.0 / 30.0;

/// One step of the feet: `target` asked for and shown as tracking left it
/// (the same), `last` shown the step before. The corrected posture.
fn step(
    feet: &mut Feet,
    (sk, roles): (&Skeleton, &RoleMap),
    target: &Pose,
    last: &Pose,
    held: &[Role],
) -> Pose {
    let shown_last = world(sk, last);
    let s = FeetStep {
        skeleton: sk,
        roles,
        target,
        shown_last: &shown_last,
        held,
        switched: false,
        settle_s: 0.12,
        contacts: None,
        dt: DT,
    };
    let mut output = target.clone();
    let mut tracker = AccelTracker::new(target.clone());
    feet.step(&s, &mut output, &mut tracker);
    output
}

/// Feet that stand planted under `pose`, after a few steps of it.
fn planted_under(sk: &Skeleton, roles: &RoleMap, pose: &Pose) -> Feet {
    let mut feet = Feet::new(roles, &world(sk, &standing(sk)), 0.85);
    let mut last = pose.clone();
    for _ in 0..5 {
        last = step(&mut feet, (sk, roles), pose, &last, &[]);
    }
    assert!(feet.planted(0) && feet.planted(1), "both feet stand");
    feet
}

#[test]
fn a_planted_foot_stays_where_it_stands_as_the_body_moves() {
    let (sk, roles) = body();
    let crouch = crouched(&sk, &roles, 0.06);
    let mut feet = planted_under(&sk, &roles, &crouch);
    let before = [Role::LeftFoot, Role::RightFoot].map(|r| at(&sk, &roles, &crouch, r));
    // The posture moves the whole body 5 cm to the side: less than a
    // step, so the feet stay and the legs bend.
    let mut last = crouch.clone();
    for i in 1..=5 {
        let target = moved(&crouch, DVec3::X * 0.01 * f64::from(i));
        last = step(&mut feet, (&sk, &roles), &target, &last, &[]);
    }
    for (k, r) in [Role::LeftFoot, Role::RightFoot].into_iter().enumerate() {
        let now = at(&sk, &roles, &last, r);
        let slid = (now - before[k]).with_y(0.0).length();
        assert!(slid < 0.002, "{r:?} slid {slid:.4} m");
    }
    assert!((at(&sk, &roles, &last, Role::Pelvis).x - 0.05).abs() < 0.002);
}

#[test]
fn a_foot_held_by_a_finger_is_the_fingers() {
    let (sk, roles) = body();
    let crouch = crouched(&sk, &roles, 0.06);
    let mut feet = planted_under(&sk, &roles, &crouch);
    let before = at(&sk, &roles, &crouch, Role::LeftFoot);
    let target = moved(&crouch, DVec3::X * 0.03);
    let out = step(
        &mut feet,
        (&sk, &roles),
        &target,
        &crouch,
        &[Role::LeftFoot],
    );
    let slid = (at(&sk, &roles, &out, Role::LeftFoot) - before).x;
    assert!(
        (slid - 0.03).abs() < 1e-6,
        "the held foot went {slid:.4} m, as asked 0.03"
    );
    assert!(!feet.planted(0) && feet.planted(1));
}

#[test]
fn a_foot_the_posture_puts_far_away_steps_there_lifted_in_an_arc() {
    let (sk, roles) = body();
    let crouch = crouched(&sk, &roles, 0.1);
    let mut feet = planted_under(&sk, &roles, &crouch);
    let start = at(&sk, &roles, &crouch, Role::LeftFoot);
    let goal = start + DVec3::Z * 0.2;
    let mut last = crouch.clone();
    let mut highest = f64::NEG_INFINITY;
    // The posture carries the foot there in a fifth of a second (1 m/s).
    for i in 1..=20 {
        let along = (f64::from(i) / 6.0).min(1.0);
        let target = foot_at(
            &sk,
            &roles,
            &crouch,
            Role::LeftFoot,
            start + (goal - start) * along,
        );
        last = step(&mut feet, (&sk, &roles), &target, &last, &[]);
        highest = highest.max(at(&sk, &roles, &last, Role::LeftFoot).y - start.y);
    }
    let end = at(&sk, &roles, &last, Role::LeftFoot);
    assert!(
        (end - goal).with_y(0.0).length() < 0.015,
        "landed at {end}, asked {goal}"
    );
    assert!(highest > 0.03, "lifted {highest:.3} m on the way");
    assert!(feet.planted(0), "planted again where it landed");
}

#[test]
fn no_sole_goes_below_the_floor() {
    let (sk, roles) = body();
    let mut feet = Feet::new(&roles, &world(&sk, &standing(&sk)), 0.85);
    // The whole body 8 cm into the floor: the legs bend, or the body rises.
    let sunk = moved(&standing(&sk), DVec3::Y * -0.08);
    let out = step(&mut feet, (&sk, &roles), &sunk, &sunk, &[]);
    let w = world(&sk, &out);
    for r in [Role::LeftFoot, Role::RightFoot] {
        let y = sole(&sk, &w, roles.get(r)).y;
        assert!(y > -0.001, "{r:?}'s sole at {y:.4} m");
    }
}

#[test]
fn a_foot_that_sweeps_the_floor_fast_is_lifted_clear_of_it() {
    let (sk, roles) = body();
    let crouch = crouched(&sk, &roles, 0.1);
    let mut feet = Feet::new(&roles, &world(&sk, &standing(&sk)), 0.85);
    // The right foot slides 3 cm along the floor in one frame (0.9 m/s).
    let start = at(&sk, &roles, &crouch, Role::RightFoot);
    let swept = foot_at(
        &sk,
        &roles,
        &crouch,
        Role::RightFoot,
        start + DVec3::Z * 0.03,
    );
    let shown_last = world(&sk, &crouch);
    let s = FeetStep {
        skeleton: &sk,
        roles: &roles,
        target: &swept,
        shown_last: &shown_last,
        held: &[],
        switched: false,
        settle_s: 0.12,
        contacts: None,
        dt: DT,
    };
    let mut out = swept.clone();
    feet.clear_swept(&s, &mut out);
    let w = world(&sk, &out);
    let right = sole(&sk, &w, roles.get(Role::RightFoot)).y;
    let left = sole(&sk, &w, roles.get(Role::LeftFoot)).y;
    assert!(
        (right - CLEARANCE_M).abs() < 0.003,
        "the sweeping foot's sole at {right:.4} m"
    );
    assert!(left.abs() < 0.002, "the still foot's sole at {left:.4} m");
}

#[test]
fn the_fingers_lifting_put_a_raised_foot_down() {
    let (sk, roles) = body();
    let crouch = crouched(&sk, &roles, 0.1);
    let feet = Feet::new(&roles, &world(&sk, &standing(&sk)), 0.85);
    let start = at(&sk, &roles, &crouch, Role::LeftFoot);
    let mut target = foot_at(
        &sk,
        &roles,
        &crouch,
        Role::LeftFoot,
        start + DVec3::new(0.05, 0.25, 0.1),
    );
    feet.settle_stance(&sk, &roles, &mut target);
    for r in [Role::LeftFoot, Role::RightFoot] {
        let y = at(&sk, &roles, &target, r).y;
        assert!(
            (y - feet.ankle_rest()).abs() < 0.005,
            "{r:?}'s ankle at {y:.4} m"
        );
    }
}
