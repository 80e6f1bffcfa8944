//! evemu recordings: the text format of the evemu tools (`# EVEMU 1.x`),
//! read and written.
//!
//! A recording is a device description (`N:`, `I:`, `P:`, `B:`, `A:`, `L:`,
//! `S:` lines) followed by `E: sec.usec type code value` events. The reader
//! takes every version from 1.0 (and the older description-plus-events files
//! joined together) to 1.3: `A:` lines with or without the resolution field,
//! `#` comments on their own lines or after an event, values written as
//! `-001` or `0904`, absolute or rebased timestamps. It never panics: a
//! malformed file is an [`EvemuError`] that names the line and what was
//! expected. A recording whose last frame has no `SYN_REPORT` keeps only the
//! complete frames and says how many events it dropped.
//!
//! The writer produces version 1.3, which `evemu-play` reads.

use std::io::{self, Write};
use std::path::{Path, PathBuf};

use thiserror::Error;

mod parse;

use super::device::{AbsInfo, DeviceDescription, InputId};
use super::event::{
    ABS_CNT, EV_ABS, EV_CNT, EV_SYN, INPUT_PROP_CNT, RawEvent, SYN_MT_REPORT, code_count,
    code_name, type_name,
};

/// Errors reading an evemu recording.
#[derive(Debug, Error)]
pub enum EvemuError {
    /// The file could not be read at all.
    #[error("cannot read {path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
    /// A line does not have the form the format requires.
    #[error("{path}:{line}: {message}")]
    Syntax {
        path: PathBuf,
        line: usize,
        message: String,
    },
    /// The file has events but no device description.
    #[error("{path}: no device description (N:/I:/B:/A: lines) before the events")]
    NoDescription { path: PathBuf },
}

impl EvemuError {
    /// The line the error is on, where there is one.
    #[must_use]
    pub fn line(&self) -> Option<usize> {
        match self {
            EvemuError::Syntax { line, .. } => Some(*line),
            _ => None,
        }
    }
}

/// A parsed recording: the device and the events of its complete frames.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Recording {
    /// `(major, minor)` from the `# EVEMU x.y` line; `(1, 0)` when absent.
    pub version: (u16, u16),
    pub device: DeviceDescription,
    /// Events up to and including the last `SYN_REPORT`.
    pub events: Vec<RawEvent>,
    /// Events after the last `SYN_REPORT` that were dropped (an unfinished
    /// last frame).
    pub dropped_trailing_events: usize,
}

impl Recording {
    /// Number of complete frames (`SYN_REPORT` events).
    #[must_use]
    pub fn frame_count(&self) -> usize {
        self.events.iter().filter(|e| e.is_syn_report()).count()
    }

    /// Time from the first to the last event, in seconds.
    #[must_use]
    /// From the earliest to the latest event time stamp (s): a clock that
    /// went back during the recording does not make it negative.
    pub fn duration_s(&self) -> f64 {
        let times = self.events.iter().map(|e| e.time_us);
        match (times.clone().min(), times.max()) {
            (Some(a), Some(b)) => (b - a) as f64 / 1e6,
            _ => 0.0,
        }
    }

    /// Write this recording in evemu 1.3 format.
    pub fn write(&self, w: &mut impl Write) -> io::Result<()> {
        write_description(w, &self.device)?;
        for e in &self.events {
            write_event(w, e)?;
        }
        Ok(())
    }
}

