//! Every real recording in ../shared/recordings/evemu parses, and the
//! tracker's counts agree with the ones INDEX.tsv gives (counted
//! independently of marionette).

mod common;

use std::collections::HashMap;

use marionette::input::device::DeviceKind;
use marionette::input::evemu::Recording;
use marionette::input::pipeline::summarize;
use marionette::input::tracker::track_events;

struct Row {
    file: String,
    direct_touchscreen: bool,
    slots_max: usize,
    frames: usize,
    protocol: String,
    truncated: bool,
    notes: String,
}

fn index() -> Vec<Row> {
    let dir = common::shared_dir().join("recordings");
    let text = std::fs::read_to_string(dir.join("INDEX.tsv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split('\t').collect();
    let col: HashMap<&str, usize> = header.iter().enumerate().map(|(i, h)| (*h, i)).collect();
    lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let f: Vec<&str> = l.split('\t').collect();
            let get = |k: &str| f.get(col[k]).copied().unwrap_or("").to_owned();
            Row {
                file: get("file"),
                direct_touchscreen: get("is_direct_touchscreen") == "yes",
                slots_max: get("n_slots_max").parse().unwrap(),
                frames: get("n_frames").parse().unwrap(),
                protocol: get("mt_protocol"),
                truncated: get("truncated").starts_with("yes"),
                notes: get("notes"),
            }
        })
        .collect()
}

#[test]
fn every_recording_matches_the_index() {
    let dir = common::shared_dir().join("recordings");
    let rows = index();
    assert!(
        rows.len() >= 20,
        "INDEX.tsv lists {} recordings",
        rows.len()
    );
    let mut failures = Vec::new();
    for row in &rows {
        let rec = Recording::read_file(&dir.join(&row.file))
            .unwrap_or_else(|e| panic!("{} does not parse: {e}", row.file));
        let (s, _) = summarize(&rec);
        let kind = rec.device.kind();
        let mut check = |what: &str, ok: bool, detail: String| {
            if !ok {
                failures.push(format!("{}: {what}: {detail}", row.file));
            }
        };
        check(
            "frames",
            s.frames == row.frames,
            format!("{} vs index {}", s.frames, row.frames),
        );
        check(
            "is a finger touchscreen",
            (kind == DeviceKind::Touchscreen) == row.direct_touchscreen,
            format!("classified {kind:?}, index says {}", row.direct_touchscreen),
        );
        // Pens and touchpads report no finger contacts (the index counts
        // the touchpad's fingers all the same).
        let expected_contacts = if matches!(kind, DeviceKind::Pen | DeviceKind::Touchpad) {
            0
        } else {
            row.slots_max
        };
        check(
            "max contacts",
            s.max_contacts == expected_contacts,
            format!("{} vs index {}", s.max_contacts, expected_contacts),
        );
        let protocol = s.protocol.map(|p| p.to_string()).unwrap_or_default();
        let expected_protocol = match row.protocol.chars().next() {
            Some('B') => "B",
            Some('A') => "A",
            _ => "single",
        };
        if kind != DeviceKind::Pen {
            check(
                "protocol",
                protocol == expected_protocol,
                format!("{protocol} vs {}", row.protocol),
            );
        }
        check(
            "truncated tail dropped",
            (rec.dropped_trailing_events > 0) == row.truncated,
            format!("{} events dropped", rec.dropped_trailing_events),
        );
        // Every finger that went down came up, except where the index says
        // the recording stops with fingers down.
        let still_down = row
            .notes
            .split("with ")
            .nth(1)
            .and_then(|p| {
                p.strip_suffix(" contacts still down")
                    .or_else(|| p.split(" contacts still down").next())
            })
            .and_then(|n| n.trim().parse::<usize>().ok())
            .unwrap_or(0);
        if rec.device.protocol().is_some() {
            let (frames, _) = track_events(&rec.device, &rec.events).unwrap();
            let down = frames.last().map_or(0, |f| {
                f.contacts.iter().filter(|c| c.phase.is_down()).count()
            });
            check(
                "contacts down at the end",
                down == still_down,
                format!("{down} vs index {still_down}"),
            );
        }
        // Where the index's notes count touch sequences, they must agree.
        if let Some(n) = row
            .notes
            .split(", ")
            .find_map(|p| p.strip_suffix(" touch sequences"))
            .and_then(|p| p.split_whitespace().last())
            .and_then(|n| n.parse::<u64>().ok())
        {
            check(
                "touch sequences",
                s.touch_sequences == n,
                format!("{} vs index {n}", s.touch_sequences),
            );
        }
    }
    assert!(
        failures.is_empty(),
        "{} mismatches:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
