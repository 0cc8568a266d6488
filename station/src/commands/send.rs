//! `station send`: one command to the robot, its Ack or Nack printed (exit 1 when refused or
//! unanswered), or repeated to measure round trips.

use std::process::ExitCode;
use std::time::Duration;

use clap::{Subcommand, ValueEnum};
use protocol::units::{point_mm, OutOfRange};
use protocol::{AckInfo, Command, Mode, ParamId};
use serde_json::json;
use tokio::time::Instant;

use super::args::{parse_metres, parse_param, parse_plan_id, parse_value, RequiredPort};
use super::connect::connect;
use crate::app::params::format_param_id;
use crate::link::api::{command_text, param_name, refusal_text};
use crate::link::{CommandOutcome, LinkEvent, PeerInfo, RunningLink};
use crate::task_end::{Ended, Ending};

/// The commands `send` knows.
#[derive(Debug, Subcommand, Clone, PartialEq)]
pub enum SendCmd {
    /// Switch mode.
    Mode { mode: ModeArg },
    /// Manual velocity: forward mm/s, turn mrad/s (counter-clockwise positive).
    #[command(allow_negative_numbers = true)]
    Teleop {
        /// Forward speed, mm/s, -2000 to 2000 (the robot clamps it to its teleop_max_mm_s).
        #[arg(value_parser = clap::value_parser!(i16).range(-2000..=2000))]
        v_mm_s: i16,
        /// Turn rate, mrad/s, -20000 to 20000, positive turning left (counter-clockwise).
        #[arg(value_parser = clap::value_parser!(i16).range(-20000..=20000))]
        w_mrad_s: i16,
    },
    /// Drive to a point, metres in the map frame.
    #[command(allow_negative_numbers = true,
              after_help = crate::commands::wait::help_table())]
    Goto {
        /// X, metres in the map frame (x right).
        #[arg(value_parser = parse_metres)]
        x: f64,
        /// Y, metres in the map frame (y up).
        #[arg(value_parser = parse_metres)]
        y: f64,
    },
    /// Read or write a parameter by name or id (the firmware's table; a wrong name lists them).
    Param {
        #[command(subcommand)]
        op: ParamOp,
    },
    /// Stop the motors and go idle.
    Stop,
    /// Telemetry rate in Hz (0 = off, at most 50).
    Rate {
        /// Telemetry frames a second, 0 to 50.
        #[arg(value_parser = clap::value_parser!(u8).range(0..=50))]
        hz: u8,
    },
    /// Start exploring: the robot searches for the goal and maps the arena as it goes
    ///
    /// Mode Explore (the Dom Dinis search); needs a compass and a beacon sensor (micro-rato). Follow
    /// the map it builds with `station download-map --ascii`.
    #[command(after_help = crate::commands::wait::help_table())]
    Explore,
    /// Segment the robot's map into free squares (Dom Dinis segmentation).
    Segment,
    /// Plan on the robot; prints the new plan's id, which `execute` takes
    ///
    /// From where the robot believes it is to its map's goal, unless --from / --to say
    /// otherwise. The robot segments its map first if needed.
    Plan {
        /// Start, metres in the map frame [default: where the robot believes it is].
        #[arg(long, value_name = "X,Y", value_parser = crate::commands::plan::parse_point,
              allow_hyphen_values = true)]
        from: Option<(f64, f64)>,
        /// Goal, metres [default: the goal of the robot's map].
        #[arg(long, value_name = "X,Y", value_parser = crate::commands::plan::parse_point,
              allow_hyphen_values = true)]
        to: Option<(f64, f64)>,
    },
    /// Execute the robot's installed plan, named by its id
    ///
    /// ID is 0x-hex or decimal, as `send plan` and `upload-plan` print it; another id is
    /// refused (plan id mismatch), so the robot never drives a plan you did not mean.
    #[command(after_help = crate::commands::wait::help_table())]
    Execute {
        #[arg(value_name = "ID", value_parser = parse_plan_id)]
        plan_id: u32,
    },
}

