//! The record of what visitors do, and its report: honest counts on
//! replayed recordings, a database that stalls, breaks or is killed
//! mid-write, a year of busy days within its bound, and bad input refused.

#![allow(
    clippy::print_stderr,
    reason = "the measurements are printed for the reader of the run"
)]
#![allow(
    clippy::disallowed_methods,
    reason = "a stalled database and a killed writer are real time: frames paced and kills timed on the clock"
)]

mod common;
#[path = "common/visits_year.rs"]
mod year;

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use marionette::app::visits::record::Row;
use marionette::app::visits::store;
use marionette::app::visits::writer::{Bounds, Writer};

const BOUNDS: Bounds = Bounds {
    keep_days: 365,
    max_bytes: 256_000_000,
};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_marionette"))
}

/// Sessions in a recording, from its touch frames alone: fingers down
/// after the table was empty for `idle_s` (or at first) start one.
fn sessions_in(recording: &Path, idle_s: f64) -> u64 {
    let o = bin()
        .args(["replay", recording.to_str().unwrap(), "--contacts"])
        .env_remove("RUST_LOG")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut down = std::collections::BTreeSet::new();
    let (mut sessions, mut empty_since) = (0, f64::NEG_INFINITY);
    for line in String::from_utf8_lossy(&o.stdout).lines() {
        let f: serde_json::Value = serde_json::from_str(line).unwrap();
        let t = f["t"].as_f64().unwrap();
        for c in f["contacts"].as_array().unwrap() {
            if c["tool"] != "finger" {
                continue;
            }
            let id = c["id"].as_u64().unwrap();
            if c["phase"] == "down" {
                if down.is_empty() && t - empty_since >= idle_s {
                    sessions += 1;
                }
                down.insert(id);
            } else if (c["phase"] == "up" || c["phase"] == "cancel")
                && down.remove(&id)
                && down.is_empty()
            {
                empty_since = t;
            }
        }
    }
    sessions
}

fn number_after(text: &str, prefix: &str) -> u64 {
    let at = text
        .find(prefix)
        .unwrap_or_else(|| panic!("{prefix:?} in {text}"))
        + prefix.len();
    text[at..]
        .split(|c: char| !c.is_ascii_digit())
        .next()
        .unwrap()
        .parse()
        .unwrap()
}

/// Replay `recording` with `--visits` and the debug log on, then report:
/// the report's counts against the replay's summary, its debug log and the
/// recording's own touches.
fn counts_agree(recording: &Path, dir: &Path) -> serde_json::Value {
    let db = dir.join("visits.db");
    let o = bin()
        .args([
            "replay",
            recording.to_str().unwrap(),
            "--visits",
            db.to_str().unwrap(),
        ])
        .env("RUST_LOG", "marionette=debug")
        .output()
        .unwrap();
    let (out, log) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(o.status.success(), "{log}");
    let grabs = number_after(&out, "grabs: ");
    let near = number_after(&out, "drags that started nothing: ");
    let actions = number_after(&out, "actions started by drags: ");
    assert_eq!(
        grabs,
        log.matches("finger holds a part").count() as u64,
        "{out}"
    );
    assert_eq!(
        near,
        log.matches("drag started no action").count() as u64,
        "{out}"
    );
    let o = bin()
        .args([
            "report",
            "--db",
            db.to_str().unwrap(),
            "--since",
            "all",
            "--out",
        ])
        .arg(dir.join("report"))
        .env_remove("RUST_LOG")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("report/report.json")).unwrap()).unwrap();
    let sessions = sessions_in(recording, 45.0);
    eprintln!(
        "{}: sessions {sessions}, grabs {grabs}, actions {actions}, near misses {near}",
        recording.display()
    );
    assert_eq!(r["sessions"], sessions, "{r}");
    assert_eq!(r["grabs"], grabs, "{r}");
    assert_eq!(r["actions_started"], actions, "{r}");
    assert_eq!(r["near_misses"], near, "{r}");
    let parts: u64 = r["parts"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["grabs"].as_u64().unwrap())
        .sum();
    assert_eq!(parts, grabs, "{r}");
    let heat: u64 = r["heat"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|row| row.as_array().unwrap())
        .map(|n| n.as_u64().unwrap())
        .sum();
    assert_eq!(heat, r["touches"].as_u64().unwrap(), "{r}");
    r
}

