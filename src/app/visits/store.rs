//! The record on disk: a SQLite database in WAL mode (a power cut loses at
//! most the transactions not yet checkpointed into the log, never the
//! file), its schema versioned with migrations, its age and size bounded,
//! and a database that cannot be used told apart from one that is busy.

use std::path::{Path, PathBuf};

use rusqlite::{Connection, ErrorCode, OpenFlags, params};

use super::record::Row;

/// The schema this build writes and reads (`PRAGMA user_version`).
pub const SCHEMA_VERSION: i64 = 1;
/// Marks the file as marionette's record (`PRAGMA application_id`, "mrnt").
pub const APPLICATION_ID: i64 = 0x6D72_6E74;

/// Migrations: entry `k` takes a database from version `k` to `k + 1`.
const MIGRATIONS: [&str; 1] = ["
CREATE TABLE sessions (
    start_ms INTEGER PRIMARY KEY,
    length_s REAL NOT NULL,
    peak_fingers INTEGER NOT NULL,
    characters INTEGER NOT NULL,
    ended INTEGER NOT NULL
);
CREATE TABLE touches (
    session_ms INTEGER NOT NULL,
    at_ms INTEGER NOT NULL,
    took TEXT NOT NULL,
    part TEXT,
    character INTEGER,
    cell_x INTEGER NOT NULL,
    cell_y INTEGER NOT NULL,
    duration_s REAL NOT NULL
);
CREATE INDEX touches_session ON touches (session_ms);
CREATE TABLE actions (
    session_ms INTEGER NOT NULL,
    at_ms INTEGER NOT NULL,
    character INTEGER NOT NULL,
    action TEXT NOT NULL,
    by_reach INTEGER NOT NULL,
    cost_m REAL,
    margin_m REAL,
    outcome TEXT NOT NULL,
    length_s REAL,
    PRIMARY KEY (at_ms, character, action)
) WITHOUT ROWID;
CREATE INDEX actions_session ON actions (session_ms);
CREATE TABLE near_misses (
    session_ms INTEGER NOT NULL,
    at_ms INTEGER NOT NULL,
    character INTEGER NOT NULL,
    action TEXT NOT NULL,
    cost_m REAL NOT NULL,
    cost_limit_m REAL NOT NULL,
    margin_m REAL NOT NULL,
    margin_needed_m REAL NOT NULL,
    held_by TEXT NOT NULL
);
CREATE INDEX near_misses_session ON near_misses (session_ms);
"];

/// What can go wrong with the record.
#[derive(Debug, thiserror::Error)]
pub enum VisitsError {
    #[error("{path}: not a marionette visits database ({why})")]
    NotOurs { path: PathBuf, why: String },
    #[error("{path}: written by a newer marionette (schema {found}, this one knows {known})")]
    Newer {
        path: PathBuf,
        found: i64,
        known: i64,
    },
    #[error("{path}: {source}")]
    Sqlite {
        path: PathBuf,
        #[source]
        source: rusqlite::Error,
    },
    #[error("{0}: no such visits database (the kiosk or `replay --visits` makes one)")]
    Missing(PathBuf),
}

/// What to do about an error.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fault {
    /// The file is not usable (not a database, corrupt, a newer schema):
    /// set it aside and start a new one.
    Unusable,
    /// Busy, full, read-only, not there to open: pause and try again later.
    Pause,
}

impl VisitsError {
    /// Whether the file should be set aside or recording paused.
    #[must_use]
    pub fn fault(&self) -> Fault {
        match self {
            Self::NotOurs { .. } | Self::Newer { .. } => Fault::Unusable,
            Self::Sqlite { source, .. } => match source.sqlite_error_code() {
                Some(ErrorCode::NotADatabase | ErrorCode::DatabaseCorrupt) => Fault::Unusable,
                _ => Fault::Pause,
            },
            Self::Missing(_) => Fault::Pause,
        }
    }
}