#[derive(Debug, Subcommand, Clone, PartialEq)]
pub enum ParamOp {
    /// Set a parameter; the robot answers with the value in force or refuses with a reason.
    #[command(allow_negative_numbers = true)]
    Set {
        #[arg(value_parser = parse_param)]
        name: u16,
        #[arg(value_parser = parse_value)]
        value: f32,
    },
    /// Read a parameter.
    Get {
        #[arg(value_parser = parse_param)]
        name: u16,
    },
}

/// Mode names on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ModeArg {
    Idle,
    Manual,
    Goto,
    Wander,
    EdgeLeft,
    EdgeRight,
    SeekLight,
    Explore,
    ExecutePlan,
    Forage,
    /// Floor-grid line correction: wander over the floor grid correcting odometry at every line.
    Survey,
    /// Khepera light calibration: turn next to a light and train the light -> angle map.
    CalibrateLight,
}

impl From<ModeArg> for Mode {
    fn from(m: ModeArg) -> Mode {
        match m {
            ModeArg::Idle => Mode::Idle,
            ModeArg::Manual => Mode::Manual,
            ModeArg::Goto => Mode::GoTo,
            ModeArg::Wander => Mode::Wander,
            ModeArg::EdgeLeft => Mode::EdgeFollowLeft,
            ModeArg::EdgeRight => Mode::EdgeFollowRight,
            ModeArg::SeekLight => Mode::SeekLight,
            ModeArg::Explore => Mode::Explore,
            ModeArg::ExecutePlan => Mode::ExecutePlan,
            ModeArg::Forage => Mode::Forage,
            ModeArg::Survey => Mode::Survey,
            ModeArg::CalibrateLight => Mode::CalibrateLight,
        }
    }
}

impl SendCmd {
    /// The mode of the task this command starts, which `--wait` follows to its end; `None`
    /// for a command that starts no task.
    pub fn task_mode(&self) -> Option<Mode> {
        match self {
            SendCmd::Goto { .. } => Some(Mode::GoTo),
            SendCmd::Execute { .. } => Some(Mode::ExecutePlan),
            SendCmd::Explore => Some(Mode::Explore),
            _ => None,
        }
    }

