//! The reader: [`Recording::read_file`] and [`Recording::parse`] take a
//! recording's lines one at a time into a device description and events,
//! every malformed line an [`EvemuError`] that names it.

use super::*;
use crate::reading::{QUOTE_CHARS, quote};

struct Parser<'a> {
    path: &'a Path,
    rec: Recording,
    prop_bytes: usize,
    mask_bytes: [usize; EV_CNT],
    seen_description: bool,
}

impl<'a> Parser<'a> {
    /// A parser at the start of a file; `path` is for messages.
    fn new(path: &'a Path) -> Self {
        Self {
            path,
            rec: Recording {
                version: (1, 0),
                ..Recording::default()
            },
            prop_bytes: 0,
            mask_bytes: [0; EV_CNT],
            seen_description: false,
        }
    }

    fn err(&self, line: usize, message: impl Into<String>) -> EvemuError {
        EvemuError::Syntax {
            path: self.path.to_owned(),
            line,
            message: message.into(),
        }
    }

    fn line(&mut self, n: usize, raw: &str) -> Result<(), EvemuError> {
        let line = raw.trim_end_matches(['\r', '\n']);
        let trimmed = line.trim_start();
        if trimmed.is_empty() {
            return Ok(());
        }
        if let Some(comment) = trimmed.strip_prefix('#') {
            if let Some(v) = comment.trim().strip_prefix("EVEMU ") {
                self.rec.version = parse_version(v.trim()).ok_or_else(|| {
                    self.err(
                        n,
                        format!("expected `# EVEMU major.minor`, found {}", quote(line)),
                    )
                })?;
                // evemu has written format 1.x since 2010; a later major
                // version would be a format this reader does not know.
                if self.rec.version.0 != 1 {
                    return Err(self.err(
                        n,
                        format!(
                            "evemu format {}.{} is not one marionette reads (1.0 to 1.3); record it again with evemu-record or marionette record",
                            self.rec.version.0, self.rec.version.1
                        ),
                    ));
                }
            }
            return Ok(());
        }
        let Some((tag, rest)) = trimmed.split_once(':') else {
            return Err(self.err(
                n,
                format!(
                    "expected a line starting with N:, I:, P:, B:, A:, L:, S:, E: or #, found {}",
                    quote(line)
                ),
            ));
        };
        // Everything after a `#` on a data line is a comment (evemu writes
        // one after each event). Device names may not contain `#` then, as in
        // evemu itself, except on the N: line which takes the whole rest.
        let data = if tag == "N" {
            rest
        } else {
            rest.split('#').next().unwrap_or("")
        };
        let fields: Vec<&str> = data.split_whitespace().collect();
        if tag != "E" {
            if !self.rec.events.is_empty() {
                return Err(self.err(
                    n,
                    format!("device description line {} after the first event; one recording describes one device", quote(&format!("{tag}:"))),
                ));
            }
            self.seen_description = true;
        }
        match tag {
            "N" => {
                if self.rec.device.name.is_empty() {
                    self.rec.device.name = clean_name(rest);
                }
                Ok(())
            }
            "I" => self.id_line(n, &fields),
            "P" => self.prop_line(n, &fields),
            "B" => self.mask_line(n, &fields),
            "A" => self.abs_line(n, &fields),
            "L" | "S" => self.state_line(n, tag, &fields),
            "E" => self.event_line(n, &fields),
            other => Err(self.err(
                n,
                format!(
                    "unknown line type {}; expected N:, I:, P:, B:, A:, L:, S: or E:",
                    quote(&format!("{other}:"))
                ),
            )),
        }
    }

    fn id_line(&mut self, n: usize, f: &[&str]) -> Result<(), EvemuError> {
        if f.len() != 4 {
            return Err(self.err(
                n,
                format!(
                    "I: needs 4 hex numbers (bus vendor product version), found {}",
                    f.len()
                ),
            ));
        }
        let mut v = [0u16; 4];
        for (slot, s) in v.iter_mut().zip(f) {
            *slot = u16::from_str_radix(s, 16).map_err(|_| {
                self.err(
                    n,
                    format!("I: expected a 16-bit hex number, found {}", quote(s)),
                )
            })?;
        }
        self.rec.device.id = InputId {
            bustype: v[0],
            vendor: v[1],
            product: v[2],
            version: v[3],
        };
        Ok(())
    }

    fn hex_bytes(&self, n: usize, tag: &str, f: &[&str]) -> Result<Vec<u8>, EvemuError> {
        f.iter()
            .map(|s| {
                u8::from_str_radix(s, 16).map_err(|_| {
                    self.err(n, format!("{tag}: expected a hex byte, found {}", quote(s)))
                })
            })
            .collect()
    }

