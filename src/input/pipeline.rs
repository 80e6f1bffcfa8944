//! Recordings through the input stack: what `inspect`, `replay --contacts`
//! and the demo print. Pure: a recording and a configuration in, summaries
//! and screen-space frames out.

use serde::Serialize;

use super::calibration::{Calibration, CalibrationError, Matrix};
use super::config::InputConfig;
use super::device::{DeviceDescription, Protocol};
use super::evemu::Recording;
use super::touch::{ScreenContact, ScreenFrame};
use super::tracker::{TouchFrame, TrackerError, TrackerStats, track_events};
use crate::screen::Picture;

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
    input: &InputConfig,
    picture: Picture,
    device: &DeviceDescription,
) -> Result<Calibration, ReplayError> {
    let matrix = input
        .device_for(device)
        .map_or(Matrix::IDENTITY, |c| c.matrix());
    let (x, y) = device
        .position_axes()
        .ok_or_else(|| TrackerError::NoPositionAxes(device.name.clone()))?;
    Calibration::new(&x, &y, matrix, picture.rotation, picture.size()).map_err(|source| {
        ReplayError::Calibration {
            device: device.name.clone(),
            source,
        }
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
pub fn replay(
    rec: &Recording,
    input: &InputConfig,
    picture: Picture,
) -> Result<Vec<ScreenFrame>, ReplayError> {
    let cal = calibration_for(input, picture, &rec.device)?;
    let (frames, _) = track_events(&rec.device, &rec.events)?;
    let t0 = rec.events.first().map_or(0, |e| e.time_us);
    Ok(frames.iter().map(|f| to_screen(f, &cal, t0)).collect())
}
