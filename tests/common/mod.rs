//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

/// `../shared` beside the checkout (or `$MARIONETTE_SHARED`): real
/// recordings and motion capture used by the tests. Panics with a message
/// that says where it looked.
pub fn shared_dir() -> PathBuf {
    let dir = std::env::var_os("MARIONETTE_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared"));
    assert!(
        dir.join("recordings/INDEX.tsv").is_file(),
        "real test data not found: expected {}/recordings/INDEX.tsv (the shared folder beside the checkout); set MARIONETTE_SHARED to its path",
        dir.display()
    );
    dir
}

/// `tests/data` in this repository.
pub fn data_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data")
}

/// The default library's character (library, posing model, action models),
/// built once per test binary.
pub fn character() -> std::sync::Arc<marionette::control::character::Character> {
    use std::sync::{Arc, OnceLock};
    static CH: OnceLock<Arc<marionette::control::character::Character>> = OnceLock::new();
    CH.get_or_init(|| {
        let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/library");
        let lib = marionette::character::library::Library::load(&dir).expect("default library");
        Arc::new(marionette::control::character::Character::from_library(lib))
    })
    .clone()
}

/// A finger contact in picture pixels, for driving a controller directly.
pub fn contact(
    id: u64,
    phase: marionette::input::touch::Phase,
    at: marionette::screen::ScreenPoint,
) -> marionette::input::touch::ScreenContact {
    marionette::input::touch::ScreenContact {
        id,
        phase,
        tool: marionette::input::touch::Tool::Finger,
        raw: marionette::input::calibration::RawPoint {
            x: at.x as i32,
            y: at.y as i32,
        },
        screen: at,
    }
}