#[test]
fn the_report_counts_what_the_replays_say() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    // The bundled demo: one visitor, every action.
    let demo = dir.path().join("demo");
    let r = counts_agree(&root.join("assets/recordings/demo.evemu"), &demo);
    // The README's summary: 13 grabs, two drags that started nothing.
    assert_eq!(r["sessions"], 1);
    assert_eq!(r["actions_started"], 8);
    assert_eq!(r["grabs"], 13);
    assert_eq!(r["near_misses"], 2);
    // A real panel's long multi-finger capture.
    let real = common::shared_dir().join("recordings/evemu/evemu-data.3m-microtouch-usb.evemu");
    let r = counts_agree(&real, &dir.path().join("3m"));
    assert!(r["peak_fingers"].as_u64().unwrap() >= 5, "{r}");
    // Two abuse recordings: fingers yanking the character at random.
    for seed in ["1", "2"] {
        let abuse = dir.path().join(format!("abuse-{seed}.evemu"));
        let o = bin()
            .args(["author-abuse", "--seconds", "60", "--seed", seed, "--out"])
            .arg(&abuse)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let r = counts_agree(&abuse, &dir.path().join(format!("abuse-{seed}")));
        assert!(r["grabs"].as_u64().unwrap() > 10, "{r}");
    }
}

/// A touch in a session `session_ms` after a recent time (the record
/// drops rows older than it keeps).
fn touch(session_ms: i64, at_ms: i64) -> Row {
    let recent = (marionette::app::visits::unix_now() * 1e3) as i64 - 60_000;
    let (session_ms, at_ms) = (recent + session_ms, recent + at_ms);
    Row::Touch {
        session_ms,
        at_ms,
        took: "part",
        part: Some("left_hand"),
        character: Some(0),
        cell: (3, 4),
        duration_s: 1.0,
    }
}

fn count(path: &Path, table: &str) -> i64 {
    let c = rusqlite::Connection::open(path).unwrap();
    c.query_row(&format!("SELECT count(*) FROM {table}"), [], |r| r.get(0))
        .unwrap()
}

fn integrity(path: &Path) -> String {
    let c = rusqlite::Connection::open(path).unwrap();
    c.query_row("PRAGMA integrity_check", [], |r| r.get(0))
        .unwrap()
}

#[test]
fn a_file_that_is_no_record_is_set_aside_and_a_missing_folder_pauses_recording() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("visits.db");
    std::fs::write(&path, "not a database, and worth keeping\n".repeat(200)).unwrap();
    let w = Writer::start(path.clone(), BOUNDS);
    w.send(vec![touch(1, 1), touch(1, 2)]);
    assert!(w.flush(Duration::from_secs(10)));
    assert_eq!(w.committed(), 2);
    let aside: Vec<PathBuf> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.to_string_lossy().ends_with(".set-aside"))
        .collect();
    assert_eq!(aside.len(), 1, "{aside:?}");
    assert!(
        std::fs::read_to_string(&aside[0])
            .unwrap()
            .starts_with("not a database")
    );
    assert_eq!(count(&path, "touches"), 2);
    w.finish();

    // A folder not there yet: paused, rows kept, written once it is.
    let later = dir.path().join("later/visits.db");
    let w = Writer::start(later.clone(), BOUNDS);
    w.send(vec![touch(5, 5)]);
    assert!(w.flush(Duration::from_secs(10)));
    assert!(w.paused() && w.committed() == 0);
    std::fs::create_dir(dir.path().join("later")).unwrap();
    let t0 = Instant::now();
    while w.committed() == 0 && t0.elapsed() < Duration::from_secs(20) {
        w.send(vec![touch(5, 6)]);
        std::thread::sleep(Duration::from_millis(100));
    }
    assert!(w.committed() >= 2 && !w.paused());
    let written = w.finish();
    assert!(written.all(), "{written:?}");
    assert_eq!(count(&later, "touches") as u64, written.sent);
}

