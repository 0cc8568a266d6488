//! Reading a recording: the parsed whole, what stops a reading, and the file it comes from.

use std::path::{Path, PathBuf};

use super::{
    check_time, parse_header, parse_record, partial_path, Meta, Record, RecordKind, MAX_LINKS,
    OLDEST_VERSION, RECORDING_FILE, VERSION,
};

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
