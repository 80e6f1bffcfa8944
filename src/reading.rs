//! Every input file comes in through one door: it is opened without
//! blocking (a pipe with no writer does not hang the reader), the opened
//! handle is checked to be a regular file (a folder, a device such as
//! `/dev/zero`, a pipe or a socket is refused, whatever its metadata says
//! of its size), and at most the reader's limit is read (`take(limit +
//! 1)`): a file that grows past it, or whose size is not what its metadata
//! said, is refused as too large before more is allocated. A file that
//! must stay inside a folder (a glTF's buffers and images, a library's
//! clips) is resolved first, symbolic links included, and refused if it
//! leads outside. Files written go out through the other door,
//! [`crate::output::replace_file`].
//!
//! What comes in is repeated in a message only through [`quote`]: cut to
//! [`QUOTE_CHARS`] characters and escaped, so no control character of a
//! file (an ESC that clears a terminal, a newline that forges a log line)
//! reaches a terminal, the journal or the screen, and a token of 200 MB
//! gives a message of a line.

use std::fmt;
use std::fs::File;
use std::io::{self, Read};
use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
use std::path::{Path, PathBuf};

/// The most characters of input a message repeats.
pub const QUOTE_CHARS: usize = 120;

/// Input repeated in a message, between backticks: escaped (no control
/// character reaches a terminal, the journal or the screen) and cut to
/// [`QUOTE_CHARS`] characters, with the input's length after a cut.
#[must_use]
pub fn quote(input: &str) -> String {
    let (shown, cut) = bare(input);
    match cut {
        None => format!("`{shown}`"),
        Some(n) => format!("`{shown}…` ({n} characters)"),
    }
}

/// [`quote`] without the backticks, for a value that stands alone (a
/// name in a list): escaped and cut, `…` marking the cut.
#[must_use]
pub fn quote_bare(input: &str) -> String {
    match bare(input) {
        (shown, None) => shown,
        (shown, Some(_)) => format!("{shown}…"),
    }
}

/// The escaped text shown, and the input's length in characters where it
/// was cut. Only what is shown is escaped: a token of 200 MB is not copied.
fn bare(input: &str) -> (String, Option<usize>) {
    let shown: String = input
        .chars()
        .take(QUOTE_CHARS + 1)
        .flat_map(escaped)
        .collect();
    if shown.chars().count() <= QUOTE_CHARS {
        (shown, None)
    } else {
        let cut: String = shown.chars().take(QUOTE_CHARS).collect();
        (cut, Some(input.chars().count()))
    }
}

/// A character as a message shows it: control characters (ESC, NUL, a
/// line break) and the marks that turn text around (bidirectional
/// overrides) written as escapes (`\n`, `\u{1b}`), every other
/// character as itself.
fn escaped(c: char) -> impl Iterator<Item = char> {
    let hidden = c.is_control()
        || matches!(c, '\u{200e}' | '\u{200f}' | '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}');
    let (one, many) = if hidden {
        (None, Some(c.escape_debug()))
    } else {
        (Some(c), None)
    };
    one.into_iter().chain(many.into_iter().flatten())
}

/// Text with every control character escaped as [`quote`] escapes it,
/// nothing cut: a line already bounded (a log record) made safe for a
/// terminal and the journal.
#[must_use]
pub fn escape_controls(text: &str) -> String {
    text.chars().flat_map(escaped).collect()
}

/// A TOML error as one message that repeats no more of the file than
/// [`quote`] does: where (line and column), what the parser said (its
/// control characters escaped, cut), and the line it stopped on. The
/// parser's own rendering shows the whole line, which can be megabytes.
#[must_use]
pub fn toml_error(text: &str, e: &toml::de::Error) -> String {
    let said = quote_bare_up_to(e.message().trim_end(), 4 * QUOTE_CHARS);
    let Some(span) = e.span() else {
        return said;
    };
    let start = span.start.min(text.len());
    let before = text.get(..start).unwrap_or("");
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    // The line it stopped on names the key; quoted, it is cut.
    let rest = text.get(start..).unwrap_or("");
    let at =
        before.rsplit('\n').next().unwrap_or("").to_owned() + rest.split('\n').next().unwrap_or("");
    if at.trim().is_empty() {
        format!("line {line}, column {column}: {said}")
    } else {
        format!(
            "line {line}, column {column}, in {}: {said}",
            quote(at.trim())
        )
    }
}

/// A parser's message, which may itself repeat the input (serde's
/// "invalid type: string \"…\""): escaped and cut to four quotes' length.
#[must_use]
pub fn parser_message(text: &str) -> String {
    quote_bare_up_to(text.trim_end(), 4 * QUOTE_CHARS)
}