fn sql(path: &Path) -> impl Fn(rusqlite::Error) -> VisitsError + '_ {
    move |source| VisitsError::Sqlite {
        path: path.to_owned(),
        source,
    }
}

/// Open (creating it if need be) the record at `path` for writing: WAL,
/// synchronous=NORMAL, migrated to [`SCHEMA_VERSION`]; the file checked
/// (`quick_check`) so that a corrupt one is found at once.
///
/// # Errors
/// See [`VisitsError`] and [`VisitsError::fault`].
pub fn open(path: &Path) -> Result<Connection, VisitsError> {
    let e = sql(path);
    let conn = Connection::open_with_flags(
        path,
        OpenFlags::SQLITE_OPEN_READ_WRITE
            | OpenFlags::SQLITE_OPEN_CREATE
            | OpenFlags::SQLITE_OPEN_NO_MUTEX,
    )
    .map_err(&e)?;
    // A lock held elsewhere is waited on this long, on the writer's
    // thread, never a frame's.
    conn.busy_timeout(std::time::Duration::from_millis(200))
        .map_err(&e)?;
    let mode: String = conn
        .query_row("PRAGMA journal_mode = WAL", [], |r| r.get(0))
        .map_err(&e)?;
    if !mode.eq_ignore_ascii_case("wal") {
        tracing::warn!(path = %path.display(), mode, "the visits database is not in WAL mode");
    }
    // A small page cache: the kiosk writes, the report reads.
    conn.execute_batch(
        "PRAGMA synchronous = NORMAL; PRAGMA journal_size_limit = 4194304; PRAGMA cache_size = -512;",
    )
        .map_err(&e)?;
    let ok: String = conn
        .query_row("PRAGMA quick_check", [], |r| r.get(0))
        .map_err(&e)?;
    if ok != "ok" {
        return Err(VisitsError::NotOurs {
            path: path.to_owned(),
            why: format!("corrupt: {ok}"),
        });
    }
    migrate(&conn, path)?;
    Ok(conn)
}

/// Open the record at `path` to read it (the report): it must exist, be
/// marionette's and of a schema this build knows.
///
/// # Errors
/// [`VisitsError::Missing`], [`VisitsError::NotOurs`], [`VisitsError::Newer`].
pub fn open_to_read(path: &Path) -> Result<Connection, VisitsError> {
    if !path.is_file() {
        return Err(VisitsError::Missing(path.to_owned()));
    }
    let e = sql(path);
    // Read-write without create: a WAL database is read through its log,
    // which needs the shared-memory file (a read-only open of a database
    // the kiosk has open works as well).
    let conn = Connection::open_with_flags(
        path,
        OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX,
    )
    .map_err(&e)?;
    conn.busy_timeout(std::time::Duration::from_secs(2))
        .map_err(&e)?;
    let (app, version) = ids(&conn).map_err(|source| match source.sqlite_error_code() {
        Some(ErrorCode::NotADatabase) => VisitsError::NotOurs {
            path: path.to_owned(),
            why: "the file is not a SQLite database".to_owned(),
        },
        _ => VisitsError::Sqlite {
            path: path.to_owned(),
            source,
        },
    })?;
    ours(path, app, version, false)?;
    if version < SCHEMA_VERSION {
        return Err(VisitsError::NotOurs {
            path: path.to_owned(),
            why: format!(
                "schema {version} (the kiosk brings it to {SCHEMA_VERSION} when it next opens it)"
            ),
        });
    }
    Ok(conn)
}

/// Whether a database that says `app` and `version` is marionette's record
/// of a schema this build can read (`empty`: a new file, none yet).
fn ours(path: &Path, app: i64, version: i64, empty: bool) -> Result<(), VisitsError> {
    if app != APPLICATION_ID && !(app == 0 && empty) {
        return Err(VisitsError::NotOurs {
            path: path.to_owned(),
            why: format!("a SQLite database of another program (application_id {app:#x})"),
        });
    }
    if version > SCHEMA_VERSION {
        return Err(VisitsError::Newer {
            path: path.to_owned(),
            found: version,
            known: SCHEMA_VERSION,
        });
    }
    Ok(())
}

