//! Recordings through the input stack: what `inspect`, `replay --contacts`
//! and the demo print. Pure: a recording and a configuration in, summaries
//! and screen-space frames out.

use serde::Serialize;
use std::borrow::Cow;

use super::calibration::{Calibration, CalibrationError, Matrix};
use super::config::InputConfig;
use super::device::{DeviceDescription, Protocol};
use super::evemu::Recording;
use super::remap::RemapError;
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
    /// Frames stamped before the frame before them (replayed at that
    /// frame's time instead).
    pub time_backwards: usize,
    /// Frames stamped the same as the frame before them.
    pub time_repeated: usize,
    /// Pauses over [`MAX_GAP_S`] (replayed shortened to it).
    pub time_gaps: usize,
    /// How long a replay runs: the duration with time kept from going
    /// back and long pauses shortened.
    pub replay_s: f64,
}

/// A pause between two frames of a recording longer than this (s) is
/// shortened to it when the recording is replayed: a panel left alone for
/// hours, or a clock that jumped, replays in seconds.
pub const MAX_GAP_S: f64 = 5.0;

/// What [`retime`] changed.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Retimed {
    pub backwards: usize,
    pub repeated: usize,
    pub gaps: usize,
    /// Time taken out of pauses (s).
    pub skipped_s: f64,
}

/// Make frame times (s) replayable: a time before the previous frame's
/// becomes that time, and a pause over [`MAX_GAP_S`] is shortened to it.
pub fn retime(times: &mut [f64]) -> Retimed {
    let mut r = Retimed::default();
    let Some(&first) = times.first() else {
        return r;
    };
    let (mut prev_raw, mut prev) = (first, first);
    for t in times.iter_mut().skip(1) {
        let raw = *t;
        let step = raw - prev_raw;
        prev_raw = raw;
        let step = if step < 0.0 || step.is_nan() {
            r.backwards += 1;
            0.0
        } else if step == 0.0 {
            r.repeated += 1;
            0.0
        } else if step > MAX_GAP_S {
            r.gaps += 1;
            r.skipped_s += step - MAX_GAP_S;
            MAX_GAP_S
        } else {
            step
        };
        prev += step;
        *t = prev;
    }
    r
}

impl Retimed {
    /// Say in the log what was changed, if anything.
    pub fn log(&self, what: &str) {
        if self.backwards > 0 {
            tracing::warn!(
                recording = what,
                frames = self.backwards,
                "frames stamped before the frame before them are replayed at that frame's time"
            );
        }
        if self.gaps > 0 {
            tracing::warn!(
                recording = what,
                pauses = self.gaps,
                skipped_s = self.skipped_s,
                max_s = MAX_GAP_S,
                "pauses longer than max_s are shortened to it"
            );
        }
        if self.repeated > 0 {
            tracing::debug!(
                recording = what,
                frames = self.repeated,
                "frames stamped the same as the frame before them"
            );
        }
    }
}

/// The times of a recording's frames (`SYN_REPORT`s), from its first event.
fn frame_times(rec: &Recording) -> Vec<f64> {
    let t0 = rec.events.first().map_or(0, |e| e.time_us);
    rec.events
        .iter()
        .filter(|e| e.is_syn_report())
        .map(|e| (e.time_us - t0) as f64 / 1e6)
        .collect()
}

/// Summarise a recording; devices without position axes give zero counts.
#[must_use]
pub fn summarize(rec: &Recording) -> (RecordingSummary, Option<TrackerStats>) {
    let stats = track_events(&rec.device, &rec.events).ok().map(|(_, s)| s);
    let mut times = frame_times(rec);
    let retimed = retime(&mut times);
    let summary = RecordingSummary {
        device: rec.device.name.clone(),
        protocol: rec.device.protocol(),
        direct: rec.device.is_direct(),
        frames: rec.frame_count(),
        duration_s: (rec.duration_s() * 1e6).round() / 1e6,
        max_contacts: stats.map_or(0, |s| s.max_fingers),
        touch_sequences: stats.map_or(0, |s| s.finger_sequences),
        time_backwards: retimed.backwards,
        time_repeated: retimed.repeated,
        time_gaps: retimed.gaps,
        replay_s: ((rec.duration_s() - retimed.skipped_s)
            .max(times.last().copied().unwrap_or(0.0))
            * 1e6)
            .round()
            / 1e6,
    };
    (summary, stats)
}

