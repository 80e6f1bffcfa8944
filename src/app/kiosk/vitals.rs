//! The kiosk's vital signs, for the people who look after it: frames per
//! second, the time to draw a frame, and the latency from a touch (its
//! event's time stamp) to the page flip that first shows it; touches and
//! actions counted. Every minute they go to the journal and, when
//! `kiosk.metrics_textfile` names a file, to node_exporter's textfile
//! collector in Prometheus text format (written whole and renamed into
//! place, so a scrape never reads half a file). The service view shows
//! the same figures on the display. Pure: times come in as seconds on the
//! kiosk's clock.

use std::io;
use std::path::Path;

/// How often the figures are summed up (s).
pub const WINDOW_S: f64 = 60.0;

/// One window's figures.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Summary {
    /// Page flips per second.
    pub fps: f64,
    pub frame_ms_p50: f64,
    pub frame_ms_p99: f64,
    pub latency_ms_p50: f64,
    pub latency_ms_p99: f64,
    /// Frames drawn and touches measured to their flip, in the window.
    pub frames: usize,
    pub latencies: usize,
}

/// Counters since the process started (and, for `starts`, since the
/// textfile was first written).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Totals {
    /// Fingers that went down.
    pub touches: u64,
    pub actions_started: u64,
    /// Blows one character's body landed on another's.
    pub hits: u64,
    /// Times the kiosk started (this one included), carried over in the
    /// textfile: a restart by systemd shows as a step.
    pub starts: u64,
    /// Sessions and actions today (local time) as the visits record
    /// counts them (restarts included); `None` without a record.
    pub today: Option<(u64, u64)>,
}

/// The figures being gathered.
#[derive(Clone, Debug, Default)]
pub struct Vitals {
    window_start: f64,
    flips: usize,
    frame_ms: Vec<f64>,
    latency_ms: Vec<f64>,
    /// The earliest touch fed since the last frame was drawn.
    pending: Option<f64>,
    /// The earliest touch in the frame waiting for its flip.
    in_flight: Option<f64>,
    pub totals: Totals,
    /// The last complete window's figures.
    pub last: Option<Summary>,
    /// Touch-to-flip latencies over the whole run: their sum (ms) and
    /// count, said when the kiosk stops.
    run_latency: (f64, u64),
}

impl Vitals {
    #[must_use]
    pub fn new(t: f64, starts: u64) -> Self {
        Self {
            window_start: t,
            totals: Totals {
                starts,
                ..Totals::default()
            },
            ..Self::default()
        }
    }

    /// A touch frame stamped `event_t` was fed; `downs` fingers went down.
    pub fn touched(&mut self, event_t: f64, downs: usize) {
        self.pending = Some(self.pending.map_or(event_t, |p| p.min(event_t)));
        self.totals.touches += downs as u64;
    }

    pub fn action_started(&mut self) {
        self.totals.actions_started += 1;
    }

    /// One character's body hit another's with `impulse_ns` (N·s).
    pub fn hit(&mut self, impulse_ns: f64) {
        self.totals.hits += 1;
        tracing::debug!(impulse_ns, hits = self.totals.hits, "hit counted");
    }

    /// A frame was drawn in `render_ms` and queued for the next flip.
    pub fn drawn(&mut self, render_ms: f64) {
        self.frame_ms.push(render_ms);
        if let Some(p) = self.pending.take() {
            self.in_flight = Some(self.in_flight.map_or(p, |f| f.min(p)));
        }
    }

    /// A page flip completed at `t`.
    pub fn flipped(&mut self, t: f64) {
        self.flips += 1;
        if let Some(te) = self.in_flight.take() {
            let ms = ((t - te) * 1e3).max(0.0);
            self.latency_ms.push(ms);
            self.run_latency.0 += ms;
            self.run_latency.1 += 1;
        }
    }

    /// The mean touch-to-flip latency over the whole run (ms) and how many
    /// touches it is of.
    #[must_use]
    pub fn run_latency(&self) -> (f64, u64) {
        let (sum, n) = self.run_latency;
        (if n > 0 { sum / n as f64 } else { 0.0 }, n)
    }

    /// The figures of the window so far, at `t`.
    #[must_use]
    pub fn summary(&self, t: f64) -> Summary {
        let span = (t - self.window_start).max(1e-3);
        let mut frame = self.frame_ms.clone();
        let mut latency = self.latency_ms.clone();
        Summary {
            fps: self.flips as f64 / span,
            frame_ms_p50: percentile(&mut frame, 0.5),
            frame_ms_p99: percentile(&mut frame, 0.99),
            latency_ms_p50: percentile(&mut latency, 0.5),
            latency_ms_p99: percentile(&mut latency, 0.99),
            frames: frame.len(),
            latencies: latency.len(),
        }
    }