/// Write the `# EVEMU 1.3` header and device description.
pub fn write_description(w: &mut impl Write, d: &DeviceDescription) -> io::Result<()> {
    writeln!(w, "# EVEMU 1.3")?;
    writeln!(w, "# Input device name: \"{}\"", d.name)?;
    writeln!(
        w,
        "# Input device ID: bus {:#04x} vendor {:#04x} product {:#04x} version {:#04x}",
        d.id.bustype, d.id.vendor, d.id.product, d.id.version
    )?;
    writeln!(
        w,
        "# Written by marionette: {} ({})",
        d.kind(),
        d.protocol()
            .map_or("no position axes".to_owned(), |p| format!("protocol {p}"))
    )?;
    for (code, a) in &d.abs {
        writeln!(
            w,
            "#   {:<20} min {} max {} fuzz {} flat {} resolution {}",
            code_name(EV_ABS, *code),
            a.minimum,
            a.maximum,
            a.fuzz,
            a.flat,
            a.resolution
        )?;
    }
    // N: takes the rest of the line; a newline in a name would break it.
    let name: String = d
        .name
        .chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect();
    writeln!(w, "N: {name}")?;
    writeln!(
        w,
        "I: {:04x} {:04x} {:04x} {:04x}",
        d.id.bustype, d.id.vendor, d.id.product, d.id.version
    )?;
    write_bytes(w, "P: ", &d.properties.0, INPUT_PROP_CNT.div_ceil(8))?;
    // EV_SYN codes; evemu always writes at least SYN_REPORT, SYN_CONFIG and
    // SYN_DROPPED, and so does every kernel device.
    if d.codes(EV_SYN).iter().next().is_some() {
        write_bytes(w, "B: 00 ", &d.codes(EV_SYN).0, 8)?;
    } else {
        writeln!(w, "B: 00 0b 00 00 00 00 00 00 00")?;
    }
    for kind in 1..EV_CNT as u16 {
        let set = d.codes(kind);
        if set.iter().next().is_none() {
            continue;
        }
        write_bytes(
            w,
            &format!("B: {kind:02x} "),
            &set.0,
            code_count(kind).div_ceil(8),
        )?;
    }
    for (code, a) in &d.abs {
        writeln!(
            w,
            "A: {:02x} {} {} {} {} {}",
            code, a.minimum, a.maximum, a.fuzz, a.flat, a.resolution
        )?;
    }
    for (code, state) in &d.leds {
        writeln!(w, "L: {code:02x} {state}")?;
    }
    for (code, state) in &d.switches {
        writeln!(w, "S: {code:02x} {state}")?;
    }
    Ok(())
}

/// Bytes as lines of 8, padded with zeros to at least `min_len` bytes.
fn write_bytes(w: &mut impl Write, prefix: &str, bytes: &[u8], min_len: usize) -> io::Result<()> {
    let len = bytes.len().max(min_len).div_ceil(8) * 8;
    for chunk in 0..len / 8 {
        write!(w, "{prefix}")?;
        for i in 0..8 {
            let b = bytes.get(chunk * 8 + i).copied().unwrap_or(0);
            write!(w, "{}{b:02x}", if i == 0 { "" } else { " " })?;
        }
        writeln!(w)?;
    }
    Ok(())
}

