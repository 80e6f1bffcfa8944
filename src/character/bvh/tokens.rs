//! BVH text as tokens, read as they are asked for: nothing is kept per
//! token, so reading a file takes the text's memory and the frames'.

use std::path::Path;

use super::{BvhError, quote};

pub(super) struct Tokens<'a> {
    /// The text not read yet, and the line it begins on.
    rest: &'a str,
    line: usize,
    /// The next token and its line, once looked at.
    peeked: Option<(usize, &'a str)>,
    pub(super) path: &'a Path,
    /// The last line of the file (for errors at its end).
    last_line: usize,
}

impl<'a> Tokens<'a> {
    /// Tokens of `text`, read as they are asked for: nothing is kept per
    /// token, so memory stays the text's and the frames'.
    pub(super) fn new(text: &'a str, path: &'a Path) -> Self {
        Self {
            rest: text,
            line: 1,
            peeked: None,
            path,
            last_line: text.lines().count().max(1),
        }
    }

    /// Skip whitespace (counting lines) and cut the next token off `rest`.
    pub(super) fn scan(rest: &mut &'a str, line: &mut usize) -> Option<(usize, &'a str)> {
        let start = rest.find(|c: char| {
            if c == '\n' {
                *line += 1;
            }
            !c.is_whitespace()
        })?;
        let after = &rest[start..];
        let end = after.find(char::is_whitespace).unwrap_or(after.len());
        let tok = &after[..end];
        *rest = &after[end..];
        Some((*line, tok))
    }

    pub(super) fn fill(&mut self) {
        if self.peeked.is_none() {
            self.peeked = Self::scan(&mut self.rest, &mut self.line);
        }
    }

    /// Put back a token just read.
    pub(super) fn unread(&mut self, line: usize, tok: &'a str) {
        debug_assert!(self.peeked.is_none());
        self.peeked = Some((line, tok));
    }

    /// How many tokens are left, and the line of the last one (a scan that
    /// allocates nothing).
    pub(super) fn remaining(&mut self) -> (usize, usize) {
        self.fill();
        let (mut rest, mut line) = (self.rest, self.line);
        let (mut n, mut last) = match self.peeked {
            Some((l, _)) => (1, l),
            None => (0, self.last_line),
        };
        while let Some((l, _)) = Self::scan(&mut rest, &mut line) {
            n += 1;
            last = l;
        }
        (n, last)
    }

    pub(super) fn line(&mut self) -> usize {
        self.fill();
        self.peeked.map_or(self.last_line, |t| t.0)
    }

    pub(super) fn err(&mut self, message: impl Into<String>) -> BvhError {
        BvhError::Syntax {
            path: self.path.to_owned(),
            line: self.line(),
            message: message.into(),
        }
    }

    pub(super) fn peek(&mut self) -> Option<&'a str> {
        self.fill();
        self.peeked.map(|t| t.1)
    }

    pub(super) fn next(&mut self, what: &str) -> Result<&'a str, BvhError> {
        let t = self
            .peek()
            .ok_or_else(|| self.err(format!("expected {what}, found the end of the file")))?;
        self.peeked = None;
        Ok(t)
    }

    pub(super) fn expect(&mut self, word: &str) -> Result<(), BvhError> {
        let line = self.line();
        let t = self.next(&format!("`{word}`"))?;
        if t.eq_ignore_ascii_case(word) {
            Ok(())
        } else {
            Err(BvhError::Syntax {
                path: self.path.to_owned(),
                line,
                message: format!("expected `{word}`, found {}", quote(t)),
            })
        }
    }

    pub(super) fn number(&mut self, what: &str) -> Result<f64, BvhError> {
        let line = self.line();
        let t = self.next(what)?;
        match t.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(BvhError::Syntax {
                path: self.path.to_owned(),
                line,
                message: format!("expected {what} (a finite number), found {}", quote(t)),
            }),
        }
    }

    /// The rest of the current token's line, as a name.
    pub(super) fn rest_of_line(&mut self, what: &str) -> Result<String, BvhError> {
        let line = self.line();
        let mut parts = Vec::new();
        loop {
            self.fill();
            match self.peeked {
                Some((l, t)) if l == line && t != "{" => {
                    parts.push(t);
                    self.peeked = None;
                }
                _ => break,
            }
        }
        if parts.is_empty() {
            return Err(self.err(format!("expected {what}")));
        }
        Ok(parts.join(" "))
    }
}
