//! The odometry calibration run (`robot_firmware::odometry_manoeuvre`), as an operator runs
//! it before a go-to: the Khepera holds the wall on its right (`robot_firmware::wall_holder`,
//! Manual mode, a teleop each observation) until laps close, turns round, holds it on its
//! left; the wheel ratio comes from the straight walls (`robot_firmware::odometry_stretch`),
//! the wheel distance from walls a lap apart; they become the parameters
//! `odo_wheel_distance_mm` and `odo_wheel_ratio_ppm`, which a later run sets before its task
//! (`ScenarioOptions::params`), as a station loads a saved parameter file. A heartbeat goes
//! on the simulated serial line each observation, as a station's link sends them, so Manual
//! mode's link failsafe does not stop the motors.
//!
//! What the recogniser sees is what the robot sees: its encoder counts, its believed heading
//! and its side IR sensor, sampled at 25 Hz (the telemetry rate a station would use). The
//! emulator's true wheel parameters are NOT given to it; they appear in the report only, to
//! say how close the calibration came.
//!
//! Layer: std, a scenario runner beside `run_scenario`. What can fail: the set-up
//! ([`ScenarioError`]); laps that do not close in time or a solution out of range are a
//! report with `error` set and no parameters.

use robot_firmware::odometry_calibration::{Calibration, CalibrationParams};
use robot_firmware::odometry_manoeuvre::{Manoeuvre, Observation, STOP};
use robot_firmware::params::id as param;
use serde::Serialize;

use super::task::{apply, ScenarioError, ScenarioOptions};
use crate::arena::Arena;
use crate::sim::Sim;

/// Sampling period, ms (25 Hz telemetry).
const SAMPLE_MS: u64 = 40;
/// Simulated seconds the two laps may take by default: a lap of a 1.2 x 1 m box with dead
/// ends is about 5 m, 100 s at the edge follower's 50 mm/s; two laps and the turn between
/// them fit in 600 s with room for a detour round a block.
pub const DEFAULT_TIMEOUT_S: f64 = 600.0;

/// One calibration run's report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CalibrationReport {
    /// The measured wheel ratio error, ppm (`odo_wheel_ratio_ppm`), if it succeeded.
    pub wheel_ratio_ppm: Option<f32>,
    /// The measured effective wheel distance, mm (`odo_wheel_distance_mm`).
    pub wheel_distance_mm: Option<f32>,
    /// Both directions closed a lap (else the mean wheel factor was taken as nominal).
    pub both_directions: bool,
    /// Each closed lap's drift before calibration, degrees (counter-clockwise, clockwise).
    pub lap_drift_deg: Vec<f64>,
    /// Each closed lap's wheel travel, metres (mean of the two wheels).
    pub lap_length_m: Vec<f64>,
    /// The emulator's true ratio error, ppm: (1 + right bias) / (1 + left bias) - 1. The
    /// robot never sees it; it is here to judge the measurement.
    pub true_ratio_ppm: f64,
    /// The emulator's true effective wheel distance, mm: the true distance over the wheels'
    /// mean factor, what `odo_wheel_distance_mm` should be with the ratio exact. The robot
    /// never sees it.
    pub true_distance_mm: f64,
    /// Straight-wall stretches accepted (`robot_firmware::odometry_stretch`): how many, their
    /// total length in metres, and how many were rejected.
    pub straight_stretches: usize,
    /// Their total length, metres.
    pub straight_m: f64,
    /// Stretches rejected (bent, a reading that is not the distance).
    pub straight_rejected: u16,
    /// Simulated seconds the calibration took.
    pub sim_s: f64,
    /// Why there is no result.
    pub error: Option<String>,
}

impl CalibrationReport {
    /// The parameters to set before a later run, empty if the calibration failed.
    pub fn params(&self) -> Vec<(u16, f32)> {
        match (self.wheel_distance_mm, self.wheel_ratio_ppm) {
            (Some(d), Some(r)) => vec![
                (param::ODO_WHEEL_DISTANCE_MM, d),
                (param::ODO_WHEEL_RATIO_PPM, r),
            ],
            _ => Vec::new(),
        }
    }
}

/// Calibrates the robot of `opts` in `arena` (at most [`DEFAULT_TIMEOUT_S`]) and sets what
/// it measured on `opts`, as an operator who calibrated once loads the parameter file before
/// the run (`run --calibrate-odometry`, `bench --calibrate-odometry`).
pub fn calibrate_before(
    arena: &Arena,
    opts: &mut ScenarioOptions,
) -> Result<CalibrationReport, ScenarioError> {
    let c = run_calibration(arena.clone(), opts, DEFAULT_TIMEOUT_S)?;
    opts.params.extend(c.params());
    Ok(c)
}

