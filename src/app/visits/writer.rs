//! The record's own thread: frames hand it rows without waiting (a full
//! queue drops them, counted), it writes them in a transaction every
//! quarter second, keeps the record within its bounds every hour, and
//! meets a database it cannot use by saying so in the journal once and
//! setting the file aside (unusable) or pausing and trying again (busy,
//! full, read-only, missing folder). The kiosk never stops or slows for it.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, SyncSender, TrySendError, sync_channel};
use std::time::{Duration, Instant};

use rusqlite::Connection;

use super::record::Row;
use super::store::{self, Fault, VisitsError};

/// Rows wait at most this long before they are written (s): a power cut
/// loses at most the last of them.
pub const BATCH_S: f64 = 0.25;
/// Messages (a frame's rows each) the queue holds before dropping.
const QUEUE: usize = 4096;
/// Rows kept while the database cannot be written; the oldest go beyond
/// (about 2 MB; ten minutes of a busy table).
const PENDING_MAX: usize = 20_000;
/// Committed rows reach the disk this often (s): with the quarter second
/// they may wait to be written, a power cut loses at most the last second.
const SYNC_S: f64 = 0.7;
/// A paused record tries again this often (s).
const RETRY_S: f64 = 5.0;
/// The record is kept within its bounds this often (s).
const PRUNE_S: f64 = 3600.0;
/// Today's counts are read again this often (s).
const TODAY_S: f64 = 30.0;

/// The record's bounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    pub keep_days: u32,
    pub max_bytes: u64,
}

/// What the thread tells the kiosk: rows written and dropped, today's
/// sessions and actions, and whether recording is paused.
#[derive(Debug, Default)]
pub struct Shared {
    sent: AtomicU64,
    committed: AtomicU64,
    /// Rows replaced by a newer row of the same session before they were
    /// written.
    merged: AtomicU64,
    dropped: AtomicU64,
    today_sessions: AtomicU64,
    today_actions: AtomicU64,
    paused: AtomicU64,
}

enum Msg {
    Rows(Vec<Row>),
    Flush(SyncSender<()>),
}

/// Rows handed to the writer, written, replaced by a newer row of the same
/// session before they were written, and dropped (a full queue, or too
/// many waiting while paused).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Written {
    pub sent: u64,
    pub committed: u64,
    pub merged: u64,
    pub dropped: u64,
}

impl Written {
    /// Whether every row handed over is in the file (or replaced there by
    /// a newer one).
    #[must_use]
    pub fn all(&self) -> bool {
        self.committed + self.merged >= self.sent && self.dropped == 0
    }
}

/// The handle the kiosk keeps.
pub struct Writer {
    tx: Option<SyncSender<Msg>>,
    thread: Option<std::thread::JoinHandle<()>>,
    shared: Arc<Shared>,
}

impl Writer {
    /// Start recording into `path`. Never fails: a database that cannot be
    /// opened is dealt with on the thread.
    #[must_use]
    pub fn start(path: PathBuf, bounds: Bounds) -> Self {
        let (tx, rx) = sync_channel(QUEUE);
        let shared = Arc::new(Shared::default());
        let s = Arc::clone(&shared);
        let thread = std::thread::Builder::new()
            .name("visits".into())
            .spawn(move || Thread::new(path, bounds, s).run(&rx))
            .map_err(|e| tracing::warn!(error = %e, "the visits record's thread did not start: nothing is recorded"))
            .ok();
        Self {
            tx: thread.as_ref().map(|_| tx),
            thread,
            shared,
        }
    }

    /// Hand over a frame's rows; never waits.
    pub fn send(&self, rows: Vec<Row>) {
        if rows.is_empty() {
            return;
        }
        let Some(tx) = &self.tx else {
            return;
        };
        let n = rows.len() as u64;
        match tx.try_send(Msg::Rows(rows)) {
            Ok(()) => {
                self.shared.sent.fetch_add(n, Ordering::Relaxed);
            }
            Err(TrySendError::Full(_) | TrySendError::Disconnected(_)) => {
                if self.shared.dropped.fetch_add(n, Ordering::Relaxed) == 0 {
                    tracing::warn!(
                        "the visits record falls behind: rows are dropped (counted in the journal when the kiosk stops)"
                    );
                }
            }
        }
    }

    /// Wait (up to `timeout`) until every row handed over so far is
    /// written or given up on; whether it was in time.
    pub fn flush(&self, timeout: Duration) -> bool {
        let Some(tx) = &self.tx else {
            return true;
        };
        let (ack, done) = sync_channel(1);
        if tx.send(Msg::Flush(ack)).is_err() {
            return false;
        }
        done.recv_timeout(timeout).is_ok()
    }

    /// Rows written so far.
    #[must_use]
    pub fn committed(&self) -> u64 {
        self.shared.committed.load(Ordering::Relaxed)
    }

    /// Rows dropped so far (a full queue, or too many waiting while paused).
    #[must_use]
    pub fn dropped(&self) -> u64 {
        self.shared.dropped.load(Ordering::Relaxed)
    }

