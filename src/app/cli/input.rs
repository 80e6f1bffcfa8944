//! Recordings and panels: `inspect` (recordings), `replay --contacts`,
//! `list-devices`.

use std::io::Write;
use std::path::Path;

use super::motion::inspect_bvh;
use super::{Failure, stdout_error};
use crate::app::config::Config;
use crate::app::exit::{self};
use crate::input::evemu::Recording;
use crate::input::pipeline;
use crate::platform::evdev as live;

pub(super) fn inspect(config: &Config, file: &Path) -> Result<(), Failure> {
    if file
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("bvh"))
    {
        return inspect_bvh(file);
    }
    if file
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb") || e.eq_ignore_ascii_case("gltf"))
    {
        return super::motion::inspect_gltf(file);
    }
    // A motion library, where a recording or a BVH file was meant.
    let library = if file.is_dir() {
        file.join("library.toml").is_file().then(|| file.to_owned())
    } else {
        (file.file_name().is_some_and(|n| n == "library.toml"))
            .then(|| file.parent().unwrap_or(Path::new(".")).to_owned())
    };
    if let Some(dir) = library {
        return Err(Failure::new(
            exit::DATAERR,
            format!(
                "{} is a motion library, not a recording or a BVH file: `marionette library check {}` shows what its drags start",
                file.display(),
                dir.display()
            ),
        ));
    }
    let read = Recording::read_file(file)?;
    let rec = pipeline::with_overrides(&read, &config.input)
        .map_err(|e| Failure::new(exit::DATAERR, e))?;
    let (summary, _) = pipeline::summarize(&rec);
    let json = serde_json::to_string(&summary).map_err(|e| Failure::new(exit::FAILURE, e))?;
    writeln!(std::io::stdout(), "{json}").map_err(stdout_error)?;
    // What a replay would refuse, inspect refuses too (after describing it).
    pipeline::check(&read, &config.input, config.display.picture()).map_err(|e| {
        Failure::new(
            exit::DATAERR,
            format!("{}: cannot be replayed as touches: {e}", file.display()),
        )
    })
}

pub(super) fn replay(config: &Config, file: &Path, contacts: bool) -> Result<(), Failure> {
    let rec = Recording::read_file(file)?;
    let frames = pipeline::replay(&rec, &config.input, config.display.picture())
        .map_err(|e| Failure::new(exit::DATAERR, e))?;
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    if contacts {
        for f in &frames {
            let line = serde_json::to_string(f).map_err(|e| Failure::new(exit::FAILURE, e))?;
            writeln!(out, "{line}").map_err(stdout_error)?;
        }
    } else {
        let rec = pipeline::with_overrides(&rec, &config.input)
            .map_err(|e| Failure::new(exit::DATAERR, e))?;
        let (summary, _) = pipeline::summarize(&rec);
        writeln!(
            out,
            "{}: {} frames, {} touch frames, {} finger contacts (at most {} at once), {:.1} s",
            summary.device,
            summary.frames,
            frames.len(),
            summary.touch_sequences,
            summary.max_contacts,
            summary.duration_s
        )
        .map_err(stdout_error)?;
    }
    out.flush().map_err(stdout_error)
}

pub(super) fn list_devices(config: &Config, json: bool) -> Result<(), Failure> {
    let found = live::list_devices(&config.input).map_err(Failure::from)?;
    let mut out = std::io::stdout().lock();
    if found.is_empty() {
        writeln!(
            out,
            "no input devices in {}",
            config.input.dev_dir.display()
        )
        .map_err(stdout_error)?;
    }
    for d in &found {
        let line = if json {
            serde_json::to_string(d).map_err(|e| Failure::new(exit::FAILURE, e))?
        } else {
            d.to_string()
        };
        writeln!(out, "{line}").map_err(stdout_error)?;
    }
    Ok(())
}
