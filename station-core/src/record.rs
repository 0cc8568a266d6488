//! Recordings: the raw bytes of both directions of a link, timestamped, in an append-only file
//! that survives a crash; and the reader that checks every byte of one.
//!
//! Layer: a file format (pure encode/parse over byte slices, like the wire code in
//! `protocol::frame`) plus the I/O around it in submodules: `writer` (the `.partial` file and
//! its rename), `live` (the link's tap and connection events to records, and the TUI's `R`
//! key), `synth` (recordings built from messages, for tests and benchmarks); the station
//! crate's `commands::record` is `station record`. Invariants: times in a file never decrease; the final name only ever
//! holds a file that was finished cleanly (it was written as `FILE.partial` and renamed);
//! every record carries a CRC, so a torn or damaged tail is found at its exact byte offset.
//! What can fail: parsing a file that is not a recording, of another version, truncated or
//! corrupted (`ReadError`, each with the byte offset), and file I/O (`RecordError`).
//!
//! # File format, version 2 (version 1 still read)
//!
//! All integers are little-endian; "varint" is unsigned LEB128 (7 bits a byte, least
//! significant group first, high bit set on every byte but the last, at most 10 bytes), as in
//! PROTOCOL.md §5. CRC is CRC-32C (PROTOCOL.md §2, the same function as the frames').
//!
//! ```text
//! header   magic     8 bytes  89 53 54 52 45 43 0d 0a   ("\x89STREC\r\n")
//!          version   u16      2 (1: the single-link format, still read)
//!          flags     u16      0 (reserved; readers ignore it)
//!          meta_len  u32      length of meta, at most 65536
//!          meta      bytes    a UTF-8 JSON object (see `Meta`; unknown keys are ignored);
//!                             version 2: `links`, the ports recorded, 1 to `MAX_LINKS`
//!          crc       u32      CRC-32C of every header byte before it
//! record   t_us      varint   microseconds since the recording started, never decreasing,
//!                             at most `MAX_T_US` (a year)
//!          kind      u8       0 from robot, 1 to robot, 2 link event, 3 end, 4 station
//!                             log line (below)
//!          link      u8       version 2 only: which link (an index into `links`); a
//!                             version 1 record is link 0
//!          len       varint   length of data, at most 1 MiB
//!          data      len bytes
//!          crc       u32      CRC-32C of the record's bytes from t_us through data
//! ```
//!
//! Several links share the one clock and the one sequence of records: a record's link says
//! whose bytes or connection change it holds. An end record ends the whole file (its link is
//! 0). A link id that names no link of the header is damage at its record's offset.
//!
//! Record kinds:
//! - 0 `FromRobot`: bytes as the station read them from the port (robot to station).
//! - 1 `ToRobot`: bytes as the station wrote them (its `Hello`s, commands, heartbeats, ...).
//! - 2 `Link`: the connection changed. `data[0]` is the state: 0 closed (the port closed or
//!   could not be opened: the start of a gap), 1 handshaking (a port is open), 2 connected,
//!   3 refused; the rest is UTF-8 text (the reason, the port, the robot, the refusal).
//! - 3 `End`: the recording was finished cleanly; UTF-8 text says why (time limit, stopped,
//!   interrupted). Nothing may follow it.
//! - 4 `StationLog`: a line of the station's own log while it recorded (a refusal, a give-up,
//!   an event in the station's words; the robot's own log lines are in its frames).
//!   `data[0]` is the level (0 debug, 1 info, 2 warn, 3 error), `data[1]` what it is about
//!   (0 a robot event, 1 a command, 2 the link, 3 the arena), the rest UTF-8 text. A reader
//!   takes an unknown level as info and an unknown subject as the station's; a record of
//!   fewer than two bytes says nothing. Added within version 2: a reader that predates it
//!   skips it as a reserved kind, and a file without it reads as before.
//! - 5..=255: reserved for later additions to versions 1 and 2; a reader skips records of a
//!   kind it does not know (after checking their CRC). A change to anything above is a new
//!   version.
//!
//! A recording is written as `FILE.partial`, flushed every second, synced to disk every five,
//! and renamed to `FILE` when it ends cleanly. After a crash `FILE.partial` holds everything up
//! to the last flush; a reader accepts it up to the last good record and reports the rest.

pub mod live;
pub mod synth;
pub mod writer;

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

pub use writer::RecordWriter;

