//! `marionette calibrate`: on-screen calibration of a touchscreen. Targets
//! are drawn one after another on the KMS display (the same presenter as
//! the kiosk); at each the touch is taken from its steady samples only (a
//! finger that slides or is lifted at once is asked again); the libinput
//! matrix is solved by least squares (`input::calibration::solve`), the
//! error is shown on a check point, and the device's calibration is
//! written into the configuration file atomically (temporary file and
//! rename, the old file kept as `.bak`). Touches that do not agree are
//! refused, with the reason on screen and in the exit code; nothing is
//! written then. The procedure itself (which panel, which touches count)
//! is the state machine in [`procedure`]; this file drives it with the
//! display and the input thread.

mod procedure;

use std::path::{Path, PathBuf};
use std::time::Duration;

use thiserror::Error;

use self::procedure::{Collecting, FindDevice, Finding, Found, TARGETS, Touches};
use super::config::Config;
use super::kiosk::InputThread;
use super::message::{screen, to_output};
use crate::display::present::{OutputChoice, PresentError, PresenterKind};
use crate::display::screen::Screen;
use crate::input::calibration::{
    Calibration, CalibrationError, RawPoint, Solution, SolveOptions, solve,
};
use crate::input::hub::{HubEvent, LiveError};
use crate::platform::clock::{Clock, Monotonic};
use crate::screen::{Rotation, ScreenPoint};

