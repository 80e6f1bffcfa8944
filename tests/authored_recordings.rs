//! Recordings the project authors itself (assets/recordings, tests/data) are
//! exactly what the synthesiser produces: regenerate them with
//! `MARIONETTE_REGENERATE=1 cargo test --test authored_recordings`.

mod common;

use std::path::Path;

use marionette::input::synth::{self, Synth};

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