    fn prop_line(&mut self, n: usize, f: &[&str]) -> Result<(), EvemuError> {
        if f.len() != 8 {
            return Err(self.err(n, format!("P: needs 8 hex bytes, found {}", f.len())));
        }
        let bytes = self.hex_bytes(n, "P", f)?;
        for (i, b) in bytes.iter().enumerate() {
            for bit in 0..8 {
                let prop = (self.prop_bytes + i) * 8 + bit;
                if b & (1 << bit) != 0 && prop < INPUT_PROP_CNT {
                    self.rec.device.properties.insert(prop as u16);
                }
            }
        }
        self.prop_bytes += 8;
        Ok(())
    }

    fn mask_line(&mut self, n: usize, f: &[&str]) -> Result<(), EvemuError> {
        if f.len() != 9 {
            return Err(self.err(
                n,
                format!(
                    "B: needs an event type and 8 hex bytes, found {} fields",
                    f.len()
                ),
            ));
        }
        let bytes = self.hex_bytes(n, "B", f)?;
        let kind = usize::from(bytes[0]);
        if kind >= EV_CNT {
            return Err(self.err(
                n,
                format!("B: event type {kind:#04x} is beyond EV_MAX (0x1f)"),
            ));
        }
        let limit = code_count(kind as u16);
        for (i, b) in bytes[1..].iter().enumerate() {
            for bit in 0..8 {
                let code = (self.mask_bytes[kind] + i) * 8 + bit;
                if b & (1 << bit) != 0 && code < limit {
                    self.rec.device.set_bit(kind as u16, code as u16);
                }
            }
        }
        self.mask_bytes[kind] += 8;
        Ok(())
    }

    fn abs_line(&mut self, n: usize, f: &[&str]) -> Result<(), EvemuError> {
        if f.len() != 5 && f.len() != 6 {
            return Err(self.err(
                n,
                format!("A: needs code, min, max, fuzz, flat and optionally resolution (5 or 6 fields), found {}", f.len()),
            ));
        }
        let code = u16::from_str_radix(f[0], 16).map_err(|_| {
            self.err(
                n,
                format!("A: expected a hex axis code, found {}", quote(f[0])),
            )
        })?;
        if usize::from(code) >= ABS_CNT {
            return Err(self.err(
                n,
                format!("A: axis code {code:#04x} is beyond ABS_MAX (0x3f)"),
            ));
        }
        let mut v = [0i32; 5];
        for (slot, s) in v.iter_mut().zip(&f[1..]) {
            *slot = parse_int(s).ok_or_else(|| {
                self.err(
                    n,
                    format!("A: expected a decimal integer, found {}", quote(s)),
                )
            })?;
        }
        self.rec.device.set_abs(
            code,
            AbsInfo {
                value: 0,
                minimum: v[0],
                maximum: v[1],
                fuzz: v[2],
                flat: v[3],
                resolution: v[4],
            },
        );
        Ok(())
    }

    fn state_line(&mut self, n: usize, tag: &str, f: &[&str]) -> Result<(), EvemuError> {
        if f.len() != 2 {
            return Err(self.err(
                n,
                format!(
                    "{tag}: needs a hex code and a state, found {} fields",
                    f.len()
                ),
            ));
        }
        let code = u16::from_str_radix(f[0], 16).map_err(|_| {
            self.err(
                n,
                format!("{tag}: expected a hex code, found {}", quote(f[0])),
            )
        })?;
        let state = parse_int(f[1]).ok_or_else(|| {
            self.err(
                n,
                format!("{tag}: expected a decimal state, found {}", quote(f[1])),
            )
        })?;
        if tag == "L" {
            self.rec.device.leds.push((code, state));
        } else {
            self.rec.device.switches.push((code, state));
        }
        Ok(())
    }

    fn event_line(&mut self, n: usize, f: &[&str]) -> Result<(), EvemuError> {
        if !self.seen_description {
            return Err(EvemuError::NoDescription {
                path: self.path.to_owned(),
            });
        }
        if f.len() != 4 {
            return Err(self.err(
                n,
                format!(
                    "E: needs `sec.usec type code value`, found {} fields",
                    f.len()
                ),
            ));
        }
        let time_us = parse_time(f[0]).ok_or_else(|| {
            self.err(
                n,
                format!("E: expected a timestamp `sec.usec`, found {}", quote(f[0])),
            )
        })?;
        let kind = u16::from_str_radix(f[1], 16).map_err(|_| {
            self.err(
                n,
                format!("E: expected a hex event type, found {}", quote(f[1])),
            )
        })?;
        if kind > crate::input::event::EV_MAX {
            return Err(self.err(
                n,
                format!("E: event type {kind:#x} is beyond EV_MAX (0x1f)"),
            ));
        }
        let code = u16::from_str_radix(f[2], 16).map_err(|_| {
            self.err(
                n,
                format!("E: expected a hex event code, found {}", quote(f[2])),
            )
        })?;
        if usize::from(code) >= code_count(kind) {
            return Err(self.err(
                n,
                format!(
                    "E: code {code:#x} is beyond the largest code of {} ({:#x})",
                    type_name(kind),
                    code_count(kind) - 1
                ),
            ));
        }
        let value = parse_int(f[3]).ok_or_else(|| {
            self.err(
                n,
                format!("E: expected a decimal 32-bit value, found {}", quote(f[3])),
            )
        })?;
        self.rec
            .events
            .push(RawEvent::new(time_us, kind, code, value));
        Ok(())
    }

