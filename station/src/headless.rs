//! What each command line form does: the TUI (on a port or the built-in emulator), `ports`,
//! `send` and `stats`.
//!
//! Layer: the binary's edge (anyhow lives here and in `main`). Headless commands start the same
//! link task as the TUI, wait for the handshake (failing at once, with the reason, when the
//! port cannot be opened or the robot refuses us), do their one thing and print plain text or
//! JSON. Exit codes: 0 done, 1 refused / unanswered / port unusable, 2 usage (clap).

use std::io::IsTerminal;
use std::path::Path;
use std::process::ExitCode;
use std::time::Duration;

use anyhow::{bail, Context as _};
use protocol::AckInfo;
use serde_json::json;
use tokio::time::Instant;

use crate::app::arena::ArenaOverlay;
use crate::app::params::format_param_id;
use crate::app::{App, AppOptions};
use crate::builtin::start_builtin_emulator_with;
use crate::cli::{Cli, RequiredPort, SendCmd, Sub};
use crate::link::api::{command_text, param_name, refusal_text};
use crate::link::robot_ids::duplicates;
use crate::link::serial::{open_exclusive, SerialConnector};
use crate::link::{
    spawn_link, CommandOutcome, Connection, LinkEvent, LinkOptions, LinkStats, PeerInfo,
    RunningLink,
};
use crate::plan::PlanState;

/// Runs what the command line asked for.
pub async fn dispatch(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        None => {
            let key = crate::cli::load_key_bytes(cli.port.key_file.as_deref())
                .map_err(anyhow::Error::msg)?;
            // Several robots: one link each (`fleet`).
            if cli.port.port.len() > 1 || cli.port.robots.is_some_and(|n| n > 1) {
                return crate::fleet::start::interactive(
                    &cli.port.port,
                    cli.port.robots.map_or(0, usize::from),
                    cli.port.baud,
                    cli.arena.as_deref(),
                    cli.profile.map(|p| p.profile()),
                    key,
                )
                .await;
            }
            interactive(
                cli.port.port.first().map(|p| p.as_path()),
                cli.port.baud,
                cli.arena.as_deref(),
                cli.profile.map(|p| p.profile()),
                key,
                cli.start,
            )
            .await
        }
        Some(Sub::Ports { json }) => ports(json),
        Some(Sub::Send {
            port,
            json,
            timeout,
            repeat,
            command,
        }) => send(&port, json, timeout, repeat, &command).await,
        Some(Sub::Stats {
            port,
            seconds,
            json,
            timeout,
        }) => stats(&port, seconds, json, timeout).await,
        Some(Sub::Params(args)) => crate::commands::params::run(&args).await,
        Some(Sub::UploadMap(args)) => crate::commands::transfer::upload_map(&args).await,
        Some(Sub::DownloadMap(args)) => crate::commands::transfer::download_map(&args).await,
        Some(Sub::UploadPlan(args)) => crate::commands::transfer::upload_plan(&args).await,
        Some(Sub::Plan(args)) => crate::commands::plan::plan(&args),
        Some(Sub::Segment(args)) => crate::commands::plan::segment(&args),
        Some(Sub::Record(args)) => crate::commands::record::run(&args).await,
        Some(Sub::Replay(args)) => crate::commands::replay::run(&args).await,
        Some(Sub::Export(args)) => crate::commands::export::run(&args),
        Some(Sub::Retrace(args)) => crate::commands::retrace::run(&args),
        Some(Sub::Calibrate(args)) => crate::commands::calibrate::dispatch(&args).await,
        Some(Sub::UploadCalibration(args)) => crate::commands::calibration::upload(&args).await,
        Some(Sub::DownloadCalibration(args)) => crate::commands::calibration::download(&args).await,
        Some(Sub::Places(args)) => crate::places::command(&args),
    }
}

