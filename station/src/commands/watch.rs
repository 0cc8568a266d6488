//! `station watch`: the robot's telemetry, progress reports, events and log lines on stdout as
//! JSON, one object a line (`station_core::watch`), each flushed as written, until Ctrl-C,
//! --count lines, --seconds, a closed stdout (exit 0) or a lost link (exit `link_lost`).

use std::io::Write;
use std::process::ExitCode;
use std::time::Duration;

use clap::{Args, ValueEnum};
use tokio::time::Instant;

use super::args::{parse_seconds, RequiredPort};
use super::connect::connect;
use super::wait::{code, usage, wake_at};
use crate::link::LinkEvent;
use crate::task_end::Ending;
use crate::watch::{Fields, Kind, Lines, LinkLoss};

/// Arguments of `station watch`.
#[derive(Debug, Args, Clone)]
pub struct WatchArgs {
    #[command(flatten)]
    pub port: RequiredPort,
    /// Which lines, comma-separated [default: all four].
    #[arg(long, value_enum, value_delimiter = ',', value_name = "KIND,...")]
    pub kind: Vec<KindArg>,
    /// Only these keys of each line, comma-separated, in this order (a dotted key reads into
    /// an array: ir.0); each line keeps its `kind`, and a line with none of them is left out.
    #[arg(long, value_name = "KEY,...")]
    pub fields: Option<String>,
    /// Stop after this many lines.
    #[arg(long, short = 'n', value_name = "N",
          value_parser = clap::value_parser!(u64).range(1..))]
    pub count: Option<u64>,
    /// Stop after this many seconds.
    #[arg(long, short = 's', value_parser = parse_seconds, allow_negative_numbers = true)]
    pub seconds: Option<f64>,
    /// Seconds to wait for the handshake.
    #[arg(long, default_value_t = 5.0, value_parser = parse_seconds,
          allow_negative_numbers = true)]
    pub timeout: f64,
}

/// Line kinds on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum KindArg {
    /// Every telemetry frame (the robot's rate: `station send rate HZ`).
    Telemetry,
    /// What the robot's task is doing, about once a second while one runs.
    Progress,
    /// The robot's events (ModeChanged, GoalReached, NoProgress, ...).
    Event,
    /// The robot's log lines.
    Log,
}

impl From<KindArg> for Kind {
    fn from(k: KindArg) -> Kind {
        match k {
            KindArg::Telemetry => Kind::Telemetry,
            KindArg::Progress => Kind::Progress,
            KindArg::Event => Kind::Event,
            KindArg::Log => Kind::Log,
        }
    }
}

/// Why a watch ended.
enum End {
    /// What was asked for: the count, the time, Ctrl-C, or nobody reads stdout any more.
    Done,
    LinkLost(String),
}

/// Runs `station watch`.
pub async fn run(args: &WatchArgs) -> anyhow::Result<ExitCode> {
    let started = Instant::now();
    let kinds: Vec<Kind> = if args.kind.is_empty() {
        Kind::ALL.to_vec()
    } else {
        args.kind.iter().map(|&k| k.into()).collect()
    };
    let fields = match args.fields.as_deref().map(|f| Fields::parse(f, &kinds)) {
        None => None,
        Some(Ok(f)) => Some(f),
        Some(Err(e)) => return Ok(usage(&e)),
    };
    let (mut link, peer) = connect(&args.port, args.timeout).await?;
    let deadline = args.seconds.map(|s| started + Duration::from_secs_f64(s));
    let mut lines = Lines::new(Some(peer.capabilities));
    let mut loss = LinkLoss::default();
    let mut printed = 0u64;
    let mut out = std::io::stdout().lock();
    let ctrl_c = tokio::signal::ctrl_c();
    tokio::pin!(ctrl_c);
    let t_us = || started.elapsed().as_micros() as u64;
    let end = loop {
        let wake = wake_at(started, deadline, loss.deadline_us());
        let until = async {
            match wake {
                Some(at) => tokio::time::sleep_until(at).await,
                None => std::future::pending().await,
            }
        };
        let ev = tokio::select! {
            ev = link.events.recv() => ev,
            () = until => {
                if let Some(why) = loss.poll(t_us()) {
                    break End::LinkLost(why);
                }
                if deadline.is_some_and(|d| Instant::now() >= d) {
                    break End::Done;
                }
                continue;
            }
            _ = &mut ctrl_c => break End::Done,
        };
        let Some(ev) = ev else {
            break End::LinkLost("the link task ended".into());
        };
        let now = t_us();
        if let LinkEvent::Connection(c) = &ev {
            if let Some(why) = loss.on_connection(now, c) {
                break End::LinkLost(why);
            }
        }
        let Some(line) = lines.line(now, &ev) else {
            continue;
        };
        if !kinds.contains(&line.kind) {
            continue;
        }
        let text = match &fields {
            Some(f) => match f.pick(&line) {
                Some(t) => t,
                None => continue,
            },
            None => line.json,
        };
        match write_line(&mut out, &text) {
            Ok(()) => {}
            // Nobody reads any more (`| head`): what was asked for is done.
            Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => break End::Done,
            Err(e) => {
                link.handle.shutdown();
                return Err(anyhow::Error::new(e).context("cannot write to stdout"));
            }
        }
        printed += 1;
        if args.count.is_some_and(|n| printed >= n) {
            break End::Done;
        }
    };
    link.handle.shutdown();
    let _ = tokio::time::timeout(Duration::from_secs(1), link.task).await;
    Ok(match end {
        End::Done => ExitCode::SUCCESS,
        End::LinkLost(why) => {
            eprintln!(
                "station: link lost: {}",
                crate::terminal_text::printable_text(&why)
            );
            ExitCode::from(code(Ending::LinkLost))
        }
    })
}

/// One line, flushed at once: a reader at the other end of a pipe sees it now.
fn write_line(out: &mut impl Write, text: &[u8]) -> std::io::Result<()> {
    out.write_all(text)?;
    out.write_all(b"\n")?;
    out.flush()
}
