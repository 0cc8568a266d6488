//! `station export`: a recording to MCAP and CSV (`station_core::export`), every output
//! complete before any takes its final name.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::bail;
use clap::Args;
use station_core::export::{check_out, csv, io, mcap, open_whole, robots};
use station_core::output_file::OutputFile;
use station_core::record::Recording;

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
    #[arg(long, value_enum, value_name = "ENCODING", default_value_t = McapEncoding::Protobuf, requires = "mcap")]
    pub mcap_encoding: McapEncoding,
    /// Write the telemetry as CSV, one row per frame (columns in docs/recordings.md); `-`
    /// writes it to stdout. A recording of several robots writes one file each (OUT with
    /// `.robot<ID>` or `.link<K>` before its extension; not to stdout).
    #[arg(long, value_name = "OUT")]
    pub csv: Option<PathBuf>,
    /// Export a damaged or torn recording up to its last good record instead of refusing it.
    #[arg(long)]
    pub salvage: bool,
    /// Overwrite output files that exist (a device, FIFO or directory is never replaced).
    #[arg(long)]
    pub force: bool,
}

/// How the MCAP file's per-frame topics are encoded (`station_core::export::mcap::Encoding`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum McapEncoding {
    /// Protocol Buffers: Foxglove's well-known schemas for poses and transforms, the station's
    /// for telemetry and truth; a file of about 40 % of JSON's bytes, written in about two
    /// thirds of the time.
    #[default]
    Protobuf,
    /// JSON text with JSON schemas, for scripts that parse the messages' JSON themselves (an
    /// MCAP reader and a JSON parser, no protobuf); a lacking sensor's reading is `null`.
    Json,
}

impl From<McapEncoding> for mcap::Encoding {
    fn from(e: McapEncoding) -> Self {
        match e {
            McapEncoding::Protobuf => mcap::Encoding::Protobuf,
            McapEncoding::Json => mcap::Encoding::Json,
        }
    }
}

/// The output name that means stdout.
const STDOUT: &str = "-";

/// Runs `station export`.
pub fn run(args: &ExportArgs) -> anyhow::Result<ExitCode> {
    let to_stdout = args.csv.as_deref() == Some(Path::new(STDOUT));
    if args.mcap.as_deref() == Some(Path::new(STDOUT)) {
        bail!("--mcap - : MCAP is binary and written whole before it is named; give a file name");
    }
    let outs: Vec<&Path> = [args.mcap.as_deref(), args.csv.as_deref()]
        .into_iter()
        .flatten()
        .filter(|p| *p != Path::new(STDOUT))
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
    if to_stdout && links.len() > 1 {
        bail!(
            "--csv - : {} holds {} robots' links, a CSV each; give a file name (OUT.robot<ID>.csv \
             each)",
            args.file.display(),
            links.len()
        );
    }
    let csvs: Vec<PathBuf> = match &args.csv {
        Some(_) if to_stdout => Vec::new(),
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
        let written = mcap::write_robots(
            &file_meta,
            &robots,
            args.mcap_encoding.into(),
            f.writer(),
            out,
        )?;
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
    // Stdout before the files take their names: a failed write leaves no file behind. A
    // reader that stops early (`| head`) is not a failure.
    if let (true, Some(rec)) = (to_stdout, links.first()) {
        let mut out = std::io::BufWriter::new(std::io::stdout().lock());
        let wrote =
            csv::write(rec, &mut out).and_then(|n| std::io::Write::flush(&mut out).map(|()| n));
        match wrote {
            Ok(n) => notes.push(format!("wrote the CSV to stdout ({n} telemetry rows)")),
            Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => {}
            Err(e) => return Err(anyhow::Error::new(e).context("cannot write the CSV to stdout")),
        }
    }
    for f in done {
        f.commit()?;
    }
    for n in notes {
        eprintln!("{n}");
    }
    Ok(ExitCode::SUCCESS)
}