async fn interactive(
    port: Option<&Path>,
    baud: u32,
    arena: Option<&Path>,
    profile: Option<&'static robot_firmware::Profile>,
    key: Option<[u8; protocol::sign::KEY_LEN]>,
    start: Option<[f64; 3]>,
) -> anyhow::Result<ExitCode> {
    if !std::io::stdout().is_terminal() {
        bail!("the TUI needs a terminal; for scripts use `station send` or `station stats`");
    }
    let arena_path = arena;
    // One load gives the drawing and the planner's grid (`plan::PlanState::for_arena`).
    let mut plan = PlanState::default();
    let mut arena = match arena {
        Some(p) => {
            // Built-in names (`builtin:forage`) as well as files.
            let name = p.to_string_lossy();
            // Without --port the built-in emulator simulates it: its world limit applies here
            // too, so a world it would refuse is refused before the drawing's walls are built.
            let load = if port.is_none() {
                emulator::arena::LoadOptions::for_simulation()
            } else {
                emulator::arena::LoadOptions::default()
            };
            let a = emulator::builtin::load(&name, &load)
                .with_context(|| format!("cannot load arena {}", p.display()))?;
            let overlay = ArenaOverlay::from_arena(&a);
            // Foraging does not plan, and a 0.3 m planning grid over a 1 m box is all walls.
            if overlay.forage.is_none() {
                plan = PlanState::for_arena(&a, &p.display().to_string());
            }
            Some(overlay)
        }
        None => None,
    };
    // Keeps the built-in emulator alive for the whole session.
    let mut builtin = None;
    let (path, label) = match port {
        Some(p) => {
            // Fail now, with the reason, rather than open a TUI on a port that cannot work
            // (busy, not a tty, no permission). A port that is not there yet is waited for, as
            // after an unplug: people start the station before plugging the robot in.
            match open_exclusive(p, baud) {
                Ok(port) => drop(port),
                Err(crate::link::transport::OpenError::NotFound { .. }) => {}
                Err(e) => return Err(e.into()),
            }
            (p.to_path_buf(), p.display().to_string())
        }
        None => {
            let simulated = arena_path.map(|p| p.to_string_lossy().into_owned());
            let mut emu =
                start_builtin_emulator_with(simulated.as_deref(), profile, key.as_ref(), start)?;
            let label = format!("built-in emulator on {}", emu.pty_path().display());
            if arena.is_none() {
                arena = emu.arena.clone();
                plan = PlanState::for_builtin();
            }
            let path = emu.path().to_path_buf();
            builtin = Some(emu);
            (path, label)
        }
    };
    // The tap feeds the record key (`R`); the recorder drops it while not recording.
    let (tap, taps) = tokio::sync::mpsc::unbounded_channel();
    let mut meta = crate::record::Meta::now(&label, baud);
    meta.arena = match (arena_path, &builtin) {
        (Some(p), _) => p.display().to_string(),
        (None, Some(_)) => emulator::builtin::MICRO_RATO_99.to_string(),
        (None, None) => String::new(),
    };
    let epoch = tokio::time::Instant::now();
    // Paced: the TUI shows the link at most 10 times a second, so reading it every 25 ms on
    // the TUI's own timer grid costs nobody anything and saves most wake-ups (README
    // "Performance").
    let link = spawn_link(
        SerialConnector::new(&path, baud).paced(true),
        LinkOptions {
            tap: Some(tap),
            paced: true,
            key: key.map(|k| protocol::LinkKey::new(&k)),
            ..LinkOptions::default()
        },
    );
    let recorder = crate::record::live::TuiRecorder::new(taps, epoch, meta);
    let mut app = App::new(AppOptions {
        port_label: label,
        arena,
    });
    app.map.plan = plan;
    // The squares are busy on a small map panel: `r` shows them.
    app.map.hidden.push(crate::ui::map_layers::REGIONS);
    crate::tui::run(app, link, recorder).await?;
    drop(builtin);
    Ok(ExitCode::SUCCESS)
}