/// The first 8 bytes of every recording. The high first byte catches 7-bit transfers and the
/// CR LF catches newline conversion, as PNG's signature does.
pub const MAGIC: [u8; 8] = *b"\x89STREC\r\n";
/// The format version this code writes (it reads `OLDEST_VERSION` to `VERSION`).
pub const VERSION: u16 = 2;
/// The oldest version this code reads: version 1, one link, its records read as link 0.
pub const OLDEST_VERSION: u16 = 1;
/// Most links one recording holds (link ids are a byte; the emulator runs at most 16).
pub const MAX_LINKS: usize = 64;
/// Bytes of the fixed header before `meta`.
pub const HEADER_FIXED: usize = 16;
/// Longest `meta` accepted.
pub const MAX_META: usize = 64 * 1024;
/// Longest record data accepted.
pub const MAX_DATA: usize = 1024 * 1024;
/// Latest record time accepted, µs: a year. A later time is damage, not a very long
/// recording: nothing records for a year, and a reader must not take a stray 2^64 - 1 at its
/// word (consumers' work is linear in the records, but durations and positions are shown).
pub const MAX_T_US: u64 = 365 * 24 * 3600 * 1_000_000;
/// What a finished recording's name gets while it is written.
pub const PARTIAL_SUFFIX: &str = ".partial";
/// What a recording file may be (`input_file`'s rule): the reader holds a whole file in
/// memory, two to four times its size once parsed; a gibibyte is about 90 hours of one robot's
/// telemetry at 50 Hz.
pub const RECORDING_FILE: crate::input_file::InputKind = crate::input_file::InputKind {
    what: "recordings",
    max_bytes: 1 << 30,
    pipes: false,
};

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

/// What the header's JSON says about a recording. Every field is optional to a reader.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Meta {
    /// Wall-clock time of `t_us = 0`, milliseconds since the Unix epoch.
    #[serde(default)]
    pub created_unix_ms: u64,
    /// The program and version that wrote it.
    #[serde(default)]
    pub writer: String,
    /// The port recorded ("/dev/ttyUSB0", "built-in emulator on /dev/pts/3").
    #[serde(default)]
    pub port: String,
    #[serde(default)]
    pub baud: u32,
    /// The link protocol version and schema fingerprint (hex) of the station that recorded.
    #[serde(default)]
    pub protocol: u8,
    #[serde(default)]
    pub fingerprint: String,
    /// The arena drawn under the map (a file, or the emulator's built-in name), if known.
    #[serde(default)]
    pub arena: String,
    /// Version 2: the ports recorded, by link id ("/tmp/robot1", "/tmp/robot2"); `port` names
    /// them all. Empty in a version 1 file (one link, `port`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub links: Vec<String>,
}

impl Meta {
    /// Metadata for a recording starting now.
    pub fn now(port: &str, baud: u32) -> Meta {
        Meta {
            created_unix_ms: std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_millis() as u64),
            writer: format!("station {}", env!("CARGO_PKG_VERSION")),
            port: port.to_string(),
            baud,
            protocol: protocol::PROTOCOL_VERSION,
            fingerprint: crate::link::machine::hex(&protocol::FINGERPRINT),
            arena: String::new(),
            links: vec![port.to_string()],
        }
    }

    /// A warning when the recording was made with another message schema than this
    /// station's (its fingerprint, PROTOCOL.md §3): frames whose layout changed since then do
    /// not decode (they are counted as undecodable), and the reader should know why. `None`
    /// when the schemas are the same, or the file names none (written by a test tool).
    pub fn schema_warning(&self) -> Option<String> {
        let ours = crate::link::machine::hex(&protocol::FINGERPRINT);
        (!self.fingerprint.is_empty() && self.fingerprint != ours).then(|| {
            format!(
                "recorded with message schema {} (protocol {}); this station's is {ours} \
                 (protocol {}): frames whose layout changed since do not decode and are \
                 counted as undecodable",
                crate::terminal_text::printable_text(&self.fingerprint),
                self.protocol,
                protocol::PROTOCOL_VERSION
            )
        })
    }

    /// Metadata for a recording of several ports starting now: `port` names them all.
    pub fn now_links(ports: &[String], baud: u32) -> Meta {
        Meta {
            links: ports.to_vec(),
            ..Meta::now(&ports.join(", "), baud)
        }
    }

    /// The port of each link, by link id: `links`, or in a version 1 file `port` alone.
    pub fn link_ports(&self) -> Vec<String> {
        if self.links.is_empty() {
            vec![self.port.clone()]
        } else {
            self.links.clone()
        }
    }
}

/// Why a recording could not be read (fully). Offsets are bytes from the file's start.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ReadError {
    #[error("not a station recording (byte 0: the file does not start with the recording magic)")]
    NotARecording,
    #[error(
        "recording format version {version} (byte 8); this station reads versions \
         {OLDEST_VERSION} to {VERSION}"
    )]
    UnsupportedVersion { version: u16 },
    #[error("bad header at byte {offset}: {why}")]
    BadHeader { offset: u64, why: String },
    #[error("truncated at byte {offset}: the file ends inside a record (a torn tail)")]
    Truncated { offset: u64 },
    #[error("corrupted record at byte {offset}: CRC {stored:08x} stored, {computed:08x} computed")]
    BadCrc {
        offset: u64,
        stored: u32,
        computed: u32,
    },
    #[error("bad record at byte {offset}: {why}")]
    BadRecord { offset: u64, why: String },
}