/// Why calibration stopped without writing.
#[derive(Debug, Error)]
pub enum CalibrateError {
    #[error(transparent)]
    Present(#[from] PresentError),
    #[error(transparent)]
    Input(#[from] LiveError),
    #[error("{0}")]
    Device(String),
    #[error("{device}: {source}")]
    Refused {
        device: String,
        #[source]
        source: CalibrationError,
    },
    #[error(
        "no touch on target {target} within {seconds} s; calibration abandoned, nothing written"
    )]
    NoTouch { target: usize, seconds: u64 },
    #[error("stopped before the end; nothing written")]
    Stopped,
    #[error("cannot write {path}: {source}")]
    Write {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    ConfigText { path: PathBuf, message: String },
}

/// How to calibrate.
#[derive(Clone, Debug)]
pub struct CalibrateOptions {
    pub dri_dir: PathBuf,
    /// The touchscreen, by name; `None`: the only one there is.
    pub device: Option<String>,
    /// The configuration file to write the calibration into.
    pub config_path: PathBuf,
    /// How long to wait for each touch.
    pub touch_timeout: Duration,
}

/// What a calibration found.
#[derive(Clone, Debug, PartialEq)]
pub struct Calibrated {
    pub device: String,
    pub solution: Solution,
    pub written: PathBuf,
    pub backup: Option<PathBuf>,
}

/// Why the configuration text cannot take a calibration.
#[derive(Debug, Error)]
pub enum ConfigEditError {
    #[error(transparent)]
    Toml(#[from] toml_edit::TomlError),
    #[error("`input` is not a table")]
    InputNotATable,
    #[error("`input.device` is not a list of [[input.device]] tables")]
    DevicesNotTables,
}

/// The configuration text with `device`'s calibration set: its
/// `[[input.device]]` entry (by `match_name`) updated, else a new entry
/// appended. Comments and layout are kept.
pub fn with_calibration(
    text: &str,
    device: &str,
    matrix: [f64; 6],
) -> Result<String, ConfigEditError> {
    let mut doc: toml_edit::DocumentMut = text.parse()?;
    let round = |v: f64| (v * 1e6).round() / 1e6;
    let mut values = toml_edit::Array::new();
    for v in matrix {
        values.push(round(v));
    }
    let input = doc
        .entry("input")
        .or_insert_with(|| toml_edit::Item::Table(toml_edit::Table::new()))
        .as_table_mut()
        .ok_or(ConfigEditError::InputNotATable)?;
    let devices = input
        .entry("device")
        .or_insert_with(|| toml_edit::Item::ArrayOfTables(toml_edit::ArrayOfTables::new()))
        .as_array_of_tables_mut()
        .ok_or(ConfigEditError::DevicesNotTables)?;
    let existing = devices
        .iter_mut()
        .find(|t| t.get("match_name").and_then(|v| v.as_str()) == Some(device));
    match existing {
        Some(t) => {
            t["calibration"] = toml_edit::value(values);
        }
        None => {
            let mut t = toml_edit::Table::new();
            t["match_name"] = toml_edit::value(device);
            t["calibration"] = toml_edit::value(values);
            devices.push(t);
        }
    }
    Ok(doc.to_string())
}

/// Write `text` to `path` whole, keeping the old file (`old`, its text,
/// where there was one) as `.bak`; both through
/// [`crate::output::replace_file`], so a link or a device there is refused.
fn write_config(
    path: &Path,
    old: Option<&str>,
    text: &str,
) -> Result<Option<PathBuf>, CalibrateError> {
    let werr = |path: &Path| {
        let path = path.to_owned();
        move |source| CalibrateError::Write { path, source }
    };
    let backup = match old {
        Some(old) => {
            let mut bak = path.as_os_str().to_owned();
            bak.push(".bak");
            let bak = PathBuf::from(bak);
            crate::output::replace_file(&bak, old.as_bytes()).map_err(werr(&bak))?;
            Some(bak)
        }
        None => None,
    };
    crate::output::replace_file(path, text.as_bytes()).map_err(werr(path))?;
    Ok(backup)
}

/// The display the calibration draws on, its pictures turned for the
/// output's rotation.
struct Board {
    presenter: Screen,
    rotation: Rotation,
    size: (u32, u32),
}

impl Board {
    /// A picture with `lines` (and a target), shown until the next.
    fn show(
        &mut self,
        target: Option<ScreenPoint>,
        lines: &[&str],
        colour: [u8; 4],
    ) -> Result<(), CalibrateError> {
        let img = screen(self.size, target, lines, colour);
        self.presenter.show_image(&to_output(&img, self.rotation))?;
        self.presenter.wait_flip(Duration::from_millis(500))?;
        Ok(())
    }
}

/// What the touches gave: the panel, its calibration before, the targets
/// and the raw point taken at each.
struct Taken {
    device: String,
    base: Calibration,
    targets: Vec<ScreenPoint>,
    raw: Vec<RawPoint>,
}

/// Calibrate a touchscreen on the display; `config` is the configuration
/// as loaded from `opts.config_path` (or the defaults if it is missing).
pub fn calibrate(config: &Config, opts: &CalibrateOptions) -> Result<Calibrated, CalibrateError> {
    crate::platform::signals::install_stop_handler();
    let choice = OutputChoice::from_config(&config.display);
    let kind = PresenterKind::parse(&config.display.presenter).unwrap_or_default();
    let presenter = Screen::open_for_pictures(&opts.dri_dir, &choice, kind)?;
    let (ow, oh) = presenter.size();
    let mut config = config.clone();
    config.display.width = ow;
    config.display.height = oh;
    let mut board = Board {
        presenter,
        rotation: config.display.rotation(),
        size: config.display.size(),
    };
    board.show(None, &["looking for touchscreens..."], [200, 200, 200, 255])?;
    let clock = Monotonic;
    let start_us = clock.now_us();
    let input = InputThread::start(config.clone(), start_us)?;
    let now = || (clock.now_us() - start_us) as f64 / 1e6;
    let taken = take_touches(&mut board, &input, &config, opts, &now);
    input.stop();
    let taken = taken?;
    let (targets, raw) = (&taken.targets, &taken.raw);
    let pairs: Vec<(ScreenPoint, RawPoint)> = targets[..4]
        .iter()
        .copied()
        .zip(raw[..4].iter().copied())
        .collect();
    let solved = solve(
        &taken.base,
        &pairs,
        (targets[4], raw[4]),
        SolveOptions::default(),
    );
    let solution = match solved {
        Ok(s) => s,
        Err(source) => {
            let why = source.to_string();
            board.show(
                None,
                &[
                    "calibration refused, nothing written:",
                    &why,
                    "run `marionette calibrate` again",
                ],
                [255, 120, 100, 255],
            )?;
            std::thread::sleep(Duration::from_secs(3));
            return Err(CalibrateError::Refused {
                device: taken.device,
                source,
            });
        }
    };
    let backup = store(&opts.config_path, &taken.device, &solution)?;
    let done = format!(
        "calibrated: the check point is off by {:.1} px (fit {:.1} px)",
        solution.check_error_px, solution.rms_px
    );
    let wrote = format!("written to {}", opts.config_path.display());
    board.show(Some(targets[4]), &[&done, &wrote], [140, 230, 140, 255])?;
    tracing::info!(
        device = %taken.device,
        check_error_px = solution.check_error_px,
        rms_px = solution.rms_px,
        matrix = ?solution.matrix.0,
        config = %opts.config_path.display(),
        "calibration written"
    );
    std::thread::sleep(Duration::from_secs(2));
    Ok(Calibrated {
        device: taken.device,
        solution,
        written: opts.config_path.clone(),
        backup,
    })
}

/// Find the touchscreen (named, or the only one) and take a touch at each
/// target, showing them one by one.
fn take_touches(
    board: &mut Board,
    input: &InputThread,
    config: &Config,
    opts: &CalibrateOptions,
    now: &dyn Fn() -> f64,
) -> Result<Taken, CalibrateError> {
    let mut events = Vec::new();
    let found = find_panel(input, opts.device.clone(), now, &mut events)?;
    let dev_name = found.name;
    tracing::info!(device = %dev_name, path = %found.path.display(), "calibrating");
    let desc = crate::platform::evdev::EvdevDevice::open(&found.path)
        .map(|d| crate::input::hub::EventDevice::description(&d).clone())
        .map_err(|source| LiveError::Io {
            path: found.path.clone(),
            source,
        })?;
    let base =
        crate::input::pipeline::calibration_for(&config.input, config.display.picture(), &desc)
            .map_err(|e| CalibrateError::Device(e.to_string()))?;
    let (xa, ya) = desc
        .position_axes()
        .ok_or_else(|| CalibrateError::Device(format!("{dev_name} has no position axes")))?;
    let range = (
        f64::from(xa.maximum) - f64::from(xa.minimum),
        f64::from(ya.maximum) - f64::from(ya.minimum),
    );
    let size = board.size;
    let targets: Vec<ScreenPoint> = TARGETS
        .iter()
        .map(|(fx, fy)| ScreenPoint::new(fx * f64::from(size.0), fy * f64::from(size.1)))
        .collect();
    let mut touches = Touches::new(
        found.device,
        range,
        targets.len(),
        opts.touch_timeout.as_secs_f64(),
        now(),
    );
    let mut next = touches.first();
    loop {
        match next {
            Collecting::Show { target, hint } => {
                let title = format!(
                    "touch the centre of the target and hold still ({}/{})",
                    target + 1,
                    targets.len()
                );
                let lines = [dev_name.as_str(), &title, hint.unwrap_or("")];
                board.show(Some(targets[target]), &lines, [230, 230, 230, 255])?;
            }
            Collecting::TimedOut { target } => {
                return Err(CalibrateError::NoTouch {
                    target: target + 1,
                    seconds: opts.touch_timeout.as_secs(),
                });
            }
            Collecting::Done(raw) => {
                return Ok(Taken {
                    device: dev_name,
                    base,
                    targets,
                    raw,
                });
            }
            Collecting::Waiting => {}
        }
        if crate::platform::signals::stop_requested() {
            return Err(CalibrateError::Stopped);
        }
        std::thread::sleep(Duration::from_millis(10));
        input.drain(&mut events);
        next = touches.step(now(), events.drain(..));
    }
}

/// The touchscreen to calibrate: `wanted`, or the only one there is.
fn find_panel(
    input: &InputThread,
    wanted: Option<String>,
    now: &dyn Fn() -> f64,
    events: &mut Vec<HubEvent>,
) -> Result<Found, CalibrateError> {
    let mut find = FindDevice::new(wanted, now());
    loop {
        input.drain(events);
        match find.step(now(), events.drain(..)) {
            Finding::Found(d) => return Ok(d),
            Finding::Failed(why) => return Err(CalibrateError::Device(why)),
            Finding::Waiting => {}
        }
        if crate::platform::signals::stop_requested() {
            return Err(CalibrateError::Stopped);
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// Write `solution` as `device`'s calibration into the configuration file
/// at `path` (kept as `.bak`), never a file the kiosk would refuse.
fn store(
    path: &Path,
    device: &str,
    solution: &Solution,
) -> Result<Option<PathBuf>, CalibrateError> {
    let max = crate::app::config::MAX_CONFIG_BYTES;
    let old = match crate::reading::read_text(path, max).map_err(std::io::Error::from) {
        Ok(t) => Some(t),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
        Err(source) => {
            return Err(CalibrateError::Write {
                path: path.to_owned(),
                source,
            });
        }
    };
    let text = old.as_deref().unwrap_or_default();
    let cerr = |message: String| CalibrateError::ConfigText {
        path: path.to_owned(),
        message,
    };
    let new_text =
        with_calibration(text, device, solution.matrix.0).map_err(|e| cerr(e.to_string()))?;
    Config::parse(&new_text, path).map_err(|e| cerr(e.to_string()))?;
    write_config(path, old.as_deref(), &new_text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_calibration_goes_into_the_config_keeping_comments() {
        let text = "# kiosk settings\n[display]\nrotation = 0 # upright\n\n[[input.device]]\nmatch_name = \"Other\"\ncalibration = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0]\n";
        let m = [1.02, 0.0, -0.01, 0.0, 0.98, 0.015];
        let out = with_calibration(text, "Panel", m).unwrap();
        assert!(out.contains("# kiosk settings") && out.contains("# upright"));
        let c = Config::parse(&out, Path::new("m.toml")).unwrap();
        assert_eq!(c.input.device.len(), 2);
        assert_eq!(c.input.device[1].match_name.as_deref(), Some("Panel"));
        assert_eq!(c.input.device[1].calibration, m);
        // Again: the entry is updated, not added.
        let again = with_calibration(&out, "Panel", [1.0, 0.0, 0.0, 0.0, 1.0, 0.0]).unwrap();
        let c = Config::parse(&again, Path::new("m.toml")).unwrap();
        assert_eq!(c.input.device.len(), 2);
        assert_eq!(
            c.input.device[1].calibration,
            [1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        );
        // An empty file gets a section.
        let fresh = with_calibration("", "Panel", m).unwrap();
        assert_eq!(
            Config::parse(&fresh, Path::new("m.toml"))
                .unwrap()
                .input
                .device
                .len(),
            1
        );
    }

    #[test]
    fn writing_keeps_the_old_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("marionette.toml");
        std::fs::write(&p, "old").unwrap();
        let bak = write_config(&p, Some("old"), "new").unwrap().unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "new");
        assert_eq!(std::fs::read_to_string(bak).unwrap(), "old");
        // Nothing else left beside them.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
    }
}
