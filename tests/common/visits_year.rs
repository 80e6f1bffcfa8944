//! A busy year at the table, made up: a session a minute, ten hours a
//! day, each with a few grabs, a camera move, an action most of the time
//! and now and then a near miss; written day by day through the record's
//! own store and kept within its bounds as the kiosk's writer does.

use std::path::Path;

use marionette::app::visits::record::Row;
use marionette::app::visits::store;

pub const DAY_MS: i64 = 86_400_000;
/// 2026-01-01 00:00 UTC.
pub const YEAR_START_MS: i64 = 1_767_225_600_000;

/// A small deterministic generator (xorshift).
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    pub fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

const PARTS: [&str; 6] = [
    "left_hand",
    "right_hand",
    "head",
    "pelvis",
    "left_foot",
    "right_foot",
];
const ACTIONS: [&str; 5] = ["punch_left", "kick_right", "wave_left", "bow", "jump"];

/// Day `d`'s rows: a session every minute from 09:00 to 19:00.
pub fn day(d: i64, rng: &mut Rng) -> Vec<Row> {
    let mut rows = Vec::new();
    for minute in 0..600 {
        let start = YEAR_START_MS + d * DAY_MS + 9 * 3_600_000 + minute * 60_000;
        let length = 5.0 + rng.below(50) as f64;
        for k in 0..3 {
            rows.push(Row::Touch {
                session_ms: start,
                at_ms: start + k * 2000,
                took: "part",
                part: Some(PARTS[rng.below(6) as usize]),
                character: Some(0),
                cell: (rng.below(16) as u32, rng.below(9) as u32),
                duration_s: 1.0 + rng.below(30) as f64 / 10.0,
            });
        }
        rows.push(Row::Touch {
            session_ms: start,
            at_ms: start + 7000,
            took: "camera",
            part: None,
            character: None,
            cell: (rng.below(16) as u32, rng.below(9) as u32),
            duration_s: 0.8,
        });
        if rng.below(10) < 7 {
            rows.push(Row::Action {
                session_ms: start,
                at_ms: start + 3000,
                character: 0,
                action: ACTIONS[rng.below(5) as usize].to_owned(),
                by_reach: false,
                cost_m: Some(0.02),
                margin_m: Some(0.03),
                outcome: "finished",
                length_s: Some(1.5),
            });
        }
        if rng.below(10) < 3 {
            rows.push(Row::NearMiss {
                session_ms: start,
                at_ms: start + 5000,
                character: 0,
                action: ACTIONS[rng.below(5) as usize].to_owned(),
                cost_m: 0.06,
                cost_limit_m: 0.04,
                margin_m: 0.01,
                margin_needed_m: 0.02,
                held_by: "cost",
            });
        }
        rows.push(Row::Session {
            start_ms: start,
            length_s: length,
            peak_fingers: 1 + rng.below(3) as u32,
            characters: 1,
            ended: true,
        });
    }
    rows
}

/// The database and its log, in bytes.
pub fn size_on_disk(path: &Path) -> u64 {
    let side = |ext: &str| {
        let mut p = path.as_os_str().to_owned();
        p.push(ext);
        std::fs::metadata(p).map_or(0, |m| m.len())
    };
    side("") + side("-wal")
}

/// Write `days` busy days into `path`, pruned every day to `max_bytes`;
/// the largest size on disk seen after a day.
pub fn write_year(path: &Path, days: i64, max_bytes: u64) -> u64 {
    let mut conn = store::open(path).expect("open the record");
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let mut largest = 0;
    for d in 0..days {
        let rows = day(d, &mut rng);
        for hour in rows.chunks(rows.len().div_ceil(10)) {
            store::insert(&mut conn, path, hour).expect("insert");
        }
        store::prune(
            &mut conn,
            path,
            YEAR_START_MS + (d + 1) * DAY_MS,
            365,
            max_bytes,
        )
        .expect("prune");
        largest = largest.max(size_on_disk(path));
    }
    largest
}
