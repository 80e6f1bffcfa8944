//! Action recognition cost: the paper's rule per frame (a 1-second trail
//! of 30 points matched against 10 actions' projected trajectories), and
//! the template recogniser per drag point (a 1-second drag of 60 points fed
//! point by point, against the default library and against a library of a
//! studio's capture, the Bandai share beside the checkout, built by
//! `library init`: 19 actions, 108 clips). `cargo bench --bench actions`.

#![allow(
    clippy::print_stderr,
    reason = "the bench says what it could not time and what it timed"
)]

use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use marionette::character::body::{Anchor, Placement};
use marionette::character::camera::Camera;
use marionette::character::library::Library;
use marionette::control::action::model::ActionModel;
use marionette::control::action::trail::{StartRule, TrailPoint, match_trail};

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

/// The Bandai share's six styles of its actions (and its one take of
/// punch, kick and slash) as `library init` makes them into a library.
fn bandai_library(dir: &std::path::Path) -> Option<Library> {
    let shared = std::env::var_os("MARIONETTE_SHARED").map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared"),
        PathBuf::from,
    );
    let bandai = shared.join("mocap/bandai");
    if !bandai.is_dir() {
        return None;
    }
    let takes = dir.join("takes");
    std::fs::create_dir_all(&takes).ok()?;
    for action in [
        "bow",
        "bye",
        "byebye",
        "guide",
        "walk",
        "walk-back",
        "walk-left",
        "walk-right",
        "run",
        "dash",
    ] {
        for style in [
            "active",
            "angry",
            "feminine",
            "happy",
            "masculinity",
            "proud",
        ] {
            let name = format!("{action}_{style}_001.bvh");
            std::os::unix::fs::symlink(bandai.join(format!("d1_{name}")), takes.join(&name))
                .ok()?;
        }
    }
    for action in ["punch", "kick", "slash"] {
        let name = format!("{action}_normal_001.bvh");
        std::os::unix::fs::symlink(bandai.join(format!("d1_{name}")), takes.join(&name)).ok()?;
    }
    let lib_dir = dir.join("lib");
    std::fs::create_dir_all(&lib_dir).ok()?;
    let plan = marionette::tools::init::plan(&takes).ok()?;
    std::fs::write(lib_dir.join("library.toml"), plan.to_toml(&lib_dir)).ok()?;
    Library::load(&lib_dir).ok()
}

fn templates(c: &mut Criterion) {
    use marionette::character::roles::Role;
    use marionette::control::action::recogniser::{DragMatch, Recogniser};
    let tmp = std::env::temp_dir().join(format!("marionette-bench-{}", std::process::id()));
    let default_lib =
        Library::load(&PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/library")).unwrap();
    let mut libs = vec![("default", default_lib)];
    match bandai_library(&tmp) {
        Some(lib) => libs.push(("bandai", lib)),
        None => eprintln!("../shared/mocap/bandai not found: the Bandai library is not timed"),
    }
    let cam = Camera {
        eye: DVec3::new(-3.0, 1.3, 0.0),
        target: DVec3::new(0.0, 1.3, 0.0),
        fov_y_deg: 45.0,
        width: 1280.0,
        height: 720.0,
    };
    let at = Placement {
        position: DVec3::ZERO,
        yaw: 0.0,
        anchor: Anchor::ClipStart,
    };
    // One second of a quick drag, 60 points (a 60 Hz panel).
    let trail: Vec<TrailPoint> = (0..60)
        .map(|k| {
            let s = f64::from(k) / 59.0;
            TrailPoint {
                at: marionette::screen::ScreenPoint::new(
                    600.0 + 300.0 * s,
                    300.0 - 80.0 * (s * 6.0).sin(),
                ),
                t: s,
            }
        })
        .collect();
    for (name, lib) in &libs {
        let models: Vec<ActionModel> = lib
            .actions
            .iter()
            .map(|a| ActionModel::build(lib, a))
            .collect();
        let recogniser = Recogniser::default();
        // The right hand leads the most actions in both libraries.
        let role = Role::RightHand;
        let n = models
            .iter()
            .filter(|m| m.def.primary == role)
            .map(|m| m.templates.len())
            .sum::<usize>();
        eprintln!("{name}: {n} templates of the right hand");
        c.bench_function(&format!("templates/{name}/right_hand/60_points"), |b| {
            b.iter(|| {
                let mut m = DragMatch::new(&recogniser, &models, role, &cam, &at, None);
                let mut started = 0;
                for p in &trail {
                    m.push(*p);
                    started += usize::from(m.decide(&models, &recogniser.thresholds).is_some());
                }
                started
            });
        });
    }
    let _ = std::fs::remove_dir_all(&tmp);
}

criterion_group!(benches, actions, templates);
criterion_main!(benches);
