//! `station export`: a recording to MCAP (for Foxglove) and to CSV (for a spreadsheet or
//! pandas), written atomically.
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
pub mod mcap_file;
pub mod mcap_msg;
pub mod mcap_proto;
pub mod qt;
pub mod robots;
pub mod scene;

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::bail;
use clap::Args;
use protocol::{Feed, FrameDecoder, FrameError, Message};

use crate::output_file::{OutputError, OutputFile};
use crate::record::{LinkState, RecordKind, Recording};

/// Arguments of `station export`.
#[derive(Debug, Args, Clone)]
#[command(group(clap::ArgGroup::new("output").required(true).multiple(true).args(["mcap", "csv"])))]
pub struct ExportArgs {
    /// The recording to export.
    #[arg(value_name = "FILE")]
    pub file: PathBuf,
    /// Write an MCAP file (channels: /telemetry, /pose, /truth, /truth_pose, /events,
    /// /log, /link, /commands, /replies, and for the 3D panel /tf, /map, /regions, /plan,
    /// /arena; /qt_model for an ALICE), for Foxglove; a recording of several robots puts each
    /// under its own prefix (/robot1/telemetry, ...).
    #[arg(long, value_name = "OUT")]
    pub mcap: Option<PathBuf>,
    /// How the MCAP file's per-frame topics (/telemetry, /pose, /truth, /truth_pose, /tf) are
    /// encoded: protobuf (Foxglove's schemas for poses and transforms; the default) or json
    /// (for tools that parse JSON text). Other topics are always JSON.
    #[arg(long, value_enum, value_name = "ENCODING", default_value_t = mcap::Encoding::Protobuf, requires = "mcap")]
    pub mcap_encoding: mcap::Encoding,
    /// Write the telemetry as CSV, one row per frame (columns in docs/recordings.md); a
    /// recording of several robots writes one file each (OUT with `.robot<ID>` or `.link<K>`
    /// before its extension).
    #[arg(long, value_name = "OUT")]
    pub csv: Option<PathBuf>,
    /// Export a damaged or torn recording up to its last good record instead of refusing it.
    #[arg(long)]
    pub salvage: bool,
    /// Overwrite output files that exist (a device, FIFO or directory is never replaced).
    #[arg(long)]
    pub force: bool,
}

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

/// Runs `station export`.
pub fn run(args: &ExportArgs) -> anyhow::Result<ExitCode> {
    let outs: Vec<&Path> = [args.mcap.as_deref(), args.csv.as_deref()]
        .into_iter()
        .flatten()
        .collect();
    for out in &outs {
        check_out(out, &args.file, args.force)?;
    }
    if outs.len() == 2 && args.mcap == args.csv {
        bail!("--mcap and --csv name the same file");
    }
    let rec = open_whole(&args.file, args.salvage)?;
    // One robot per link: a file of several gets per-robot topics and CSV files (`robots`).
    let file_meta = rec.meta.clone();
    let links = if rec.link_count() > 1 {
        rec.links()
    } else {
        vec![rec]
    };
    let labels = robots::labels(&links);
    let csvs: Vec<PathBuf> = match &args.csv {
        Some(out) => labels.iter().map(|l| robots::csv_path(out, l)).collect(),
        None => Vec::new(),
    };
    if links.len() > 1 {
        for out in &csvs {
            check_out(out, &args.file, args.force)?;
        }
    }
    // Every output is complete before any takes its final name; an output not committed is
    // removed when dropped.
    let mut done = Vec::new();
    let mut notes = Vec::new();
    if let Some(out) = &args.mcap {
        let mut f = OutputFile::create(out, args.force)?;
        let robots: Vec<(&str, &Recording)> =
            labels.iter().map(String::as_str).zip(&links).collect();
        let written = mcap::write_robots(&file_meta, &robots, args.mcap_encoding, f.writer(), out)?;
        done.push(f);
        notes.push(format!(
            "wrote {} ({} messages)",
            out.display(),
            written.messages
        ));
        notes.extend(written.notes);
    }
    for (out, rec) in csvs.iter().zip(&links) {
        let mut f = OutputFile::create(out, args.force)?;
        let n = csv::write(rec, f.writer()).map_err(|e| io(out, e))?;
        done.push(f);
        notes.push(format!("wrote {} ({n} telemetry rows)", out.display()));
    }
    for f in done {
        f.commit()?;
    }
    for n in notes {
        eprintln!("{n}");
    }
    Ok(ExitCode::SUCCESS)
}

/// Opens a recording for a command that writes something from it: a damaged one (corrupted
/// or torn) is refused unless `salvage`, which keeps the records before the damage.
pub(crate) fn open_whole(path: &Path, salvage: bool) -> anyhow::Result<Recording> {
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
pub(crate) fn check_out(out: &Path, input: &Path, force: bool) -> anyhow::Result<()> {
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

fn io(path: &Path, source: std::io::Error) -> ExportError {
    ExportError::Io {
        path: path.to_path_buf(),
        source,
    }
}
