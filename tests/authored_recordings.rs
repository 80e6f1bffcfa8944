//! Recordings the project authors itself (assets/recordings, tests/data) are
//! exactly what the synthesiser produces: regenerate them with
//! `MARIONETTE_REGENERATE=1 cargo test --test authored_recordings`.

mod common;

use std::path::Path;

use marionette::tools::synth;
use marionette::tools::synth::Synth;

fn check(path: &Path, synth: &Synth) {
    let text = synth.to_text();
    if std::env::var_os("MARIONETTE_REGENERATE").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, &text).unwrap();
    }
    let on_disk = std::fs::read_to_string(path).unwrap_or_else(|e| {
        panic!(
            "{}: {e}; regenerate with MARIONETTE_REGENERATE=1",
            path.display()
        )
    });
    assert!(
        on_disk == text,
        "{} differs from what the synthesiser writes; regenerate with MARIONETTE_REGENERATE=1",
        path.display()
    );
}

#[test]
fn demo_recording_is_regenerated_identically() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/recordings/demo-two-hands.evemu");
    check(&path, &synth::demo_two_hands());
}

#[test]
fn character_demo_recording_is_regenerated_identically() {
    // Authored against the default library's character: the drags start on
    // the body parts and follow the actions' trajectories.
    let config = marionette::app::config::Config::default();
    let settings = config.control_settings();
    let synth = marionette::tools::demo::author_demo(
        common::character(),
        settings,
        &config.input,
        config.display.picture(),
    );
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/recordings/demo.evemu");
    check(&path, &synth);
}

#[test]
fn duel_recording_is_regenerated_identically() {
    // Authored against two of the default library's characters facing
    // each other as `demo --scene duel` places them.
    let config = marionette::app::config::Config::default().duel();
    let stage = marionette::app::headless::table(
        vec![common::character(), common::character()],
        &config,
        true,
        0.0,
    );
    let synth =
        marionette::tools::demo::author_duel(stage, &config.input, config.display.picture());
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/recordings/duel.evemu");
    check(&path, &synth);
}

/// Four fingers moving for 600 frames with no time between them: played
/// through uinput this overflows the evdev buffer of a reader that is not
/// scheduled in time (a real SYN_DROPPED); then they rest and lift.
fn burst() -> Synth {
    let mut s = Synth::new(synth::panel("marionette burst panel", 10, 4095));
    for f in 0..4 {
        s.down(f, 500 + f * 800, 2000);
    }
    s.frame(0);
    for k in 0..600 {
        for f in 0..4 {
            let t = f64::from(k) / 40.0 + f64::from(f);
            s.to(
                f,
                500 + f * 800 + (300.0 * t.sin()) as i32,
                2000 + (900.0 * t.cos()) as i32,
            );
        }
        s.frame(0);
    }
    s.frame(500_000);
    for f in 0..4 {
        s.up(f);
    }
    s.frame(10_000);
    s
}

/// Two fingers drag and the recording stops with them down: played through
/// uinput, the device disappears mid-drag.
fn unplug_mid_drag() -> Synth {
    let mut s = Synth::new(synth::panel("marionette unplug panel", 10, 4095));
    s.down(0, 1000, 1000).down(1, 3000, 3000).frame(16_667);
    s.glide(&[(0, 1500, 1200), (1, 2600, 2800)], 20, 16_667);
    s
}

#[test]
fn vm_recordings_are_regenerated_identically() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    check(&dir.join("burst-overflow.evemu"), &burst());
    check(&dir.join("unplug-mid-drag.evemu"), &unplug_mid_drag());
}
