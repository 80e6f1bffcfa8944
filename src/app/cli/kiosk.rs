//! The display: `run` (the kiosk), `calibrate`, `list-outputs`.

use std::io::Write;
use std::path::{Path, PathBuf};

use super::replay::cast;
use super::{Failure, stdout_error};
use crate::app::config::Config;
use crate::app::exit::{self};

/// `marionette calibrate`: targets on the display, the solved matrix into
/// the configuration file.
pub(super) fn calibrate(
    config: &Config,
    config_path: &Path,
    device: Option<String>,
    dri: PathBuf,
    timeout: u64,
) -> Result<(), Failure> {
    use crate::app::calibrate;
    let opts = calibrate::CalibrateOptions {
        dri_dir: dri,
        device,
        config_path: config_path.to_owned(),
        touch_timeout: std::time::Duration::from_secs(timeout.max(1)),
    };
    let done = calibrate::calibrate(config, &opts).map_err(Failure::from)?;
    let m = done.solution.matrix.0;
    writeln!(
        std::io::stdout(),
        "{}: calibration [{:.6}, {:.6}, {:.6}, {:.6}, {:.6}, {:.6}]; fit {:.1} px, check point off by {:.1} px; written to {}{}",
        done.device,
        m[0],
        m[1],
        m[2],
        m[3],
        m[4],
        m[5],
        done.solution.rms_px,
        done.solution.check_error_px,
        done.written.display(),
        done.backup
            .map(|b| format!(" (the old file kept as {})", b.display()))
            .unwrap_or_default()
    )
    .map_err(stdout_error)
}

/// `marionette run`: the kiosk.
pub(super) fn run_kiosk(
    config: &Config,
    dri: PathBuf,
    seconds: Option<f64>,
) -> Result<(), Failure> {
    use crate::app::kiosk as run;
    let cast = cast(config)?;
    let opts = run::RunOptions {
        dri_dir: dri,
        seconds,
        ..run::RunOptions::default()
    };
    run::run(cast, config, &opts)
        .map(|_| ())
        .map_err(Failure::from)
}

pub(super) fn list_outputs(dir: &Path, json: bool) -> Result<(), Failure> {
    let found = crate::platform::kms::list_outputs(dir).map_err(Failure::from)?;
    let mut out = std::io::stdout().lock();
    for o in &found {
        let line = if json {
            serde_json::to_string(o).map_err(|e| Failure::new(exit::FAILURE, e))?
        } else {
            o.to_string()
        };
        writeln!(out, "{line}").map_err(stdout_error)?;
    }
    Ok(())
}
