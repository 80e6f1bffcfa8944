//! `marionette report`: what visitors did at the table, read from the
//! visits record, for the curator (sessions per hour and day, dwell time,
//! how many started an action, how many people at once) and the exhibit
//! builder (the actions visitors try and fail to start, the parts they
//! grab, where fingers land). Written as `report.json` and a
//! self-contained `report.html` ([`html`]: charts as inline SVG).

pub mod html;

use std::collections::BTreeMap;
use std::path::Path;

use rusqlite::Connection;
use serde::Serialize;

use crate::app::visits::record::GRID;
use crate::app::visits::store::{self, VisitsError};

/// How far back a report looks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Since {
    /// The last this many seconds.
    Last(f64),
    All,
}

impl std::str::FromStr for Since {
    type Err = String;

    /// `7d`, `24h`, `90m` or `all`.
    fn from_str(s: &str) -> Result<Self, String> {
        let s = s.trim();
        if s == "all" {
            return Ok(Self::All);
        }
        let (n, unit) = s.split_at(s.len().saturating_sub(1));
        let scale = match unit {
            "d" => 86_400.0,
            "h" => 3_600.0,
            "m" => 60.0,
            _ => {
                return Err(format!(
                    "{s:?}: a number of days, hours or minutes (7d, 24h, 90m) or all"
                ));
            }
        };
        match n.parse::<f64>() {
            Ok(v) if v.is_finite() && v > 0.0 && v <= 36_500.0 * 86_400.0 / scale => {
                Ok(Self::Last(v * scale))
            }
            _ => Err(format!(
                "{s:?}: a number of days, hours or minutes (7d, 24h, 90m) or all"
            )),
        }
    }
}

/// An action's row: how often visitors started it, how those ended, and
/// how often a drag came nearest to it and started nothing.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ActionRow {
    pub action: String,
    pub started: u64,
    pub finished: u64,
    pub cancelled: u64,
    pub near_misses: u64,
    /// Near misses held back by the cost (the drag's shape) rather than the
    /// margin (another action as close).
    pub held_by_cost: u64,
    /// What the exhibit builder could do, when visitors often fail to
    /// start it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub advice: Option<String>,
}

/// A body part's row.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct PartRow {
    pub part: String,
    pub grabs: u64,
    pub mean_s: f64,
}

/// What the report says.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Report {
    pub db: String,
    /// What SQLite's `integrity_check` says of the file (`ok`).
    pub integrity: String,
    /// The window: from this Unix time (ms) on; none for all.
    pub since_ms: Option<i64>,
    /// The first and last session in it (Unix ms).
    pub first_ms: Option<i64>,
    pub last_ms: Option<i64>,
    pub sessions: u64,
    /// By local hour of day (0..24), and by local day (`YYYY-MM-DD`).
    pub sessions_per_hour: Vec<u64>,
    pub sessions_per_day: Vec<(String, u64)>,
    /// Session lengths (s): mean, median, 90th percentile, and how many
    /// fall in each of [`DWELL_BINS`].
    pub dwell_mean_s: f64,
    pub dwell_median_s: f64,
    pub dwell_p90_s: f64,
    pub dwell_bins: Vec<(String, u64)>,
    /// Sessions in which a character started an action, and their share.
    pub sessions_with_action: u64,
    pub share_with_action: f64,
    /// Most fingers down at once in a session, and how many sessions had
    /// each number as their most.
    pub peak_fingers: u64,
    pub fingers_at_once: Vec<(u64, u64)>,
    /// Fingers that landed: on a part (grabs), on the floor (the camera),
    /// or on nothing.
    pub touches: u64,
    pub grabs: u64,
    pub camera_moves: u64,
    pub actions_started: u64,
    pub actions_finished: u64,
    pub near_misses: u64,
    pub actions: Vec<ActionRow>,
    pub parts: Vec<PartRow>,
    /// Where fingers landed: `heat[row][column]` over a
    /// [`GRID`] of the picture.
    pub heat: Vec<Vec<u64>>,
    pub advice: Vec<String>,
}

/// Session lengths are counted in these bins (upper bounds, s).
pub const DWELL_BINS: [(f64, &str); 7] = [
    (10.0, "< 10 s"),
    (30.0, "10-30 s"),
    (60.0, "30-60 s"),
    (120.0, "1-2 min"),
    (300.0, "2-5 min"),
    (600.0, "5-10 min"),
    (f64::INFINITY, "> 10 min"),
];

/// Advice is given for an action visitors tried at least this often...
const ADVICE_MIN_TRIES: u64 = 3;
/// ...and started at most this share of the tries.
const ADVICE_MAX_SHARE: f64 = 0.75;

