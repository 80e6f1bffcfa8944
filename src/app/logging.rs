//! Logging setup: tracing to stderr (the journal, under systemd). Every
//! record is one line: a control character that a logged value carries
//! (a newline in a configured path, an ESC in a device's name) is written
//! escaped, so no value forges a record or moves a terminal's cursor.

use std::io::{self, Write};

use tracing_subscriber::EnvFilter;

/// A record as it is written: every control character escaped but the
/// line break that ends it.
fn one_line(buf: &[u8]) -> String {
    let text = String::from_utf8_lossy(buf);
    let (body, end) = match text.strip_suffix('\n') {
        Some(body) => (body, "\n"),
        None => (&*text, ""),
    };
    crate::reading::escape_controls(body) + end
}

/// Standard error, each record written with its control characters
/// escaped (the formatter hands over one whole record per write, its
/// own line break last).
struct OneLine;

impl Write for OneLine {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        io::stderr().lock().write_all(one_line(buf).as_bytes())?;
        Ok(buf.len())
    }

    fn flush(&mut self) -> io::Result<()> {
        io::stderr().flush()
    }
}

/// Install the global subscriber. `RUST_LOG` wins over `default_level`.
/// Lines carry no timestamps under systemd (the journal adds its own).
pub fn init(default_level: &str) {
    let filter =
        EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new(default_level));
    let under_journal = std::env::var_os("JOURNAL_STREAM").is_some();
    let builder = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(|| OneLine)
        .with_target(false)
        // Colours are control characters too: the records stay plain.
        .with_ansi(false);
    let result = if under_journal {
        builder.without_time().try_init()
    } else {
        builder.try_init()
    };
    // A second init (tests) keeps the first subscriber.
    let _ = result;
}

#[cfg(test)]
mod tests {
    use super::one_line;

    #[test]
    fn a_record_stays_one_line_whatever_its_values_hold() {
        let record = b"WARN cannot open path=/tmp/a\nERROR forged\x1b[2J\x00 x\n";
        let line = one_line(record);
        assert_eq!(
            line,
            "WARN cannot open path=/tmp/a\\nERROR forged\\u{1b}[2J\\0 x\n"
        );
        assert_eq!(line.matches('\n').count(), 1);
    }
}
