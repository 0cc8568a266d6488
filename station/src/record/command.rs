//! `station record`: record a link to a file, headless.
//!
//! Layer: the binary's edge (anyhow). Checks everything it can before it creates a file (the
//! output name, the port), then runs the link with its tap into a `LiveRecorder` until the time
//! is up or Ctrl-C, and finishes the file cleanly either way. The link reconnects by itself
//! while it records; every loss and return of the session is a link record (a gap marker).
//! Exit codes: 0 recorded, 1 no file could be made or written, or no robot ever answered (the
//! file is kept: it shows what the port said), 2 usage.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use anyhow::{bail, Context as _};
use clap::Args;
use protocol::Command;
use serde_json::json;
use tokio::sync::mpsc;
use tokio::time::Instant;

use super::live::LiveRecorder;
use super::writer::Written;
use super::{partial_path, Meta};
use crate::builtin::start_builtin_emulator;
use crate::cli::{parse_baud, parse_seconds};
use crate::link::serial::{open_exclusive, SerialConnector, DEFAULT_BAUD};
use crate::link::{spawn_link, Connection, LinkEvent, LinkOptions};

/// Arguments of `station record`.
#[derive(Debug, Args, Clone)]
pub struct RecordArgs {
    /// Serial port (or pty) of the robot. Without it, the built-in emulator is started and
    /// recorded.
    #[arg(long, short = 'p', value_name = "PATH")]
    pub port: Option<PathBuf>,
    /// Baud rate (ignored by ptys).
    #[arg(long, short = 'b', default_value_t = DEFAULT_BAUD, value_parser = parse_baud)]
    pub baud: u32,
    /// The recording to write. It is FILE.partial until the recording ends, then renamed.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub out: PathBuf,
    /// Seconds to record; without it, until Ctrl-C.
    #[arg(long, short = 's', value_parser = parse_seconds,
          allow_negative_numbers = true)]
    pub seconds: Option<f64>,
    /// Ask the robot for this telemetry rate (Hz, 1..=50) at every handshake.
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=50))]
    pub rate: Option<u8>,
    /// Send this command (as `station send` takes it, e.g. "mode wander", "goto 1.2 0.8",
    /// "param set hal_trace 1") once the robot first answers; repeat for several, sent in order.
    #[arg(long = "send", value_name = "CMD")]
    pub send: Vec<String>,
    /// Overwrite FILE if it exists (a device, FIFO or directory is never replaced).
    #[arg(long)]
    pub force: bool,
    /// Print a JSON summary.
    #[arg(long)]
    pub json: bool,
    /// Link authentication key file (64 hex digits, PROTOCOL.md §13). Without --port the
    /// built-in emulator is given the same key.
    #[arg(long, value_name = "PATH")]
    pub key_file: Option<PathBuf>,
}