impl ReadError {
    /// Where the problem is.
    pub fn offset(&self) -> u64 {
        match self {
            ReadError::NotARecording => 0,
            ReadError::UnsupportedVersion { .. } => 8,
            ReadError::BadHeader { offset, .. }
            | ReadError::Truncated { offset }
            | ReadError::BadCrc { offset, .. }
            | ReadError::BadRecord { offset, .. } => *offset,
        }
    }
}

/// Why a recording file could not be used.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {source}")]
    Read { path: PathBuf, source: ReadError },
    #[error("{path} does not exist{hint}")]
    Missing { path: PathBuf, hint: String },
    #[error(transparent)]
    Input(crate::input_file::InputError),
    #[error(transparent)]
    Output(#[from] crate::output_file::OutputError),
    #[error(
        "{path} exists: an unfinished recording (a crash?); replay or rename it, then try again"
    )]
    PartialExists { path: PathBuf },
}

/// A parsed recording: everything up to the last good record, and what stopped the reading.
#[derive(Clone, Debug, PartialEq)]
pub struct Recording {
    /// The file's format version (1 or 2).
    pub version: u16,
    pub meta: Meta,
    pub records: Vec<Record>,
    /// The `End` record's text, when the recording was finished cleanly.
    pub end: Option<String>,
    /// Why reading stopped before the end of the file, if it did.
    pub damage: Option<ReadError>,
    /// Bytes in the file.
    pub file_len: u64,
}

impl Recording {
    /// Reads a whole recording: the first damage is an error.
    pub fn parse_strict(bytes: &[u8]) -> Result<Recording, ReadError> {
        let r = Recording::parse(bytes)?;
        match r.damage {
            Some(e) => Err(e),
            None => Ok(r),
        }
    }

    /// Reads a recording up to its last good record; damage after the header is reported in
    /// `damage`, not as an error. A bad header is an error.
    pub fn parse(bytes: &[u8]) -> Result<Recording, ReadError> {
        let (header, mut at) = parse_header(bytes)?;
        let meta = header.meta;
        let links = meta.link_ports().len();
        let mut records = Vec::new();
        let mut end = None;
        let mut damage = None;
        let mut last_t = 0u64;
        while at < bytes.len() {
            if end.is_some() {
                damage = Some(ReadError::BadRecord {
                    offset: at as u64,
                    why: "data after the end record".into(),
                });
                break;
            }
            match parse_record(bytes, at, header.version, links) {
                Ok((rec, next)) => {
                    if let Err(e) = check_time(last_t, rec.t_us, at) {
                        damage = Some(e);
                        break;
                    }
                    last_t = rec.t_us;
                    if rec.kind == RecordKind::End {
                        end = Some(String::from_utf8_lossy(&rec.data).into_owned());
                    }
                    records.push(rec);
                    at = next;
                }
                Err(e) => {
                    damage = Some(e);
                    break;
                }
            }
        }
        Ok(Recording {
            version: header.version,
            meta,
            records,
            end,
            damage,
            file_len: bytes.len() as u64,
        })
    }

    /// Reads a file leniently (see `parse`). A missing `FILE` whose `FILE.partial` exists is
    /// reported with a hint to use the partial one.
    pub fn open(path: &Path) -> Result<Recording, RecordError> {
        let bytes = read_file(path)?;
        Recording::parse(&bytes).map_err(|source| RecordError::Read {
            path: path.to_path_buf(),
            source,
        })
    }

    /// Time of the last record, µs.
    pub fn duration_us(&self) -> u64 {
        self.records.last().map_or(0, |r| r.t_us)
    }

    /// How many links the file holds (1 for a version 1 file).
    pub fn link_count(&self) -> usize {
        self.meta.link_ports().len()
    }

    /// One link of the file as a recording of its own: its records (and the end record, which
    /// ends every link), its port as `meta.port`, the file's damage and length. Every consumer
    /// of a one-link recording (summary, export, replay) then works per link unchanged.
    pub fn link(&self, id: u8) -> Recording {
        let port = self
            .meta
            .link_ports()
            .get(usize::from(id))
            .cloned()
            .unwrap_or_default();
        Recording {
            version: self.version,
            meta: Meta {
                port: port.clone(),
                links: vec![port],
                ..self.meta.clone()
            },
            records: self
                .records
                .iter()
                .filter(|r| r.link == id || r.kind == RecordKind::End)
                .cloned()
                .collect(),
            end: self.end.clone(),
            damage: self.damage.clone(),
            file_len: self.file_len,
        }
    }

    /// Every link as a recording of its own (`link`), by link id.
    pub fn links(&self) -> Vec<Recording> {
        (0..self.link_count().min(MAX_LINKS))
            .map(|i| self.link(u8::try_from(i).unwrap_or(u8::MAX)))
            .collect()
    }
}

/// A record's time at byte `at`, after one at `last_t`: never earlier, and at most
/// `MAX_T_US`. Every reader of records checks it (`Recording::parse`, the retrace's loader).
pub fn check_time(last_t: u64, t_us: u64, at: usize) -> Result<(), ReadError> {
    let why = if t_us < last_t {
        format!("time goes back from {last_t} us to {t_us} us")
    } else if t_us > MAX_T_US {
        format!("time {t_us} us is more than a year ({MAX_T_US} us) after the recording's start")
    } else {
        return Ok(());
    };
    Err(ReadError::BadRecord {
        offset: at as u64,
        why,
    })
}

