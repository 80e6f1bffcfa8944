//! Events per second through the input stack: evemu parsing, the contact
//! tracker, calibration to screen pixels. Run with
//! `cargo bench --bench input_pipeline`.
//!
//! Inputs: a synthesised 10-finger recording (always available) and the
//! real 3M 10-finger capture from ../shared when it is there.

use std::hint::black_box;
use std::path::{Path, PathBuf};

use criterion::{Criterion, Throughput, criterion_group, criterion_main};

use marionette::input::calibration::{Calibration, Matrix};
use marionette::input::evemu::Recording;
use marionette::input::tracker::{ContactTracker, ResyncSource};
use marionette::screen::Rotation;
use marionette::tools::synth::{Synth, panel};

/// Ten fingers wandering for `frames` frames at 120 Hz.
fn ten_fingers(frames: u32) -> String {
    let mut s = Synth::new(panel("bench panel", 10, 32767));
    for f in 0..10 {
        s.down(f, 3000 + f * 2500, 16000);
    }
    s.frame(8333);
    for k in 0..frames {
        for f in 0..10 {
            let t = f64::from(k) / 60.0 + f64::from(f);
            s.to(
                f,
                (3000.0 + f64::from(f) * 2500.0 + 1500.0 * t.sin()) as i32,
                (16000.0 + 9000.0 * t.cos()) as i32,
            );
        }
        s.frame(8333);
    }
    for f in 0..10 {
        s.up(f);
    }
    s.frame(8333);
    s.to_text()
}

/// Every event through a fresh tracker, every contact to screen pixels.
fn track_and_calibrate(rec: &Recording, cal: &Calibration) -> f64 {
    let mut t = ContactTracker::new(&rec.device, ResyncSource::Reconcile, 0).unwrap();
    let mut frames = Vec::new();
    let mut sum = 0.0;
    for e in &rec.events {
        t.push(e, &mut frames);
        for f in frames.drain(..) {
            for c in &f.contacts {
                sum += cal.to_screen(c.raw).x;
            }
        }
    }
    black_box(sum)
}

fn bench_input(c: &mut Criterion, name: &str, text: &str) {
    let rec = Recording::parse(text, Path::new(name)).unwrap();
    let events = rec.events.len() as u64;
    let (x, y) = rec.device.position_axes().unwrap();
    let cal = Calibration::new(&x, &y, Matrix::IDENTITY, Rotation::R0, (1920, 1080)).unwrap();
    let mut g = c.benchmark_group(format!("input/{name}"));
    g.throughput(Throughput::Elements(events));
    g.bench_function("parse", |b| {
        b.iter(|| Recording::parse(black_box(text), Path::new(name)).unwrap())
    });
    g.bench_function("track+calibrate", |b| {
        b.iter(|| track_and_calibrate(&rec, &cal))
    });
    g.bench_function("parse+track+calibrate", |b| {
        b.iter(|| {
            let rec = Recording::parse(black_box(text), Path::new(name)).unwrap();
            track_and_calibrate(&rec, &cal)
        })
    });
    g.finish();
}

fn input(c: &mut Criterion) {
    bench_input(c, "synth-10-fingers", &ten_fingers(2000));
    let shared = std::env::var_os("MARIONETTE_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared"));
    let real = shared.join("recordings/evemu/evemu-data.3m-microtouch-usb.evemu");
    if let Ok(text) = std::fs::read_to_string(&real) {
        bench_input(c, "3m-microtouch-10-fingers", &text);
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).measurement_time(std::time::Duration::from_secs(4));
    targets = input
}
criterion_main!(benches);