/// Runs the calibration in `arena` with `opts`' robot, seed and noise, for at most
/// `timeout_s` simulated seconds.
pub fn run_calibration(
    arena: Arena,
    opts: &ScenarioOptions,
    timeout_s: f64,
) -> Result<CalibrationReport, ScenarioError> {
    if !(timeout_s.is_finite() && timeout_s > 0.0) {
        return Err(ScenarioError::BadTimeout(timeout_s));
    }
    let mut sim = Sim::new(arena, opts.sim_config())?;
    let bias = sim.wheel_bias();
    let true_ratio_ppm = ((1.0 + bias[1]) / (1.0 + bias[0]) - 1.0) * 1e6;
    let profile = opts.profile;
    // The driving sequence is the one a station runs over the link (`station calibrate
    // odometry`): one state machine for both.
    let mut m = Manoeuvre::new(
        CalibrationParams::default(),
        profile.pulse_m * 1000.0,
        profile.wheel_distance_m * 1000.0,
    );
    apply(&mut sim, m.start(), "SetMode(Manual)")?;
    let mut seq = 0u16;
    let end_ms = (timeout_s * 1000.0).ceil() as u64;
    let mut outcome = None;
    while sim.now_us() / 1000 < end_ms {
        keep_alive(&mut sim, &mut seq);
        sim.run_for(SAMPLE_MS);
        let core = sim.robot();
        let Some(enc) = core.sensors().encoders else {
            return Err(ScenarioError::Refused {
                what: "calibration (the robot has no encoders)",
                reason: protocol::NackReason::Unsupported,
            });
        };
        let step = m.step(Observation {
            pulses: [i64::from(enc[0]), i64::from(enc[1])],
            heading_rad: core.pose().heading,
            ir: core.sensors().ir,
        });
        for c in step.commands() {
            apply(&mut sim, c, "calibration manoeuvre")?;
        }
        if let Some(r) = step.done {
            outcome = Some(r);
            break;
        }
    }
    // Out of time: whatever laps closed (one direction is still a wheel ratio).
    let outcome = outcome.unwrap_or_else(|| m.finish());
    let _ = apply(&mut sim, STOP, "SetMode(Idle)");
    let sim_s = sim.now_us() as f64 * 1e-6;
    let mut report = CalibrationReport {
        wheel_ratio_ppm: None,
        wheel_distance_mm: None,
        both_directions: false,
        lap_drift_deg: Vec::new(),
        lap_length_m: Vec::new(),
        true_ratio_ppm,
        true_distance_mm: sim.body().params().wheel_distance_m * 1000.0
            / (1.0 + (bias[0] + bias[1]) / 2.0),
        straight_stretches: m.straight_walls().stretches().len(),
        straight_m: f64::from(m.straight_walls().total_mm()) / 1000.0,
        straight_rejected: m.straight_walls().rejected,
        sim_s,
        error: None,
    };
    match outcome {
        Ok(c) => fill(&mut report, &c),
        Err(e) => report.error = Some(format!("{e:?} after {sim_s:.0} s")),
    }
    Ok(report)
}

/// A heartbeat on the simulated serial line, as the station's link sends them: the
/// manoeuvre drives the robot in Manual mode, whose failsafe stops the motors when the link
/// is silent (commands applied directly are not link traffic). The robot's answers are
/// drained and dropped.
fn keep_alive(sim: &mut Sim, seq: &mut u16) {
    let mut buf = [0u8; protocol::MAX_FRAME];
    let hb = protocol::Message::Heartbeat(protocol::Heartbeat {
        time_ms: (sim.now_us() / 1000) as u32,
    });
    // A heartbeat is small and fixed: encoding cannot fail.
    if let Ok(n) = protocol::encode(*seq, &hb, &mut buf) {
        sim.uart_mut().push_inbound(&buf[..n]);
    }
    *seq = seq.wrapping_add(1);
    let _ = sim.uart_mut().take_outbound();
}

fn fill(report: &mut CalibrationReport, c: &Calibration) {
    report.wheel_ratio_ppm = Some((c.wheel_ratio - 1.0) * 1e6);
    report.wheel_distance_mm = Some(c.wheel_distance_mm);
    report.both_directions = c.both_directions;
    for lap in &c.laps {
        report
            .lap_drift_deg
            .push(f64::from(lap.drift_rad).to_degrees());
        report
            .lap_length_m
            .push(f64::from(lap.left_mm.abs() + lap.right_mm.abs()) / 2000.0);
    }
}
