//! Action recognition cost per frame: a 1-second trail (30 points) matched
//! against 10 actions' projected trajectories, with the start rule.
//! `cargo bench --bench actions`.

use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use marionette::character::camera::Camera;
use marionette::character::library::Library;
use marionette::control::action::model::ActionModel;
use marionette::control::action::trail::{StartRule, TrailPoint, match_trail};
use marionette::control::posing::sample::{Anchor, Placement};

fn actions(c: &mut Criterion) {
    let lib =
        Library::load(&PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/library")).unwrap();
    let models: Vec<ActionModel> = lib
        .actions
        .iter()
        .take(10)
        .map(|a| ActionModel::build(&lib, a))
        .collect();
    assert_eq!(models.len(), 10);
    let cam = Camera {
        eye: DVec3::new(3.0, 1.1, 0.0),
        target: DVec3::new(0.0, 1.1, 0.0),
        fov_y_deg: 45.0,
        width: 1280.0,
        height: 720.0,
    };
    let at = Placement {
        position: DVec3::ZERO,
        yaw: 0.0,
        anchor: Anchor::ClipStart,
    };
    // One second of a drag, 30 points.
    let trail: Vec<TrailPoint> = (0..30)
        .map(|k| {
            let s = f64::from(k) / 29.0;
            TrailPoint {
                at: marionette::screen::ScreenPoint::new(600.0 + 200.0 * s, 300.0 - 40.0 * s),
                t: s,
            }
        })
        .collect();
    let rule = StartRule::default();
    c.bench_function("recognition/10_actions/1s_trail", |b| {
        b.iter(|| {
            let mut started = 0;
            for m in &models {
                let projected = m.projected(&cam, &at);
                if let Some(r) = match_trail(&trail, &projected, rule.h, rule.tempo) {
                    started += usize::from(rule.starts(&r, &trail, 60.0));
                }
            }
            started
        });
    });
}

criterion_group!(benches, actions);
criterion_main!(benches);
