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

/// What a file holds, by its first bytes (its name's extension only
/// where they say nothing).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Content {
    /// A glTF: a GLB (`.glb`, `.vrm`, any name) or glTF JSON.
    Gltf,
    Bvh,
    /// An evemu recording.
    Recording,
    /// None of these (or unreadable: the reader says why).
    Unknown,
}

/// The content of `file` from its first bytes: the GLB magic `glTF`, JSON
/// with an `asset`, BVH's `HIERARCHY`, an evemu header or line.
pub(super) fn sniff(file: &Path) -> Content {
    use std::io::Read;
    let mut head = Vec::new();
    let read = crate::reading::open(file)
        .map_err(std::io::Error::from)
        .and_then(|f| f.take(4096).read_to_end(&mut head));
    let by_name = || {
        let ext = file
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            Some("bvh") => Content::Bvh,
            Some("glb" | "gltf" | "vrm") => Content::Gltf,
            Some("evemu") => Content::Recording,
            _ => Content::Unknown,
        }
    };
    if read.is_err() || !file.is_file() {
        return by_name();
    }
    let text = String::from_utf8_lossy(&head);
    let text = text.trim_start_matches('\u{feff}').trim_start();
    if head.starts_with(b"glTF") || (text.starts_with('{') && text.contains("\"asset\"")) {
        Content::Gltf
    } else if text.starts_with("HIERARCHY") {
        Content::Bvh
    } else if text.starts_with("# EVEMU")
        || ["N:", "I:", "P:", "B:", "A:", "L:", "S:", "E:"]
            .iter()
            .any(|p| text.starts_with(p))
    {
        Content::Recording
    } else {
        by_name()
    }
}

pub(super) fn inspect(config: &Config, file: &Path) -> Result<(), Failure> {
    let content = sniff(file);
    match content {
        Content::Bvh => return inspect_bvh(file),
        Content::Gltf => return super::motion::inspect_gltf(file),
        Content::Recording | Content::Unknown => {}
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
    if content == Content::Unknown && file.is_file() {
        return Err(Failure::new(
            exit::DATAERR,
            format!(
                "{}: neither an evemu recording, a BVH file nor a glTF character (.glb, .gltf, .vrm) by its content",
                file.display()
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