    /// The wire command; a point beyond the wire's millimetres is refused by name.
    pub fn to_command(&self) -> Result<Command, OutOfRange> {
        Ok(match *self {
            SendCmd::Mode { mode } => Command::SetMode(mode.into()),
            SendCmd::Teleop { v_mm_s, w_mrad_s } => Command::Teleop { v_mm_s, w_mrad_s },
            SendCmd::Goto { x, y } => Command::GoTo(point_mm(["goto X", "goto Y"], (x, y))?),
            SendCmd::Param {
                op: ParamOp::Set { name, value },
            } => Command::SetParam {
                id: ParamId(name),
                value,
            },
            SendCmd::Param {
                op: ParamOp::Get { name },
            } => Command::GetParam { id: ParamId(name) },
            SendCmd::Stop => Command::Stop,
            SendCmd::Rate { hz } => Command::SetTelemetryRate { hz },
            SendCmd::Explore => Command::StartExploration,
            SendCmd::Segment => Command::Segment,
            SendCmd::Plan { from, to } => Command::Plan {
                from: from
                    .map(|p| point_mm(["--from X", "--from Y"], p))
                    .transpose()?,
                to: to.map(|p| point_mm(["--to X", "--to Y"], p)).transpose()?,
            },
            SendCmd::Execute { plan_id } => Command::ExecutePlan { plan_id },
        })
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
pub struct RoundTrips {
    pub samples: usize,
    pub p50_us: u64,
    pub p99_us: u64,
    pub max_us: u64,
}

impl RoundTrips {
    pub fn of(mut us: Vec<u64>) -> Option<RoundTrips> {
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

/// Seconds `send` waits for the handshake when --timeout does not say.
pub const HANDSHAKE_S: f64 = 5.0;

/// Submits `command` and waits for its answer in the link's event stream, so that what the
/// stream holds after it (events, telemetry) is known to come after the answer. Also gives the
/// last telemetry frame before the answer: where the robot was when it took the command.
async fn call_in_order(
    link: &mut RunningLink,
    command: Command,
) -> (CommandOutcome, Option<protocol::Telemetry>) {
    let id = link.handle.submit(command);
    let mut last = None;
    while let Some(ev) = link.events.recv().await {
        match ev {
            LinkEvent::CommandDone {
                id: done, outcome, ..
            } if done == id => return (outcome, last),
            LinkEvent::Telemetry(t) => last = Some(t),
            _ => {}
        }
    }
    (
        CommandOutcome::Failed(crate::link::CommandFailure::Shutdown),
        last,
    )
}

/// What `station send` was asked to do.
pub struct SendArgs<'a> {
    pub port: &'a RequiredPort,
    pub json: bool,
    /// --timeout: the handshake's limit; with `wait`, the whole command's.
    pub timeout: Option<f64>,
    pub repeat: u32,
    /// --wait: follow the task the command starts to its end.
    pub wait: bool,
    pub cmd: &'a SendCmd,
}

pub async fn send(args: SendArgs<'_>) -> anyhow::Result<ExitCode> {
    let SendArgs {
        port,
        json,
        timeout,
        repeat,
        wait,
        cmd,
    } = args;
    let started = Instant::now();
    let task = match (wait, cmd.task_mode()) {
        (false, _) => None,
        (true, None) => {
            return Ok(super::wait::usage(
                "--wait goes with goto, execute or explore (the commands that start a task)",
            ))
        }
        (true, Some(_)) if repeat > 1 => {
            return Ok(super::wait::usage("--wait and --repeat do not go together"))
        }
        (true, Some(mode)) => Some(mode),
    };
    let command = cmd.to_command()?;
    let (mut link, peer) = connect(port, timeout.unwrap_or(HANDSHAKE_S)).await?;
    // The robot starts its telemetry as the session starts: a command sent at once was
    // answered behind the first telemetry and truth frames (p50 9 ms for 2.1 ms of bytes).
    let mut round_trips = Vec::new();
    let mut at_command = None;
    let mut outcome = CommandOutcome::Failed(crate::link::CommandFailure::NotConnected);
    for _ in 0..repeat {
        after_periodic_burst(&mut link, &peer).await;
        let sent = Instant::now();
        outcome = match task {
            Some(_) => {
                let (outcome, before) = call_in_order(&mut link, command).await;
                at_command = before;
                outcome
            }
            None => link.handle.call(command).await,
        };
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
    let what = command_text(&command);
    // The refusal in words, for --wait's reason too.
    let mut refusal: Option<String> = None;
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
            let why = refusal.insert(refusal_text(&command, reason));
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
    if !json {
        if ok {
            println!("{}", crate::terminal_text::printable_text(&text));
        } else {
            eprintln!("{}", crate::terminal_text::printable_text(&text));
        }
    }
    // --wait: the task's end, once the robot took the command.
    let waited = match (task, &outcome) {
        (Some(mode), CommandOutcome::Acked { .. }) => {
            let deadline = timeout.map(|s| started + Duration::from_secs_f64(s));
            Some(super::wait::until_end(&mut link, mode, at_command, deadline, started).await)
        }
        (Some(_), CommandOutcome::Nacked { .. }) => Some(super::wait::Waited {
            ended: Ended::new(Ending::Refused, refusal.unwrap_or_default()),
            seconds: started.elapsed().as_secs_f64(),
            telemetry: None,
        }),
        (Some(_), CommandOutcome::Failed(crate::link::CommandFailure::LinkLost)) => {
            Some(super::wait::Waited {
                ended: Ended::new(Ending::LinkLost, "link lost before the robot answered"),
                seconds: started.elapsed().as_secs_f64(),
                telemetry: None,
            })
        }
        _ => None,
    };
    link.handle.shutdown();
    let _ = tokio::time::timeout(Duration::from_secs(1), link.task).await;
    if let (Some(w), Some(obj)) = (&waited, value.as_object_mut()) {
        obj.insert("wait".into(), w.json());
    }
    if json {
        println!("{}", crate::json_text::pretty(&value)?);
    }
    if let Some(w) = &waited {
        eprintln!("{}", crate::terminal_text::printable_text(&w.line()));
        return Ok(w.exit_code());
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