/// The report over the record at `db` for the window `since` before
/// `now_ms`.
///
/// # Errors
/// A missing file, one that is not marionette's record or of a newer
/// schema ([`VisitsError`]); SQLite's.
pub fn gather(db: &Path, since: Since, now_ms: i64) -> Result<Report, VisitsError> {
    let conn = store::open_to_read(db)?;
    let e = |source| VisitsError::Sqlite {
        path: db.to_owned(),
        source,
    };
    let since_ms = match since {
        Since::All => None,
        Since::Last(s) => Some(now_ms - (s * 1e3) as i64),
    };
    let from = since_ms.unwrap_or(i64::MIN);
    let mut r = Report {
        db: db.display().to_string(),
        since_ms,
        ..Report::default()
    };
    r.integrity = conn
        .query_row("PRAGMA integrity_check", [], |row| row.get(0))
        .map_err(e)?;
    if r.integrity != "ok" {
        tracing::warn!(db = %db.display(), integrity = %r.integrity, "the visits database is damaged: the report shows what can still be read");
    }
    sessions(&conn, from, &mut r).map_err(e)?;
    touches(&conn, from, &mut r).map_err(e)?;
    actions(&conn, from, &mut r).map_err(e)?;
    r.advice = r.actions.iter().filter_map(|a| a.advice.clone()).collect();
    Ok(r)
}

fn sessions(conn: &Connection, from: i64, r: &mut Report) -> rusqlite::Result<()> {
    let mut lengths = Vec::new();
    let mut hours = vec![0u64; 24];
    let mut days: BTreeMap<String, u64> = BTreeMap::new();
    let mut peaks: BTreeMap<u64, u64> = BTreeMap::new();
    let mut st = conn.prepare(
        "SELECT start_ms, length_s, peak_fingers,
                CAST(strftime('%H', start_ms / 1000, 'unixepoch', 'localtime') AS INTEGER),
                date(start_ms / 1000, 'unixepoch', 'localtime')
         FROM sessions WHERE start_ms >= ?1 ORDER BY start_ms",
    )?;
    let mut rows = st.query([from])?;
    while let Some(row) = rows.next()? {
        let start: i64 = row.get(0)?;
        let length: f64 = row.get(1)?;
        let peak: i64 = row.get(2)?;
        let hour: i64 = row.get(3)?;
        let day: String = row.get(4)?;
        r.first_ms.get_or_insert(start);
        r.last_ms = Some(start);
        lengths.push(length.max(0.0));
        hours[hour.clamp(0, 23) as usize] += 1;
        *days.entry(day).or_default() += 1;
        *peaks.entry(peak.max(0) as u64).or_default() += 1;
    }
    r.sessions = lengths.len() as u64;
    r.sessions_per_hour = hours;
    r.sessions_per_day = days.into_iter().collect();
    r.peak_fingers = peaks.keys().next_back().copied().unwrap_or(0);
    r.fingers_at_once = peaks.into_iter().collect();
    r.dwell_bins = DWELL_BINS
        .iter()
        .enumerate()
        .map(|(k, (hi, label))| {
            let lo = if k == 0 {
                f64::NEG_INFINITY
            } else {
                DWELL_BINS[k - 1].0
            };
            let n = lengths.iter().filter(|l| **l >= lo && **l < *hi).count();
            ((*label).to_owned(), n as u64)
        })
        .collect();
    if !lengths.is_empty() {
        r.dwell_mean_s = lengths.iter().sum::<f64>() / lengths.len() as f64;
        lengths.sort_by(f64::total_cmp);
        let q = |p: f64| {
            lengths[((p * lengths.len() as f64).ceil() as usize).clamp(1, lengths.len()) - 1]
        };
        r.dwell_median_s = q(0.5);
        r.dwell_p90_s = q(0.9);
    }
    r.sessions_with_action = conn.query_row(
        "SELECT count(DISTINCT session_ms) FROM actions WHERE session_ms >= ?1",
        [from],
        |row| row.get::<_, i64>(0),
    )? as u64;
    r.share_with_action = if r.sessions > 0 {
        r.sessions_with_action as f64 / r.sessions as f64
    } else {
        0.0
    };
    Ok(())
}

