//! `station record`: record a link, or several (`--port A --port B`), to one file, headless.
//!
//! Layer: the binary's edge (anyhow). Checks everything it can before it creates a file (the
//! output name, the port), then runs the link with its tap into a `LiveRecorder` until the time
//! is up or Ctrl-C, and finishes the file cleanly either way. The link reconnects by itself
//! while it records; every loss and return of the session is a link record (a gap marker), and
//! what the station says of the robot's events and its commands' outcomes is a station log
//! record.
//! Exit codes: 0 recorded, 1 no file could be made or written, or no robot ever answered (the
//! file is kept: it shows what the port said), 2 usage.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use anyhow::{bail, Context as _};
use clap::Args;
use protocol::{Command, LogLevel};
use robot_firmware::params::id::HAL_TRACE;
use serde_json::json;
use tokio::sync::mpsc;
use tokio::time::Instant;

use crate::builtin::start_builtin_emulator;
use crate::commands::args::{parse_baud, parse_seconds};
use crate::link::robot_ids::duplicates;
use crate::link::serial::{open_exclusive, SerialConnector, DEFAULT_BAUD};
use crate::link::{spawn_link, Connection, LinkEvent, LinkOptions, TapRecord};
use station_core::link::api::{command_text, refusal_text, CommandOutcome};
use station_core::record::live::{LiveCounts, LiveRecorder};
use station_core::record::writer::Written;
use station_core::record::{partial_path, LogSource, Meta, StationLine, MAX_LINKS};

/// Arguments of `station record`.
#[derive(Debug, Args, Clone)]
pub struct RecordArgs {
    /// Serial port (or pty) of the robot; repeat it to record several robots into one file
    /// (link 0, 1, ... in this order). Without it, the built-in emulator is started and
    /// recorded.
    #[arg(long, short = 'p', value_name = "PATH")]
    pub port: Vec<PathBuf>,
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
    /// Record the robot's hardware trace (parameter 34 hal_trace), so that `station retrace`
    /// can re-run the recording through the firmware's code. The built-in emulator then
    /// streams it from power-up (an exact retrace); a robot on --port is set hal_trace = 1
    /// once it answers and put back as it was when the recording ends (its state before the
    /// trace began is not in it: a retrace with --param compares, but cannot match bit for
    /// bit).
    #[arg(long)]
    pub hal_trace: bool,
    /// Overwrite FILE if it exists (a device, FIFO or directory is never replaced).
    #[arg(long)]
    pub force: bool,
    /// Print a JSON summary.
    #[arg(long)]
    pub json: bool,
    /// Link authentication key file (64 hex digits, PROTOCOL.md §13), for every port. Without
    /// --port the built-in emulator is given the same key.
    #[arg(long, value_name = "PATH")]
    pub key_file: Option<PathBuf>,
}

/// What a link tells the recording loop, tagged with its link id.
enum FromLink {
    Tap(u8, TapRecord),
    Event(u8, LinkEvent),
}

