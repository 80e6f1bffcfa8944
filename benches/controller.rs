//! The whole controller step (touches → posing or action → tracking with
//! the ragdoll's physical effects → foot IK) for one character and for
//! four, with two fingers posing.
//! `cargo bench --bench controller`.

use std::sync::Arc;

use criterion::{Criterion, criterion_group, criterion_main};
use marionette::character::library::Library;
use marionette::character::roles::Role;
use marionette::control::character::Character;
use marionette::control::controller::{Controller, Settings};
use marionette::input::calibration::RawPoint;
use marionette::input::touch::{Phase, Tool};
use marionette::input::touch::{ScreenContact, ScreenFrame};
use marionette::screen::ScreenPoint;

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
        let mut ctl = Controller::new(ch.clone(), Settings::default(), 1280.0, 720.0, 0.0);
        ctl.advance(1.0 / 30.0);
        let cam = ctl.rig.camera();
        let at = |r: Role| cam.project(ctl.world().positions[ch.roles.get(r)]).unwrap();
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
}

criterion_group!(benches, bench);
criterion_main!(benches);