/// Text escaped and cut to `max` characters (`…` marks a cut): a longer
/// message written by a parser, which may itself repeat the input.
fn quote_bare_up_to(input: &str, max: usize) -> String {
    let shown: String = input
        .chars()
        .take(max + 1)
        // A parser's own line breaks stay readable as spaces.
        .flat_map(|c| escaped(if c == '\n' { ' ' } else { c }))
        .collect();
    if shown.chars().count() <= max {
        shown
    } else {
        let mut cut: String = shown.chars().take(max).collect();
        cut.push('…');
        cut
    }
}

/// Why a file could not be read. Its message does not repeat the path:
/// the caller says which file.
#[derive(Debug)]
pub enum ReadError {
    /// The system refused: missing, unreadable, a read that failed.
    Io(io::Error),
    /// Something other than a regular file stands there.
    NotRegular(&'static str),
    /// Longer than the reader takes (`limit` bytes); `said`: its length as
    /// the opened file gave it (under the limit where it grew as it was
    /// read).
    TooLarge { limit: u64, said: u64 },
    /// It leads (through `..` or a symbolic link) outside `folder`.
    Outside { folder: PathBuf },
    /// Its text is not UTF-8.
    NotText,
}

impl fmt::Display for ReadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Io(e) => write!(f, "{e}"),
            Self::NotRegular(what) => write!(f, "it is {what}, not a regular file"),
            Self::TooLarge { limit, said } if said > limit => write!(
                f,
                "it is {said} bytes, over the {} marionette reads of it",
                size(*limit)
            ),
            Self::TooLarge { limit, .. } => write!(
                f,
                "it grew past the {} marionette reads of it as it was read",
                size(*limit)
            ),
            Self::Outside { folder } => write!(
                f,
                "it leads outside {} (a `..` or a symbolic link): keep it inside that folder",
                folder.display()
            ),
            Self::NotText => write!(f, "it is not UTF-8 text"),
        }
    }
}

impl std::error::Error for ReadError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Io(e) => Some(e),
            _ => None,
        }
    }
}

impl From<io::Error> for ReadError {
    fn from(e: io::Error) -> Self {
        Self::Io(e)
    }
}

impl From<ReadError> for io::Error {
    /// For readers whose errors carry an `io::Error`: the kind says what
    /// it was, the message says it as [`ReadError`] does.
    fn from(e: ReadError) -> Self {
        match e {
            ReadError::Io(e) => e,
            ReadError::NotRegular("a folder") => io::Error::new(io::ErrorKind::IsADirectory, e),
            ReadError::NotRegular(_) => io::Error::new(io::ErrorKind::InvalidInput, e),
            ReadError::TooLarge { .. } => {
                io::Error::new(io::ErrorKind::FileTooLarge, e.to_string())
            }
            ReadError::Outside { .. } => {
                io::Error::new(io::ErrorKind::PermissionDenied, e.to_string())
            }
            ReadError::NotText => io::Error::new(io::ErrorKind::InvalidData, e.to_string()),
        }
    }
}

/// Whether an input could not be read for what stands at its path
/// (missing, forbidden, a folder, a device or a pipe) rather than for what
/// is in it: exit 66, missing input.
#[must_use]
pub fn unreadable(e: &io::Error) -> bool {
    matches!(
        e.kind(),
        io::ErrorKind::NotFound | io::ErrorKind::PermissionDenied | io::ErrorKind::IsADirectory
    ) || e
        .get_ref()
        .and_then(|inner| inner.downcast_ref::<ReadError>())
        .is_some_and(|r| matches!(r, ReadError::NotRegular(_)))
}

/// A limit said in the unit that reads best (rounded up).
fn size(bytes: u64) -> String {
    if bytes >= 1 << 20 {
        format!("{} MB", bytes.div_ceil(1 << 20))
    } else if bytes >= 1 << 10 {
        format!("{} KB", bytes.div_ceil(1 << 10))
    } else {
        format!("{bytes} bytes")
    }
}

/// What stands there, where it is not a regular file.
fn not_regular(t: std::fs::FileType) -> Option<&'static str> {
    if t.is_file() {
        None
    } else if t.is_dir() {
        Some("a folder")
    } else if t.is_fifo() {
        Some("a pipe")
    } else if t.is_socket() {
        Some("a socket")
    } else if t.is_char_device() || t.is_block_device() {
        Some("a device")
    } else {
        Some("not a file")
    }
}

/// Open `path` for reading: without blocking on a pipe, checked on the
/// opened handle to be a regular file.
#[allow(clippy::disallowed_methods)]
pub fn open(path: &Path) -> Result<File, ReadError> {
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK | libc::O_CLOEXEC)
        .open(path)?;
    if let Some(what) = not_regular(file.metadata()?.file_type()) {
        return Err(ReadError::NotRegular(what));
    }
    Ok(file)
}

