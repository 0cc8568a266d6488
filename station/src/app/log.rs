//! The log pane's lines: robot log text, robot events, command outcomes and link changes.
//!
//! Layer: app state, no I/O. Bounded; the newest line is last. Times are the station's clock
//! (seconds since start) so lines from the robot and the station interleave correctly.

use std::collections::VecDeque;

/// Lines kept.
pub const LOG_LINES: usize = 1000;

/// Severity, for colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Level {
    Debug,
    Info,
    Warn,
    Error,
}

impl From<protocol::LogLevel> for Level {
    fn from(l: protocol::LogLevel) -> Self {
        match l {
            protocol::LogLevel::Debug => Level::Debug,
            protocol::LogLevel::Info => Level::Info,
            protocol::LogLevel::Warn => Level::Warn,
            protocol::LogLevel::Error => Level::Error,
        }
    }
}

/// Where a line came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// A `Log` frame.
    Robot,
    /// An `Event` frame.
    Event,
    /// A command's outcome.
    Command,
    /// The link itself.
    Link,
    /// The arena file's importer (warnings about the file).
    Arena,
}

#[derive(Clone, Debug, PartialEq)]
pub struct LogLine {
    pub t_ms: u64,
    pub level: Level,
    pub source: Source,
    pub text: String,
}

#[derive(Debug, Default)]
pub struct LogBuffer {
    lines: VecDeque<LogLine>,
    /// Lines scrolled back from the newest.
    pub scroll: usize,
}

impl LogBuffer {
    pub fn push(&mut self, line: LogLine) {
        if self.lines.len() == LOG_LINES {
            self.lines.pop_front();
        }
        self.lines.push_back(line);
        if self.scroll > 0 {
            // Keep the operator's place while they read back.
            self.scroll = (self.scroll + 1).min(self.lines.len().saturating_sub(1));
        }
    }

    pub fn scroll_by(&mut self, delta: i32) {
        let max = self.lines.len().saturating_sub(1) as i64;
        self.scroll = (self.scroll as i64 + i64::from(delta)).clamp(0, max) as usize;
    }

    /// The `n` lines ending `scroll` lines before the newest, oldest first.
    pub fn window(&self, n: usize) -> impl Iterator<Item = &LogLine> {
        let end = self.lines.len().saturating_sub(self.scroll);
        let start = end.saturating_sub(n);
        self.lines.range(start..end)
    }

    pub fn len(&self) -> usize {
        self.lines.len()
    }

    pub fn is_empty(&self) -> bool {
        self.lines.is_empty()
    }
}