    /// At the end of a window: its figures, and a new window begins.
    pub fn window_due(&mut self, t: f64) -> Option<Summary> {
        if t - self.window_start < WINDOW_S {
            return None;
        }
        let s = self.summary(t);
        self.window_start = t;
        self.flips = 0;
        self.frame_ms.clear();
        self.latency_ms.clear();
        self.last = Some(s);
        Some(s)
    }
}

impl Vitals {
    /// At `t`: at the end of a window its figures go to the journal and,
    /// with `textfile`, to that file, as they do the `first` time (the
    /// window so far) with `panels` touchscreens read; whether they were
    /// told.
    pub fn tell(&mut self, t: f64, first: bool, panels: usize, textfile: Option<&Path>) -> bool {
        let due = self.window_due(t);
        if due.is_none() && !first {
            return false;
        }
        let s = due.unwrap_or_else(|| self.summary(t));
        let totals = self.totals;
        if due.is_some() {
            tracing::info!(
                fps = (s.fps * 10.0).round() / 10.0,
                frame_ms_p50 = (s.frame_ms_p50 * 100.0).round() / 100.0,
                frame_ms_p99 = (s.frame_ms_p99 * 100.0).round() / 100.0,
                touch_to_flip_ms_p50 = (s.latency_ms_p50 * 10.0).round() / 10.0,
                touch_to_flip_ms_p99 = (s.latency_ms_p99 * 10.0).round() / 10.0,
                touches = totals.touches,
                actions_started = totals.actions_started,
                hits = totals.hits,
                touchscreens = panels,
                "vitals over the last minute"
            );
        }
        if let Some(path) = textfile
            && let Err(e) = write_atomically(path, &prometheus(&s, &totals, panels))
        {
            tracing::warn!(path = %path.display(), error = %e, "cannot write the metrics textfile (ReadWritePaths= in the unit?)");
        }
        true
    }
}

/// The `p` quantile (0..1) by nearest rank; 0 for no values.
fn percentile(v: &mut [f64], p: f64) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    let rank = (p * v.len() as f64).ceil() as usize;
    v[rank.clamp(1, v.len()) - 1]
}

/// The figures in Prometheus text format.
#[must_use]
pub fn prometheus(s: &Summary, totals: &Totals, panels: usize) -> String {
    let mut out = String::new();
    let mut metric = |name: &str, kind: &str, help: &str, samples: &[(&str, f64)]| {
        out.push_str(&format!("# HELP {name} {help}\n# TYPE {name} {kind}\n"));
        for (labels, v) in samples {
            out.push_str(&format!("{name}{labels} {v}\n"));
        }
    };
    metric(
        "marionette_up",
        "gauge",
        "1 while the kiosk runs (the file's age says when it last did).",
        &[("", 1.0)],
    );
    metric(
        "marionette_fps",
        "gauge",
        "Page flips per second over the last minute.",
        &[("", round(s.fps))],
    );
    metric(
        "marionette_frame_seconds",
        "gauge",
        "Time to draw a frame over the last minute.",
        &[
            ("{quantile=\"0.5\"}", round(s.frame_ms_p50 / 1e3)),
            ("{quantile=\"0.99\"}", round(s.frame_ms_p99 / 1e3)),
        ],
    );
    metric(
        "marionette_touch_to_flip_seconds",
        "gauge",
        "From a touch's event time stamp to the page flip that shows it, over the last minute.",
        &[
            ("{quantile=\"0.5\"}", round(s.latency_ms_p50 / 1e3)),
            ("{quantile=\"0.99\"}", round(s.latency_ms_p99 / 1e3)),
        ],
    );
    metric(
        "marionette_touches_total",
        "counter",
        "Fingers that went down since the kiosk started.",
        &[("", totals.touches as f64)],
    );
    metric(
        "marionette_actions_started_total",
        "counter",
        "Actions the character started since the kiosk started.",
        &[("", totals.actions_started as f64)],
    );
    metric(
        "marionette_hits_total",
        "counter",
        "Blows one character's body landed on another's since the kiosk started.",
        &[("", totals.hits as f64)],
    );
    metric(
        "marionette_starts_total",
        "counter",
        "Times the kiosk started (restarts included).",
        &[("", totals.starts as f64)],
    );
    if let Some((sessions, actions)) = totals.today {
        metric(
            "marionette_sessions_today",
            "gauge",
            "Visitor sessions since local midnight (the visits record).",
            &[("", sessions as f64)],
        );
        metric(
            "marionette_actions_today",
            "gauge",
            "Actions started since local midnight (the visits record).",
            &[("", actions as f64)],
        );
    }
    metric(
        "marionette_touchscreens",
        "gauge",
        "Touchscreens read now (0: none plugged in).",
        &[("", panels as f64)],
    );
    out
}

