//! Posing control: synthesis from 1 and 5 touches on about 5,000 sample
//! postures, through the grid and by scoring every sample (and the search
//! alone on about 5,000 and 10,000, and larger grid searches on 5,000);
//! and baking a model of about 10,000 postures. `cargo bench --bench posing` (needs
//! ../shared/mocap).

#![allow(
    clippy::print_stdout,
    clippy::print_stderr,
    reason = "measurements are printed for the reader of the run"
)]

use std::path::PathBuf;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use marionette::character::body::Placement;
use marionette::character::camera::Camera;
use marionette::character::library::Library;
use marionette::character::roles::Role;
use marionette::character::skeleton::forward_kinematics;
use marionette::control::posing::constraint::{Constraint, SynthOptions, Target};
use marionette::control::posing::model::{LearnedModel, posing_samples};
use marionette::control::posing::synth::{select, synthesize};

fn posing(c: &mut Criterion) {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/libraries/cmu-cc");
    let Ok(lib) = Library::load(&dir) else {
        eprintln!("skipping: ../shared/mocap is not beside the checkout");
        return;
    };
    let (_, samples) = posing_samples(&lib);
    let full = samples.len();
    let mut g = c.benchmark_group("posing");
    g.sample_size(10).measurement_time(Duration::from_secs(20));
    g.bench_function(format!("bake/{full}_postures"), |b| {
        b.iter(|| LearnedModel::build(samples.clone()))
    });
    let whole = LearnedModel::build(samples.clone());
    let model = LearnedModel::build(samples.into_iter().step_by(2).collect());
    let held_out = marionette::character::motion::Clip::from_bvh(
        marionette::character::bvh::read_file(&lib.clips_dir.join("007_12.bvh")).unwrap(),
        &Default::default(),
    )
    .unwrap();
    let (sk, roles) = (&lib.skeleton, &held_out.roles);
    let frame = &held_out.frames[60];
    let truth = forward_kinematics(sk, frame);
    let at = Placement::of(sk, roles, frame);
    let cam = Camera {
        eye: truth.positions[0] + glam::DVec3::new(3.0, 0.3, 0.0),
        target: truth.positions[0],
        fov_y_deg: 45.0,
        width: 1280.0,
        height: 720.0,
    };
    let touches = |n: usize| -> Vec<Constraint> {
        [
            Role::RightHand,
            Role::LeftHand,
            Role::RightFoot,
            Role::LeftFoot,
            Role::Head,
        ][..n]
            .iter()
            .map(|&role| {
                let p = truth.positions[roles.get(role)];
                Constraint {
                    role,
                    target: Target::Ray(cam.ray(cam.project(p).unwrap())),
                }
            })
            .collect()
    };
    let n = model.samples.len();
    g.sample_size(30).measurement_time(Duration::from_secs(5));
    for parts in [1, 5] {
        let cs = touches(parts);
        for (name, use_grid) in [("grid", true), ("all_samples", false)] {
            let opts = SynthOptions {
                use_grid,
                ..SynthOptions::default()
            };
            g.bench_function(format!("synth/{n}_postures/{parts}_touches/{name}"), |b| {
                b.iter(|| synthesize(sk, roles, &model, &cs, &at, None, &opts));
            });
            // The part the grid speeds up: finding the samples to blend.
            g.bench_function(format!("select/{n}_postures/{parts}_touches/{name}"), |b| {
                b.iter(|| select(&model, &cs, &at, &opts));
            });
            // The grid's search grows slower than the library.
            g.bench_function(
                format!("select/{full}_postures/{parts}_touches/{name}"),
                |b| {
                    b.iter(|| select(&whole, &cs, &at, &opts));
                },
            );
        }
        // Larger searches (blocks x cells; 0 blocks: every cell), which
        // come nearer scoring every sample's error.
        for (blocks, cells) in [(24, 24), (32, 32), (48, 48), (0, 16)] {
            let opts = SynthOptions {
                blocks,
                cells,
                ..SynthOptions::default()
            };
            g.bench_function(
                format!("select/{n}_postures/{parts}_touches/grid_{blocks}x{cells}"),
                |b| {
                    b.iter(|| select(&model, &cs, &at, &opts));
                },
            );
        }
    }
    g.finish();
}

criterion_group!(benches, posing);
criterion_main!(benches);