/// Runs `station record`.
pub async fn run(args: &RecordArgs) -> anyhow::Result<ExitCode> {
    let mut to_send = args
        .send
        .iter()
        .map(|s| parse_send(s))
        .collect::<anyhow::Result<Vec<Command>>>()?;
    check_out(&args.out, args.force)?;
    let raw_key =
        crate::cli::load_key_bytes(args.key_file.as_deref()).map_err(anyhow::Error::msg)?;
    let key = raw_key.map(|k| protocol::LinkKey::new(&k));
    let mut builtin = None;
    let (path, label) = match &args.port {
        Some(p) => {
            drop(open_exclusive(p, args.baud)?);
            (p.clone(), p.display().to_string())
        }
        None => {
            let mut emu = start_builtin_emulator(raw_key.as_ref())?;
            let label = format!("built-in emulator on {}", emu.pty_path().display());
            let path = emu.path().to_path_buf();
            builtin = Some(emu);
            (path, label)
        }
    };
    let mut meta = Meta::now(&label, args.baud);
    if builtin.is_some() {
        meta.arena = emulator::builtin::MICRO_RATO_99.to_string();
    }
    let epoch = Instant::now();
    let mut rec = LiveRecorder::start(
        &args.out,
        &meta,
        args.force,
        epoch,
        &Connection::Closed {
            reason: "starting".into(),
        },
    )?;
    let (tap_tx, mut tap) = mpsc::unbounded_channel();
    // Paced like the TUI's port: one read (so one record) per 32 ms slot while bytes keep
    // coming, instead of one a millisecond (206k records for 10 min at 50 Hz, the file 1.87x
    // the link's bytes, 1.8 % of a core). Awaited replies are still read as they come, so the
    // round trips a replay measures keep their times; frames carry their own robot time.
    let mut link = spawn_link(
        SerialConnector::new(&path, args.baud).paced(true),
        LinkOptions {
            station: format!("station-record {}", env!("CARGO_PKG_VERSION")),
            tap: Some(tap_tx),
            paced: true,
            key,
            ..LinkOptions::default()
        },
    );
    if !args.json {
        eprintln!(
            "recording {} to {} ({})",
            label,
            rec.path().display(),
            match args.seconds {
                Some(s) => format!("{s} s"),
                None => "Ctrl-C stops".into(),
            }
        );
    }
    let deadline = args.seconds.map(|s| epoch + Duration::from_secs_f64(s));
    // On the pace grid, so the flush shares the paced reads' wake-ups.
    let every = crate::pace::slots(Duration::from_millis(250));
    let mut flush = tokio::time::interval_at(crate::pace::next_slot(), every);
    let ctrl_c = tokio::signal::ctrl_c();
    tokio::pin!(ctrl_c);
    let mut failure: Option<anyhow::Error> = None;
    let reason = loop {
        let until = async {
            match deadline {
                Some(d) => tokio::time::sleep_until(d).await,
                None => std::future::pending().await,
            }
        };
        let step = tokio::select! {
            Some(t) = tap.recv() => rec.on_tap(&t),
            Some(ev) = link.events.recv() => match ev {
                LinkEvent::Connection(c) => {
                    if let (Connection::Connected(_), Some(hz)) = (&c, args.rate) {
                        link.handle.submit(Command::SetTelemetryRate { hz });
                    }
                    if matches!(c, Connection::Connected(_)) {
                        for cmd in to_send.drain(..) {
                            link.handle.submit(cmd);
                        }
                    }
                    rec.on_connection(&c)
                }
                _ => Ok(()),
            },
            _ = flush.tick() => rec.tick(Instant::now()),
            () = until => break "time limit",
            _ = &mut ctrl_c => break "interrupted",
        };
        if let Err(e) = step {
            failure = Some(e.into());
            break "write failed";
        }
    };
    // Stop the link, keeping the bytes of its last moments (its final writes to the port).
    link.handle.shutdown();
    let _ = tokio::time::timeout(Duration::from_secs(1), &mut link.task).await;
    while let Ok(t) = tap.try_recv() {
        if failure.is_none() {
            if let Err(e) = rec.on_tap(&t) {
                failure = Some(e.into());
            }
        }
    }
    // The link's own "stopped" is not a gap: the end record says why the recording ended.
    drop(builtin);
    if let Some(e) = failure {
        return Err(e.context(format!(
            "recording stopped; what was written is in {}",
            partial_path(&args.out).display()
        )));
    }
    let counts = rec.counts();
    let written = rec.finish(reason)?;
    report(args, &written, counts, reason)?;
    if !counts.connected {
        eprintln!(
            "station: no robot answered on {label}; the recording holds only what the port said"
        );
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}

/// One `--send` command, parsed as `station send` parses its command.
fn parse_send(s: &str) -> anyhow::Result<Command> {
    #[derive(clap::Parser)]
    #[command(no_binary_name = true)]
    struct One {
        #[command(subcommand)]
        cmd: crate::cli::SendCmd,
    }
    let one = <One as clap::Parser>::try_parse_from(s.split_whitespace()).map_err(|e| {
        anyhow::anyhow!(
            "--send {:?}: {}",
            crate::terminal_text::printable(s),
            e.render()
        )
    })?;
    one.cmd
        .to_command()
        .map_err(|e| anyhow::anyhow!("--send {:?}: {e}", crate::terminal_text::printable(s)))
}

/// Refuses an output that cannot be written, before a port is opened or a file created.
fn check_out(out: &Path, force: bool) -> anyhow::Result<()> {
    crate::output_file::check(out, force)?;
    let partial = partial_path(out);
    if partial.exists() {
        bail!(
            "{} exists: an unfinished recording (a crash?); replay or rename it, then try again",
            partial.display()
        );
    }
    Ok(())
}

fn report(
    args: &RecordArgs,
    w: &Written,
    counts: super::live::LiveCounts,
    reason: &str,
) -> anyhow::Result<()> {
    let duration_s = w.duration_us as f64 / 1e6;
    if args.json {
        let v = json!({
            "file": w.path.display().to_string(),
            "records": w.records,
            "bytes": w.bytes,
            "duration_s": duration_s,
            "bytes_from_robot": counts.bytes_from_robot,
            "bytes_to_robot": counts.bytes_to_robot,
            "link_events": counts.link_events,
            "gaps": counts.gaps,
            "connected": counts.connected,
            "end": reason,
        });
        println!(
            "{}",
            serde_json::to_string_pretty(&v).context("cannot print JSON")?
        );
    } else {
        println!(
            "recorded {:.1} s to {} ({reason}): {} records, {} bytes from the robot, {} to it, \
             {} gap(s)",
            duration_s,
            w.path.display(),
            w.records,
            counts.bytes_from_robot,
            counts.bytes_to_robot,
            counts.gaps
        );
    }
    Ok(())
}
