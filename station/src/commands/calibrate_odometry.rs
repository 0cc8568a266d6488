//! `station calibrate odometry --port P`: the Khepera's odometry calibration run on a real
//! robot over the link (`robot_firmware::odometry_calibration`, docs/station.md "Odometry
//! calibration"). The robot follows the wall one way until it closes a lap, turns round,
//! follows it the other way; the wheel ratio and the effective wheel distance come out and
//! are set as `odo_wheel_ratio_ppm` and `odo_wheel_distance_mm` (`params set` semantics: the
//! value the robot put in force is printed, or its refusal), both or neither: a value refused
//! puts the one already set back.
//!
//! The driving sequence is `robot_firmware::odometry_manoeuvre`, the one the emulator's
//! `bench --calibrate-odometry` runs; here it is fed the robot's telemetry (encoders,
//! believed heading, side IR) frame by frame. Every command is awaited: one refused or
//! unanswered ends the run with the robot stopped (a motion command is executed or refused;
//! on link loss the robot's failsafe stops the motors itself). The robot is stopped at the
//! end, on Ctrl-C and on `--timeout`; a timeout still uses the laps closed so far, Ctrl-C
//! sets nothing.
//!
//! Exit status: 0 calibrated (and set, unless `--dry-run`), 1 no result, refused, interrupted,
//! link lost, 2 usage.

use std::process::ExitCode;
use std::time::Duration;

use anyhow::bail;
use clap::Args;
use protocol::{caps, AckInfo, Command, Mode, ParamId, ProfileId, Telemetry};
use robot_firmware::odometry_calibration::{Calibration, CalibrationParams, WallSide};
use robot_firmware::odometry_manoeuvre::{Manoeuvre, Observation};
use robot_firmware::params::id as param;
use serde::Serialize;
use tokio::time::Instant;

use crate::commands::args::RequiredPort;
use crate::link::api::refusal_text;
use crate::link::{CommandOutcome, Connection, LinkEvent, RunningLink};

/// Seconds to wait for the handshake.
const HANDSHAKE_S: f64 = 5.0;

/// Arguments of `station calibrate odometry`.
#[derive(Debug, Args, Clone)]
pub struct OdometryArgs {
    #[command(flatten)]
    pub port: RequiredPort,
    /// Seconds the laps may take; then the robot is stopped and the laps closed so far are
    /// used (a lap of a 1.2 x 1 m box is about 100 s at the edge follower's speed).
    #[arg(long, default_value_t = 600.0, value_parser = crate::commands::args::parse_seconds,
          allow_negative_numbers = true)]
    pub timeout: f64,
    /// Measure and print, but set no parameter.
    #[arg(long)]
    pub dry_run: bool,
    /// Print the report as one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// One parameter's change.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Change {
    pub name: &'static str,
    pub id: u16,
    pub before: f32,
    /// What the calibration measured.
    pub measured: f32,
    /// The value the robot put in force (`None`: dry run or refused).
    pub after: Option<f32>,
    /// The robot's reason for refusing.
    pub refused: Option<String>,
    /// Set, then put back because a later value was refused: the value in force again.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub restored: Option<f32>,
    /// Why putting it back failed (it stays at `after`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub restore_failed: Option<String>,
}

impl Change {
    /// Parameter `id`, in force `before`, measured `measured`: nothing set yet.
    fn new(id: u16, before: f32, measured: f32) -> Change {
        Change {
            name: robot_firmware::params::info(id).map_or("?", |p| p.name),
            id,
            before,
            measured,
            after: None,
            refused: None,
            restored: None,
            restore_failed: None,
        }
    }
}

/// What the run gave.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Report {
    /// Each closed lap: direction, drift before calibration (deg), wheel travel (m).
    pub laps: Vec<LapReport>,
    pub both_directions: bool,
    pub seconds: f64,
    pub dry_run: bool,
    pub changes: Vec<Change>,
    /// Why there is no result (or what cut the run short).
    pub error: Option<String>,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LapReport {
    pub direction: &'static str,
    pub drift_deg: f64,
    pub length_m: f64,
}