fn touches(conn: &Connection, from: i64, r: &mut Report) -> rusqlite::Result<()> {
    let mut heat = vec![vec![0u64; GRID.0 as usize]; GRID.1 as usize];
    let mut st = conn.prepare(
        "SELECT took, cell_x, cell_y, count(*) FROM touches WHERE session_ms >= ?1 GROUP BY took, cell_x, cell_y",
    )?;
    let mut rows = st.query([from])?;
    while let Some(row) = rows.next()? {
        let took: String = row.get(0)?;
        let (x, y, n): (i64, i64, i64) = (row.get(1)?, row.get(2)?, row.get(3)?);
        let n = n.max(0) as u64;
        r.touches += n;
        match took.as_str() {
            "part" => r.grabs += n,
            "camera" => r.camera_moves += n,
            _ => {}
        }
        if let (Ok(x), Ok(y)) = (usize::try_from(x), usize::try_from(y))
            && let Some(cell) = heat.get_mut(y).and_then(|row| row.get_mut(x))
        {
            *cell += n;
        }
    }
    r.heat = heat;
    let mut st = conn.prepare(
        "SELECT part, count(*), avg(duration_s) FROM touches
         WHERE session_ms >= ?1 AND took = 'part' GROUP BY part ORDER BY count(*) DESC, part",
    )?;
    r.parts = st
        .query_map([from], |row| {
            Ok(PartRow {
                part: row.get::<_, Option<String>>(0)?.unwrap_or_default(),
                grabs: row.get::<_, i64>(1)?.max(0) as u64,
                mean_s: row.get::<_, Option<f64>>(2)?.unwrap_or(0.0),
            })
        })?
        .collect::<rusqlite::Result<_>>()?;
    Ok(())
}

fn actions(conn: &Connection, from: i64, r: &mut Report) -> rusqlite::Result<()> {
    let mut by: BTreeMap<String, ActionRow> = BTreeMap::new();
    let mut st = conn.prepare(
        "SELECT action, outcome, count(*) FROM actions WHERE session_ms >= ?1 GROUP BY action, outcome",
    )?;
    let mut rows = st.query([from])?;
    while let Some(row) = rows.next()? {
        let action: String = row.get(0)?;
        let outcome: String = row.get(1)?;
        let n = row.get::<_, i64>(2)?.max(0) as u64;
        let a = by.entry(action).or_default();
        a.started += n;
        match outcome.as_str() {
            "finished" => a.finished += n,
            "cancelled" => a.cancelled += n,
            _ => {}
        }
    }
    let mut st = conn.prepare(
        "SELECT action, count(*), sum(held_by = 'cost') FROM near_misses WHERE session_ms >= ?1 GROUP BY action",
    )?;
    let mut rows = st.query([from])?;
    while let Some(row) = rows.next()? {
        let action: String = row.get(0)?;
        let a = by.entry(action).or_default();
        a.near_misses = row.get::<_, i64>(1)?.max(0) as u64;
        a.held_by_cost = row.get::<_, Option<i64>>(2)?.unwrap_or(0).max(0) as u64;
    }
    for (name, a) in &mut by {
        a.action.clone_from(name);
        r.actions_started += a.started;
        r.actions_finished += a.finished;
        r.near_misses += a.near_misses;
        let tries = a.started + a.near_misses;
        if tries >= ADVICE_MIN_TRIES && (a.started as f64) <= ADVICE_MAX_SHARE * tries as f64 {
            a.advice = Some(format!(
                "visitors tried {name} {tries} times and it started {} times: record more takes of {name} (`marionette library check` shows what its takes start)",
                a.started
            ));
        }
    }
    r.actions = by.into_values().collect();
    r.actions.sort_by(|a, b| {
        (b.started + b.near_misses)
            .cmp(&(a.started + a.near_misses))
            .then(a.action.cmp(&b.action))
    });
    Ok(())
}

/// Write `report.json` and `report.html` into `out` (each whole or not
/// at all); the two paths.
///
/// # Errors
/// The writes'.
pub fn write(
    report: &Report,
    out: &Path,
) -> std::io::Result<(std::path::PathBuf, std::path::PathBuf)> {
    std::fs::create_dir_all(out)?;
    let json = out.join("report.json");
    let text = serde_json::to_string_pretty(report).map_err(std::io::Error::other)? + "\n";
    crate::output::replace_file(&json, text.as_bytes())?;
    let page = out.join("report.html");
    crate::output::replace_file(&page, html::page(report).as_bytes())?;
    Ok((json, page))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn since_reads_days_hours_minutes_or_all() {
        assert_eq!("7d".parse::<Since>(), Ok(Since::Last(7.0 * 86_400.0)));
        assert_eq!("24h".parse::<Since>(), Ok(Since::Last(86_400.0)));
        assert_eq!("90m".parse::<Since>(), Ok(Since::Last(5_400.0)));
        assert_eq!("all".parse::<Since>(), Ok(Since::All));
        for bad in ["", "7", "d", "-1d", "7w", "nand", "1e300d"] {
            assert!(bad.parse::<Since>().is_err(), "{bad}");
        }
    }
}
