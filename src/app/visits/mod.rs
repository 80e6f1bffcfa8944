//! The record of what visitors do at the table (`[kiosk] visits`): sessions,
//! grabs and camera moves, actions started and near misses, as rows
//! ([`record`]) written by a thread of their own ([`writer`]) into a SQLite
//! database ([`store`]) that `marionette report` reads. The kiosk and
//! `replay --visits` fill it alike.

pub mod record;
pub mod store;
pub mod writer;

use std::path::PathBuf;

use self::record::{Row, Visits};
use self::writer::{Bounds, Writer};
use crate::control::action::timeline::ActionEvent;
use crate::control::stage::TouchEvent;

/// The record being kept: the rows made from each frame's events, handed
/// to the writer's thread.
pub struct Recording {
    visits: Visits,
    writer: Writer,
    rows: Vec<Row>,
}

impl Recording {
    /// Record into `path` within `bounds`; the frames' time 0 is
    /// `epoch_unix_s`, a session ends after `idle_after_s` without a
    /// finger, the picture is `width` x `height`.
    #[must_use]
    pub fn start(
        path: PathBuf,
        bounds: Bounds,
        epoch_unix_s: f64,
        idle_after_s: f64,
        (width, height): (f64, f64),
    ) -> Self {
        Self {
            visits: Visits::new(epoch_unix_s, idle_after_s, width, height),
            writer: Writer::start(path, bounds),
            rows: Vec::new(),
        }
    }

    /// The record configured in `[kiosk]`, if any.
    #[must_use]
    pub fn configured(config: &crate::app::config::Config, epoch_unix_s: f64) -> Option<Self> {
        let k = &config.kiosk;
        if k.visits.as_os_str().is_empty() {
            return None;
        }
        Some(Self::into_file(k.visits.clone(), config, epoch_unix_s))
    }

    /// A record into `path`, with `config`'s bounds, idle time and picture.
    #[must_use]
    pub fn into_file(
        path: PathBuf,
        config: &crate::app::config::Config,
        epoch_unix_s: f64,
    ) -> Self {
        let k = &config.kiosk;
        let (w, h) = config.display.size();
        Self::start(
            path,
            bounds(k.visits_keep_days, k.visits_max_mb),
            epoch_unix_s,
            k.idle_after_s,
            (f64::from(w), f64::from(h)),
        )
    }

    /// A frame at `t`: the table's touch events and action events taken
    /// from it this frame (`Stage::take_touches`, `Stage::take_events`).
    /// With `visitors` false (the attract loop performing) nothing is
    /// recorded.
    pub fn frame(
        &mut self,
        touches: &[TouchEvent],
        events: &[(usize, ActionEvent)],
        t: f64,
        visitors: bool,
    ) {
        if visitors {
            for e in touches {
                self.visits.touched(e, &mut self.rows);
            }
            for (k, e) in events {
                self.visits.action(*k, e, &mut self.rows);
            }
        }
        self.visits.tick(t, &mut self.rows);
        self.writer.send(std::mem::take(&mut self.rows));
    }

    #[must_use]
    pub fn writer(&self) -> &Writer {
        &self.writer
    }

    /// The session going on ends, everything is written, and the thread
    /// stops: what was recorded, and how many rows reached the file.
    pub fn finish(mut self) -> (record::Counts, writer::Written) {
        self.visits.end(&mut self.rows);
        self.writer.send(std::mem::take(&mut self.rows));
        let written = self.writer.finish();
        let c = self.visits.counts;
        tracing::info!(
            sessions = c.sessions,
            touches = c.touches,
            grabs = c.grabs,
            actions = c.actions,
            near_misses = c.near_misses,
            "visits recorded this run"
        );
        (c, written)
    }
}

/// `[kiosk]`'s bounds as the writer takes them.
#[must_use]
pub fn bounds(keep_days: f64, max_mb: f64) -> Bounds {
    Bounds {
        keep_days: keep_days.round().clamp(1.0, 36_500.0) as u32,
        max_bytes: (max_mb * 1e6) as u64,
    }
}

/// Now, in Unix seconds (the record's times).
#[must_use]
pub fn unix_now() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}