/// Encoder counts wrap at 16 bits in telemetry; the calibrator wants them unwrapped.
#[derive(Default)]
struct Unwrap {
    last: Option<[u16; 2]>,
    total: [i64; 2],
}

impl Unwrap {
    fn feed(&mut self, enc: [u16; 2]) -> [i64; 2] {
        if let Some(last) = self.last {
            for k in 0..2 {
                // A frame apart the wheels move a few pulses: the short way round is right.
                self.total[k] += i64::from(enc[k].wrapping_sub(last[k]) as i16);
            }
        }
        self.last = Some(enc);
        self.total
    }
}

/// How the laps ended.
enum End {
    Done(Result<Calibration, String>),
    Interrupted,
    Failed(String),
}

/// Runs `station calibrate odometry`.
pub async fn run(args: &OdometryArgs) -> anyhow::Result<ExitCode> {
    let (mut link, peer) = crate::commands::connect::connect(&args.port, HANDSHAKE_S).await?;
    let result = calibrate(&mut link, &peer, args).await;
    link.handle.shutdown();
    let _ = tokio::time::timeout(Duration::from_secs(1), link.task).await;
    result
}

/// Telemetry rate during the manoeuvre, Hz (the emulator scenario samples at 25 Hz).
const HOLD_HZ: u8 = 25;