    fn finish(mut self) -> Result<Recording, EvemuError> {
        if !self.seen_description {
            return Err(EvemuError::NoDescription {
                path: self.path.to_owned(),
            });
        }
        let complete = self
            .rec
            .events
            .iter()
            .rposition(RawEvent::is_syn_report)
            .map_or(0, |i| i + 1);
        let dropped = self.rec.events.len() - complete;
        if dropped > 0 {
            tracing::warn!(
                path = %self.path.display(),
                dropped_events = dropped,
                "recording ends in the middle of a frame; dropping its unfinished last frame"
            );
            self.rec.events.truncate(complete);
        }
        self.rec.dropped_trailing_events = dropped;
        Ok(self.rec)
    }
}

/// A device name as one printable line: control characters become spaces,
/// surrounding blanks go, and at most [`QUOTE_CHARS`] characters stay
/// (the kernel keeps 80).
pub(super) fn clean_name(s: &str) -> String {
    let cleaned: String = s
        .trim()
        .chars()
        .take(QUOTE_CHARS)
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect();
    cleaned.trim().to_owned()
}

pub(super) fn parse_version(s: &str) -> Option<(u16, u16)> {
    let (a, b) = s.split_once('.')?;
    Some((a.parse().ok()?, b.trim().parse().ok()?))
}

/// A decimal integer as evemu writes it (`%04d`: `-001`, `0904`).
pub(super) fn parse_int(s: &str) -> Option<i32> {
    let (neg, digits) = match s.strip_prefix('-') {
        Some(d) => (true, d),
        None => (false, s.strip_prefix('+').unwrap_or(s)),
    };
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let v: i64 = digits.parse().ok()?;
    i32::try_from(if neg { -v } else { v }).ok()
}

/// `sec.usec` as evemu writes it (`%lu.%06u`): microseconds are the integer
/// after the dot, as evemu's own reader takes them.
pub(super) fn parse_time(s: &str) -> Option<i64> {
    let (sec, usec) = s.split_once('.')?;
    if sec.is_empty() || usec.is_empty() || usec.len() > 6 {
        return None;
    }
    if !sec.bytes().all(|b| b.is_ascii_digit()) || !usec.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let sec: i64 = sec.parse().ok()?;
    let usec: i64 = usec.parse().ok()?;
    sec.checked_mul(1_000_000)?.checked_add(usec)
}

/// The largest recording read (bytes): days of touches.
pub const MAX_RECORDING_BYTES: u64 = 1 << 30;

impl Recording {
    /// Read a recording from a file.
    pub fn read_file(path: &Path) -> Result<Self, EvemuError> {
        let bytes =
            crate::reading::read(path, MAX_RECORDING_BYTES).map_err(|e| EvemuError::Io {
                path: path.to_owned(),
                source: e.into(),
            })?;
        let text = String::from_utf8_lossy(&bytes);
        Self::parse(&text, path)
    }

    /// Parse recording text; `path` is used only in messages.
    pub fn parse(text: &str, path: &Path) -> Result<Self, EvemuError> {
        let mut p = Parser::new(path);
        // A file that ends without a newline was cut while being written:
        // an event line cut short there is dropped with its unfinished
        // frame, as a cut between lines is, not the whole file.
        let cut = !text.is_empty() && !text.ends_with('\n');
        let count = text.lines().count();
        let mut cut_line = false;
        for (i, raw_line) in text.lines().enumerate() {
            match p.line(i + 1, raw_line) {
                Err(e) if cut && i + 1 == count && raw_line.trim_start().starts_with("E:") => {
                    tracing::warn!(path = %path.display(), line = i + 1, error = %e, "the last line is cut short; dropping it");
                    cut_line = true;
                }
                r => r?,
            }
        }
        let mut rec = p.finish()?;
        rec.dropped_trailing_events += usize::from(cut_line);
        Ok(rec)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_and_int_forms() {
        assert_eq!(parse_time("1284881103.697884"), Some(1_284_881_103_697_884));
        assert_eq!(parse_time("0.5"), Some(5));
        assert_eq!(parse_time("-1.0"), None);
        assert_eq!(parse_int("-001"), Some(-1));
        assert_eq!(parse_int("0904"), Some(904));
        assert_eq!(parse_int("2147483648"), None);
        assert_eq!(parse_int("-"), None);
    }
}