fn ports(json: bool) -> anyhow::Result<ExitCode> {
    let serial = serialport::available_ports().unwrap_or_default();
    let mut ptys: Vec<String> = std::fs::read_dir("/dev/pts")
        .map(|d| {
            d.flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| n.chars().all(|c| c.is_ascii_digit()))
                .map(|n| format!("/dev/pts/{n}"))
                .collect()
        })
        .unwrap_or_default();
    ptys.sort_by_key(|p| p.rsplit('/').next().and_then(|n| n.parse::<u32>().ok()));
    let describe = |t: &serialport::SerialPortType| match t {
        serialport::SerialPortType::UsbPort(u) => format!(
            "USB {:04x}:{:04x} {} {}",
            u.vid,
            u.pid,
            u.manufacturer.as_deref().unwrap_or(""),
            u.product.as_deref().unwrap_or("")
        )
        .trim_end()
        .to_string(),
        serialport::SerialPortType::PciPort => "PCI".into(),
        serialport::SerialPortType::BluetoothPort => "Bluetooth".into(),
        serialport::SerialPortType::Unknown => "serial".into(),
    };
    if json {
        let v = json!({
            "serial": serial.iter().map(|p| json!({
                "path": p.port_name,
                "kind": describe(&p.port_type),
            })).collect::<Vec<_>>(),
            "pty": ptys,
        });
        println!("{}", crate::json_text::pretty(&v)?);
    } else {
        if serial.is_empty() {
            println!("no serial ports found");
        }
        for p in &serial {
            println!("{:<24} {}", p.port_name, describe(&p.port_type));
        }
        if !ptys.is_empty() {
            println!();
            println!("pseudo-terminals (an emulator's port is one of these; it prints which):");
            for p in &ptys {
                println!("  {p}");
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// Starts a link and waits for the handshake; fails fast on a port that cannot be opened or a
/// robot that refuses us.
pub(crate) async fn connect(
    port: &RequiredPort,
    timeout_s: f64,
) -> anyhow::Result<(RunningLink, PeerInfo)> {
    let mut link = spawn_link(
        SerialConnector::new(&port.port, port.baud),
        LinkOptions {
            station: format!("station-cli {}", env!("CARGO_PKG_VERSION")),
            key: crate::cli::load_key(port.key_file.as_deref()).map_err(anyhow::Error::msg)?,
            ..LinkOptions::default()
        },
    );
    let deadline = Instant::now() + Duration::from_secs_f64(timeout_s);
    loop {
        let ev = match tokio::time::timeout_at(deadline, link.events.recv()).await {
            Ok(Some(ev)) => ev,
            Ok(None) => bail!("the link task ended"),
            Err(_) => bail!(
                "no handshake with a robot on {} within {timeout_s} s (is the robot on this \
                 port, at this baud rate?)",
                port.port.display()
            ),
        };
        match ev {
            LinkEvent::Connection(Connection::Connected(p)) => return Ok((link, p)),
            LinkEvent::Connection(Connection::Closed { reason }) => bail!("{reason}"),
            LinkEvent::Connection(Connection::Refused { message }) => bail!("{message}"),
            _ => {}
        }
    }
}

/// Longest wait for the robot's periodic frames to pass before a command goes out, ms (on
/// top of one telemetry period).
const QUIET_WAIT_MARGIN_MS: u64 = 50;

/// Waits until the robot's next periodic burst (a telemetry frame, and the emulator's truth
/// frame that follows it) has been received, so that the line towards us is quiet and the
/// command's ack does not queue behind it in the robot's transmitter. Returns at once for a
/// robot that sends no telemetry, and after one telemetry period at most.
async fn after_periodic_burst(link: &mut RunningLink, peer: &PeerInfo) {
    if peer.telemetry_hz == 0 {
        return;
    }
    while link.events.try_recv().is_ok() {}
    let period = 1000 / u64::from(peer.telemetry_hz);
    let deadline = Instant::now() + Duration::from_millis(period + QUIET_WAIT_MARGIN_MS);
    let truth_follows = peer.has(protocol::caps::EMULATED);
    let mut seen_telemetry = false;
    while let Ok(Some(ev)) = tokio::time::timeout_at(deadline, link.events.recv()).await {
        match ev {
            LinkEvent::Telemetry(_) if !truth_follows => return,
            LinkEvent::Telemetry(_) => seen_telemetry = true,
            LinkEvent::Truth(_) if seen_telemetry => return,
            _ => {}
        }
    }
}

/// The robot's arena bounds (parameters `arena_min_x_m`, `arena_max_x_m`, `arena_min_y_m`,
/// `arena_max_y_m`), or `None` if it does not answer all four.
async fn arena_bounds(link: &crate::link::LinkHandle) -> Option<[f32; 4]> {
    use robot_firmware::params::id;
    let mut out = [0.0f32; 4];
    let ids = [
        id::ARENA_MIN_X_M,
        id::ARENA_MAX_X_M,
        id::ARENA_MIN_Y_M,
        id::ARENA_MAX_Y_M,
    ];
    for (slot, i) in out.iter_mut().zip(ids) {
        let get = protocol::Command::GetParam {
            id: protocol::ParamId(i),
        };
        match link.call(get).await {
            CommandOutcome::Acked {
                info: AckInfo::Param { value, .. },
                ..
            } => *slot = value,
            _ => return None,
        }
    }
    Some(out)
}

/// Round trips of a repeated `send`, microseconds (nearest rank).
#[derive(Debug, serde::Serialize)]
struct RoundTrips {
    samples: usize,
    p50_us: u64,
    p99_us: u64,
    max_us: u64,
}

impl RoundTrips {
    fn of(mut us: Vec<u64>) -> Option<RoundTrips> {
        us.sort_unstable();
        let pick = |q: f64| {
            let i = ((us.len() as f64 * q).ceil() as usize).clamp(1, us.len());
            us.get(i - 1).copied().unwrap_or(0)
        };
        Some(RoundTrips {
            samples: us.len(),
            p50_us: pick(0.5),
            p99_us: pick(0.99),
            max_us: *us.last()?,
        })
    }
}

async fn send(
    port: &RequiredPort,
    json: bool,
    timeout: f64,
    repeat: u32,
    cmd: &SendCmd,
) -> anyhow::Result<ExitCode> {
    let (mut link, peer) = connect(port, timeout).await?;
    let command = cmd.to_command()?;
    // The robot starts its telemetry as the session starts: a command sent at once was
    // answered behind the first telemetry and truth frames (p50 9 ms for 2.1 ms of bytes).
    let mut round_trips = Vec::new();
    let mut outcome = CommandOutcome::Failed(crate::link::CommandFailure::NotConnected);
    for _ in 0..repeat {
        after_periodic_burst(&mut link, &peer).await;
        let sent = Instant::now();
        outcome = link.handle.call(command).await;
        if !outcome.is_ack() {
            break;
        }
        round_trips.push(sent.elapsed().as_micros() as u64);
    }
    let round_trips = if repeat > 1 {
        RoundTrips::of(round_trips)
    } else {
        None
    };
    // A plan made on the robot is named by its PlanInstalled event: `execute` needs the id.
    let plan_id = match (command, outcome.is_ack()) {
        (protocol::Command::Plan { .. }, true) => {
            crate::commands::transfer::plan_id_after(&mut link.events).await
        }
        _ => None,
    };
    // A go-to refused as outside the arena: name the robot's bounds, read from it.
    let bounds = match (command, &outcome) {
        (
            protocol::Command::GoTo(_),
            CommandOutcome::Nacked {
                reason: protocol::NackReason::BadPoint,
                ..
            },
        ) => arena_bounds(&link.handle).await,
        _ => None,
    };
    link.handle.shutdown();
    let _ = tokio::time::timeout(Duration::from_secs(1), link.task).await;
    let what = command_text(&command);
    let (ok, text, value) = match outcome {
        CommandOutcome::Acked {
            info,
            sends,
            rtt_ms,
        } => {
            let (text, detail) = match info {
                AckInfo::Param { id, value } => (
                    format!(
                        "ack: {} = {}",
                        param_name(id.0),
                        format_param_id(id.0, value)
                    ),
                    json!({"param": param_name(id.0), "id": id.0, "value": value}),
                ),
                AckInfo::Object {
                    object,
                    id,
                    len,
                    crc,
                } => (
                    format!("ack: {what}: object {object:?} id {id:#010x}, {len} bytes"),
                    json!({"object": format!("{object:?}"), "id": id, "len": len, "crc": crc}),
                ),
                AckInfo::Done => match plan_id {
                    Some(id) => (
                        format!("ack: {what}: plan id {id:#010x}"),
                        json!({"plan_id": id, "plan_id_hex": format!("{id:#010x}")}),
                    ),
                    None => (format!("ack: {what}"), json!(null)),
                },
            };
            let v = json!({"outcome": "ack", "command": what, "sends": sends, "rtt_ms": rtt_ms,
                           "info": detail});
            // The robot that answered, as its HelloReply states: on a fleet's lines, that is
            // what says a cable goes where the operator thinks.
            (
                true,
                format!("{text} ({rtt_ms} ms, robot {})", peer.robot_id),
                v,
            )
        }
        CommandOutcome::Nacked { reason, sends } => {
            let mut why = refusal_text(&command, reason);
            if let Some([x0, x1, y0, y1]) = bounds {
                why.push_str(&format!(
                    " (the robot's arena: x {x0:.2} .. {x1:.2} m, y {y0:.2} .. {y1:.2} m)"
                ));
            }
            let mut v = json!({"outcome": "nack", "command": what, "sends": sends,
                   "reason": format!("{reason:?}"), "reason_text": why});
            if let (Some(b), Some(obj)) = (bounds, v.as_object_mut()) {
                obj.insert(
                    "arena".into(),
                    json!({"min_x_m": b[0], "max_x_m": b[1], "min_y_m": b[2], "max_y_m": b[3]}),
                );
            }
            (false, format!("nack: {what}: {why}"), v)
        }
        CommandOutcome::Failed(why) => (
            false,
            format!("failed: {what}: {why}"),
            json!({"outcome": "failed", "command": what, "error": why.to_string()}),
        ),
    };
    let mut value = value;
    if let Some(obj) = value.as_object_mut() {
        obj.insert("robot_id".into(), json!(peer.robot_id));
        if let Some(r) = &round_trips {
            obj.insert("round_trip".into(), serde_json::to_value(r)?);
        }
    }
    if json {
        println!("{}", crate::json_text::pretty(&value)?);
    } else if ok {
        println!("{}", crate::terminal_text::printable_text(&text));
    } else {
        eprintln!("{}", crate::terminal_text::printable_text(&text));
    }
    if let (Some(r), false) = (&round_trips, json) {
        println!(
            "round trip over {} sends: p50 {:.2} ms, p99 {:.2} ms, max {:.2} ms",
            r.samples,
            r.p50_us as f64 / 1000.0,
            r.p99_us as f64 / 1000.0,
            r.max_us as f64 / 1000.0
        );
    }
    Ok(if ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

/// The round-trip probe of `station stats`: reading a parameter, which changes nothing.
const PROBE: protocol::Command = protocol::Command::GetParam {
    id: protocol::ParamId(0),
};
/// Time between two probes, ms: a few a second, a small share of the link.
const PROBE_PERIOD_MS: u64 = 250;

/// What `station stats` measured on one port.
struct Watched {
    port: String,
    peer: PeerInfo,
    stats: LinkStats,
    round_trip: Option<RoundTrips>,
    probe_failures: Vec<String>,
}

impl Watched {
    fn json(&self) -> serde_json::Value {
        json!({"port": self.port, "peer": self.peer, "stats": self.stats,
               "round_trip": self.round_trip, "probe": command_text(&PROBE),
               "probe_failures": self.probe_failures})
    }
}

/// `station stats`: one port as before; several watched at once, each reported on its own
/// (a port that fails does not stop the others), with robots that state the same id named.
async fn stats(
    ports: &crate::cli::StatsPorts,
    seconds: f64,
    json: bool,
    timeout: f64,
) -> anyhow::Result<ExitCode> {
    let each = ports.each();
    if let [one] = each.as_slice() {
        let w = watch(one, seconds, timeout).await?;
        if json {
            println!("{}", crate::json_text::pretty(&w.json())?);
        } else {
            print_watched(&w);
        }
        return Ok(ExitCode::SUCCESS);
    }
    crate::cli::distinct_ports(each.iter().map(|p| p.port.as_path()))
        .map_err(anyhow::Error::msg)?;
    let tasks: Vec<_> = each
        .into_iter()
        .map(|p| tokio::spawn(async move { (p.port.clone(), watch(&p, seconds, timeout).await) }))
        .collect();
    let mut results = Vec::new();
    for t in tasks {
        results.push(t.await.context("a port's watch ended abnormally")?);
    }
    let ids: Vec<(String, Option<u8>)> = results
        .iter()
        .map(|(p, r)| {
            (
                p.display().to_string(),
                r.as_ref().ok().map(|w| w.peer.robot_id),
            )
        })
        .collect();
    let dups = duplicates(ids.iter().map(|(p, id)| (p.as_str(), *id)));
    let failed = results.iter().any(|(_, r)| r.is_err());
    if json {
        let links: Vec<serde_json::Value> = results
            .iter()
            .map(|(p, r)| match r {
                Ok(w) => w.json(),
                Err(e) => json!({"port": p.display().to_string(), "error": format!("{e:#}")}),
            })
            .collect();
        let v = json!({"links": links, "duplicate_robot_ids": dups});
        println!("{}", crate::json_text::pretty(&v)?);
    } else {
        for (i, (p, r)) in results.iter().enumerate() {
            if i > 0 {
                println!();
            }
            match r {
                Ok(w) => print_watched(w),
                Err(e) => {
                    println!("port        {}", p.display());
                    println!(
                        "error       {}",
                        crate::terminal_text::printable_text(&format!("{e:#}"))
                    );
                }
            }
        }
    }
    for d in &dups {
        eprintln!(
            "station: warning: {}",
            crate::terminal_text::printable_text(&d.warning())
        );
    }
    for (p, r) in &results {
        if let Err(e) = r {
            eprintln!("station: {}: {e:#}", p.display());
        }
    }
    Ok(if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

/// Watches one port for `seconds`, probing the round trip.
async fn watch(port: &RequiredPort, seconds: f64, timeout: f64) -> anyhow::Result<Watched> {
    let (mut link, peer) = connect(port, timeout).await?;
    let deadline = Instant::now() + Duration::from_secs_f64(seconds);
    let mut last: Option<LinkStats> = None;
    // The round trip is measured, not waited for: a harmless probe (reading a parameter
    // changes nothing on the robot) goes out every PROBE_PERIOD_MS while the link is watched,
    // at whatever moment of the robot's telemetry cycle it falls (unlike `send --repeat`,
    // which picks the quiet moment), so it is the round trip a command meets.
    let mut probes: Vec<u64> = Vec::new();
    let mut probe_failures: Vec<String> = Vec::new();
    let mut next_probe = Instant::now();
    loop {
        let wake = next_probe.min(deadline);
        match tokio::time::timeout_at(wake, link.events.recv()).await {
            Ok(Some(LinkEvent::Stats(s))) => last = Some(*s),
            Ok(Some(_)) => {}
            Ok(None) => break,
            Err(_) if Instant::now() >= deadline => break,
            Err(_) => {
                next_probe += Duration::from_millis(PROBE_PERIOD_MS);
                let sent = Instant::now();
                match link.handle.call(PROBE).await {
                    CommandOutcome::Acked { .. } => probes.push(sent.elapsed().as_micros() as u64),
                    other => probe_failures.push(match other {
                        CommandOutcome::Nacked { reason, .. } => refusal_text(&PROBE, reason),
                        CommandOutcome::Failed(why) => why.to_string(),
                        CommandOutcome::Acked { .. } => String::new(),
                    }),
                }
            }
        }
    }
    let round_trip = RoundTrips::of(probes);
    link.handle.shutdown();
    let _ = tokio::time::timeout(Duration::from_secs(1), link.task).await;
    let Some(stats) = last else {
        bail!("no statistics were published in {seconds} s");
    };
    Ok(Watched {
        port: port.port.display().to_string(),
        peer,
        stats,
        round_trip,
        probe_failures,
    })
}

fn print_watched(w: &Watched) {
    let (peer, s, round_trip) = (&w.peer, &w.stats, &w.round_trip);
    let probe = command_text(&PROBE);
    println!("port        {}", w.port);
    println!(
        "robot       {} {} {:?}, robot id {}",
        crate::terminal_text::printable(&peer.firmware),
        crate::terminal_text::printable(&peer.firmware_version),
        peer.profile,
        peer.robot_id
    );
    println!(
        "state       {} for {:.1} s",
        s.state,
        s.session_ms as f64 / 1000.0
    );
    println!(
        "frames      in {} out {}  bytes in {} ({:.0}/s) out {} ({:.0}/s)",
        s.frames_in, s.frames_out, s.bytes_in, s.bytes_in_per_s, s.bytes_out, s.bytes_out_per_s
    );
    println!(
        "telemetry   {:.1} Hz ({} frames)",
        s.telemetry_hz, s.telemetry_frames
    );
    println!(
        "loss        robot {} ({:.2}%)  truth {}  duplicates {}",
        s.robot_seq.lost, s.robot_seq.loss_percent, s.truth_seq.lost, s.robot_seq.duplicates
    );
    println!(
        "errors      CRC {}  bad frames {}  dropped bytes {}",
        s.decoder.crc_errors,
        s.decoder.errors(),
        s.decoder.bytes_dropped
    );
    if s.auth.keyed || s.auth.refused() > 0 {
        let a = &s.auth;
        println!(
            "auth        {}; verified {}  bad signature {}  stale {}  unsigned {}  \
             unexpected signature {}",
            if a.keyed { "signed" } else { "no key" },
            a.verified,
            a.bad_signature,
            a.stale_timestamp,
            a.unsigned,
            a.unexpected_signature
        );
    }
    println!(
        "commands    {} ok, {} refused, {} failed, {} superseded",
        s.commands.acked, s.commands.nacked, s.commands.failed, s.commands.superseded
    );
    match round_trip {
        Some(r) => println!(
            "round trip  p50 {:.2} ms, p99 {:.2} ms, max {:.2} ms over {} probes ({probe}, \
             every {PROBE_PERIOD_MS} ms)",
            r.p50_us as f64 / 1000.0,
            r.p99_us as f64 / 1000.0,
            r.max_us as f64 / 1000.0,
            r.samples
        ),
        None => println!("round trip  no answer to any probe ({probe})"),
    }
    if let Some(why) = w.probe_failures.first() {
        println!(
            "probes      {} unanswered or refused: {}",
            w.probe_failures.len(),
            crate::terminal_text::printable_text(why)
        );
    }
}