#[test]
fn a_database_locked_for_ten_seconds_never_holds_a_frame_up() {
    use marionette::app::visits::Recording;
    use marionette::control::stage::{Took, TouchEvent};
    use marionette::screen::ScreenPoint;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("visits.db");
    drop(store::open(&path).unwrap());
    // Another program holds the database's write lock for ten seconds.
    let (locked, lock) = std::sync::mpsc::channel();
    let holder = {
        let path = path.clone();
        std::thread::spawn(move || {
            let c = rusqlite::Connection::open(&path).unwrap();
            c.execute_batch("BEGIN EXCLUSIVE; INSERT INTO sessions VALUES (0, 0, 0, 0, 1);")
                .unwrap();
            locked.send(()).unwrap();
            std::thread::sleep(Duration::from_secs(10));
            c.execute_batch("COMMIT").unwrap();
        })
    };
    lock.recv().unwrap();
    let mut rec = Recording::start(path.clone(), BOUNDS, 1.8e9, 45.0, (1600.0, 900.0));
    // Frames at 60 Hz for twelve seconds, a finger landing and lifting
    // every half second.
    let (mut slowest, start) = (Duration::ZERO, Instant::now());
    for n in 0..720u32 {
        let t = f64::from(n) / 60.0;
        let touches = match n % 30 {
            0 => vec![TouchEvent::Down {
                id: u64::from(n),
                t,
                at: ScreenPoint::new(800.0, 450.0),
                took: Took::Camera,
            }],
            15 => vec![TouchEvent::Up {
                id: u64::from(n - 15),
                t,
            }],
            _ => Vec::new(),
        };
        let before = Instant::now();
        rec.frame(&touches, &[], t, true);
        slowest = slowest.max(before.elapsed());
        let due = start + Duration::from_secs_f64(f64::from(n + 1) / 60.0);
        std::thread::sleep(due.saturating_duration_since(Instant::now()));
    }
    let took = start.elapsed().as_secs_f64();
    eprintln!("12 s of frames in {took:.2} s, the slowest frame's record call {slowest:?}");
    // A call that waited on the lock would take its 200 ms busy timeout
    // (or the lock's 10 s); a busy machine may hold a thread up for a few
    // of its time slices.
    assert!(slowest < Duration::from_millis(100), "{slowest:?}");
    assert!(took < 12.5, "{took}");
    holder.join().unwrap();
    let (counts, written) = rec.finish();
    assert!(written.all(), "{written:?}");
    assert_eq!(count(&path, "touches") as u64, counts.touches);
    assert_eq!(counts.touches, 24);
}

/// The writer the next test kills: rows handed over as fast as frames
/// would, its committed count printed as it grows.
#[test]
fn writer_child() {
    let Some(path) = std::env::var_os("MARIONETTE_VISITS_CHILD") else {
        return;
    };
    use std::io::Write;
    let w = Writer::start(PathBuf::from(path), BOUNDS);
    let mut out = std::io::stdout().lock();
    // (The test harness has written "test writer_child ... " on this line.)
    writeln!(out, "ready").unwrap();
    let (mut last, mut k) = (u64::MAX, 0i64);
    loop {
        w.send((0..20).map(|j| touch(1, k * 20 + j)).collect());
        k += 1;
        std::thread::sleep(Duration::from_millis(4));
        let c = w.committed();
        if c != last {
            writeln!(out, "committed {c}").unwrap();
            out.flush().unwrap();
            last = c;
        }
    }
}