fn round(v: f64) -> f64 {
    (v * 1e6).round() / 1e6
}

/// How many times the kiosk had started, from the textfile it wrote last
/// (0 when there is none or it says nothing of it).
#[must_use]
pub fn starts_before(text: &str) -> u64 {
    text.lines()
        .find_map(|l| l.strip_prefix("marionette_starts_total "))
        .and_then(|v| v.trim().parse::<f64>().ok())
        .map_or(0, |v| v.max(0.0) as u64)
}

/// Write `text` to `path` whole, over a regular file only
/// ([`crate::output::replace_file`]).
pub fn write_atomically(path: &Path, text: &str) -> io::Result<()> {
    crate::output::replace_file(path, text.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latency_runs_from_the_touch_to_the_flip_that_shows_it() {
        let mut v = Vitals::new(0.0, 1);
        // Two touch frames before a frame is drawn: the earlier counts.
        v.touched(1.000, 1);
        v.touched(1.004, 0);
        v.drawn(3.0);
        v.flipped(1.030);
        // A flip with no touch in its frame measures nothing.
        v.drawn(5.0);
        v.flipped(1.047);
        v.touched(1.050, 2);
        v.drawn(4.0);
        v.flipped(1.064);
        let s = v.summary(2.0);
        assert_eq!(s.latencies, 2);
        assert!((s.latency_ms_p50 - 14.0).abs() < 1e-6, "{s:?}");
        assert!((s.latency_ms_p99 - 30.0).abs() < 1e-6, "{s:?}");
        assert_eq!(s.frames, 3);
        assert!((s.frame_ms_p50 - 4.0).abs() < 1e-9);
        assert!((s.fps - 1.5).abs() < 1e-9);
        assert_eq!(v.totals.touches, 3);
        // The whole run's mean outlives the window.
        let _ = v.window_due(100.0);
        let (mean, n) = v.run_latency();
        assert_eq!(n, 2);
        assert!((mean - 22.0).abs() < 1e-6, "{mean}");
    }

    #[test]
    fn a_window_closes_every_minute_and_starts_afresh() {
        let mut v = Vitals::new(10.0, 1);
        for k in 0..600 {
            let t = 10.0 + f64::from(k) * 0.1;
            v.drawn(2.0);
            v.flipped(t);
            assert_eq!(v.window_due(t), None);
        }
        let s = v.window_due(70.0).unwrap();
        assert!((s.fps - 10.0).abs() < 1e-9, "{s:?}");
        assert_eq!(v.last, Some(s));
        assert_eq!(v.summary(71.0).frames, 0);
        assert_eq!(v.window_due(100.0), None);
    }

    #[test]
    fn prometheus_text_carries_every_figure_and_the_starts_read_back() {
        let s = Summary {
            fps: 59.94,
            frame_ms_p50: 3.0,
            frame_ms_p99: 9.5,
            latency_ms_p50: 21.0,
            latency_ms_p99: 38.0,
            frames: 3596,
            latencies: 120,
        };
        let totals = Totals {
            touches: 42,
            actions_started: 7,
            hits: 2,
            starts: 3,
            today: Some((12, 30)),
        };
        let text = prometheus(&s, &totals, 1);
        assert!(text.contains("marionette_sessions_today 12\n"), "{text}");
        assert!(text.contains("marionette_actions_today 30\n"), "{text}");
        let without = prometheus(
            &s,
            &Totals {
                today: None,
                ..totals
            },
            1,
        );
        assert!(!without.contains("today"), "{without}");
        for want in [
            "marionette_fps 59.94\n",
            "marionette_frame_seconds{quantile=\"0.99\"} 0.0095\n",
            "marionette_touch_to_flip_seconds{quantile=\"0.5\"} 0.021\n",
            "marionette_touches_total 42\n",
            "marionette_hits_total 2\n",
            "marionette_actions_started_total 7\n",
            "marionette_touchscreens 1\n",
            "# TYPE marionette_starts_total counter\n",
        ] {
            assert!(text.contains(want), "{want} in\n{text}");
        }
        // Every sample line is `name[{labels}] value`.
        for l in text.lines().filter(|l| !l.starts_with('#')) {
            let (_, v) = l.rsplit_once(' ').unwrap();
            assert!(v.parse::<f64>().is_ok(), "{l}");
        }
        assert_eq!(starts_before(&text), 3);
        assert_eq!(starts_before("garbage"), 0);
    }

    #[test]
    fn the_textfile_is_replaced_whole() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("marionette.prom");
        write_atomically(&path, "a 1\n").unwrap();
        write_atomically(&path, "a 2\n").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "a 2\n");
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(names.len(), 1, "no temporary file left");
        assert!(write_atomically(&dir.path().join("no/such/dir.prom"), "x").is_err());
    }
}