/// CRC-32C of a record: `protocol::crc32c`, computed 16 bytes a step (a 16 KB table; the
/// protocol's own takes one byte a step with 1 KB, small enough for the robot). Reading a
/// recording checks every record's CRC; byte by byte that was a third of a replay.
pub fn record_crc(bytes: &[u8]) -> u32 {
    const CRC: crc::Crc<u32, crc::Table<16>> =
        crc::Crc::<u32, crc::Table<16>>::new(&crc::CRC_32_ISCSI);
    CRC.checksum(bytes)
}

/// A recording's bytes, by `input_file`'s rule (a regular file of at most
/// `RECORDING_FILE.max_bytes`). A missing `FILE` whose `FILE.partial` exists is reported with
/// a hint to use the partial one.
pub fn read_file(path: &Path) -> Result<Vec<u8>, RecordError> {
    crate::input_file::read(path, &RECORDING_FILE).map_err(|e| {
        if !e.is_not_found() {
            return RecordError::Input(e);
        }
        let partial = partial_path(path);
        let hint = if partial.exists() {
            format!(
                "; an unfinished recording {} does (replay or export that)",
                partial.display()
            )
        } else {
            String::new()
        };
        RecordError::Missing {
            path: path.to_path_buf(),
            hint,
        }
    })
}

/// Where the TUI's `R` key records without `--record-dir`: the platform's data directory
/// (`$XDG_DATA_HOME`, else `~/.local/share`; on macOS `~/Library/Application Support`) plus
/// `station/recordings`. Err when neither is known: the caller asks for `--record-dir` rather
/// than writing into whatever the current directory happens to be.
pub fn default_recordings_dir() -> Result<PathBuf, String> {
    let env = |name: &str| {
        std::env::var_os(name)
            .map(PathBuf::from)
            .filter(|p| p.is_absolute())
    };
    let base = if cfg!(target_os = "macos") {
        env("HOME").map(|h| h.join("Library").join("Application Support"))
    } else {
        env("XDG_DATA_HOME").or_else(|| env("HOME").map(|h| h.join(".local").join("share")))
    };
    base.map(|b| b.join("station").join("recordings"))
        .ok_or_else(|| {
            "no data directory to record into (neither $XDG_DATA_HOME nor $HOME is set): \
         give one with --record-dir"
                .to_string()
        })
}

/// Creates `dir` (and what is missing above it) readable by its owner alone: recordings hold
/// everything the robot and the station said. An existing directory is left as it is.
pub fn create_private_dir(dir: &Path) -> std::io::Result<()> {
    if dir.is_dir() {
        return Ok(());
    }
    let mut b = std::fs::DirBuilder::new();
    b.recursive(true);
    #[cfg(unix)]
    std::os::unix::fs::DirBuilderExt::mode(&mut b, 0o700);
    b.create(dir)
}

/// `FILE.partial` for `FILE`.
pub fn partial_path(path: &Path) -> PathBuf {
    let mut s = path.as_os_str().to_os_string();
    s.push(PARTIAL_SUFFIX);
    PathBuf::from(s)
}

/// The header's bytes (version 2). A meta without `links` is given one link, its `port`.
pub fn encode_header(meta: &Meta) -> Vec<u8> {
    let mut meta = meta.clone();
    if meta.links.is_empty() {
        meta.links = vec![meta.port.clone()];
    }
    let json = serde_json::to_vec(&meta).unwrap_or_else(|_| b"{}".to_vec());
    let mut out = Vec::with_capacity(HEADER_FIXED + json.len() + 4);
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&0u16.to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(&json);
    let crc = protocol::crc32c(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    out
}

/// Appends one record's bytes (version 2) to `out`. Data longer than `MAX_DATA` must be split
/// by the caller (`writer` does).
pub fn encode_record(out: &mut Vec<u8>, t_us: u64, kind: RecordKind, link: u8, data: &[u8]) {
    let start = out.len();
    put_varint(out, t_us);
    out.push(kind.code());
    out.push(link);
    put_varint(out, data.len() as u64);
    out.extend_from_slice(data);
    let crc = record_crc(out.get(start..).unwrap_or(&[]));
    out.extend_from_slice(&crc.to_le_bytes());
}

fn put_varint(out: &mut Vec<u8>, mut v: u64) {
    loop {
        let b = (v & 0x7f) as u8;
        v >>= 7;
        if v == 0 {
            out.push(b);
            return;
        }
        out.push(b | 0x80);
    }
}

/// Reads a varint at `at`: the value and the next offset. `Ok(None)` when the input ends.
fn get_varint(bytes: &[u8], at: usize) -> Result<Option<(u64, usize)>, String> {
    let mut v = 0u64;
    for i in 0..10 {
        let Some(&b) = bytes.get(at + i) else {
            return Ok(None);
        };
        let part = u64::from(b & 0x7f);
        if i == 9 && part > 1 {
            return Err("varint overflows 64 bits".into());
        }
        v |= part << (7 * i);
        if b & 0x80 == 0 {
            return Ok(Some((v, at + i + 1)));
        }
    }
    Err("varint longer than 10 bytes".into())
}

fn le_u16(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(b.get(at..at + 2)?.try_into().ok()?))
}