async fn calibrate(
    link: &mut RunningLink,
    peer: &crate::link::PeerInfo,
    args: &OdometryArgs,
) -> anyhow::Result<ExitCode> {
    let profile = match peer.profile {
        ProfileId::Khepera => &robot_firmware::profile::KHEPERA,
        ProfileId::MicroRato => &robot_firmware::profile::MICRO_RATO,
        ProfileId::Alice => &robot_firmware::profile::ALICE,
    };
    if !peer.has(caps::ENCODERS) {
        bail!(
            "the robot ({}) has no wheel encoders: nothing to calibrate",
            profile.name
        );
    }
    if peer.telemetry_hz == 0 {
        bail!("the robot sends no telemetry: the laps are recognised from it");
    }
    let ids = [param::ODO_WHEEL_DISTANCE_MM, param::ODO_WHEEL_RATIO_PPM];
    let mut before = [0.0f32; 2];
    for (b, id) in before.iter_mut().zip(ids) {
        *b = read_param(link, id).await?;
    }
    // The wheel distance in force is the one a one-direction result keeps.
    let mut m = Manoeuvre::new(
        CalibrationParams::default(),
        profile.pulse_m * 1000.0,
        before[0],
    );
    // The wall holder steers once per telemetry frame: at the robot's default 10 Hz a
    // Khepera moves 3 mm between corrections, so ask for the emulator scenario's 25 Hz for
    // the manoeuvre, and put the rate back after it.
    let rate = peer.telemetry_hz;
    if rate < HOLD_HZ {
        send(link, Command::SetTelemetryRate { hz: HOLD_HZ })
            .await
            .map_err(|e| anyhow::anyhow!(e))?;
    }
    let t0 = Instant::now();
    let end = drive(link, &mut m, args).await;
    // Whatever happened, the robot stops (a link already lost has stopped it).
    let stop = link.handle.call(Command::Stop).await;
    if rate < HOLD_HZ {
        let _ = link
            .handle
            .call(Command::SetTelemetryRate { hz: rate })
            .await;
    }
    let seconds = t0.elapsed().as_secs_f64();
    let mut report = Report {
        laps: laps(&m),
        both_directions: false,
        seconds,
        dry_run: args.dry_run,
        changes: Vec::new(),
        error: None,
    };
    let outcome = match end {
        End::Done(r) => r,
        End::Interrupted => Err("interrupted (Ctrl-C): nothing set".into()),
        End::Failed(why) => Err(why),
    };
    if !stop.is_ack() {
        say(
            args.json,
            &format!("warning: stop: {}", outcome_text(&Command::Stop, &stop)),
        );
    }
    let mut ok = false;
    match outcome {
        Err(e) => report.error = Some(e),
        Ok(c) => {
            report.both_directions = c.both_directions;
            let measured = [c.wheel_distance_mm, (c.wheel_ratio - 1.0) * 1e6];
            report.changes = ids
                .into_iter()
                .zip(before)
                .zip(measured)
                .map(|((id, before), measured)| Change::new(id, before, measured))
                .collect();
            ok = args.dry_run || apply(&mut report.changes, |c| link.handle.call(c)).await;
        }
    }
    print_report(args.json, &report);
    Ok(if ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

/// Sets the measured values in order, all or none: once one is refused (or unanswered),
/// those already set are put back to their values before, so a refusal never leaves the
/// odometry half calibrated (this run's wheel distance with the old ratio is neither
/// calibration). Returns whether every value was set.
async fn apply<F, Fut>(changes: &mut [Change], mut call: F) -> bool
where
    F: FnMut(Command) -> Fut,
    Fut: std::future::Future<Output = CommandOutcome>,
{
    for i in 0..changes.len() {
        let command = Command::SetParam {
            id: ParamId(changes[i].id),
            value: changes[i].measured,
        };
        match call(command).await {
            CommandOutcome::Acked {
                info: AckInfo::Param { value, .. },
                ..
            } => changes[i].after = Some(value),
            other => {
                changes[i].refused = Some(outcome_text(&command, &other));
                for done in changes[..i].iter_mut().rev() {
                    let back = Command::SetParam {
                        id: ParamId(done.id),
                        value: done.before,
                    };
                    match call(back).await {
                        CommandOutcome::Acked {
                            info: AckInfo::Param { value, .. },
                            ..
                        } => done.restored = Some(value),
                        other => done.restore_failed = Some(outcome_text(&back, &other)),
                    }
                }
                return false;
            }
        }
    }
    true
}

/// Drives the manoeuvre from telemetry until it is done, the time is up, Ctrl-C, or a
/// command is not executed.
async fn drive(link: &mut RunningLink, m: &mut Manoeuvre, args: &OdometryArgs) -> End {
    let deadline = Instant::now() + Duration::from_secs_f64(args.timeout);
    let ctrl_c = tokio::signal::ctrl_c();
    tokio::pin!(ctrl_c);
    if let Err(why) = send(link, m.start()).await {
        return End::Failed(why);
    }
    say(
        args.json,
        "following the wall on the right (counter-clockwise) until a lap closes",
    );
    let mut unwrap = Unwrap::default();
    let mut shown = 0;
    // The mode the robot must be in, once seen: a robot that leaves it (its own failsafe,
    // another station) is no longer calibrating, whatever the telemetry says.
    let mut expected: Option<(Mode, bool)> = Some((Mode::EdgeFollowRight, false));
    loop {
        let ev = tokio::select! {
            _ = &mut ctrl_c => return End::Interrupted,
            _ = tokio::time::sleep_until(deadline) => {
                say(args.json, &format!("time is up after {} s: using the laps closed so far",
                    args.timeout));
                return End::Done(m.finish().map_err(|e| format!("{e:?} after {} s", args.timeout)));
            }
            ev = link.events.recv() => ev,
        };
        let t: Telemetry = match ev {
            None => return End::Failed("the link task ended".into()),
            Some(LinkEvent::Telemetry(t)) => t,
            Some(LinkEvent::Connection(c)) if !matches!(c, Connection::Connected(_)) => {
                return End::Failed(format!(
                    "link lost ({}); the robot's failsafe stops its motors",
                    c.name()
                ))
            }
            Some(_) => continue,
        };
        if let Some((mode, seen)) = expected.as_mut() {
            if t.mode == *mode {
                *seen = true;
            } else if *seen {
                return End::Failed(format!(
                    "the robot left {mode:?} for {:?}: calibration abandoned",
                    t.mode
                ));
            }
        }
        let step = m.step(Observation {
            pulses: unwrap.feed(t.wheels.encoders),
            heading_rad: f32::from(t.pose.heading_mrad) / 1000.0,
            ir: t.ir.values(),
        });
        for c in step.commands() {
            if let Err(why) = send(link, c).await {
                return End::Failed(why);
            }
            if let Command::SetMode(mode) = c {
                expected = Some((mode, false));
            }
        }
        let closed = m.calibrator().closed_laps();
        for (k, lap) in closed.iter().enumerate().skip(shown) {
            say(
                args.json,
                &format!(
                    "lap {} closed ({}): drift {:.1} deg over {:.2} m",
                    k + 1,
                    direction(lap.turns),
                    f64::from(lap.drift_rad).to_degrees(),
                    f64::from(lap.left_mm.abs() + lap.right_mm.abs()) / 2000.0
                ),
            );
        }
        shown = closed.len();
        if let Some(side) = step.turned_to {
            say(
                args.json,
                match side {
                    WallSide::Left => "turning round: now the wall on the left (clockwise)",
                    WallSide::Right => "turning round: now the wall on the right",
                },
            );
        }
        if let Some(r) = step.done {
            return End::Done(r.map_err(|e| format!("{e:?}")));
        }
    }
}

/// Sends one command and waits for its answer: anything but an ack ends the run.
async fn send(link: &mut RunningLink, c: Command) -> Result<(), String> {
    let outcome = link.handle.call(c).await;
    if outcome.is_ack() {
        Ok(())
    } else {
        Err(outcome_text(&c, &outcome))
    }
}

fn outcome_text(c: &Command, outcome: &CommandOutcome) -> String {
    let what = crate::link::api::command_text(c);
    match outcome {
        CommandOutcome::Acked { .. } => format!("{what}: done"),
        CommandOutcome::Nacked { reason, .. } => {
            format!("{what}: refused: {}", refusal_text(c, *reason))
        }
        CommandOutcome::Failed(why) => format!("{what}: no answer: {why}"),
    }
}

async fn read_param(link: &mut RunningLink, id: u16) -> anyhow::Result<f32> {
    let command = Command::GetParam { id: ParamId(id) };
    match link.handle.call(command).await {
        CommandOutcome::Acked {
            info: AckInfo::Param { value, .. },
            ..
        } => Ok(value),
        other => bail!(
            "reading {}: {}",
            crate::link::api::param_name(id),
            outcome_text(&command, &other)
        ),
    }
}

fn direction(turns: i32) -> &'static str {
    if turns >= 0 {
        "counter-clockwise"
    } else {
        "clockwise"
    }
}

fn laps(m: &Manoeuvre) -> Vec<LapReport> {
    m.calibrator()
        .closed_laps()
        .iter()
        .map(|lap| LapReport {
            direction: direction(lap.turns),
            drift_deg: f64::from(lap.drift_rad).to_degrees(),
            length_m: f64::from(lap.left_mm.abs() + lap.right_mm.abs()) / 2000.0,
        })
        .collect()
}

/// Progress goes to stderr with --json (stdout holds the one JSON object), else stdout.
fn say(json: bool, line: &str) {
    if json {
        eprintln!("{line}");
    } else {
        println!("{line}");
    }
}

fn print_report(json: bool, r: &Report) {
    if json {
        println!("{}", crate::json_text::pretty(r).unwrap_or_default());
        return;
    }
    if let Some(e) = &r.error {
        eprintln!("no calibration: {e}");
        return;
    }
    println!(
        "{} laps in {:.0} s ({})",
        r.laps.len(),
        r.seconds,
        if r.both_directions {
            "both directions"
        } else {
            "one direction: wheel distance kept"
        }
    );
    for c in &r.changes {
        match (&c.after, &c.refused) {
            (Some(a), _) => match (c.restored, &c.restore_failed) {
                (Some(v), _) => eprintln!(
                    "{}: set to {a}, put back to {v} because the next value was refused",
                    c.name
                ),
                (None, Some(why)) => eprintln!(
                    "{}: set to {a}; putting it back to {} failed: {why}",
                    c.name, c.before
                ),
                (None, None) => println!("{}: {} -> {}", c.name, c.before, a),
            },
            (None, Some(why)) => eprintln!("{} = {}: {why}", c.name, c.measured),
            (None, None) => println!(
                "{}: {} -> {} (dry run: not set)",
                c.name, c.before, c.measured
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use protocol::NackReason;
    use std::cell::RefCell;

    fn changes() -> Vec<Change> {
        [
            (param::ODO_WHEEL_DISTANCE_MM, 53.0, 52.6),
            (param::ODO_WHEEL_RATIO_PPM, 0.0, -3650.0),
        ]
        .into_iter()
        .map(|(id, before, measured)| Change::new(id, before, measured))
        .collect()
    }

    /// Runs `apply` against a robot that holds parameters in `held` and refuses a value
    /// when `refuse` says so; returns whether all were set.
    fn run(
        changes: &mut [Change],
        held: &RefCell<Vec<(u16, f32)>>,
        refuse: impl Fn(u16, f32) -> bool,
    ) -> bool {
        let robot = |c: Command| {
            let Command::SetParam { id, value } = c else {
                panic!("only SetParam is sent: {c:?}");
            };
            std::future::ready(if refuse(id.0, value) {
                CommandOutcome::Nacked {
                    reason: NackReason::OutOfRange,
                    sends: 1,
                }
            } else {
                held.borrow_mut().retain(|(i, _)| *i != id.0);
                held.borrow_mut().push((id.0, value));
                CommandOutcome::Acked {
                    info: AckInfo::Param { id, value },
                    sends: 1,
                    rtt_ms: 3,
                }
            })
        };
        tokio::runtime::Builder::new_current_thread()
            .build()
            .expect("runtime")
            .block_on(apply(changes, robot))
    }

    #[test]
    fn both_values_are_set_when_both_are_accepted() {
        let held = RefCell::new(vec![]);
        let mut c = changes();
        assert!(run(&mut c, &held, |_, _| false));
        assert_eq!(c[0].after, Some(52.6));
        assert_eq!(c[1].after, Some(-3650.0));
        assert!(c
            .iter()
            .all(|c| c.restored.is_none() && c.refused.is_none()));
    }

    /// The second value refused: the first, already set, goes back to its value before,
    /// so the robot's odometry is as it was, not half calibrated.
    #[test]
    fn a_refused_ratio_puts_the_wheel_distance_back() {
        let held = RefCell::new(vec![]);
        let mut c = changes();
        let ratio = param::ODO_WHEEL_RATIO_PPM;
        assert!(!run(&mut c, &held, |id, _| id == ratio));
        assert!(c[1]
            .refused
            .as_deref()
            .is_some_and(|r| r.contains("refused")));
        assert_eq!(c[0].restored, Some(53.0));
        assert_eq!(*held.borrow(), vec![(param::ODO_WHEEL_DISTANCE_MM, 53.0)]);
    }

    /// Putting back refused too: said, not hidden.
    #[test]
    fn a_failed_restore_is_reported() {
        let held = RefCell::new(vec![]);
        let mut c = changes();
        let ratio = param::ODO_WHEEL_RATIO_PPM;
        assert!(!run(&mut c, &held, |id, v| id == ratio || v == 53.0));
        assert_eq!(c[0].after, Some(52.6));
        assert_eq!(c[0].restored, None);
        assert!(c[0].restore_failed.is_some());
    }
}
