//! The log: every line the operator reads about what happened — robot log text, robot events,
//! command outcomes, link changes, importer warnings. The one place log entries live; every
//! writer goes through [`LogBuffer::push`] (the app's `note`, the replay's notes).
//!
//! Layer: app state, no I/O. Bounded; the newest entry is last. Times are the station's clock
//! (milliseconds since start) so lines from the robot and the station interleave correctly.
//!
//! Repeats are coalesced rather than scrolling the log away: an entry with a [`Group`] joins
//! the entry of the same group among the last [`COALESCE_WINDOW`] ones, which then counts the
//! repeats, keeps the first and last time, shows the latest text and moves to the bottom
//! (the log stays ordered by last time). A beacon calibration once a second is one line with a
//! count; 31 parameter reads are one summary line.
//!
//! What is shown is filtered (minimum severity, a text) and scrolled; the scroll counts shown
//! entries back from the newest, 0 follows the newest.

use std::collections::VecDeque;

/// Entries kept.
pub const LOG_LINES: usize = 1000;
/// How far back (entries) a repeat finds the entry it joins. A few, so that a periodic event
/// interleaved with another periodic event still coalesces, but an event separated from its
/// last repeat by real news starts a new entry.
pub const COALESCE_WINDOW: usize = 8;
/// Longest text filter, characters.
pub const FILTER_MAX: usize = 40;

/// Severity.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Level {
    Debug,
    Info,
    Warn,
    Error,
}

impl Level {
    /// One letter, so severity reads without colour.
    pub fn letter(self) -> char {
        match self {
            Level::Debug => 'D',
            Level::Info => 'I',
            Level::Warn => 'W',
            Level::Error => 'E',
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Level::Debug => "debug",
            Level::Info => "info",
            Level::Warn => "warn",
            Level::Error => "error",
        }
    }

    /// The next minimum severity the filter key steps to (wrapping back to all).
    pub fn next(self) -> Level {
        match self {
            Level::Debug => Level::Info,
            Level::Info => Level::Warn,
            Level::Warn => Level::Error,
            Level::Error => Level::Debug,
        }
    }
}

impl From<Level> for protocol::LogLevel {
    fn from(l: Level) -> Self {
        match l {
            Level::Debug => protocol::LogLevel::Debug,
            Level::Info => protocol::LogLevel::Info,
            Level::Warn => protocol::LogLevel::Warn,
            Level::Error => protocol::LogLevel::Error,
        }
    }
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

impl Source {
    /// What a recording calls a line of this source; `None` for the robot's own lines, which
    /// the recording holds as the robot's frames.
    pub fn recorded(self) -> Option<crate::record::LogSource> {
        use crate::record::LogSource;
        match self {
            Source::Robot => None,
            Source::Event => Some(LogSource::Event),
            Source::Command => Some(LogSource::Command),
            Source::Link => Some(LogSource::Link),
            Source::Arena => Some(LogSource::Arena),
        }
    }
}

/// Which repeats an entry joins.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Group {
    /// Entries with the same key coalesce.
    pub key: &'static str,
    /// Whether this entry counts as a repeat (false: it only updates the text, as a pose
    /// correction completes the line crossing before it).
    pub counts: bool,
    /// Said instead of the text once there are repeats, e.g. "parameters read" ->
    /// "31 parameters read; last: ...". None: the text with "×N".
    pub summary: Option<&'static str>,
}

impl Group {
    pub const fn new(key: &'static str) -> Group {
        Group {
            key,
            counts: true,
            summary: None,
        }
    }

    pub const fn summary(self, s: &'static str) -> Group {
        Group {
            summary: Some(s),
            ..self
        }
    }