fn le_u32(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?))
}

/// What the header says: the format version and the metadata.
#[derive(Clone, Debug, PartialEq)]
pub struct Header {
    pub version: u16,
    pub meta: Meta,
}

/// Parses the header: the version, the metadata and the offset of the first record.
pub fn parse_header(bytes: &[u8]) -> Result<(Header, usize), ReadError> {
    let short = |offset: usize| ReadError::BadHeader {
        offset: offset as u64,
        why: "the file ends inside the header".into(),
    };
    match bytes.get(..MAGIC.len()) {
        Some(m) if m == MAGIC => {}
        Some(_) => return Err(ReadError::NotARecording),
        None if MAGIC.starts_with(bytes) && !bytes.is_empty() => return Err(short(bytes.len())),
        None => return Err(ReadError::NotARecording),
    }
    let version = le_u16(bytes, 8).ok_or_else(|| short(bytes.len()))?;
    if !(OLDEST_VERSION..=VERSION).contains(&version) {
        return Err(ReadError::UnsupportedVersion { version });
    }
    let meta_len = le_u32(bytes, 12).ok_or_else(|| short(bytes.len()))? as usize;
    if meta_len > MAX_META {
        return Err(ReadError::BadHeader {
            offset: 12,
            why: format!("metadata length {meta_len} is over {MAX_META}"),
        });
    }
    let crc_at = HEADER_FIXED + meta_len;
    let stored = le_u32(bytes, crc_at).ok_or_else(|| short(bytes.len()))?;
    let covered = bytes.get(..crc_at).ok_or_else(|| short(bytes.len()))?;
    let computed = protocol::crc32c(covered);
    if stored != computed {
        return Err(ReadError::BadHeader {
            offset: crc_at as u64,
            why: format!("header CRC {stored:08x} stored, {computed:08x} computed"),
        });
    }
    let json = bytes.get(HEADER_FIXED..crc_at).unwrap_or(&[]);
    let meta: Meta = serde_json::from_slice(json).map_err(|e| ReadError::BadHeader {
        offset: HEADER_FIXED as u64,
        why: format!("metadata is not a JSON object: {e}"),
    })?;
    // Version 2 names its links: record link ids are checked against them.
    if version >= 2 && !(1..=MAX_LINKS).contains(&meta.links.len()) {
        return Err(ReadError::BadHeader {
            offset: HEADER_FIXED as u64,
            why: format!(
                "metadata names {} links; a version {version} recording names 1 to {MAX_LINKS}",
                meta.links.len()
            ),
        });
    }
    Ok((Header { version, meta }, crc_at + 4))
}