    /// Sessions and actions recorded today (local time), as last read.
    #[must_use]
    pub fn today(&self) -> (u64, u64) {
        (
            self.shared.today_sessions.load(Ordering::Relaxed),
            self.shared.today_actions.load(Ordering::Relaxed),
        )
    }

    /// Whether recording is paused (the database busy, full or read-only).
    #[must_use]
    pub fn paused(&self) -> bool {
        self.shared.paused.load(Ordering::Relaxed) != 0
    }

    /// Write what is left and stop the thread: how many rows were handed
    /// over, written and dropped.
    pub fn finish(mut self) -> Written {
        self.stop();
        let w = Written {
            sent: self.shared.sent.load(Ordering::Relaxed),
            committed: self.committed(),
            merged: self.shared.merged.load(Ordering::Relaxed),
            dropped: self.dropped(),
        };
        if !w.all() {
            tracing::warn!(
                sent = w.sent,
                committed = w.committed,
                dropped = w.dropped,
                "visits record closed with rows not written (the journal said why)"
            );
        } else {
            tracing::info!(
                committed = w.committed,
                dropped = w.dropped,
                "visits record closed"
            );
        }
        w
    }
}

impl Writer {
    /// Close the queue and wait for the thread to write what is left.
    fn stop(&mut self) {
        self.tx = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for Writer {
    fn drop(&mut self) {
        self.stop();
    }
}

/// The thread's state.
struct Thread {
    path: PathBuf,
    bounds: Bounds,
    shared: Arc<Shared>,
    conn: Option<Connection>,
    pending: Vec<Row>,
    /// The session row waiting in `pending`, and where.
    session_at: Option<(i64, usize)>,
    /// When the database last failed, and the fault already said.
    failed_at: Option<Instant>,
    said: Option<String>,
    last_commit: Instant,
    /// When the log was last made durable, and whether it holds commits
    /// since.
    last_sync: Instant,
    unsynced: bool,
    last_prune: Option<Instant>,
    last_today: Option<Instant>,
}

fn now_ms() -> i64 {
    (super::unix_now() * 1e3) as i64
}

/// A date and time for a set-aside file's name (UTC).
fn stamp() -> String {
    let s = now_ms() / 1000;
    let (days, secs) = (s.div_euclid(86_400), s.rem_euclid(86_400));
    let (y, m, d) = civil(days);
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}{:02}{:02}",
        secs / 3600,
        secs / 60 % 60,
        secs % 60
    )
}

/// Days since 1970-01-01 as a date (proleptic Gregorian).
#[must_use]
pub fn civil(days: i64) -> (i64, i64, i64) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    (yoe + era * 400 + i64::from(m <= 2), m, d)
}

impl Thread {
    fn new(path: PathBuf, bounds: Bounds, shared: Arc<Shared>) -> Self {
        Self {
            path,
            bounds,
            shared,
            conn: None,
            pending: Vec::new(),
            session_at: None,
            failed_at: None,
            said: None,
            last_commit: Instant::now(),
            last_sync: Instant::now(),
            unsynced: false,
            last_prune: None,
            last_today: None,
        }
    }

    fn run(mut self, rx: &Receiver<Msg>) {
        self.connect();
        loop {
            let wait = (BATCH_S - self.last_commit.elapsed().as_secs_f64()).max(0.01);
            match rx.recv_timeout(Duration::from_secs_f64(wait)) {
                Ok(Msg::Rows(rows)) => self.take(rows),
                Ok(Msg::Flush(ack)) => {
                    while let Ok(Msg::Rows(rows)) = rx.try_recv() {
                        self.take(rows);
                    }
                    self.commit();
                    let _ = ack.send(());
                }
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => {
                    // The last rows: one more try, however recent the
                    // last failure.
                    self.failed_at = None;
                    self.commit();
                    self.sync(true);
                    return;
                }
            }
            if self.last_commit.elapsed().as_secs_f64() >= BATCH_S {
                self.commit();
                self.housekeeping();
            }
        }
    }

    fn take(&mut self, rows: Vec<Row>) {
        for row in rows {
            // A session told again replaces its row still waiting.
            if let Row::Session { start_ms, .. } = row
                && let Some(k) = self
                    .session_at
                    .filter(|(s, _)| *s == start_ms)
                    .map(|(_, k)| k)
                && k < self.pending.len()
            {
                self.pending[k] = row;
                self.shared.merged.fetch_add(1, Ordering::Relaxed);
                continue;
            }
            if let Row::Session { start_ms, .. } = row {
                self.session_at = Some((start_ms, self.pending.len()));
            }
            self.pending.push(row);
        }
        if self.pending.len() > PENDING_MAX {
            let over = self.pending.len() - PENDING_MAX;
            self.pending.drain(..over);
            self.session_at = None;
            self.shared
                .dropped
                .fetch_add(over as u64, Ordering::Relaxed);
        }
    }

