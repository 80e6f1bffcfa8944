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

/// Run the marionette binary with `args` (RUST_LOG cleared, so the log
/// level is the configuration's), and what it printed and returned.
pub fn marionette(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_marionette"))
        .args(args)
        .env_remove("RUST_LOG")
        .output()
        .expect("run marionette")
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

/// A real touchscreen's single-finger drag (Atmel maXTouch).
pub const ATMEL_DRAG: &str = "recordings/evemu/atmel-maxtouch.1-finger-drag-up-down.evemu";

/// The Atmel drag as an eGalax 0eef:0001 single-touch panel reports it:
/// its single-touch position on `ABS_Z`/`ABS_RX`, `BTN_TOOL_PEN` with every
/// `BTN_TOUCH`, no multitouch axes.
pub fn egalax_like() -> marionette::input::evemu::Recording {
    use marionette::input::device::{BitSet, DeviceDescription, InputId};
    use marionette::input::evemu::Recording;
    use marionette::input::event::{
        ABS_X, ABS_Y, BTN_TOOL_PEN, BTN_TOUCH, EV_ABS, EV_KEY, EV_SYN, RawEvent,
    };
    const ABS_Z: u16 = 0x02;
    const ABS_RX: u16 = 0x03;
    let real = Recording::read_file(&shared_dir().join(ATMEL_DRAG)).unwrap();
    let mut device = DeviceDescription {
        name: "eGalax Inc. USB TouchController".to_owned(),
        id: InputId {
            bustype: 3,
            vendor: 0x0eef,
            product: 0x0001,
            version: 0x0100,
        },
        ..DeviceDescription::default()
    };
    device.bits = vec![BitSet::default(); usize::from(EV_ABS) + 1];
    device.bits[usize::from(EV_SYN)].insert(0);
    for k in [BTN_TOUCH, BTN_TOOL_PEN] {
        device.bits[usize::from(EV_KEY)].insert(k);
    }
    for (from, to) in [(ABS_X, ABS_Z), (ABS_Y, ABS_RX)] {
        device.bits[usize::from(EV_ABS)].insert(to);
        device.abs.insert(to, real.device.abs[&from]);
    }
    let mut events = Vec::new();
    for e in &real.events {
        match (e.kind, e.code) {
            (EV_ABS, ABS_X) => events.push(RawEvent::new(e.time_us, EV_ABS, ABS_Z, e.value)),
            (EV_ABS, ABS_Y) => events.push(RawEvent::new(e.time_us, EV_ABS, ABS_RX, e.value)),
            (EV_ABS, _) => {}
            (EV_KEY, BTN_TOUCH) => {
                events.push(RawEvent::new(e.time_us, EV_KEY, BTN_TOOL_PEN, e.value));
                events.push(*e);
            }
            _ => events.push(*e),
        }
    }
    Recording {
        device,
        events,
        ..real
    }
}

/// The Bandai split the recognition tests use: a library's takes from six
/// styles of ten actions (and the single normal takes of punch, kick and
/// slash), and the four other styles held out. `d1_<action>_<style>_001.bvh`
/// is linked as `<action>_<style>_001.bvh` (`library init` names actions
/// by the text before the first `_`).
pub mod bandai {
    use std::path::Path;

    pub const LIBRARY_STYLES: [&str; 6] = [
        "active",
        "angry",
        "feminine",
        "happy",
        "masculinity",
        "proud",
    ];
    pub const HELD_OUT_STYLES: [&str; 4] = ["childish", "giant", "musical", "normal"];
    pub const ACTIONS: [&str; 10] = [
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
    ];
    /// Actions the share has one take of (normal style): library only.
    pub const ONE_TAKE: [&str; 3] = ["punch", "kick", "slash"];

    fn link(dir: &Path, action: &str, style: &str) {
        let bandai = super::shared_dir().join("mocap/bandai");
        std::os::unix::fs::symlink(
            bandai.join(format!("d1_{action}_{style}_001.bvh")),
            dir.join(format!("{action}_{style}_001.bvh")),
        )
        .unwrap();
    }

    /// The library `library init` makes of the library's takes, in
    /// `dir` (its takes linked into `dir/takes`, the library in
    /// `dir/lib`, whose path is returned).
    pub fn library(dir: &Path) -> std::path::PathBuf {
        let takes = dir.join("takes");
        std::fs::create_dir_all(&takes).unwrap();
        split(&takes, None);
        let lib = dir.join("lib");
        let out = super::marionette(&[
            "library",
            "init",
            takes.to_str().unwrap(),
            "--out",
            lib.to_str().unwrap(),
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        lib
    }

    /// The library's takes into `takes`, the held-out ones into `held`
    /// (when given); both folders must exist.
    pub fn split(takes: &Path, held: Option<&Path>) {
        for action in ACTIONS {
            for style in LIBRARY_STYLES {
                link(takes, action, style);
            }
            if let Some(held) = held {
                for style in HELD_OUT_STYLES {
                    link(held, action, style);
                }
            }
        }
        for action in ONE_TAKE {
            link(takes, action, "normal");
        }
    }
}

/// Pixels of two pictures of one size (RGBA) whose colour differs by more
/// than `by` of 255 in some channel.
pub fn pixels_apart(a: &[u8], b: &[u8], by: u8) -> usize {
    a.chunks(4)
        .zip(b.chunks(4))
        .filter(|(p, q)| (0..3).any(|c| p[c].abs_diff(q[c]) > by))
        .count()
}

/// The largest resident set (bytes) of the children this process has
/// waited for: in a test binary of one test, that test's child.
#[must_use]
pub fn children_peak_bytes() -> f64 {
    // SAFETY: rusage is plain integers, for which zero is a value.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    // SAFETY: getrusage writes only the struct it is given.
    let done = unsafe { libc::getrusage(libc::RUSAGE_CHILDREN, &mut usage) };
    assert_eq!(done, 0);
    usage.ru_maxrss as f64 * 1024.0
}
