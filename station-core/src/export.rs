//! A recording to MCAP (for Foxglove) and to CSV (for a spreadsheet or pandas), written
//! atomically; `station export` runs it.
//!
//! Layer: a walk over a parsed `Recording` that decodes both directions with the protocol's
//! `FrameDecoder` (one per direction, the robot's reset when a port closed, as live) and hands
//! each message to a writer (`csv`, `mcap`), plus the file I/O: each output is written to a
//! temporary file beside it (`output_file`), and the outputs are renamed to their final names
//! only when all of them are complete.
//! Invariants: bad input (not a recording, another version, a torn or corrupted record) is
//! refused before any output file is created, with the byte offset, unless `--salvage` asks
//! for everything before the damage; a failed export leaves no file behind. What can fail:
//! reading the input (`RecordError`), writing the outputs (`ExportError`).

pub mod csv;
pub mod mcap;
pub mod mcap_msg;
pub mod mcap_proto;
pub mod qt;
pub mod robots;
pub mod scene;

use std::path::{Path, PathBuf};

use anyhow::bail;
use protocol::{Feed, FrameDecoder, FrameError, Message};

use crate::output_file::OutputError;
use crate::record::{LinkState, RecordKind, Recording, StationLine};

/// Why an export failed.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: MCAP: {message}")]
    Mcap { path: PathBuf, message: String },
    #[error(transparent)]
    Output(#[from] OutputError),
}

/// Which way a frame went.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direction {
    FromRobot,
    ToRobot,
}

/// One step of the walk over a recording.
#[derive(Debug)]
pub enum Item<'a> {
    /// A good frame.
    Frame {
        t_us: u64,
        dir: Direction,
        seq: u16,
        msg: &'a Message<'a>,
    },
    /// A frame that did not decode.
    BadFrame {
        t_us: u64,
        dir: Direction,
        error: FrameError,
    },
    /// A connection change.
    Link {
        t_us: u64,
        state: LinkState,
        text: &'a str,
    },
    /// A line the station logged while it recorded.
    StationLog { t_us: u64, line: &'a StationLine },
}

/// Decodes every frame of a recording, both ways, in recorded order.
pub fn walk(rec: &Recording, mut f: impl FnMut(Item<'_>)) {
    let mut from = FrameDecoder::new();
    let mut to = FrameDecoder::new();
    for r in &rec.records {
        let t_us = r.t_us;
        let (dec, dir) = match r.kind {
            RecordKind::FromRobot => (&mut from, Direction::FromRobot),
            RecordKind::ToRobot => (&mut to, Direction::ToRobot),
            RecordKind::Link => {
                if let Some((state, text)) = r.link() {
                    if state == LinkState::Closed {
                        from.reset();
                    }
                    f(Item::Link {
                        t_us,
                        state,
                        text: &text,
                    });
                }
                continue;
            }
            RecordKind::StationLog => {
                if let Some(line) = r.station_log() {
                    f(Item::StationLog { t_us, line: &line });
                }
                continue;
            }
            RecordKind::End | RecordKind::Unknown(_) => continue,
        };
        let mut input = r.data.as_slice();
        loop {
            match dec.feed(input) {
                Feed::NeedMore => break,
                Feed::Error { error, rest } => {
                    input = rest;
                    f(Item::BadFrame { t_us, dir, error });
                }
                Feed::Frame { frame, rest } => {
                    input = rest;
                    f(Item::Frame {
                        t_us,
                        dir,
                        seq: frame.header.seq,
                        msg: &frame.message,
                    });
                }
            }
        }
    }
}

/// Opens a recording for a command that writes something from it: a damaged one (corrupted
/// or torn) is refused unless `salvage`, which keeps the records before the damage.
pub fn open_whole(path: &Path, salvage: bool) -> anyhow::Result<Recording> {
    let rec = Recording::open(path)?;
    if let Some(w) = rec.meta.schema_warning() {
        eprintln!("station: {}: {w}", path.display());
    }
    if let Some(d) = &rec.damage {
        let n = rec.records.len();
        if !salvage {
            bail!(
                "{}: {d}; nothing was written (--salvage uses the {n} records before it)",
                path.display()
            );
        }
        eprintln!(
            "station: {}: {d}; using the {n} records before it",
            path.display()
        );
    }
    Ok(rec)
}

/// Refuses an output that `output_file::check` refuses (a special file, a directory, a
/// missing directory, an existing file without `force`) or that is the input.
pub fn check_out(out: &Path, input: &Path, force: bool) -> anyhow::Result<()> {
    let same = match (out.canonicalize(), input.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => out == input,
    };
    if same {
        bail!("the output {} is the input", out.display());
    }
    crate::output_file::check(out, force)?;
    Ok(())
}

/// An I/O error writing `path`.
pub fn io(path: &Path, source: std::io::Error) -> ExportError {
    ExportError::Io {
        path: path.to_path_buf(),
        source,
    }
}