/// Why a recording cannot be replayed as touches.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    #[error(transparent)]
    Tracker(#[from] TrackerError),
    #[error("device \"{device}\": {source} (see its [[input.device]] axes)")]
    Remap {
        device: String,
        #[source]
        source: RemapError,
    },
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

/// A recording as the configuration's overrides make it read (`axes`,
/// `tool` of its `[[input.device]]`): what inspect and every replay read.
pub fn with_overrides<'a>(
    rec: &'a Recording,
    input: &InputConfig,
) -> Result<Cow<'a, Recording>, ReplayError> {
    match input.remap_for(&rec.device) {
        Ok(None) => Ok(Cow::Borrowed(rec)),
        Ok(Some(r)) => Ok(Cow::Owned(Recording {
            device: r.description(&rec.device),
            events: rec.events.iter().filter_map(|e| r.event(e)).collect(),
            ..rec.clone()
        })),
        Err(source) => Err(ReplayError::Remap {
            device: rec.device.name.clone(),
            source,
        }),
    }
}

/// Whether a recording can be replayed as touches with this
/// configuration: its overrides apply, it has position axes, and their
/// ranges calibrate. One check for `inspect` and every replay.
pub fn check(rec: &Recording, input: &InputConfig, picture: Picture) -> Result<(), ReplayError> {
    let rec = with_overrides(rec, input)?;
    calibration_for(input, picture, &rec.device)?;
    Ok(())
}

/// Replay a whole recording into screen-space frames, its time made
/// replayable ([`retime`]).
pub fn replay(
    rec: &Recording,
    input: &InputConfig,
    picture: Picture,
) -> Result<Vec<ScreenFrame>, ReplayError> {
    // Remapped and calibrated once (what `check` checks, in its order).
    let rec = &with_overrides(rec, input)?;
    let cal = calibration_for(input, picture, &rec.device)?;
    let (frames, _) = track_events(&rec.device, &rec.events)?;
    let t0 = rec.events.first().map_or(0, |e| e.time_us);
    let mut frames: Vec<ScreenFrame> = frames.iter().map(|f| to_screen(f, &cal, t0)).collect();
    let mut times: Vec<f64> = frames.iter().map(|f| f.t).collect();
    retime(&mut times).log(&rec.device.name);
    for (f, t) in frames.iter_mut().zip(times) {
        f.t = t;
    }
    Ok(frames)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_that_goes_back_is_held_and_long_pauses_are_shortened() {
        // Frames at 0, 0.1, then the clock jumps 1e5 s, goes back 2 s,
        // repeats, and runs on.
        let mut t = vec![0.0, 0.1, 1e5, 1e5 - 2.0, 1e5 - 2.0, 1e5 - 1.9];
        let r = retime(&mut t);
        assert_eq!(
            r,
            Retimed {
                backwards: 1,
                repeated: 1,
                gaps: 1,
                skipped_s: 1e5 - 0.1 - MAX_GAP_S,
            }
        );
        let want = [
            0.0,
            0.1,
            0.1 + MAX_GAP_S,
            0.1 + MAX_GAP_S,
            0.1 + MAX_GAP_S,
            0.2 + MAX_GAP_S,
        ];
        for (a, b) in t.iter().zip(want) {
            assert!((a - b).abs() < 1e-6, "{t:?}");
        }
        // Ordinary time is left alone.
        let mut t = vec![0.0, 0.01, 0.02, 4.9];
        assert_eq!(retime(&mut t), Retimed::default());
        assert_eq!(t, vec![0.0, 0.01, 0.02, 4.9]);
    }
}