fn ids(conn: &Connection) -> rusqlite::Result<(i64, i64)> {
    let app: i64 = conn.query_row("PRAGMA application_id", [], |r| r.get(0))?;
    let version: i64 = conn.query_row("PRAGMA user_version", [], |r| r.get(0))?;
    Ok((app, version))
}

/// Bring the database to [`SCHEMA_VERSION`], each step in a transaction.
fn migrate(conn: &Connection, path: &Path) -> Result<(), VisitsError> {
    let e = sql(path);
    let (app, version) = ids(conn).map_err(&e)?;
    let tables: i64 = conn
        .query_row("SELECT count(*) FROM sqlite_schema", [], |r| r.get(0))
        .map_err(&e)?;
    ours(path, app, version, tables == 0)?;
    for (k, step) in MIGRATIONS.iter().enumerate().skip(version.max(0) as usize) {
        let batch = format!(
            "BEGIN; {step} PRAGMA application_id = {APPLICATION_ID}; PRAGMA user_version = {}; COMMIT;",
            k + 1
        );
        if let Err(err) = conn.execute_batch(&batch) {
            let _ = conn.execute_batch("ROLLBACK");
            return Err(e(err));
        }
        tracing::info!(path = %path.display(), version = k + 1, "visits database schema brought up to date");
    }
    Ok(())
}

/// Write `rows` in one transaction.
///
/// # Errors
/// SQLite's, with the path.
pub fn insert(conn: &mut Connection, path: &Path, rows: &[Row]) -> Result<(), VisitsError> {
    let e = sql(path);
    let tx = conn.transaction().map_err(&e)?;
    {
        let mut session = tx
            .prepare_cached("INSERT OR REPLACE INTO sessions VALUES (?1, ?2, ?3, ?4, ?5)")
            .map_err(&e)?;
        let mut touch = tx
            .prepare_cached("INSERT INTO touches VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8)")
            .map_err(&e)?;
        let mut action = tx
            .prepare_cached(
                "INSERT OR REPLACE INTO actions VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9)",
            )
            .map_err(&e)?;
        let mut near = tx
            .prepare_cached("INSERT INTO near_misses VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9)")
            .map_err(&e)?;
        for r in rows {
            match r {
                Row::Session {
                    start_ms,
                    length_s,
                    peak_fingers,
                    characters,
                    ended,
                } => session.execute(params![start_ms, length_s, peak_fingers, characters, ended]),
                Row::Touch {
                    session_ms,
                    at_ms,
                    took,
                    part,
                    character,
                    cell,
                    duration_s,
                } => touch.execute(params![
                    session_ms, at_ms, took, part, character, cell.0, cell.1, duration_s
                ]),
                Row::Action {
                    session_ms,
                    at_ms,
                    character,
                    action: name,
                    by_reach,
                    cost_m,
                    margin_m,
                    outcome,
                    length_s,
                } => action.execute(params![
                    session_ms, at_ms, character, name, by_reach, cost_m, margin_m, outcome,
                    length_s
                ]),
                Row::NearMiss {
                    session_ms,
                    at_ms,
                    character,
                    action: name,
                    cost_m,
                    cost_limit_m,
                    margin_m,
                    margin_needed_m,
                    held_by,
                } => near.execute(params![
                    session_ms,
                    at_ms,
                    character,
                    name,
                    cost_m,
                    cost_limit_m,
                    margin_m,
                    margin_needed_m,
                    held_by
                ]),
            }
            .map_err(&e)?;
        }
    }
    tx.commit().map_err(&e)
}

/// How much was dropped to keep the record within its bounds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Pruned {
    /// Days of rows dropped for the size bound.
    pub days: u32,
    /// Sessions dropped (for age or size).
    pub sessions: u64,
}

