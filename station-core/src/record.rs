//! Recordings: the raw bytes of both directions of a link, timestamped, in an append-only file
//! that survives a crash; and the reader that checks every byte of one.
//!
//! Layer: a file format (pure encode/parse over byte slices in `format`, like the wire code in
//! `protocol::frame`; what records hold in `kinds`, the header's JSON in `meta`, a parsed file
//! in `reader`; all re-exported here) plus the I/O around it: `writer` (the `.partial` file and
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

mod format;
mod kinds;
pub mod live;
mod meta;
mod reader;
pub mod synth;
pub mod writer;

use std::path::{Path, PathBuf};

pub use format::{
    check_time, encode_header, encode_record, parse_header, parse_record, record_crc, Header,
};
pub use kinds::{LinkState, LogSource, Record, RecordKind, StationLine, MAX_STATION_TEXT};
pub use meta::Meta;
pub use reader::{read_file, ReadError, RecordError, Recording};
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

#[cfg(test)]
mod tests;
