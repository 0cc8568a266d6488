//! What a recording holds: the record kinds, the link states and station log lines their
//! data encodes, and one record as read.

use serde::Serialize;

/// What a record holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum RecordKind {
    FromRobot,
    ToRobot,
    Link,
    End,
    /// A line of the station's own log (`Record::station_log`).
    StationLog,
    /// A kind this reader does not know (skipped by consumers).
    Unknown(u8),
}

impl RecordKind {
    /// The kind's byte.
    pub fn code(self) -> u8 {
        match self {
            RecordKind::FromRobot => 0,
            RecordKind::ToRobot => 1,
            RecordKind::Link => 2,
            RecordKind::End => 3,
            RecordKind::StationLog => 4,
            RecordKind::Unknown(c) => c,
        }
    }

    /// The kind for a byte.
    pub fn from_code(c: u8) -> RecordKind {
        match c {
            0 => RecordKind::FromRobot,
            1 => RecordKind::ToRobot,
            2 => RecordKind::Link,
            3 => RecordKind::End,
            4 => RecordKind::StationLog,
            c => RecordKind::Unknown(c),
        }
    }
}

/// The connection states a `Link` record names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum LinkState {
    Closed,
    Handshaking,
    Connected,
    Refused,
}

impl LinkState {
    pub fn code(self) -> u8 {
        match self {
            LinkState::Closed => 0,
            LinkState::Handshaking => 1,
            LinkState::Connected => 2,
            LinkState::Refused => 3,
        }
    }

    pub fn from_code(c: u8) -> Option<LinkState> {
        Some(match c {
            0 => LinkState::Closed,
            1 => LinkState::Handshaking,
            2 => LinkState::Connected,
            3 => LinkState::Refused,
            _ => return None,
        })
    }
}

/// What a station log line is about (`RecordKind::StationLog`'s `data[1]`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum LogSource {
    /// A robot event, in the station's words.
    Event,
    /// A command's outcome (a refusal, a failure, an answer).
    Command,
    /// The link: connection changes, the recording itself.
    Link,
    /// The arena file.
    Arena,
    /// Anything else the station said (and a subject this reader does not know).
    Station,
}

impl LogSource {
    pub fn code(self) -> u8 {
        match self {
            LogSource::Event => 0,
            LogSource::Command => 1,
            LogSource::Link => 2,
            LogSource::Arena => 3,
            LogSource::Station => 255,
        }
    }

    pub fn from_code(c: u8) -> LogSource {
        match c {
            0 => LogSource::Event,
            1 => LogSource::Command,
            2 => LogSource::Link,
            3 => LogSource::Arena,
            _ => LogSource::Station,
        }
    }

    /// Its name, as the export's `/log` names a line's origin (`station/command`, ...).
    pub fn name(self) -> &'static str {
        match self {
            LogSource::Event => "station/event",
            LogSource::Command => "station/command",
            LogSource::Link => "station/link",
            LogSource::Arena => "station/arena",
            LogSource::Station => "station",
        }
    }
}

/// A line of the station's log, as a `StationLog` record holds it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StationLine {
    pub level: protocol::LogLevel,
    pub source: LogSource,
    pub text: String,
}

/// Longest station log text recorded, bytes: a log line is a sentence; a longer one is cut
/// (at a character boundary) rather than split over records.
pub const MAX_STATION_TEXT: usize = 4096;

impl StationLine {
    /// The record's data: level, source, then the text (cut to `MAX_STATION_TEXT`).
    pub fn encode(&self) -> Vec<u8> {
        let mut end = self.text.len().min(MAX_STATION_TEXT);
        while !self.text.is_char_boundary(end) {
            end -= 1;
        }
        let level = match self.level {
            protocol::LogLevel::Debug => 0,
            protocol::LogLevel::Info => 1,
            protocol::LogLevel::Warn => 2,
            protocol::LogLevel::Error => 3,
        };
        let mut data = Vec::with_capacity(2 + end);
        data.push(level);
        data.push(self.source.code());
        data.extend_from_slice(self.text.get(..end).unwrap_or_default().as_bytes());
        data
    }

    /// A record's data read back (see `RecordKind::StationLog`); `None` when it is too short.
    pub fn decode(data: &[u8]) -> Option<StationLine> {
        let (&level, rest) = data.split_first()?;
        let (&source, text) = rest.split_first()?;
        Some(StationLine {
            level: match level {
                0 => protocol::LogLevel::Debug,
                2 => protocol::LogLevel::Warn,
                3 => protocol::LogLevel::Error,
                _ => protocol::LogLevel::Info,
            },
            source: LogSource::from_code(source),
            text: String::from_utf8_lossy(text).into_owned(),
        })
    }
}

/// One record.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Record {
    pub t_us: u64,
    pub kind: RecordKind,
    /// Which link (an index into the header's `links`); 0 in a version 1 file.
    pub link: u8,
    pub data: Vec<u8>,
}

impl Record {
    /// A `Link` record's state and text, if this is one and it is well formed.
    pub fn link(&self) -> Option<(LinkState, String)> {
        if self.kind != RecordKind::Link {
            return None;
        }
        let (&code, text) = self.data.split_first()?;
        Some((
            LinkState::from_code(code)?,
            String::from_utf8_lossy(text).into_owned(),
        ))
    }

    /// A `StationLog` record's line, if this is one and it says anything.
    pub fn station_log(&self) -> Option<StationLine> {
        if self.kind != RecordKind::StationLog {
            return None;
        }
        StationLine::decode(&self.data)
    }

    /// A `Link` record.
    pub fn link_event(t_us: u64, state: LinkState, text: &str) -> Record {
        let mut data = Vec::with_capacity(1 + text.len());
        data.push(state.code());
        data.extend_from_slice(text.as_bytes());
        Record {
            t_us,
            kind: RecordKind::Link,
            link: 0,
            data,
        }
    }
}
