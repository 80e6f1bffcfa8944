//! Recordings through the input stack: what `inspect`, `replay --contacts`
//! and the demo print. Pure: a recording and a configuration in, summaries
//! and screen-space frames out.

use serde::Serialize;

use super::calibration::{Calibration, CalibrationError, Matrix};
use super::device::{DeviceDescription, Protocol};
use super::evemu::Recording;
use super::touch::{ScreenContact, ScreenFrame};
use super::tracker::{ContactId, Phase, TouchFrame, TrackerError, TrackerStats, track_events};
use crate::app::config::Config;
use crate::screen::ScreenPoint;

/// What `marionette inspect FILE.evemu` prints.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RecordingSummary {
    pub device: String,
    /// `"B"`, `"A"` or `"single"`; `null` for devices without positions.
    pub protocol: Option<Protocol>,
    /// Whether the device's coordinates are on the screen (see
    /// [`DeviceDescription::is_direct`]).
    pub direct: bool,
    /// Completed `SYN_REPORT` frames.
    pub frames: usize,
    pub duration_s: f64,
    /// Most finger contacts down at once.
    pub max_contacts: usize,
    /// Finger contacts that went down.
    pub touch_sequences: u64,
}

/// Summarise a recording; devices without position axes give zero counts.
#[must_use]
pub fn summarize(rec: &Recording) -> (RecordingSummary, Option<TrackerStats>) {
    let stats = track_events(&rec.device, &rec.events).ok().map(|(_, s)| s);
    let summary = RecordingSummary {
        device: rec.device.name.clone(),
        protocol: rec.device.protocol(),
        direct: rec.device.is_direct(),
        frames: rec.frame_count(),
        duration_s: (rec.duration_s() * 1e6).round() / 1e6,
        max_contacts: stats.map_or(0, |s| s.max_fingers),
        touch_sequences: stats.map_or(0, |s| s.finger_sequences),
    };
    (summary, stats)
}

/// Why a recording cannot be replayed as touches.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    #[error(transparent)]
    Tracker(#[from] TrackerError),
    #[error("device \"{device}\": {source}")]
    Calibration {
        device: String,
        #[source]
        source: CalibrationError,
    },
}

/// The calibration the configuration gives a device.
pub fn calibration_for(
    config: &Config,
    device: &DeviceDescription,
) -> Result<Calibration, ReplayError> {
    let matrix = config
        .device_for(device)
        .map_or(Matrix::IDENTITY, |c| c.matrix());
    let (x, y) = device
        .position_axes()
        .ok_or_else(|| TrackerError::NoPositionAxes(device.name.clone()))?;
    Calibration::new(
        &x,
        &y,
        matrix,
        config.display.rotation(),
        config.display.size(),
    )
    .map_err(|source| ReplayError::Calibration {
        device: device.name.clone(),
        source,
    })
}

/// A tracker frame's contacts in screen pixels.
#[must_use]
pub fn screen_contacts(frame: &TouchFrame, cal: &Calibration) -> Vec<ScreenContact> {
    frame
        .contacts
        .iter()
        .map(|c| ScreenContact {
            id: c.id,
            phase: c.phase,
            tool: c.tool,
            raw: c.raw,
            screen: cal.to_screen(c.raw),
        })
        .collect()
}

/// Map a tracker frame to screen pixels, `t` relative to `t0_us`.
#[must_use]
pub fn to_screen(frame: &TouchFrame, cal: &Calibration, t0_us: i64) -> ScreenFrame {
    ScreenFrame {
        t: (frame.time_us - t0_us) as f64 / 1e6,
        contacts: screen_contacts(frame, cal),
    }
}

/// Replay a whole recording into screen-space frames.
pub fn replay(rec: &Recording, config: &Config) -> Result<Vec<ScreenFrame>, ReplayError> {
    let cal = calibration_for(config, &rec.device)?;
    let (frames, _) = track_events(&rec.device, &rec.events)?;
    let t0 = rec.events.first().map_or(0, |e| e.time_us);
    Ok(frames.iter().map(|f| to_screen(f, &cal, t0)).collect())
}

/// The demo's human-readable account of a replay.
#[must_use]
pub fn demo_summary(rec: &Recording, frames: &[ScreenFrame], config: &Config) -> String {
    use std::collections::BTreeMap;
    use std::fmt::Write;
    let (summary, stats) = summarize(rec);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "replayed \"{}\" (protocol {}), {:.2} s, {} frames, on a {}x{} screen at {}",
        summary.device,
        summary.protocol.map_or("-".to_owned(), |p| p.to_string()),
        summary.duration_s,
        summary.frames,
        config.display.width,
        config.display.height,
        config.display.rotation()
    );
    let _ = writeln!(
        s,
        "{} touch frames, {} finger contacts, at most {} at once",
        frames.len(),
        summary.touch_sequences,
        summary.max_contacts
    );
    struct Track {
        start: (f64, ScreenPoint),
        end: (f64, ScreenPoint),
        length: f64,
        ended: Phase,
    }
    let mut tracks: BTreeMap<ContactId, Track> = BTreeMap::new();
    for f in frames {
        for c in &f.contacts {
            let t = tracks.entry(c.id).or_insert(Track {
                start: (f.t, c.screen),
                end: (f.t, c.screen),
                length: 0.0,
                ended: Phase::Hold,
            });
            t.length += t.end.1.distance(c.screen);
            t.end = (f.t, c.screen);
            if !c.phase.is_down() {
                t.ended = c.phase;
            }
        }
    }
    for (id, t) in &tracks {
        let _ = writeln!(
            s,
            "  contact {:>3}: {:5.2}s-{:5.2}s  ({:6.1},{:6.1}) -> ({:6.1},{:6.1}) px, path {:6.1} px, {}",
            id & 0xffff_ffff,
            t.start.0,
            t.end.0,
            t.start.1.x,
            t.start.1.y,
            t.end.1.x,
            t.end.1.y,
            t.length,
            match t.ended {
                Phase::Up => "lifted",
                Phase::Cancel => "cancelled",
                _ => "still down at the end",
            }
        );
    }
    if let Some(st) = stats {
        if st.clamped + st.bad_slots + st.dropped > 0 {
            let _ = writeln!(
                s,
                "device problems: {} values clamped, {} bad slots, {} SYN_DROPPED",
                st.clamped, st.bad_slots, st.dropped
            );
        }
    }
    s
}