/// Parses the record at `at` of a file of format `version` with `links` links: the record and
/// the offset after it.
pub fn parse_record(
    bytes: &[u8],
    at: usize,
    version: u16,
    links: usize,
) -> Result<(Record, usize), ReadError> {
    let offset = at as u64;
    let bad = |why: String| ReadError::BadRecord { offset, why };
    let truncated = ReadError::Truncated { offset };
    let (t_us, p) = get_varint(bytes, at)
        .map_err(bad)?
        .ok_or(truncated.clone())?;
    let code = *bytes.get(p).ok_or(truncated.clone())?;
    let (link, p) = if version >= 2 {
        (*bytes.get(p + 1).ok_or(truncated.clone())?, p + 2)
    } else {
        (0, p + 1)
    };
    let (len, p) = get_varint(bytes, p)
        .map_err(bad)?
        .ok_or(truncated.clone())?;
    let len = usize::try_from(len).unwrap_or(usize::MAX);
    if len > MAX_DATA {
        return Err(bad(format!("record length {len} is over {MAX_DATA}")));
    }
    let data = bytes.get(p..p + len).ok_or(truncated.clone())?;
    let stored = le_u32(bytes, p + len).ok_or(truncated)?;
    let computed = record_crc(bytes.get(at..p + len).unwrap_or(&[]));
    if stored != computed {
        return Err(ReadError::BadCrc {
            offset,
            stored,
            computed,
        });
    }
    let kind = RecordKind::from_code(code);
    // After the CRC: a wrong id in a record whose bytes are intact is a writer's fault (or a
    // forgery), named as such; a damaged byte is a CRC error like any other.
    if usize::from(link) >= links {
        return Err(bad(format!(
            "link id {link}, but the header names {links} link(s) (ids 0 to {})",
            links.saturating_sub(1)
        )));
    }
    if kind == RecordKind::Link
        && data
            .first()
            .and_then(|&c| LinkState::from_code(c))
            .is_none()
    {
        return Err(bad("link record without a known state".into()));
    }
    Ok((
        Record {
            t_us,
            kind,
            link,
            data: data.to_vec(),
        },
        p + len + 4,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A recording of another schema is said to be one (its undecodable frames explained);
    /// this station's own, or one naming none, is not; a hostile fingerprint reaches the
    /// terminal without its control characters.
    #[test]
    fn a_recording_of_another_message_schema_is_flagged() {
        let now = Meta::now("p", 115_200);
        assert_eq!(now.schema_warning(), None);
        assert_eq!(Meta::default().schema_warning(), None);
        let old = Meta {
            fingerprint: "2104a2c0f39dd1a0\x1b[2J".into(),
            ..now
        };
        let w = old.schema_warning().expect("a warning");
        assert!(w.contains("2104a2c0f39dd1a0"), "{w}");
        assert!(
            w.contains(&crate::link::machine::hex(&protocol::FINGERPRINT)),
            "{w}"
        );
        assert!(!w.contains('\x1b'), "{w:?}");
    }

    fn sample() -> Vec<u8> {
        let mut b = encode_header(&Meta {
            port: "memory".into(),
            ..Meta::default()
        });
        encode_record(&mut b, 0, RecordKind::Link, 0, &[1, b'm']);
        encode_record(&mut b, 10, RecordKind::ToRobot, 0, &[0, 1, 2]);
        encode_record(&mut b, 300, RecordKind::FromRobot, 0, &[5; 200]);
        encode_record(&mut b, 301, RecordKind::End, 0, b"done");
        b
    }

    #[test]
    fn a_record_has_the_documented_bytes() {
        let mut b = Vec::new();
        encode_record(&mut b, 300, RecordKind::ToRobot, 0, &[0xaa, 0x00]);
        let crc = protocol::crc32c(&[0xac, 0x02, 0x01, 0x00, 0x02, 0xaa, 0x00]).to_le_bytes();
        let mut want = vec![0xac, 0x02, 0x01, 0x00, 0x02, 0xaa, 0x00];
        want.extend_from_slice(&crc);
        assert_eq!(b, want);
    }

    #[test]
    fn the_header_starts_with_magic_and_version() {
        let h = encode_header(&Meta::default());
        assert_eq!(&h[..8], b"\x89STREC\r\n");
        assert_eq!(&h[8..12], &[2, 0, 0, 0]);
        let (header, at) = parse_header(&h).unwrap();
        assert_eq!(header.version, 2);
        assert_eq!(header.meta.links, vec![String::new()], "one link, the port");
        assert_eq!(at, h.len());
    }

    #[test]
    fn a_whole_recording_reads_back() {
        let r = Recording::parse_strict(&sample()).unwrap();
        assert_eq!(r.records.len(), 4);
        assert_eq!(r.end.as_deref(), Some("done"));
        assert_eq!(r.meta.port, "memory");
        assert_eq!(r.duration_us(), 301);
        assert_eq!(
            r.records[0].link(),
            Some((LinkState::Handshaking, "m".into()))
        );
    }

    #[test]
    fn every_truncation_reads_up_to_the_last_whole_record() {
        let full = sample();
        let (_, first) = parse_header(&full).unwrap();
        for cut in first..full.len() {
            let r = Recording::parse(&full[..cut]).unwrap();
            let whole = r.records.len();
            if let Some(e) = &r.damage {
                assert!(matches!(e, ReadError::Truncated { .. }), "{cut}: {e}");
            }
            assert!(whole < 4, "{cut}");
        }
        for cut in 0..first {
            assert!(Recording::parse(&full[..cut]).is_err(), "{cut}");
        }
    }

    #[test]
    fn a_flipped_bit_is_found_at_its_record() {
        let full = sample();
        let (_, first) = parse_header(&full).unwrap();
        for i in first..full.len() {
            for bit in 0..8 {
                let mut b = full.clone();
                b[i] ^= 1 << bit;
                let r = Recording::parse(&b).unwrap();
                let e = r.damage.expect("damage found");
                assert!(e.offset() as usize <= i, "{i}.{bit}: {e}");
                assert!(r.records.len() < 4);
            }
        }
    }

    #[test]
    fn bad_headers_are_named() {
        assert_eq!(Recording::parse(b"hello"), Err(ReadError::NotARecording));
        assert_eq!(Recording::parse(b""), Err(ReadError::NotARecording));
        let mut v3 = sample();
        v3[8] = 3;
        assert_eq!(
            Recording::parse(&v3),
            Err(ReadError::UnsupportedVersion { version: 3 })
        );
        let mut v0 = sample();
        v0[8] = 0;
        assert_eq!(
            Recording::parse(&v0),
            Err(ReadError::UnsupportedVersion { version: 0 })
        );
        let mut meta = sample();
        meta[HEADER_FIXED] ^= 0x20;
        assert!(matches!(
            Recording::parse(&meta),
            Err(ReadError::BadHeader { .. })
        ));
    }

    #[test]
    fn the_record_crc_is_the_protocols_crc32c() {
        let bytes: Vec<u8> = (0..1000u32).map(|i| (i * 7 + i / 13) as u8).collect();
        for n in [0, 1, 15, 16, 17, 100, 1000] {
            assert_eq!(
                record_crc(&bytes[..n]),
                protocol::crc32c(&bytes[..n]),
                "{n}"
            );
        }
    }

    #[test]
    fn unknown_kinds_are_kept_for_consumers_to_skip() {
        let mut b = encode_header(&Meta::default());
        encode_record(&mut b, 5, RecordKind::Unknown(200), 0, b"future");
        let r = Recording::parse_strict(&b).unwrap();
        assert_eq!(r.records[0].kind, RecordKind::Unknown(200));
    }

    /// A station log record (kind 4) reads back in a version 2 file: the format version is
    /// unchanged, since a reader that predates the kind skips it as reserved.
    #[test]
    fn a_station_log_record_reads_back() {
        let line = StationLine {
            level: protocol::LogLevel::Error,
            source: LogSource::Command,
            text: "refused: go-to (9.00, 0.50): out of the arena".into(),
        };
        let mut b = encode_header(&Meta::default());
        encode_record(&mut b, 5, RecordKind::StationLog, 0, &line.encode());
        let r = Recording::parse_strict(&b).unwrap();
        assert_eq!(r.version, VERSION);
        assert_eq!(r.records[0].kind, RecordKind::StationLog);
        assert_eq!(r.records[0].data[..2], [3, 1], "level, then subject");
        assert_eq!(r.records[0].station_log(), Some(line));
        assert_eq!(RecordKind::from_code(4), RecordKind::StationLog);
    }

    #[test]
    fn station_log_lines_read_leniently_and_are_cut_at_a_character() {
        assert_eq!(
            StationLine::decode(&[9, 77, b'x']),
            Some(StationLine {
                level: protocol::LogLevel::Info,
                source: LogSource::Station,
                text: "x".into()
            }),
            "an unknown level is info, an unknown subject the station's"
        );
        assert_eq!(StationLine::decode(&[1]), None);
        let line = StationLine {
            level: protocol::LogLevel::Info,
            source: LogSource::Link,
            text: "€".repeat(MAX_STATION_TEXT),
        };
        let data = line.encode();
        assert!(data.len() <= 2 + MAX_STATION_TEXT);
        let text = std::str::from_utf8(&data[2..]).unwrap();
        assert_eq!(text.len(), MAX_STATION_TEXT / 3 * 3);
    }

    #[test]
    fn overlong_varints_and_huge_lengths_are_refused() {
        let mut b = encode_header(&Meta::default());
        let at = b.len();
        b.extend_from_slice(&[0xff; 11]);
        let r = Recording::parse(&b).unwrap();
        assert!(
            matches!(r.damage, Some(ReadError::BadRecord { offset, .. }) if offset == at as u64)
        );
        let mut b = encode_header(&Meta::default());
        b.extend_from_slice(&[0x00, 0x00, 0xff, 0xff, 0xff, 0x7f]);
        let r = Recording::parse(&b).unwrap();
        assert!(matches!(r.damage, Some(ReadError::BadRecord { .. })));
    }

    #[test]
    fn a_time_beyond_a_year_is_damage_at_its_record() {
        for t in [MAX_T_US + 1, u64::MAX] {
            let mut b = encode_header(&Meta::default());
            encode_record(&mut b, 0, RecordKind::Link, 0, &[1, b'm']);
            encode_record(&mut b, MAX_T_US, RecordKind::FromRobot, 0, &[0]);
            let at = b.len() as u64;
            encode_record(&mut b, t, RecordKind::FromRobot, 0, &[0]);
            let r = Recording::parse(&b).unwrap();
            let e = r.damage.clone().expect("refused");
            assert_eq!(e.offset(), at);
            assert!(e.to_string().contains("more than a year"), "{e}");
            assert_eq!(r.duration_us(), MAX_T_US, "read up to there");
        }
    }

    #[test]
    fn records_after_the_end_are_damage() {
        let mut b = sample();
        encode_record(&mut b, 400, RecordKind::FromRobot, 0, &[1]);
        let r = Recording::parse(&b).unwrap();
        assert!(matches!(r.damage, Some(ReadError::BadRecord { .. })));
        assert_eq!(r.records.len(), 4);
    }

    /// A version 1 header and record, as the station wrote them before links existed.
    fn v1_header(meta: &Meta) -> Vec<u8> {
        let mut h = encode_header(meta);
        // The same header with version 1 and the meta without `links`, CRC recomputed.
        let json = serde_json::to_vec(meta).unwrap();
        h.truncate(8);
        h.extend_from_slice(&1u16.to_le_bytes());
        h.extend_from_slice(&0u16.to_le_bytes());
        h.extend_from_slice(&(json.len() as u32).to_le_bytes());
        h.extend_from_slice(&json);
        let crc = protocol::crc32c(&h);
        h.extend_from_slice(&crc.to_le_bytes());
        h
    }

    fn v1_record(out: &mut Vec<u8>, t_us: u64, kind: RecordKind, data: &[u8]) {
        let start = out.len();
        put_varint(out, t_us);
        out.push(kind.code());
        put_varint(out, data.len() as u64);
        out.extend_from_slice(data);
        let crc = protocol::crc32c(&out[start..]);
        out.extend_from_slice(&crc.to_le_bytes());
    }

    #[test]
    fn a_version_1_file_reads_as_link_0() {
        let mut b = v1_header(&Meta {
            port: "/dev/ttyUSB0".into(),
            ..Meta::default()
        });
        v1_record(&mut b, 0, RecordKind::Link, &[1, b'm']);
        v1_record(&mut b, 7, RecordKind::FromRobot, &[5; 20]);
        v1_record(&mut b, 9, RecordKind::End, b"done");
        let r = Recording::parse_strict(&b).unwrap();
        assert_eq!(r.version, 1);
        assert_eq!(r.link_count(), 1);
        assert_eq!(r.meta.link_ports(), vec!["/dev/ttyUSB0".to_string()]);
        assert!(r.records.iter().all(|x| x.link == 0));
        assert_eq!(r.link(0).records, r.records);
    }

    fn two_links() -> Vec<u8> {
        let mut b = encode_header(&Meta {
            links: vec!["/tmp/robot1".into(), "/tmp/robot2".into()],
            ..Meta::default()
        });
        encode_record(&mut b, 0, RecordKind::Link, 0, &[1, b'a']);
        encode_record(&mut b, 1, RecordKind::Link, 1, &[1, b'b']);
        encode_record(&mut b, 5, RecordKind::FromRobot, 1, &[2; 30]);
        encode_record(&mut b, 6, RecordKind::FromRobot, 0, &[3; 30]);
        encode_record(&mut b, 9, RecordKind::End, 0, b"done");
        b
    }

    #[test]
    fn links_split_into_recordings_of_their_own() {
        let r = Recording::parse_strict(&two_links()).unwrap();
        assert_eq!(r.link_count(), 2);
        let [a, b] = <[Recording; 2]>::try_from(r.links()).unwrap();
        assert_eq!(a.meta.port, "/tmp/robot1");
        assert_eq!(b.meta.port, "/tmp/robot2");
        let data = |x: &Recording| -> Vec<u8> {
            x.records
                .iter()
                .filter(|r| r.kind == RecordKind::FromRobot)
                .flat_map(|r| r.data.clone())
                .collect()
        };
        assert_eq!(data(&a), vec![3; 30]);
        assert_eq!(data(&b), vec![2; 30]);
        // The end record ends every link.
        assert_eq!(a.end.as_deref(), Some("done"));
        assert_eq!(b.records.last().map(|r| r.kind), Some(RecordKind::End));
    }

    #[test]
    fn a_link_id_the_header_does_not_name_is_damage_at_its_record() {
        let mut b = encode_header(&Meta {
            links: vec!["a".into(), "b".into()],
            ..Meta::default()
        });
        encode_record(&mut b, 0, RecordKind::Link, 1, &[1, b'b']);
        let at = b.len() as u64;
        encode_record(&mut b, 3, RecordKind::FromRobot, 2, &[0]);
        let r = Recording::parse(&b).unwrap();
        let e = r.damage.expect("refused");
        assert_eq!(e.offset(), at);
        assert!(
            e.to_string()
                .contains("link id 2, but the header names 2 link(s)"),
            "{e}"
        );
        assert_eq!(r.records.len(), 1);
    }

    #[test]
    fn a_version_2_header_without_links_is_refused() {
        let mut meta = Meta::default();
        meta.links.clear();
        let mut h = v1_header(&meta);
        h[8] = 2;
        let n = h.len();
        let crc = protocol::crc32c(&h[..n - 4]);
        h[n - 4..].copy_from_slice(&crc.to_le_bytes());
        let e = Recording::parse(&h).unwrap_err();
        assert!(matches!(e, ReadError::BadHeader { offset: 16, .. }), "{e}");
        assert!(e.to_string().contains("names 0 links"), "{e}");
    }

    #[test]
    fn every_truncation_of_a_two_link_file_is_named_at_its_record() {
        let full = two_links();
        let (_, first) = parse_header(&full).unwrap();
        for cut in first + 1..full.len() {
            let r = Recording::parse(&full[..cut]).unwrap();
            // A cut at a record boundary reads cleanly (without an end record).
            let Some(e) = r.damage else { continue };
            let ReadError::Truncated { offset } = e else {
                panic!("{cut}: {e}");
            };
            assert!(offset as usize <= cut, "{cut}");
            let (_, next) = parse_record(&full, offset as usize, 2, 2).unwrap();
            assert!(next > cut, "{cut}: the record at {offset} is the one cut");
        }
    }
}