#[test]
fn a_writer_killed_mid_batch_a_hundred_times_loses_nothing_committed() {
    let dir = tempfile::tempdir().unwrap();
    let me = std::env::current_exe().unwrap();
    let mut rng = year::Rng(0x2545_F491_4F6C_DD1D);
    let runs: Vec<(PathBuf, u64)> = (0..100)
        .map(|k| {
            (
                dir.path().join(format!("kill-{k}.db")),
                300 + rng.below(900),
            )
        })
        .collect();
    let results: Vec<(i64, u64, String)> = std::thread::scope(|s| {
        let workers: Vec<_> = runs
            .chunks(25)
            .map(|chunk| {
                let me = &me;
                s.spawn(move || {
                    chunk
                        .iter()
                        .map(|(path, after_ms)| {
                            let mut child = Command::new(me)
                                .args([
                                    "--exact",
                                    "writer_child",
                                    "--nocapture",
                                    "--test-threads",
                                    "1",
                                ])
                                .env("MARIONETTE_VISITS_CHILD", path)
                                .stdout(Stdio::piped())
                                .stderr(Stdio::null())
                                .spawn()
                                .unwrap();
                            let lines = BufReader::new(child.stdout.take().unwrap());
                            let (tx, rx) = std::sync::mpsc::channel();
                            let reader = std::thread::spawn(move || {
                                for l in lines.lines().map_while(Result::ok) {
                                    if tx.send(l).is_err() {
                                        break;
                                    }
                                }
                            });
                            // From "ready" on, kill after a while.
                            let mut seen = 0u64;
                            let mut ready = None;
                            let spawned = Instant::now();
                            loop {
                                assert!(
                                    ready.is_some() || spawned.elapsed() < Duration::from_secs(60),
                                    "the writer never said it was ready"
                                );
                                if let Ok(l) = rx.recv_timeout(Duration::from_millis(5)) {
                                    if l.ends_with("ready") {
                                        ready = Some(Instant::now());
                                    } else if let Some(c) = l.strip_prefix("committed ") {
                                        seen = c.parse().unwrap();
                                    }
                                }
                                if ready.is_some_and(|r| {
                                    r.elapsed() >= Duration::from_millis(*after_ms)
                                }) {
                                    break;
                                }
                            }
                            // Every count the child said before the kill was
                            // committed before it.
                            while let Ok(l) = rx.try_recv() {
                                if let Some(c) = l.strip_prefix("committed ") {
                                    seen = c.parse().unwrap();
                                }
                            }
                            child.kill().unwrap();
                            child.wait().unwrap();
                            reader.join().unwrap();
                            (count(path, "touches"), seen, integrity(path))
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|w| w.join().unwrap())
            .collect()
    });
    let mut least_margin = i64::MAX;
    for (k, (rows, seen, ok)) in results.iter().enumerate() {
        assert_eq!(ok, "ok", "run {k}");
        assert!(
            *rows >= *seen as i64,
            "run {k}: {rows} rows, {seen} said committed"
        );
        least_margin = least_margin.min(*rows - *seen as i64);
        // The database opens as the kiosk would open it.
        drop(store::open(&runs[k].0).unwrap());
    }
    let committed: i64 = results.iter().map(|r| r.0).sum();
    eprintln!("100 kills: {committed} rows kept in all, every committed row there");
    assert!(
        committed > 100 * 200,
        "the writer wrote little: {committed}"
    );
}

#[test]
fn a_busy_year_stays_within_its_bound() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("visits.db");
    let max = 24_000_000;
    let largest = year::write_year(&path, 365, max);
    let c = rusqlite::Connection::open(&path).unwrap();
    let (first, last, n): (i64, i64, i64) = c
        .query_row(
            "SELECT min(start_ms), max(start_ms), count(*) FROM sessions",
            [],
            |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)),
        )
        .unwrap();
    let days_kept = (last - first) / year::DAY_MS + 1;
    eprintln!(
        "a year of a session a minute: {largest} bytes at most on disk (bound {max}), {days_kept} days kept, {n} sessions"
    );
    assert!(largest <= max, "{largest}");
    // The newest days are the ones kept, whole.
    assert_eq!(
        last,
        year::YEAR_START_MS + 364 * year::DAY_MS + 9 * 3_600_000 + 599 * 60_000
    );
    assert_eq!(n, days_kept * 600);
    assert!(days_kept > 30 && days_kept < 365, "{days_kept}");
    assert_eq!(integrity(&path), "ok");
}

#[test]
fn report_refuses_what_is_no_record_and_a_since_it_cannot_read() {
    let dir = tempfile::tempdir().unwrap();
    let junk = dir.path().join("junk.db");
    std::fs::write(&junk, "hello\n".repeat(1000)).unwrap();
    let newer = dir.path().join("newer.db");
    drop(store::open(&newer).unwrap());
    rusqlite::Connection::open(&newer)
        .unwrap()
        .execute_batch("PRAGMA user_version = 7")
        .unwrap();
    let other = dir.path().join("other.db");
    rusqlite::Connection::open(&other)
        .unwrap()
        .execute_batch("CREATE TABLE t (x); INSERT INTO t VALUES (1);")
        .unwrap();
    for (db, says) in [
        (&junk, "not a SQLite database"),
        (&newer, "newer marionette"),
        (&other, "another program"),
    ] {
        let o = bin()
            .args(["report", "--db", db.to_str().unwrap(), "--out"])
            .arg(dir.path().join("out"))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(65), "{err}");
        assert!(
            err.contains(db.to_str().unwrap()) && err.contains(says),
            "{err}"
        );
    }
    assert!(!dir.path().join("out/report.html").exists());
    let o = bin()
        .args([
            "report",
            "--db",
            newer.to_str().unwrap(),
            "--since",
            "last week",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--since"), "{err}");
    let o = bin()
        .args(["report", "--db"])
        .arg(dir.path().join("nothing-here.db"))
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(66),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // replay --visits onto a file that is not a record: refused, the file
    // left as it was.
    let o = bin()
        .args([
            "replay",
            "assets/recordings/demo.evemu",
            "--visits",
            junk.to_str().unwrap(),
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(65),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert_eq!(
        std::fs::read_to_string(&junk).unwrap(),
        "hello\n".repeat(1000)
    );
}
