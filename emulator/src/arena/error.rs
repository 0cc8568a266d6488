//! Errors of the arena importers, and the small text helpers every importer shares.
//!
//! Layer: arena importers (std). Arena files are untrusted: every importer turns bad input into
//! an [`ArenaError`] that says what is wrong and where, `path:line[:column]: message` for text,
//! XML and YAML, `path: byte N: message` for binary PGM data; none of them panics.
//! Lines and columns are 1-based, columns count characters (not bytes).

use std::fmt;
use std::path::{Path, PathBuf};

use crate::input_file::{self, InputError, InputKind};

/// Largest file any importer reads: a 16-bit 8192 x 8192 PGM is 128 MiB, anything past this
/// is refused before it is read.
pub const MAX_FILE_BYTES: u64 = 160 * 1024 * 1024;

/// Where in a file a problem is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Position {
    /// The file as a whole.
    File,
    /// A 1-based line and, when known, a 1-based column (characters).
    Line {
        /// Line number, from 1.
        line: u32,
        /// Column, from 1.
        column: Option<u32>,
    },
    /// A byte offset from the start of the file (binary data).
    Byte(u64),
}

/// A file and a position in it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Location {
    /// The file, as the caller named it.
    pub path: PathBuf,
    /// Where in it.
    pub position: Position,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let p = self.path.display();
        match self.position {
            Position::File => write!(f, "{p}"),
            Position::Line { line, column: None } => write!(f, "{p}:{line}"),
            Position::Line {
                line,
                column: Some(c),
            } => write!(f, "{p}:{line}:{c}"),
            Position::Byte(b) => write!(f, "{p}: byte {b}"),
        }
    }
}

/// Why an arena could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum ArenaError {
    /// The file could not be opened or read.
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// The content is wrong: what and where.
    #[error("{at}: {message}")]
    Invalid {
        /// Where the problem is.
        at: Location,
        /// What is wrong, in words.
        message: String,
    },
    /// A [`super::LoadOptions`] field is out of range.
    #[error("load option {name}: {message}")]
    Option {
        /// The field's name.
        name: &'static str,
        /// What is wrong with it.
        message: String,
    },
}

impl ArenaError {
    /// Where the problem is, when it is in a file's content.
    pub fn location(&self) -> Option<&Location> {
        match self {
            ArenaError::Invalid { at, .. } => Some(at),
            _ => None,
        }
    }

    pub(crate) fn io(path: &Path, source: std::io::Error) -> Self {
        ArenaError::Io {
            path: path.to_path_buf(),
            source,
        }
    }

    pub(crate) fn at(path: &Path, position: Position, message: impl Into<String>) -> Self {
        let at = Location {
            path: path.to_path_buf(),
            position,
        };
        // The last line of defence for item 12 of issue 13: a message that quotes file content
        // without `excerpt` still cannot flood a terminal.
        let message = message.into();
        let message = if message.len() > MAX_MESSAGE_BYTES {
            excerpt_n(&message, MAX_MESSAGE_BYTES)
        } else {
            message
        };
        ArenaError::Invalid { at, message }
    }

    pub(crate) fn at_line(
        path: &Path,
        line: u32,
        column: Option<u32>,
        message: impl Into<String>,
    ) -> Self {
        Self::at(path, Position::Line { line, column }, message)
    }

    pub(crate) fn at_file(path: &Path, message: impl Into<String>) -> Self {
        Self::at(path, Position::File, message)
    }
}

/// A text file being parsed: its name and content, to turn byte offsets into line:column.
#[derive(Clone, Copy)]
pub(crate) struct Text<'a> {
    pub path: &'a Path,
    pub text: &'a str,
}

impl<'a> Text<'a> {
    /// 1-based (line, column) of a byte offset (clamped to the text).
    pub fn line_col(&self, offset: usize) -> (u32, u32) {
        let offset = offset.min(self.text.len());
        let before = self.text.get(..offset).unwrap_or(self.text);
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        let column = before.get(line_start..).map_or(0, |s| s.chars().count()) + 1;
        (to_u32(line), to_u32(column))
    }

    /// An error at a byte offset.
    pub fn err_at(&self, offset: usize, message: impl Into<String>) -> ArenaError {
        let (line, column) = self.line_col(offset);
        ArenaError::at_line(self.path, line, Some(column), message)
    }
}

/// How much of a file's text an error message quotes: enough to recognise a name or value.
pub const EXCERPT_CHARS: usize = 48;

/// Longest error message (the file's location aside); longer ones are cut, see [`excerpt`].
const MAX_MESSAGE_BYTES: usize = 1024;

/// File text quoted in a message: at most [`EXCERPT_CHARS`] characters, control characters
/// escaped (they must not reach a terminal raw), and the length of what was left out, so that
/// a two-million-element value or a 100 KB key reads as a short line. Every importer quotes
/// file content through this.
pub(crate) fn excerpt(s: &str) -> String {
    excerpt_n(s, EXCERPT_CHARS)
}

/// [`excerpt`] with a longer limit, for a library's message that may quote the file.
pub(crate) fn excerpt_n(s: &str, max_chars: usize) -> String {
    let end = s.char_indices().nth(max_chars).map_or(s.len(), |(i, _)| i);
    let mut out = crate::terminal_text::printable(s.get(..end).unwrap_or(s)).into_owned();
    if end < s.len() {
        out.push_str(&format!("… ({} more bytes)", s.len() - end));
    }
    out
}

pub(crate) fn to_u32(n: usize) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
}

/// What an arena file may be (`input_file`'s rule).
pub const ARENA_FILE: InputKind = InputKind {
    what: "arena files",
    max_bytes: MAX_FILE_BYTES,
    pipes: false,
};

