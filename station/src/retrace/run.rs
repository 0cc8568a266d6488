//! Running the firmware's own `Robot` (the profile's composition, `AnyRobot`) over a recorded
//! hardware trace, through `robot_firmware::hal_trace::playback::Playback`.
//!
//! Layer: pure computation over a loaded recording. The robot is built as the recorded one
//! was (the trace's `START`: profile, seed, start pose, the beacon and arena it was told,
//! tracing on from power-up), given the `--param` values, then stepped once per recorded pass
//! of its main loop. What it does is kept: its serial bytes (framed later), its motor and
//! gripper commands (compared with the recorded ones pass by pass), its pose every control
//! cycle. What can fail: a malformed trace (with the file's byte offset), a refused parameter.

use protocol::{Command, ParamId};
use robot_firmware::hal_trace::playback::{Next, Playback};
use robot_firmware::odometry::Pose;
use robot_firmware::{AnyRobot, RobotOptions, KHEPERA, MICRO_RATO};

use super::load::Loaded;

/// Why a retrace stopped.
#[derive(Clone, Debug, PartialEq)]
pub enum Stop {
    /// The trace ended (the recording did).
    End,
    /// The robot could not send some passes (its trace buffer was full): none past here.
    Gap { steps: u32, file_offset: u64 },
    /// Tracing was switched off and on again: a new stream, not retraced.
    Restart { file_offset: u64 },
    /// `--until-ms` reached.
    Until,
}

/// A pass where the retraced firmware commanded otherwise than the recorded one.
#[derive(Clone, Debug, PartialEq)]
pub struct CommandDivergence {
    pub step: u64,
    pub cycle: u64,
    pub time_ms: u32,
    pub field: &'static str,
    pub recorded: String,
    pub retraced: String,
}

/// One frame the retraced robot sent, and when.
#[derive(Clone, Debug)]
pub struct OutFrame {
    pub raw: Vec<u8>,
    pub step: u64,
    pub cycle: u64,
    pub time_ms: u32,
}

/// What one retrace gave.
#[derive(Clone, Debug)]
pub struct Run {
    pub steps: u64,
    pub cycles: u64,
    pub stop: Stop,
    /// Passes before tracing began (0: the trace covers the robot from power-up).
    pub steps_before: u32,
    pub frames: Vec<OutFrame>,
    pub command_divergence: Option<CommandDivergence>,
    /// The believed pose after every control cycle: (robot time ms, pose).
    pub poses: Vec<(u32, Pose)>,
    /// Values the retraced firmware asked for that the recording did not have.
    pub misses: u64,
    pub first_miss: Option<(u64, &'static str)>,
    pub last_ms: u32,
}

/// Retraces `loaded` with `params` (id, value) set before the first pass.
pub fn retrace(
    loaded: &Loaded,
    params: &[(u16, f32)],
    until_ms: Option<u32>,
) -> Result<Run, String> {
    let at_file = |at: usize| loaded.file_offset_of(at);
    let mut play = Playback::new(&loaded.trace)
        .map_err(|e| format!("byte {}: hardware trace: {e}", at_file(offset_of(&e))))?;
    let start = play.start;
    let profile = match start.profile {
        0 => &KHEPERA,
        1 => &MICRO_RATO,
        2 => &robot_firmware::ALICE,
        p => {
            return Err(format!(
            "byte {}: hardware trace: START names profile {p}, which this station does not know",
            at_file(0)
        ))
        }
    };
    // The HelloReply names the firmware's version; the retraced robot answers with the same.
    let version: &'static str = match &loaded.firmware_version {
        Some(v) => Box::leak(v.clone().into_boxed_str()),
        None => env!("CARGO_PKG_VERSION"),
    };
    let mut robot = AnyRobot::new(RobotOptions {
        profile,
        seed: start.seed,
        start: start.start,
        emulated: start.emulated,
        firmware_version: version,
    });
    // What its host told the recorded robot before its first pass (START carries it).
    let dead = robot.dead_mut();
    dead.params.beacon = start.beacon;
    dead.set_bounds(robot_firmware::deadreckon::Bounds {
        min: start.bounds_min,
        max: start.bounds_max,
        ..dead.params.bounds
    });
    let mut all = vec![(robot_firmware::params::id::HAL_TRACE, 1.0)];
    all.extend_from_slice(params);
    for &(id, value) in &all {
        let reply = robot.apply(
            Command::SetParam {
                id: ParamId(id),
                value,
            },
            0,
        );
        if let robot_firmware::link::Reply::Nack(r) = reply {
            let name = robot_firmware::params::info(id).map_or("?", |i| i.name);
            return Err(format!(
                "--param {name}={value}: the robot refuses it ({r:?})"
            ));
        }
    }

    let mut run = Run {
        steps: 0,
        cycles: 0,
        stop: Stop::End,
        steps_before: start.steps_before,
        frames: Vec::new(),
        command_divergence: None,
        poses: Vec::new(),
        misses: 0,
        first_miss: None,
        last_ms: 0,
    };
    let mut partial: Vec<u8> = Vec::new();
    loop {
        let next = play
            .next_step()
            .map_err(|e| format!("byte {}: hardware trace: {e}", at_file(offset_of(&e))))?;
        match next {
            Next::Step => {}
            Next::End => break,
            Next::Gap { steps, offset } => {
                run.stop = Stop::Gap {
                    steps,
                    file_offset: at_file(offset),
                };
                break;
            }
            Next::Restart { offset } => {
                run.stop = Stop::Restart {
                    file_offset: at_file(offset),
                };
                break;
            }
        }
        let time_ms = (play.recorded().clock_us / 1000) as u32;
        if until_ms.is_some_and(|u| time_ms > u) {
            run.stop = Stop::Until;
            break;
        }
        robot.step(&mut play);
        run.steps = play.steps;
        run.cycles = play.cycles;
        run.last_ms = time_ms;
        for &b in play.written() {
            if b != 0 {
                partial.push(b);
            } else if !partial.is_empty() {
                run.frames.push(OutFrame {
                    raw: std::mem::take(&mut partial),
                    step: play.steps,
                    cycle: play.cycles,
                    time_ms,
                });
            }
        }
        let rec = play.recorded();
        if run.command_divergence.is_none() {
            let mine = &play.motors_out[..play.n_motors_out];
            let theirs = &rec.motors[..rec.n_motors];
            let grips = (
                &play.grips_out[..play.n_grips_out],
                &rec.grips[..rec.n_grips],
            );
            let diverged = if mine != theirs {
                Some(("motor command", format!("{theirs:?}"), format!("{mine:?}")))
            } else if grips.0 != grips.1 {
                Some((
                    "gripper command",
                    format!("{:?}", grips.1),
                    format!("{:?}", grips.0),
                ))
            } else {
                None
            };
            if let Some((field, recorded, retraced)) = diverged {
                run.command_divergence = Some(CommandDivergence {
                    step: play.steps,
                    cycle: play.cycles,
                    time_ms,
                    field,
                    recorded,
                    retraced,
                });
            }
        }
        if rec.cycle {
            run.poses.push((time_ms, robot.pose()));
        }
    }
    run.misses = play.misses;
    run.first_miss = play.first_miss;
    Ok(run)
}

fn offset_of(e: &robot_firmware::hal_trace::playback::TraceError) -> usize {
    use robot_firmware::hal_trace::playback::TraceError as E;
    match *e {
        E::Truncated { offset }
        | E::UnknownTag { offset, .. }
        | E::BadValue { offset, .. }
        | E::NoStart { offset }
        | E::TooMany { offset, .. } => offset,
    }
}
