//! The whole controller step (touches → posing or action → tracking with
//! the ragdoll's physical effects → foot IK) for one character and for
//! four, with two fingers posing; and tables of two and four characters
//! standing within reach of each other, a finger posing each one's hand,
//! collisions between their bodies included; and one character walking
//! after a finger that leads its pelvis round a circle on the floor, alone
//! and with a wave laid over the walk by a second finger.
//! `cargo bench --bench controller`.

#![allow(clippy::print_stderr, reason = "the contacts seen are printed")]

use std::sync::Arc;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use marionette::character::library::Library;
use marionette::character::roles::Role;
use marionette::control::character::Character;
use marionette::control::controller::{Controller, Mode, Settings};
use marionette::control::stage::{Actor, Stage};
use marionette::input::calibration::RawPoint;
use marionette::input::touch::{Phase, Tool};
use marionette::input::touch::{ScreenContact, ScreenFrame};
use marionette::screen::ScreenPoint;
use marionette::tools::eval::layer::SecondFinger;

fn contact(id: u64, phase: Phase, at: ScreenPoint) -> ScreenContact {
    ScreenContact {
        id,
        phase,
        tool: Tool::Finger,
        raw: RawPoint { x: 0, y: 0 },
        screen: at,
    }
}

fn bench(c: &mut Criterion) {
    let lib =
        Library::load(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/library"))
            .unwrap();
    let ch = Arc::new(Character::from_library(lib));
    let make = || {
        let mut ctl = Stage::single(
            Controller::new(ch.clone(), Settings::default(), 0.0),
            1280.0,
            720.0,
        );
        ctl.advance(1.0 / 30.0);
        let cam = ctl.rig().camera();
        let at = |r: Role| {
            cam.project(ctl.ctl().world().positions[ch.roles.get(r)])
                .unwrap()
        };
        let (l, r) = (at(Role::LeftHand), at(Role::RightHand));
        ctl.touch(&ScreenFrame {
            t: 0.04,
            contacts: vec![contact(1, Phase::Down, l), contact(2, Phase::Down, r)],
        });
        (ctl, l, r)
    };
    let mut g = c.benchmark_group("controller step");
    for n in [1usize, 4] {
        let mut ctls: Vec<_> = (0..n).map(|_| make()).collect();
        let mut k = 2u32;
        g.bench_function(format!("{n} character(s), two fingers posing"), |b| {
            b.iter(|| {
                k += 1;
                let t = f64::from(k) / 30.0;
                // A slow circle: posing, never an action.
                let a = t * 0.8;
                for (ctl, l, r) in &mut ctls {
                    ctl.touch(&ScreenFrame {
                        t,
                        contacts: vec![
                            contact(
                                1,
                                Phase::Move,
                                ScreenPoint::new(l.x + 40.0 * a.cos(), l.y - 40.0 * a.sin()),
                            ),
                            contact(
                                2,
                                Phase::Move,
                                ScreenPoint::new(r.x - 40.0 * a.sin(), r.y - 40.0 * a.cos()),
                            ),
                        ],
                    });
                    ctl.advance(t);
                }
            })
        });
    }
    g.finish();
    table(c, &ch);
}

/// `n` characters on a circle 0.7 m across, facing its centre: each body
/// within reach of its neighbours.
fn circle(ch: &Arc<Character>, n: usize) -> Stage {
    let actors = (0..n)
        .map(|k| {
            let a = k as f64 / n as f64 * std::f64::consts::TAU;
            let at = glam::DVec3::new(0.35 * a.cos(), 0.0, 0.35 * a.sin());
            // Facing the centre: yaw 0 faces +Z.
            let yaw = (-at.x).atan2(-at.z);
            Actor::standing(ch.clone(), Settings::default(), at, yaw, None)
        })
        .collect();
    Stage::new(actors, 1280.0, 720.0, 0.0)
}

fn table(c: &mut Criterion, ch: &Arc<Character>) {
    let mut g = c.benchmark_group("table step");
    for n in [2usize, 4] {
        let mut stage = circle(ch, n);
        stage.advance(1.0 / 30.0);
        let cam = stage.rig().camera();
        let hands: Vec<ScreenPoint> = stage
            .actors()
            .iter()
            .map(|a| {
                let w = a.ctl.world();
                cam.project(w.positions[ch.roles.get(Role::RightHand)])
                    .unwrap()
            })
            .collect();
        stage.touch(&ScreenFrame {
            t: 0.04,
            contacts: hands
                .iter()
                .enumerate()
                .map(|(k, p)| contact(k as u64 + 1, Phase::Down, *p))
                .collect(),
        });
        let mut k = 2u32;
        let mut hits = 0usize;
        let mut deepest: f64 = 0.0;
        g.bench_function(
            format!("{n} characters in reach, a finger posing each"),
            |b| {
                b.iter(|| {
                    k += 1;
                    let t = f64::from(k) / 30.0;
                    let a = t * 0.8;
                    stage.touch(&ScreenFrame {
                        t,
                        contacts: hands
                            .iter()
                            .enumerate()
                            .map(|(i, p)| {
                                contact(
                                    i as u64 + 1,
                                    Phase::Move,
                                    ScreenPoint::new(p.x + 60.0 * a.cos(), p.y - 60.0 * a.sin()),
                                )
                            })
                            .collect(),
                    });
                    stage.advance(t);
                    hits += stage.take_hits().len();
                    deepest = deepest.max(stage.depth_left());
                })
            },
        );
        eprintln!(
            "{n} characters: {hits} hits over {k} steps, deepest overlap left {deepest:.3} m"
        );
    }
    // Walking: the pelvis finger goes round a circle of 1.2 m about where
    // the character stood, at 0.8 m/s, put each step over the circle's
    // point at the pelvis's height as the camera shows it then.
    let mut ctl = Stage::single(
        Controller::new(ch.clone(), Settings::default(), 0.0),
        1280.0,
        720.0,
    );
    ctl.advance(1.0 / 30.0);
    let pelvis = ctl.ctl().world().positions[ch.roles.get(Role::Pelvis)];
    let on_circle = |t: f64| {
        let a = t * 0.8 / 1.2;
        pelvis + glam::DVec3::new(1.2 * a.cos() - 1.2, 0.0, 1.2 * a.sin())
    };
    let down = ctl.rig().camera().project(pelvis).unwrap();
    ctl.touch(&ScreenFrame {
        t: 0.04,
        contacts: vec![contact(1, Phase::Down, down)],
    });
    let mut k = 2u32;
    let mut step = |ctl: &mut Stage| {
        k += 1;
        let t = f64::from(k) / 30.0;
        let at = ctl.rig().camera().project(on_circle(t - 0.07)).unwrap();
        ctl.touch(&ScreenFrame {
            t,
            contacts: vec![contact(1, Phase::Move, at)],
        });
        ctl.advance(t);
        matches!(ctl.ctl().mode(), Mode::Walk(_))
    };
    for _ in 0..60 {
        step(&mut ctl);
    }
    let (mut walking, mut steps) = (0usize, 0usize);
    g.bench_function("1 character walking after the pelvis finger", |b| {
        b.iter(|| {
            walking += usize::from(step(&mut ctl));
            steps += 1;
        })
    });
    eprintln!("walking in {walking} of {steps} measured steps");
    // The same walk with a wave laid over it: a second finger drags the
    // left hand's wave as it walks (as `eval walk --layer` does); each
    // measured step starts from a copy of the controller with the wave at
    // full weight.
    let wave = ch
        .actions
        .iter()
        .position(|a| a.def.name == "wave_left")
        .unwrap();
    let mut ctl = Stage::single(
        Controller::new(ch.clone(), Settings::default(), 0.0),
        1280.0,
        720.0,
    );
    ctl.advance(1.0 / 30.0);
    ctl.touch(&ScreenFrame {
        t: 0.04,
        contacts: vec![contact(1, Phase::Down, down)],
    });
    let mut second = SecondFinger::new(wave);
    let frame = |ctl: &Stage, second: &mut SecondFinger, k: u32| {
        let t = f64::from(k) / 30.0;
        let at = ctl.rig().camera().project(on_circle(t - 0.07)).unwrap();
        let mut contacts = vec![contact(1, Phase::Move, at)];
        if let Some((phase, p)) = second.contact(ch, ctl.ctl(), &ctl.rig().camera(), t) {
            contacts.push(contact(2, phase, p));
        }
        ScreenFrame { t, contacts }
    };
    let mut k = 2u32;
    while ctl.ctl().layered().is_none_or(|l| l.weight < 1.0) {
        k += 1;
        assert!(k < 600, "the wave was not laid over the walk");
        let f = frame(&ctl, &mut second, k);
        ctl.step(std::slice::from_ref(&f), f.t);
    }
    assert!(matches!(ctl.ctl().mode(), Mode::Walk(_)), "walking");
    let next = frame(&ctl, &mut second, k + 1);
    g.bench_function("1 character walking with a wave laid over it", |b| {
        b.iter_batched_ref(
            || ctl.clone(),
            |c| c.step(std::slice::from_ref(&next), next.t),
            BatchSize::SmallInput,
        );
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
