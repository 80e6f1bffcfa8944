//! The record of what visitors do, measured: the table's frame (touches,
//! the controller's step, the events taken) with the record off and on in
//! one run (fingers landing and lifting every second, so rows are made
//! and written by the record's thread), and `marionette report` over a
//! busy year (a session a minute, ten hours a day, 219,000 sessions).
//! `cargo bench --bench visits`.

#[path = "../tests/common/visits_year.rs"]
mod year;

use std::sync::Arc;

use criterion::{Criterion, criterion_group, criterion_main};
use marionette::app::visits::Recording;
use marionette::app::visits::writer::Bounds;
use marionette::character::library::Library;
use marionette::character::roles::Role;
use marionette::control::character::Character;
use marionette::control::controller::{Controller, Settings};
use marionette::control::stage::Stage;
use marionette::input::calibration::RawPoint;
use marionette::input::touch::{Phase, ScreenContact, ScreenFrame, Tool};
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

fn frames(c: &mut Criterion) {
    let lib =
        Library::load(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/library"))
            .unwrap();
    let ch = Arc::new(Character::from_library(lib));
    let dir = tempfile::tempdir().unwrap();
    let mut g = c.benchmark_group("table frame");
    for on in [false, true] {
        let mut ctl = Stage::single(
            Controller::new(ch.clone(), Settings::default(), 0.0),
            1280.0,
            720.0,
        );
        ctl.advance(1.0 / 30.0);
        let cam = ctl.rig().camera();
        let hand = cam
            .project(ctl.ctl().world().positions[ch.roles.get(Role::LeftHand)])
            .unwrap();
        let mut rec = on.then(|| {
            Recording::start(
                dir.path().join("visits.db"),
                Bounds {
                    keep_days: 365,
                    max_bytes: 256_000_000,
                },
                1.8e9,
                45.0,
                (1280.0, 720.0),
            )
        });
        let mut k = 0u64;
        g.bench_function(
            if on {
                "visits record on"
            } else {
                "visits record off"
            },
            |b| {
                b.iter(|| {
                    k += 1;
                    let t = (k + 1) as f64 / 30.0;
                    // A finger on the hand, moving it a little; it lifts
                    // every second and lands again as a new touch.
                    let id = k / 30;
                    let at = ScreenPoint::new(hand.x + (t * 2.0).sin() * 20.0, hand.y);
                    let phase = match k % 30 {
                        0 => Phase::Down,
                        29 => Phase::Up,
                        _ => Phase::Move,
                    };
                    ctl.touch(&ScreenFrame {
                        t,
                        contacts: vec![contact(id, phase, at)],
                    });
                    ctl.advance(t);
                    let events = ctl.take_events();
                    let touches = ctl.take_touches();
                    if let Some(r) = &mut rec {
                        r.frame(&touches, &events, t, true);
                    }
                });
            },
        );
        if let Some(r) = rec {
            let (counts, written) = r.finish();
            assert!(counts.touches > 0 && written.all());
        }
    }
    g.finish();
}

fn report(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    let db = dir.path().join("visits.db");
    year::write_year(&db, 365, 256_000_000);
    let mut g = c.benchmark_group("report");
    g.sample_size(10);
    g.bench_function(
        "a busy year (219,000 sessions): report.json and report.html",
        |b| {
            b.iter(|| {
                let r = marionette::app::report::gather(
                    &db,
                    marionette::app::report::Since::All,
                    year::YEAR_START_MS + 366 * year::DAY_MS,
                )
                .unwrap();
                assert_eq!(r.sessions, 365 * 600);
                marionette::app::report::write(&r, &dir.path().join("out")).unwrap();
            });
        },
    );
    g.finish();
}

criterion_group!(benches, frames, report);
criterion_main!(benches);