    pub const fn amends(self) -> Group {
        Group {
            counts: false,
            ..self
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct LogLine {
    /// The last time, ms.
    pub t_ms: u64,
    /// The first time, ms (differs from `t_ms` once repeats have joined).
    pub first_ms: u64,
    pub level: Level,
    pub source: Source,
    /// The latest text.
    pub text: String,
    /// Occurrences (1 until a repeat joins).
    pub count: u32,
    pub group: Option<Group>,
}

impl LogLine {
    pub fn new(t_ms: u64, level: Level, source: Source, text: String) -> LogLine {
        LogLine {
            t_ms,
            first_ms: t_ms,
            level,
            source,
            text,
            count: 1,
            group: None,
        }
    }

    pub fn grouped(self, group: Group) -> LogLine {
        LogLine {
            group: Some(group),
            ..self
        }
    }

    /// What the log shows: the text, or with repeats their count and since when.
    pub fn display(&self) -> String {
        if self.count <= 1 {
            return self.text.clone();
        }
        let since = self.first_ms as f64 / 1000.0;
        match self.group.and_then(|g| g.summary) {
            Some(s) => format!("{} {s} since {since:.1} s; last: {}", self.count, self.text),
            None => format!("{} (×{} since {since:.1} s)", self.text, self.count),
        }
    }
}

/// What is shown.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Filter {
    /// Entries below this severity are hidden.
    pub min: Level,
    /// Only entries containing this text (any case); empty: all.
    pub text: String,
}

impl Default for Filter {
    fn default() -> Self {
        Filter {
            min: Level::Debug,
            text: String::new(),
        }
    }
}

impl Filter {
    pub fn shows(&self, l: &LogLine) -> bool {
        l.level >= self.min
            && (self.text.is_empty()
                || l.display()
                    .to_lowercase()
                    .contains(&self.text.to_lowercase()))
    }

    /// Whether anything is hidden.
    pub fn active(&self) -> bool {
        self.min > Level::Debug || !self.text.is_empty()
    }
}

#[derive(Debug, Default)]
pub struct LogBuffer {
    lines: VecDeque<LogLine>,
    /// Shown entries scrolled back from the newest; 0 follows the newest.
    pub scroll: usize,
    pub filter: Filter,
    /// The text filter being typed (`/`), shown in the panel; Enter applies it.
    pub filter_input: Option<String>,
}

impl LogBuffer {
    pub fn push(&mut self, line: LogLine) {
        // Where the operator reads while scrolled back, as the index past their newest entry.
        let anchor = (self.scroll > 0).then(|| self.end_index());
        let joined = line.group.and_then(|g| {
            let from = self.lines.len().saturating_sub(COALESCE_WINDOW);
            (from..self.lines.len())
                .rev()
                .find(|&i| self.lines.get(i).and_then(|l| l.group).map(|h| h.key) == Some(g.key))
        });
        match joined.and_then(|i| Some((i, self.lines.remove(i)?))) {
            Some((i, mut old)) => {
                let g = line.group;
                if g.is_some_and(|g| g.counts) {
                    old.count = old.count.saturating_add(1);
                }
                old.t_ms = line.t_ms;
                old.text = line.text;
                old.level = old.level.max(line.level);
                // The group's summary is the first entry's, unless it had none.
                old.group = old.group.or(g);
                self.lines.push_back(old);
                if let Some(a) = anchor {
                    // Entries newer than the removed one moved up by one.
                    let a = if i < a { a - 1 } else { a };
                    self.scroll = self.shown_from(a);
                }
            }
            None => {
                let dropped = self.lines.len() == LOG_LINES;
                if dropped {
                    self.lines.pop_front();
                }
                self.lines.push_back(line);
                if let Some(a) = anchor {
                    // Keep the operator's place while they read back.
                    let a = if dropped { a.saturating_sub(1) } else { a };
                    self.scroll = self.shown_from(a);
                }
            }
        }
    }

    /// Index (into all entries) just past the newest shown entry the view ends at.
    fn end_index(&self) -> usize {
        let mut left = self.scroll;
        for (i, l) in self.lines.iter().enumerate().rev() {
            if self.filter.shows(l) {
                if left == 0 {
                    return i + 1;
                }
                left -= 1;
            }
        }
        0
    }

    /// Shown entries at or after index `i`.
    fn shown_from(&self, i: usize) -> usize {
        self.lines
            .range(i.min(self.lines.len())..)
            .filter(|l| self.filter.shows(l))
            .count()
    }

    /// Entries that pass the filter, oldest first.
    pub fn shown(&self) -> Vec<&LogLine> {
        self.lines.iter().filter(|l| self.filter.shows(l)).collect()
    }

    /// Scrolls by `delta` entries (positive: older) in a panel of `rows` rows: it stops when
    /// the oldest entry is at the top, not when only the oldest is left.
    pub fn scroll_by(&mut self, delta: i32, rows: usize) {
        let max = self.max_scroll(rows) as i64;
        self.scroll = (self.scroll as i64 + i64::from(delta)).clamp(0, max) as usize;
    }

    /// The scroll that puts the oldest shown entry at the top of `rows` rows.
    pub fn max_scroll(&self, rows: usize) -> usize {
        self.shown().len().saturating_sub(rows.max(1))
    }

    /// Back to following the newest entry.
    pub fn follow(&mut self) {
        self.scroll = 0;
    }

    pub fn to_top(&mut self, rows: usize) {
        self.scroll = self.max_scroll(rows);
    }

    /// The shown entries of a window of `n` ending `scroll` entries before the newest, oldest
    /// first.
    pub fn window(&self, n: usize) -> impl Iterator<Item = &LogLine> {
        let shown = self.shown();
        let end = shown.len().saturating_sub(self.scroll);
        let start = end.saturating_sub(n);
        shown.into_iter().skip(start).take(end - start)
    }

    /// Steps the minimum severity shown; the view follows the newest again.
    pub fn cycle_level(&mut self) {
        self.filter.min = self.filter.min.next();
        self.scroll = 0;
    }

    pub fn set_text_filter(&mut self, text: String) {
        self.filter.text = text;
        self.scroll = 0;
    }

    /// All entries, oldest first, whether shown or not.
    pub fn all(&self) -> impl Iterator<Item = &LogLine> {
        self.lines.iter()
    }

    pub fn len(&self) -> usize {
        self.lines.len()
    }

    pub fn is_empty(&self) -> bool {
        self.lines.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(t_ms: u64, level: Level, text: &str) -> LogLine {
        LogLine::new(t_ms, level, Source::Event, text.into())
    }

    const BEACON: Group = Group::new("beacon");

    #[test]
    fn a_repeated_event_is_one_entry_with_a_count_and_its_last_time() {
        let mut log = LogBuffer::default();
        log.push(line(0, Level::Info, "connected"));
        for s in 1..=60u64 {
            log.push(
                line(
                    s * 1000,
                    Level::Debug,
                    "beacon calibration, confidence 1.000",
                )
                .grouped(BEACON),
            );
        }
        assert_eq!(log.len(), 2);
        let last = log.window(1).next().unwrap();
        assert_eq!(last.count, 60);
        assert_eq!((last.first_ms, last.t_ms), (1000, 60_000));
        assert_eq!(
            last.display(),
            "beacon calibration, confidence 1.000 (×60 since 1.0 s)"
        );
    }

    #[test]
    fn repeats_interleaved_with_other_periodic_events_still_coalesce() {
        let mut log = LogBuffer::default();
        for s in 0..20u64 {
            log.push(line(s, Level::Debug, "beacon").grouped(BEACON));
            log.push(line(s, Level::Debug, "map updated").grouped(Group::new("map")));
        }
        assert_eq!(log.len(), 2);
    }

    #[test]
    fn a_group_separated_by_news_starts_a_new_entry() {
        let mut log = LogBuffer::default();
        log.push(line(0, Level::Debug, "beacon").grouped(BEACON));
        for i in 0..COALESCE_WINDOW {
            log.push(line(1, Level::Info, &format!("news {i}")));
        }
        log.push(line(2, Level::Debug, "beacon").grouped(BEACON));
        assert_eq!(log.len(), COALESCE_WINDOW + 2);
    }

    #[test]
    fn an_amending_entry_updates_the_text_without_counting() {
        let mut log = LogBuffer::default();
        let g = Group::new("floor lines");
        for n in 1..=5 {
            log.push(line(n, Level::Debug, &format!("line {n} crossed")).grouped(g));
            log.push(
                line(
                    n,
                    Level::Info,
                    &format!("line {n} crossed, pose corrected by 3 mm"),
                )
                .grouped(g.amends()),
            );
        }
        assert_eq!(log.len(), 1);
        let l = log.window(1).next().unwrap();
        assert_eq!(l.count, 5);
        assert!(l
            .display()
            .starts_with("line 5 crossed, pose corrected by 3 mm (×5"));
    }

    #[test]
    fn a_summary_group_reads_as_a_summary() {
        let mut log = LogBuffer::default();
        let g = Group::new("param read").summary("parameters read");
        for i in 0..31 {
            log.push(line(i, Level::Info, &format!("p{i} = 1")).grouped(g));
        }
        assert_eq!(log.len(), 1);
        assert_eq!(
            log.window(1).next().unwrap().display(),
            "31 parameters read since 0.0 s; last: p30 = 1"
        );
    }

    #[test]
    fn page_up_stops_with_the_oldest_entry_at_the_top() {
        let mut log = LogBuffer::default();
        for i in 0..30 {
            log.push(line(i, Level::Info, &format!("l{i}")));
        }
        for _ in 0..20 {
            log.scroll_by(5, 10);
        }
        assert_eq!(log.scroll, 20);
        assert_eq!(log.window(10).next().unwrap().text, "l0");
        assert_eq!(log.window(10).count(), 10, "a full page, not one line");
        // One page down moves at once: nothing was counted past the top.
        log.scroll_by(-5, 10);
        assert_eq!(log.window(10).next().unwrap().text, "l5");
    }

    #[test]
    fn scrolled_back_the_view_stays_put_as_lines_arrive_and_repeats_join() {
        let mut log = LogBuffer::default();
        for i in 0..30 {
            log.push(line(i, Level::Info, &format!("l{i}")));
        }
        log.push(line(30, Level::Debug, "beacon").grouped(BEACON));
        log.scroll_by(10, 5);
        let before: Vec<String> = log.window(5).map(|l| l.text.clone()).collect();
        log.push(line(31, Level::Info, "new"));
        log.push(line(32, Level::Debug, "beacon").grouped(BEACON));
        let after: Vec<String> = log.window(5).map(|l| l.text.clone()).collect();
        assert_eq!(before, after);
        log.follow();
        assert_eq!(log.window(1).next().unwrap().text, "beacon");
    }

    #[test]
    fn the_filter_hides_by_severity_and_text_and_scrolls_over_what_is_shown() {
        let mut log = LogBuffer::default();
        log.push(line(0, Level::Debug, "light at +3.0 deg"));
        log.push(line(1, Level::Warn, "collision"));
        log.push(line(2, Level::Error, "refused: go-to: out of the arena"));
        log.push(line(3, Level::Info, "goal reached"));
        log.cycle_level();
        log.cycle_level();
        assert_eq!(log.filter.min, Level::Warn);
        let shown: Vec<&str> = log.window(10).map(|l| l.text.as_str()).collect();
        assert_eq!(shown, ["collision", "refused: go-to: out of the arena"]);
        log.set_text_filter("REFUSED".into());
        assert_eq!(log.window(10).count(), 1);
        log.cycle_level();
        log.cycle_level();
        assert_eq!(log.filter.min, Level::Debug, "wraps back to all");
    }
}