const DAY_MS: i64 = 86_400_000;

/// Drop rows older than `keep_days` before `now_ms`, then the oldest days
/// while the rows take more than eight tenths of `max_bytes` (the file
/// keeps its freed pages for the next rows, so it stays under the bound;
/// the log is kept to a tenth).
///
/// # Errors
/// SQLite's, with the path.
pub fn prune(
    conn: &mut Connection,
    path: &Path,
    now_ms: i64,
    keep_days: u32,
    max_bytes: u64,
) -> Result<Pruned, VisitsError> {
    let e = sql(path);
    // The write-ahead log is checkpointed and cut back at a tenth of the
    // bound (4 MB at most).
    let log = (max_bytes / 10).min(4 << 20);
    conn.execute_batch(&format!(
        "PRAGMA wal_autocheckpoint = {}; PRAGMA journal_size_limit = {log};",
        (log / 4096).max(16)
    ))
    .map_err(&e)?;
    let mut pruned = Pruned::default();
    pruned.sessions += drop_before(conn, now_ms - i64::from(keep_days) * DAY_MS).map_err(&e)?;
    let budget = max_bytes / 10 * 8;
    while used_bytes(conn).map_err(&e)? > budget {
        let oldest: Option<i64> = conn
            .query_row("SELECT min(start_ms) FROM sessions", [], |r| r.get(0))
            .map_err(&e)?;
        let Some(oldest) = oldest else {
            break;
        };
        pruned.sessions +=
            drop_before(conn, oldest - oldest.rem_euclid(DAY_MS) + DAY_MS).map_err(&e)?;
        pruned.days += 1;
    }
    if pruned.sessions > 0 {
        tracing::info!(
            path = %path.display(),
            sessions = pruned.sessions,
            days_for_size = pruned.days,
            keep_days,
            max_bytes,
            "old visits dropped to keep the record within its bounds"
        );
    }
    Ok(pruned)
}

/// Bytes the database's rows take (its pages less the free ones).
///
/// # Errors
/// SQLite's.
pub fn used_bytes(conn: &Connection) -> rusqlite::Result<u64> {
    let pages: i64 = conn.query_row("PRAGMA page_count", [], |r| r.get(0))?;
    let free: i64 = conn.query_row("PRAGMA freelist_count", [], |r| r.get(0))?;
    let size: i64 = conn.query_row("PRAGMA page_size", [], |r| r.get(0))?;
    Ok(((pages - free).max(0) * size) as u64)
}

/// Drop every row of sessions that started before `ms`; how many sessions.
fn drop_before(conn: &mut Connection, ms: i64) -> rusqlite::Result<u64> {
    let tx = conn.transaction()?;
    let n = tx.execute("DELETE FROM sessions WHERE start_ms < ?1", [ms])?;
    for table in ["touches", "actions", "near_misses"] {
        tx.execute(&format!("DELETE FROM {table} WHERE session_ms < ?1"), [ms])?;
    }
    tx.commit()?;
    Ok(n as u64)
}