impl From<InputError> for ArenaError {
    fn from(e: InputError) -> Self {
        match e {
            InputError::Io { path, source } => ArenaError::io(&path, source),
            other => ArenaError::at_file(other.path(), other.reason()),
        }
    }
}

/// Reads a whole arena file (a regular file of at most [`MAX_FILE_BYTES`]).
pub(crate) fn read_bytes(path: &Path) -> Result<Vec<u8>, ArenaError> {
    Ok(input_file::read(path, &ARENA_FILE)?)
}

/// Reads at most the first `max` bytes of an arena file (a header, before deciding to read
/// the rest).
pub(crate) fn read_head(path: &Path, max: u64) -> Result<Vec<u8>, ArenaError> {
    Ok(input_file::read_head(path, &ARENA_FILE, max)?)
}

/// Reads a whole UTF-8 text file; invalid UTF-8 is reported at its line and column.
pub(crate) fn read_text(path: &Path) -> Result<String, ArenaError> {
    let bytes = read_bytes(path)?;
    String::from_utf8(bytes).map_err(|e| {
        let good = e.utf8_error().valid_up_to();
        let prefix = String::from_utf8_lossy(&e.as_bytes()[..good]).into_owned();
        let (line, col) = Text {
            path,
            text: &prefix,
        }
        .line_col(good);
        ArenaError::at_line(
            path,
            line,
            Some(col),
            format!("invalid UTF-8 (byte {good})"),
        )
    })
}

/// Parses a finite decimal number; `inf`, `NaN` and junk are `None`.
pub(crate) fn parse_finite(s: &str) -> Option<f64> {
    s.trim().parse::<f64>().ok().filter(|v| v.is_finite())
}

/// The known name a misspelt one most likely meant (edit distance <= 2, ignoring case).
pub(crate) fn did_you_mean<'k>(word: &str, known: &[&'k str]) -> Option<&'k str> {
    let w = word.to_ascii_lowercase();
    let chars = w.chars().count();
    known
        .iter()
        // Lengths more than 2 apart are more than 2 edits apart: a huge name costs nothing.
        .filter(|k| k.chars().count().abs_diff(chars) <= 2)
        .map(|k| (edit_distance(&w, &k.to_ascii_lowercase()), *k))
        .filter(|(d, _)| *d <= 2)
        .min_by_key(|(d, _)| *d)
        .map(|(_, k)| k)
}

/// The policy for names a format does not define (XML elements and attributes, YAML keys):
/// one within edit distance 2 of a known name is almost surely a typo that would silently drop
/// a setting, so it is an error (`Err(message)`); anything else is kept as a warning
/// (`Ok(message)`), as the original tools ignore unknown names too.
pub(crate) fn unknown_name(what: &str, name: &str, known: &[&str]) -> Result<String, String> {
    match did_you_mean(name, known) {
        Some(k) => Err(format!(
            "unknown {what} '{}'; did you mean '{k}'?",
            excerpt(name)
        )),
        None => Ok(format!(
            "unknown {what} '{}' ignored (known: {})",
            excerpt(name),
            known.join(", ")
        )),
    }
}

fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            cur[j + 1] = (prev[j] + usize::from(ca != *cb))
                .min(prev[j + 1] + 1)
                .min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locations_print_as_path_line_column_or_byte() {
        let l = |position| {
            Location {
                path: PathBuf::from("a/b.xml"),
                position,
            }
            .to_string()
        };
        assert_eq!(
            l(Position::Line {
                line: 3,
                column: Some(7)
            }),
            "a/b.xml:3:7"
        );
        assert_eq!(
            l(Position::Line {
                line: 3,
                column: None
            }),
            "a/b.xml:3"
        );
        assert_eq!(l(Position::Byte(42)), "a/b.xml: byte 42");
    }

    #[test]
    fn line_col_counts_characters_from_one() {
        let t = Text {
            path: Path::new("x"),
            text: "ab\ncdé\nf",
        };
        assert_eq!(t.line_col(0), (1, 1));
        assert_eq!(t.line_col(3), (2, 1));
        assert_eq!(t.line_col(7), (2, 4));
        assert_eq!(t.line_col(999), (3, 2));
    }

    #[test]
    fn excerpts_are_short_and_escape_control_characters() {
        assert_eq!(excerpt("origin"), "origin");
        assert_eq!(excerpt("a\x1b]0;x\x07"), "a\\x1b]0;x\\x07");
        let long = "0, ".repeat(2_000_000);
        let e = excerpt(&long);
        assert!(e.len() < 100, "{e}");
        assert!(e.ends_with("… (5999952 more bytes)"), "{e}");
        // Cut on a character boundary.
        assert!(excerpt(&"é".repeat(100)).starts_with(&"é".repeat(EXCERPT_CHARS)));
    }

    #[test]
    fn messages_are_capped_whatever_they_quote() {
        let e = ArenaError::at_line(Path::new("m.yaml"), 1, None, "x".repeat(1 << 20));
        assert!(e.to_string().len() < 1200);
        let name = "k".repeat(100_000);
        let w = unknown_name("key", &name, &["image"]).unwrap();
        assert!(w.len() < 200, "{w}");
    }

    #[test]
    fn near_misses_are_errors_and_strangers_are_warnings() {
        let known = ["resolution", "origin", "negate"];
        assert!(unknown_name("key", "resoluton", &known).is_err());
        assert!(unknown_name("key", "negat", &known).is_err());
        assert!(unknown_name("key", "comment", &known).is_ok());
    }
}