/// Runs `station record`.
pub async fn run(args: &RecordArgs) -> anyhow::Result<ExitCode> {
    let to_send = args
        .send
        .iter()
        .map(|s| parse_send(s))
        .collect::<anyhow::Result<Vec<Command>>>()?;
    check_out(&args.out, args.force)?;
    if args.port.len() > MAX_LINKS {
        bail!(
            "--port is given {} times; a recording holds at most {MAX_LINKS} links",
            args.port.len()
        );
    }
    crate::commands::args::distinct_ports(args.port.iter().map(PathBuf::as_path))
        .map_err(anyhow::Error::msg)?;
    let raw_key = crate::commands::args::load_key_bytes(args.key_file.as_deref())
        .map_err(anyhow::Error::msg)?;
    let key = raw_key.map(|k| protocol::LinkKey::new(&k));
    let mut builtin = None;
    // (path opened, label recorded) per link.
    let mut ports: Vec<(PathBuf, String)> = Vec::new();
    for p in &args.port {
        drop(open_exclusive(p, args.baud)?);
        ports.push((p.clone(), p.display().to_string()));
    }
    // Robots on ports get the trace switched on when they answer; the built-in one has it
    // from power-up.
    let switch_trace = args.hal_trace && !ports.is_empty();
    if ports.is_empty() {
        let mut emu = if args.hal_trace {
            crate::builtin::start_builtin_emulator_traced(raw_key.as_ref())?
        } else {
            start_builtin_emulator(raw_key.as_ref())?
        };
        let label = format!("built-in emulator on {}", emu.pty_path().display());
        ports.push((emu.path().to_path_buf(), label));
        builtin = Some(emu);
    }
    let labels: Vec<String> = ports.iter().map(|(_, l)| l.clone()).collect();
    let label = labels.join(", ");
    let mut meta = Meta::now_links(&labels, args.baud);
    if builtin.is_some() {
        meta.arena = emulator::builtin::MICRO_RATO_99.to_string();
    }
    // One link task per port, as the one-port recording has; their taps and events come to
    // this loop tagged with the link id, so one file holds them all on one clock.
    let (tx, mut from_links) = mpsc::unbounded_channel();
    let mut links = Vec::new();
    let mut epochs = Vec::new();
    let mut forwarders = Vec::new();
    for (i, (path, _)) in ports.iter().enumerate() {
        let id = u8::try_from(i).unwrap_or(u8::MAX);
        let (tap_tx, mut tap) = mpsc::unbounded_channel();
        epochs.push((
            Instant::now(),
            Connection::Closed {
                reason: "starting".into(),
            },
        ));
        // Paced like the TUI's port: one read (so one record) per 32 ms slot while bytes
        // keep coming, instead of one a millisecond (206k records for 10 min at 50 Hz, the
        // file 1.87x the link's bytes, 1.8 % of a core). Awaited replies are still read as
        // they come, so the round trips a replay measures keep their times; frames carry
        // their own robot time.
        let mut link = spawn_link(
            SerialConnector::new(path, args.baud).paced(true),
            LinkOptions {
                station: format!("station-record {}", env!("CARGO_PKG_VERSION")),
                tap: Some(tap_tx),
                paced: true,
                key: key.clone(),
                ..LinkOptions::default()
            },
        );
        let (taps, events) = (tx.clone(), tx.clone());
        let mut ev = std::mem::replace(&mut link.events, mpsc::unbounded_channel().1);
        forwarders.push(tokio::spawn(async move {
            while let Some(t) = tap.recv().await {
                if taps.send(FromLink::Tap(id, t)).is_err() {
                    break;
                }
            }
        }));
        forwarders.push(tokio::spawn(async move {
            while let Some(e) = ev.recv().await {
                if events.send(FromLink::Event(id, e)).is_err() {
                    break;
                }
            }
        }));
        links.push(link);
    }
    drop(tx);
    let mut rec = LiveRecorder::start_links(&args.out, &meta, args.force, &epochs)?;
    let epoch = Instant::now();
    if !args.json {
        eprintln!(
            "recording {} to {} ({}{})",
            label,
            rec.path().display(),
            match args.seconds {
                Some(s) => format!("{s} s"),
                None => "Ctrl-C stops".into(),
            },
            match (args.hal_trace, switch_trace) {
                (false, _) => "",
                (true, false) => "; hardware trace from power-up",
                (true, true) => "; hardware trace on, hal_trace put back at the end",
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
    let mut ids: Vec<Option<u8>> = vec![None; links.len()];
    let mut warned = Vec::new();
    let mut sent = vec![false; links.len()];
    // Each robot's hal_trace before the recording switched it on, to put back at the end.
    let mut trace_before: Vec<Option<f32>> = vec![None; links.len()];
    let reason = loop {
        let until = async {
            match deadline {
                Some(d) => tokio::time::sleep_until(d).await,
                None => std::future::pending().await,
            }
        };
        let step = tokio::select! {
            Some(m) = from_links.recv() => match m {
                FromLink::Tap(id, t) => rec.on_link_tap(id, &t),
                FromLink::Event(id, LinkEvent::Connection(c)) => {
                    if let Connection::Connected(p) = &c {
                        if let Some(hz) = args.rate {
                            if let Some(l) = links.get(usize::from(id)) {
                                l.handle.submit(Command::SetTelemetryRate { hz });
                            }
                        }
                        if let Some(slot) = ids.get_mut(usize::from(id)) {
                            *slot = Some(p.robot_id);
                        }
                        warn_duplicates(&labels, &ids, &mut warned);
                    }
                    if let (true, Connection::Connected(_), Some(l)) =
                        (switch_trace, &c, links.get(usize::from(id)))
                    {
                        // At every handshake: a robot that restarted has it off again. The
                        // read first, answered before the switch, says what to put back.
                        l.handle.submit(Command::GetParam { id: protocol::ParamId(HAL_TRACE) });
                        l.handle.submit(Command::SetParam {
                            id: protocol::ParamId(HAL_TRACE),
                            value: 1.0,
                        });
                    }
                    if matches!(c, Connection::Connected(_)) {
                        // `--send`: once per link, on its first handshake.
                        let first = sent.get_mut(usize::from(id)).is_some_and(|s| !std::mem::replace(s, true));
                        if let (true, Some(l)) = (first, links.get(usize::from(id))) {
                            for cmd in &to_send {
                                l.handle.submit(*cmd);
                            }
                        }
                    }
                    rec.on_link_connection(id, &c)
                }
                FromLink::Event(id, e) => {
                    if let Some(v) = trace_value(&e) {
                        if let Some(slot) = trace_before.get_mut(usize::from(id)) {
                            slot.get_or_insert(v);
                        }
                    }
                    match station_line(&e) {
                        Some(line) => rec.on_station_log(id, &line),
                        None => Ok(()),
                    }
                }
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
    // The trace as it was before the recording (off when its read went unanswered): sent
    // before the shutdown, which writes what was submitted before it.
    if switch_trace {
        for (l, before) in links.iter().zip(&trace_before) {
            let before = before.unwrap_or(0.0);
            if before != 1.0 {
                l.handle.submit(Command::SetParam {
                    id: protocol::ParamId(HAL_TRACE),
                    value: before,
                });
            }
        }
    }
    // Stop the links, keeping the bytes of their last moments (their final writes to the
    // ports): each task ends, its tap closes, its forwarder passes on what was left.
    for l in &links {
        l.handle.shutdown();
    }
    for l in links {
        let _ = tokio::time::timeout(Duration::from_secs(1), l.task).await;
    }
    for f in forwarders {
        let _ = tokio::time::timeout(Duration::from_secs(1), f).await;
    }
    while let Ok(m) = from_links.try_recv() {
        if let (FromLink::Tap(id, t), None) = (m, &failure) {
            if let Err(e) = rec.on_link_tap(id, &t) {
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
    let per_link = rec.link_counts();
    let counts = rec.counts();
    let written = rec.finish(reason)?;
    report(args, &written, counts, reason, &labels, &per_link, &ids)?;
    let silent: Vec<&str> = labels
        .iter()
        .zip(&per_link)
        .filter(|(_, c)| !c.connected)
        .map(|(l, _)| l.as_str())
        .collect();
    if !silent.is_empty() {
        eprintln!(
            "station: no robot answered on {}; the recording holds only what the port said",
            silent.join(", ")
        );
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}

/// The hal_trace value a robot reported, from the answer to a read of it.
fn trace_value(e: &LinkEvent) -> Option<f32> {
    match e {
        LinkEvent::CommandDone {
            command: Command::GetParam { .. },
            outcome:
                CommandOutcome::Acked {
                    info: protocol::AckInfo::Param { id, value },
                    ..
                },
            ..
        } if id.0 == HAL_TRACE => Some(*value),
        _ => None,
    }
}

/// What the station says of a link event, for the recording's log as the TUI's log says it:
/// a robot event in the station's words (`format::event_text`), a command's outcome. The rest
/// (frames, connection changes) the recording holds already.
fn station_line(e: &LinkEvent) -> Option<StationLine> {
    let (level, source, text) = match e {
        LinkEvent::Robot(e) => {
            let (level, text) = station_core::format::event_text(e);
            (level, LogSource::Event, text)
        }
        LinkEvent::CommandDone {
            command, outcome, ..
        } => {
            let what = command_text(command);
            let (level, text) = match outcome {
                CommandOutcome::Acked { rtt_ms, .. } => {
                    (LogLevel::Info, format!("ok: {what} ({rtt_ms} ms)"))
                }
                CommandOutcome::Nacked { reason, .. } => (
                    LogLevel::Error,
                    format!("refused: {what}: {}", refusal_text(command, *reason)),
                ),
                CommandOutcome::Failed(why) => (LogLevel::Error, format!("failed: {what}: {why}")),
            };
            (level, LogSource::Command, text)
        }
        _ => return None,
    };
    Some(StationLine {
        level,
        source,
        text,
    })
}

/// Warns (once per id) of two links whose robots state the same id.
fn warn_duplicates(labels: &[String], ids: &[Option<u8>], warned: &mut Vec<u8>) {
    let dups = duplicates(labels.iter().map(String::as_str).zip(ids.iter().copied()));
    for d in dups {
        if !warned.contains(&d.robot_id) {
            warned.push(d.robot_id);
            eprintln!(
                "station: warning: {}",
                crate::terminal_text::printable_text(&d.warning())
            );
        }
    }
}

/// One `--send` command, parsed as `station send` parses its command.
fn parse_send(s: &str) -> anyhow::Result<Command> {
    #[derive(clap::Parser)]
    #[command(no_binary_name = true)]
    struct One {
        #[command(subcommand)]
        cmd: crate::commands::send::SendCmd,
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
    counts: LiveCounts,
    reason: &str,
    labels: &[String],
    per_link: &[LiveCounts],
    ids: &[Option<u8>],
) -> anyhow::Result<()> {
    let duration_s = w.duration_us as f64 / 1e6;
    let dups = duplicates(labels.iter().map(String::as_str).zip(ids.iter().copied()));
    if args.json {
        let links: Vec<serde_json::Value> = labels
            .iter()
            .zip(per_link)
            .zip(ids)
            .enumerate()
            .map(|(i, ((port, c), id))| {
                json!({
                    "link": i,
                    "port": port,
                    "robot_id": id,
                    "bytes_from_robot": c.bytes_from_robot,
                    "bytes_to_robot": c.bytes_to_robot,
                    "link_events": c.link_events,
                    "gaps": c.gaps,
                    "connected": c.connected,
                })
            })
            .collect();
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
            "links": links,
            "duplicate_robot_ids": dups,
        });
        println!(
            "{}",
            crate::json_text::pretty(&v).context("cannot print JSON")?
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
        if labels.len() > 1 {
            for (i, ((port, c), id)) in labels.iter().zip(per_link).zip(ids).enumerate() {
                println!(
                    "  link {i} {}: robot id {}, {} bytes from the robot, {} to it, {} gap(s)",
                    crate::terminal_text::printable(port),
                    id.map_or("unknown".to_string(), |id| id.to_string()),
                    c.bytes_from_robot,
                    c.bytes_to_robot,
                    c.gaps
                );
            }
        }
    }
    Ok(())
}