/// Write one `E:` line with evemu's comment.
pub fn write_event(w: &mut impl Write, e: &RawEvent) -> io::Result<()> {
    let sec = e.time_us.div_euclid(1_000_000);
    let usec = e.time_us.rem_euclid(1_000_000);
    write!(
        w,
        "E: {sec}.{usec:06} {:04x} {:04x} {:04}\t",
        e.kind, e.code, e.value
    )?;
    if e.kind == EV_SYN {
        let sep = if e.code == SYN_MT_REPORT {
            "++++++++++++"
        } else {
            "------------"
        };
        let tail = if e.code == SYN_MT_REPORT {
            "++++++++++"
        } else {
            "----------"
        };
        writeln!(
            w,
            "# {sep} {} ({}) {tail}",
            code_name(e.kind, e.code),
            e.value
        )
    } else {
        writeln!(
            w,
            "# {} / {:<20} {}",
            type_name(e.kind),
            code_name(e.kind, e.code),
            e.value
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SMALL: &str = "# EVEMU 1.3\n\
N: Test Panel\n\
I: 0003 1234 5678 0001\n\
P: 02 00 00 00 00 00 00 00\n\
B: 00 0b 00 00 00 00 00 00 00\n\
B: 01 00 00 00 00 00 00 00 00\n\
B: 01 00 00 00 00 00 00 00 00\n\
B: 01 00 00 00 00 00 00 00 00\n\
B: 01 00 00 00 00 00 00 00 00\n\
B: 01 00 00 00 00 00 00 00 00\n\
B: 01 00 04 00 00 00 00 00 00\n\
B: 03 03 00 00 00 00 80 60 02\n\
A: 00 0 4095 0 0 12\n\
A: 01 0 4095 0 0 12\n\
A: 2f 0 9 0 0 0\n\
A: 35 0 4095 0 0 12\n\
A: 36 0 4095 0 0 12\n\
A: 39 0 65535 0 0 0\n\
E: 0.000000 0003 0039 0001\t# EV_ABS / ABS_MT_TRACKING_ID 1\n\
E: 0.000000 0003 0035 0904\n\
E: 0.000000 0003 0036 100\n\
E: 0.000000 0001 014a 0001\n\
E: 0.000000 0000 0000 0000\n\
E: 0.016000 0003 0039 -001\n\
E: 0.016000 0000 0000 0000\n";

    #[test]
    fn parses_description_and_events() {
        let r = Recording::parse(SMALL, Path::new("small")).unwrap();
        assert_eq!(r.version, (1, 3));
        assert_eq!(r.device.name, "Test Panel");
        assert_eq!(r.device.id.vendor, 0x1234);
        assert!(
            r.device
                .has(crate::input::event::EV_KEY, crate::input::event::BTN_TOUCH)
        );
        assert_eq!(r.device.abs[&0x35].maximum, 4095);
        assert_eq!(r.device.abs[&0x35].resolution, 12);
        assert_eq!(r.events.len(), 7);
        assert_eq!(
            r.events[1].value, 904,
            "leading zeros are decimal, not octal"
        );
        assert_eq!(r.events[5].value, -1);
        assert_eq!(r.events[5].time_us, 16_000);
        assert_eq!(r.frame_count(), 2);
    }

    #[test]
    fn round_trips_through_the_writer() {
        let r = Recording::parse(SMALL, Path::new("small")).unwrap();
        let mut out = Vec::new();
        r.write(&mut out).unwrap();
        let text = String::from_utf8(out).unwrap();
        assert!(text.contains("E: 0.016000 0003 0039 -001\t"), "{text}");
        let again = Recording::parse(&text, Path::new("again")).unwrap();
        assert_eq!(again.device, r.device);
        assert_eq!(again.events, r.events);
    }

    #[test]
    fn unfinished_last_frame_is_dropped() {
        let text = format!("{SMALL}E: 0.020000 0003 0039 0002\nE: 0.020000 0003 0035 5\n");
        let r = Recording::parse(&text, Path::new("t")).unwrap();
        assert_eq!(r.dropped_trailing_events, 2);
        assert_eq!(r.frame_count(), 2);
    }

    #[test]
    fn errors_name_the_line_and_what_was_expected() {
        let bad = SMALL.replace("E: 0.000000 0003 0036 100", "E: 0.000000 0003 zz 100");
        let e = Recording::parse(&bad, Path::new("f.evemu")).unwrap_err();
        assert_eq!(e.line(), Some(21), "{e}");
        assert!(e.to_string().contains("f.evemu:21"), "{e}");
        assert!(e.to_string().contains("hex event code"), "{e}");

        let bad = SMALL.replace("A: 2f 0 9 0 0 0", "A: 2f 0 9");
        let e = Recording::parse(&bad, Path::new("f")).unwrap_err();
        assert_eq!(e.line(), Some(15));

        let bad = SMALL.replace(
            "E: 0.016000 0000 0000 0000",
            "E: 0.016000 0000 0000 99999999999",
        );
        assert!(
            Recording::parse(&bad, Path::new("f"))
                .unwrap_err()
                .to_string()
                .contains("32-bit")
        );

        let e = Recording::parse("E: 0.0 0 0 0\n", Path::new("f")).unwrap_err();
        assert!(matches!(e, EvemuError::NoDescription { .. }));
        let e = Recording::parse("hello\n", Path::new("f")).unwrap_err();
        assert_eq!(e.line(), Some(1));
    }

    #[test]
    fn five_field_abs_lines_and_crlf_are_accepted() {
        let text = SMALL.replace(" 0 0 12\n", " 0 0\n").replace('\n', "\r\n");
        let r = Recording::parse(&text, Path::new("t")).unwrap();
        assert_eq!(r.device.abs[&0].maximum, 4095);
        assert_eq!(r.device.abs[&0].resolution, 0);
        assert_eq!(r.frame_count(), 2);
    }

    #[test]
    fn device_name_with_control_characters_round_trips() {
        // Found by the fuzzer: a name with control characters came back
        // changed after writing, because the writer has to keep N: on one
        // line. Names are normalised to one printable line when read.
        let text = SMALL.replace("N: Test Panel", "N: Test\u{e}\0Panel\r");
        let r = Recording::parse(&text, Path::new("t")).unwrap();
        assert_eq!(r.device.name, "Test  Panel");
        let mut out = Vec::new();
        r.write(&mut out).unwrap();
        let again = Recording::parse(&String::from_utf8(out).unwrap(), Path::new("again")).unwrap();
        assert_eq!(again.device, r.device);
    }
}