/// Rename the database at `path` (and its log) out of the way, with `stamp`
/// (a date) in the new name; the name it now has.
///
/// # Errors
/// The rename's.
pub fn set_aside(path: &Path, stamp: &str) -> std::io::Result<PathBuf> {
    let name = path
        .file_name()
        .map_or_else(|| "visits.db".into(), |n| n.to_string_lossy().into_owned());
    let mut k = 0;
    let aside = loop {
        let suffix = if k == 0 {
            String::new()
        } else {
            format!("-{k}")
        };
        let p = path.with_file_name(format!("{name}.{stamp}{suffix}.set-aside"));
        if !p.exists() {
            break p;
        }
        k += 1;
    };
    std::fs::rename(path, &aside)?;
    for ext in ["-wal", "-shm"] {
        let side = path.with_file_name(format!("{name}{ext}"));
        if side.exists() {
            let _ = std::fs::rename(
                &side,
                aside.with_file_name(format!(
                    "{}{ext}",
                    aside.file_name().unwrap_or_default().to_string_lossy()
                )),
            );
        }
    }
    Ok(aside)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn session(start_ms: i64) -> Row {
        Row::Session {
            start_ms,
            length_s: 30.0,
            peak_fingers: 2,
            characters: 1,
            ended: true,
        }
    }

    #[test]
    fn rows_go_in_and_a_session_told_again_replaces_itself() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("visits.db");
        let mut conn = open(&path).unwrap();
        insert(&mut conn, &path, &[session(1), session(1), session(2)]).unwrap();
        let n: i64 = conn
            .query_row("SELECT count(*) FROM sessions", [], |r| r.get(0))
            .unwrap();
        assert_eq!(n, 2);
        drop(conn);
        let read = open_to_read(&path).unwrap();
        assert_eq!(ids(&read).unwrap(), (APPLICATION_ID, SCHEMA_VERSION));
    }

    #[test]
    fn a_file_that_is_no_database_or_of_a_newer_schema_is_unusable() {
        let dir = tempfile::tempdir().unwrap();
        let junk = dir.path().join("junk.db");
        std::fs::write(&junk, vec![b'x'; 8192]).unwrap();
        let err = open(&junk).unwrap_err();
        assert_eq!(err.fault(), Fault::Unusable, "{err}");
        assert!(matches!(
            open_to_read(&junk),
            Err(VisitsError::NotOurs { .. })
        ));
        let newer = dir.path().join("newer.db");
        drop(open(&newer).unwrap());
        Connection::open(&newer)
            .unwrap()
            .execute_batch("PRAGMA user_version = 99")
            .unwrap();
        let err = open(&newer).unwrap_err();
        assert!(matches!(err, VisitsError::Newer { found: 99, .. }), "{err}");
        assert_eq!(err.fault(), Fault::Unusable);
        assert!(
            open_to_read(&newer)
                .unwrap_err()
                .to_string()
                .contains("newer")
        );
        let aside = set_aside(&newer, "2026-11-29T0300").unwrap();
        assert!(
            aside
                .to_string_lossy()
                .ends_with("newer.db.2026-11-29T0300.set-aside")
        );
        assert!(!newer.exists());
        assert!(open(&newer).is_ok());
    }

    #[test]
    fn old_days_go_first_when_the_record_outgrows_its_size() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("visits.db");
        let mut conn = open(&path).unwrap();
        let rows: Vec<Row> = (0..40 * 24)
            .flat_map(|h| {
                let start = i64::from(h) * 3_600_000;
                (0..3)
                    .map(move |k| Row::Touch {
                        session_ms: start,
                        at_ms: start + k,
                        took: "part",
                        part: Some("left_hand"),
                        character: Some(0),
                        cell: (1, 2),
                        duration_s: 1.5,
                    })
                    .chain([session(start)])
            })
            .collect();
        insert(&mut conn, &path, &rows).unwrap();
        let before = used_bytes(&conn).unwrap();
        // Everything younger than 30 days kept by age: 10 days go.
        let now = 40 * DAY_MS;
        let p = prune(&mut conn, &path, now, 30, u64::MAX).unwrap();
        assert_eq!(
            p,
            Pruned {
                days: 0,
                sessions: 240
            }
        );
        // Then a bound under what is left: the oldest days go first.
        let p = prune(&mut conn, &path, now, 30, before / 2).unwrap();
        assert!(
            p.days > 0 && used_bytes(&conn).unwrap() <= before / 2 / 10 * 9,
            "{p:?}"
        );
        let oldest: i64 = conn
            .query_row("SELECT min(start_ms) FROM sessions", [], |r| r.get(0))
            .unwrap();
        assert_eq!(oldest, (10 + i64::from(p.days)) * DAY_MS);
    }
}