/// The bytes of `path`, at most `limit` of them (see the module).
pub fn read(path: &Path, limit: u64) -> Result<Vec<u8>, ReadError> {
    let file = open(path)?;
    let said = file.metadata()?.len();
    if said > limit {
        return Err(ReadError::TooLarge { limit, said });
    }
    let mut bytes = Vec::with_capacity(usize::try_from(said.min(limit)).unwrap_or(0));
    file.take(limit.saturating_add(1)).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(ReadError::TooLarge { limit, said });
    }
    Ok(bytes)
}

/// The text of `path` (UTF-8), at most `limit` bytes.
pub fn read_text(path: &Path, limit: u64) -> Result<String, ReadError> {
    String::from_utf8(read(path, limit)?).map_err(|_| ReadError::NotText)
}

/// Where `path` leads (symbolic links resolved), if that is inside
/// `folder` (resolved too).
pub fn inside(path: &Path, folder: &Path) -> Result<PathBuf, ReadError> {
    let real = path.canonicalize()?;
    let home = folder.canonicalize()?;
    if real.starts_with(&home) {
        Ok(real)
    } else {
        Err(ReadError::Outside {
            folder: folder.to_owned(),
        })
    }
}

/// The bytes of `path`, which must stay inside `folder`, at most `limit`.
pub fn read_inside(path: &Path, folder: &Path, limit: u64) -> Result<Vec<u8>, ReadError> {
    read(&inside(path, folder)?, limit)
}

#[cfg(test)]
mod tests {

    #[test]
    fn a_quote_is_escaped_and_cut() {
        assert_eq!(quote("can't"), "`can't`");
        assert_eq!(quote("a\u{1b}[2J\0\n"), "`a\\u{1b}[2J\\0\\n`");
        assert_eq!(quote("\u{202e}txt"), "`\\u{202e}txt`");
        let long = "x".repeat(1_000_000);
        let q = quote(&long);
        assert_eq!(
            q,
            format!("`{}…` (1000000 characters)", "x".repeat(QUOTE_CHARS))
        );
        assert_eq!(quote_bare(&long).chars().count(), QUOTE_CHARS + 1);
        // Escapes count towards the cut: 120 characters shown at most.
        let q = quote(&"\u{7}".repeat(200));
        assert_eq!(
            q.chars().count(),
            QUOTE_CHARS + 2 + 1 + " (200 characters)".len()
        );
    }

    #[test]
    fn a_toml_error_says_where_without_the_whole_line() {
        let text = format!("[log]\nlevel = {}\u{1b}\n", "x".repeat(100_000));
        let e = toml::from_str::<toml::Table>(&text).unwrap_err();
        let m = toml_error(&text, &e);
        assert!(m.starts_with("line 2, column 9"), "{m}");
        assert!(m.len() < 600, "{m}");
        assert!(!m.chars().any(char::is_control), "{m}");
    }

    use super::*;

    #[test]
    fn a_regular_file_is_read_up_to_its_limit() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.txt");
        std::fs::write(&p, b"12345").unwrap();
        assert_eq!(read(&p, 5).unwrap(), b"12345");
        assert!(matches!(
            read(&p, 4),
            Err(ReadError::TooLarge { limit: 4, said: 5 })
        ));
        assert_eq!(read_text(&p, 10).unwrap(), "12345");
    }

    #[test]
    fn devices_folders_and_pipes_are_refused_without_reading_or_waiting() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("fifo");
        nix::unistd::mkfifo(&fifo, nix::sys::stat::Mode::S_IRWXU).unwrap();
        for (path, what) in [
            (Path::new("/dev/zero"), "a device"),
            (dir.path(), "a folder"),
            (fifo.as_path(), "a pipe"),
        ] {
            let e = read(path, 1 << 30).unwrap_err();
            assert!(
                matches!(e, ReadError::NotRegular(w) if w == what),
                "{}: {e}",
                path.display()
            );
        }
    }

    #[test]
    fn a_link_out_of_its_folder_is_refused_and_one_inside_followed() {
        let dir = tempfile::tempdir().unwrap();
        let home = dir.path().join("home");
        std::fs::create_dir(&home).unwrap();
        let secret = dir.path().join("secret.txt");
        std::fs::write(&secret, b"secret").unwrap();
        let mine = home.join("mine.txt");
        std::fs::write(&mine, b"mine").unwrap();
        std::os::unix::fs::symlink(&secret, home.join("out.txt")).unwrap();
        std::os::unix::fs::symlink(&mine, home.join("in.txt")).unwrap();
        assert!(matches!(
            read_inside(&home.join("out.txt"), &home, 100),
            Err(ReadError::Outside { .. })
        ));
        assert!(matches!(
            read_inside(&home.join("../secret.txt"), &home, 100),
            Err(ReadError::Outside { .. })
        ));
        assert_eq!(
            read_inside(&home.join("in.txt"), &home, 100).unwrap(),
            b"mine"
        );
    }
}