    /// Open the database if it is not open and a retry is due.
    fn connect(&mut self) {
        if self.conn.is_some()
            || self
                .failed_at
                .is_some_and(|t| t.elapsed().as_secs_f64() < RETRY_S)
        {
            return;
        }
        match store::open(&self.path) {
            Ok(conn) => {
                if self.said.take().is_some() {
                    tracing::info!(path = %self.path.display(), "visits database usable again: recording goes on");
                } else {
                    tracing::info!(path = %self.path.display(), "recording visits");
                }
                self.conn = Some(conn);
                self.failed_at = None;
                self.shared.paused.store(0, Ordering::Relaxed);
            }
            Err(e) => self.fault(&e),
        }
    }

    /// Write the rows waiting, if any.
    fn commit(&mut self) {
        self.last_commit = Instant::now();
        if self.pending.is_empty() {
            return;
        }
        self.connect();
        let Some(conn) = self.conn.as_mut() else {
            return;
        };
        match store::insert(conn, &self.path, &self.pending) {
            Ok(()) => {
                self.shared
                    .committed
                    .fetch_add(self.pending.len() as u64, Ordering::Relaxed);
                self.pending.clear();
                self.session_at = None;
                self.unsynced = true;
            }
            Err(e) => {
                self.fault(&e);
                return;
            }
        }
        self.sync(false);
    }

    /// In WAL mode with synchronous=NORMAL a commit is not flushed to the
    /// disk; a checkpoint flushes the log first. One runs (passive: it
    /// waits on no reader) when commits are older than [`SYNC_S`], or now
    /// with `now`.
    fn sync(&mut self, now: bool) {
        if !self.unsynced || (!now && self.last_sync.elapsed().as_secs_f64() < SYNC_S) {
            return;
        }
        let Some(conn) = self.conn.as_ref() else {
            return;
        };
        match conn.query_row("PRAGMA wal_checkpoint(PASSIVE)", [], |_| Ok(())) {
            Ok(()) => {
                self.last_sync = Instant::now();
                self.unsynced = false;
            }
            Err(e) => tracing::debug!(error = %e, "visits log not flushed yet"),
        }
    }

    /// Say a fault once, and set the file aside or pause.
    fn fault(&mut self, e: &VisitsError) {
        self.conn = None;
        self.failed_at = Some(Instant::now());
        self.shared.paused.store(1, Ordering::Relaxed);
        let said = e.to_string();
        match e.fault() {
            Fault::Unusable => {
                let stamp = stamp();
                match store::set_aside(&self.path, &stamp) {
                    Ok(aside) => {
                        tracing::error!(error = %e, kept_as = %aside.display(), "visits database unusable: set aside, a new one is started");
                        // A fresh file at once.
                        self.failed_at = None;
                        self.said = None;
                        self.connect();
                    }
                    Err(io) => {
                        if self.said.as_deref() != Some(&said) {
                            tracing::error!(error = %e, rename_error = %io, "visits database unusable and cannot be set aside: recording paused");
                        }
                        self.said = Some(said);
                    }
                }
            }
            Fault::Pause => {
                if self.said.as_deref() != Some(&said) {
                    tracing::warn!(error = %e, retry_s = RETRY_S, "visits database cannot be written: recording paused, rows kept until it can (the kiosk goes on)");
                }
                self.said = Some(said);
            }
        }
    }

    /// Bounds every hour, today's counts every half minute.
    fn housekeeping(&mut self) {
        let due =
            |t: Option<Instant>, every: f64| t.is_none_or(|t| t.elapsed().as_secs_f64() >= every);
        let prune = due(self.last_prune, PRUNE_S);
        let today = due(self.last_today, TODAY_S);
        let Some(conn) = self.conn.as_mut() else {
            return;
        };
        if prune {
            self.last_prune = Some(Instant::now());
            let b = self.bounds;
            if let Err(e) = store::prune(conn, &self.path, now_ms(), b.keep_days, b.max_bytes) {
                self.fault(&e);
                return;
            }
        }
        if today {
            self.last_today = Some(Instant::now());
            if let Ok((s, a)) = today_counts(conn, now_ms()) {
                self.shared.today_sessions.store(s, Ordering::Relaxed);
                self.shared.today_actions.store(a, Ordering::Relaxed);
            }
        }
    }
}

/// Sessions and actions since local midnight before `now_ms`.
fn today_counts(conn: &Connection, now_ms: i64) -> rusqlite::Result<(u64, u64)> {
    let midnight: i64 = conn.query_row(
        "SELECT CAST(strftime('%s', ?1 / 1000, 'unixepoch', 'localtime', 'start of day', 'utc') AS INTEGER) * 1000",
        [now_ms],
        |r| r.get(0),
    )?;
    let sessions: i64 = conn.query_row(
        "SELECT count(*) FROM sessions WHERE start_ms >= ?1",
        [midnight],
        |r| r.get(0),
    )?;
    let actions: i64 = conn.query_row(
        "SELECT count(*) FROM actions WHERE at_ms >= ?1",
        [midnight],
        |r| r.get(0),
    )?;
    Ok((sessions as u64, actions as u64))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_for_file_names() {
        assert_eq!(civil(0), (1970, 1, 1));
        assert_eq!(civil(20_786), (2026, 11, 29));
        assert_eq!(civil(-1), (1969, 12, 31));
    }
}
