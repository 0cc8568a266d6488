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
use robot_firmware::{AnyRobot, RobotOptions};

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
    let profile = play.profile();
    // The HelloReply names the firmware's version; the retraced robot answers with the same.
    let version = loaded
        .firmware_version
        .as_deref()
        .map_or(env!("CARGO_PKG_VERSION"), interned);
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
    let robot_time_limit = loaded
        .span_us
        .saturating_mul(MAX_SPEEDUP)
        .saturating_add(GRACE_US);
    let mut first_clock = None;
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
        let clock_us = play.recorded().clock_us;
        // The firmware's own milliseconds (they wrap after 49 days, as the robot's do).
        let time_ms = (clock_us / 1000) as u32;
        // Compared in µs, unwrapped: a clock past 2^32 ms must not wrap below the limit.
        if until_ms.is_some_and(|u| clock_us > u64::from(u) * 1000) {
            run.stop = Stop::Until;
            break;
        }
        let first = *first_clock.get_or_insert(clock_us);
        if clock_us.saturating_sub(first) > robot_time_limit {
            return Err(format!(
                "byte {}: hardware trace: trace byte {}: STEP time makes {:.3} s of robot time \
                 since the trace's first pass; the recording spans {:.3} s, and a robot's clock \
                 runs at most {MAX_SPEEDUP} times as fast as the station's (plus {} s): at most \
                 {:.3} s",
                at_file(play.pass_offset()),
                play.pass_offset(),
                clock_us.saturating_sub(first) as f64 / 1e6,
                loaded.span_us as f64 / 1e6,
                GRACE_US / 1_000_000,
                robot_time_limit as f64 / 1e6,
            ));
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

/// `v` as the `&'static str` the firmware's identity holds: each distinct version is leaked
/// once a process and kept here, not once a retrace (the retrace fuzz target's leak checker
/// found one a run; a replay retraces as often as it is asked to).
fn interned(v: &str) -> &'static str {
    static SEEN: std::sync::Mutex<Vec<&'static str>> = std::sync::Mutex::new(Vec::new());
    let Ok(mut seen) = SEEN.lock() else {
        return env!("CARGO_PKG_VERSION");
    };
    if let Some(&s) = seen.iter().find(|&&s| s == v) {
        return s;
    }
    let s: &'static str = Box::leak(v.into());
    seen.push(s);
    s
}

/// How much faster than the station's clock a recorded robot's may run: `robot-emulator
/// --speed max` ran about 1,800 times real time here (and its trace then stops at a gap, the
/// link being too slow for it). A trace claiming more robot time than this allows over the
/// recording's span claims what no run made (issue 31: 4,295 s in a recording of 2 ms).
pub const MAX_SPEEDUP: u64 = 100_000;
/// Robot time a trace may claim beyond `MAX_SPEEDUP` times the recording's span: what a
/// robot's trace buffer held before the first recorded frame, generously.
pub const GRACE_US: u64 = 60_000_000;

fn offset_of(e: &robot_firmware::hal_trace::playback::TraceError) -> usize {
    use robot_firmware::hal_trace::playback::TraceError as E;
    match *e {
        E::Truncated { offset }
        | E::UnknownTag { offset, .. }
        | E::BadValue { offset, .. }
        | E::NoStart { offset }
        | E::TooMany { offset, .. }
        | E::Implausible { offset, .. } => offset,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use robot_firmware::hal_trace::tag;

    fn varint(out: &mut Vec<u8>, mut v: u64) {
        while v >= 0x80 {
            out.push(v as u8 | 0x80);
            v >>= 7;
        }
        out.push(v as u8);
    }

    /// A trace's START (format 1, Khepera, traced from power-up) and a first control cycle (a
    /// STEP with its IR reading) `first_us` into the robot's clock.
    fn started(first_us: u64) -> Vec<u8> {
        let mut t = vec![tag::START, 1, 0];
        t.extend_from_slice(&42u32.to_le_bytes());
        for v in [0.5f32, 0.5, 0.0] {
            t.extend_from_slice(&v.to_le_bytes());
        }
        varint(&mut t, 0);
        t.push(1);
        for v in [2.5f32, 2.5, 0.0, 0.0, 5.0, 5.0] {
            t.extend_from_slice(&v.to_le_bytes());
        }
        t.push(tag::STEP);
        varint(&mut t, first_us);
        t.push(tag::IR);
        t.extend_from_slice(&[0; 8]);
        t
    }

    fn loaded(trace: Vec<u8>, span_us: u64) -> Loaded {
        Loaded {
            trace,
            trace_map: vec![(0, 100)],
            span_us,
            ..Loaded::default()
        }
    }

    /// Issue 31 item 2: one 8-byte IDLE entry claimed 2^32 - 1 passes 0 µs apart, 95 s of
    /// CPU, and `--until-ms` could not stop it (the clock never moved). It is refused before
    /// a pass is played, naming the trace byte, the field and the limit.
    #[test]
    fn an_idle_entry_claiming_more_passes_than_a_control_period_holds_is_refused() {
        let mut t = started(0);
        let idle_at = t.len();
        t.push(tag::IDLE);
        varint(&mut t, u64::from(u32::MAX));
        varint(&mut t, 0);
        t.extend_from_slice(&[tag::STEP, 0]);
        let e = retrace(&loaded(t, 2_000), &[], Some(100)).expect_err("refused");
        assert_eq!(
            e,
            format!(
                "byte 100: hardware trace: trace byte {idle_at}: IDLE count makes 4294967295 \
                 passes without a control cycle; the firmware runs one every 80000 us and makes \
                 at most a pass a microsecond, so at most 160000 passes come between two (two \
                 periods)"
            )
        );
    }

    /// Control cycles may be any time apart (a stalled robot), but not more robot time than
    /// the recording could hold.
    #[test]
    fn more_robot_time_than_the_recording_spans_is_refused() {
        let mut t = started(0);
        t.extend_from_slice(&[tag::STEP]);
        varint(&mut t, 1_000_000_000_000);
        t.push(tag::IR);
        t.extend_from_slice(&[0; 8]);
        t.extend_from_slice(&[tag::STEP, 0]);
        let e = retrace(&loaded(t.clone(), 10_000), &[], None).expect_err("refused");
        assert!(
            e.contains("1000000.000 s of robot time") && e.contains("spans 0.010 s"),
            "{e}"
        );
        // Over a recording of 11 days, the same trace is a stalled robot.
        assert!(retrace(&loaded(t, 11 * 24 * 3_600_000_000), &[], None).is_ok());
    }

    /// `--until-ms` compares the robot's clock unwrapped: a robot up for 50 days (its
    /// milliseconds past 2^32) is past 100 ms at its first pass.
    #[test]
    fn until_ms_stops_a_clock_past_2_to_the_32_ms() {
        let mut t = started((1u64 << 32) * 1000 + 5_000);
        for _ in 0..10 {
            t.extend_from_slice(&[tag::STEP]);
            varint(&mut t, 1000);
        }
        let run = retrace(&loaded(t, 10_000), &[], Some(100)).expect("retraces");
        assert_eq!(run.stop, Stop::Until);
        assert_eq!(run.steps, 0);
    }
}
