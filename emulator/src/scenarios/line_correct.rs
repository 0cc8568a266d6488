//! The seed 003 scenario: a Khepera surveys a floor grid for a long run and its three pose
//! estimates (line-corrected, plain odometry, nearest-line baseline) are judged against the
//! truth (`robot-emulator run --task line-correct`).
//!
//! Layer: std, on top of [`Sim`], beside `task`. The firmware is told only what a
//! station would tell it: `SetMode(Survey)`. It knows the grid's pitch and that a line passes
//! through the origin (its `GridGeometry` default); the emulator's grid starts at the arena's
//! lower-left corner, so the arena must put that corner on a line ([`LineCorrectError`]
//! otherwise). The wheels carry seed 003 §2.3's constant per-wheel speed bias, drawn per run
//! with sigma `noise.motors` (0.5 %) and clipped to two sigma (±1 %, the thesis's "at most
//! ±1 %"), unless given. The run ends after `distance_m` of true travel or at the timeout.
//!
//! Errors are sampled every control cycle; the report gives max, mean and final error of each
//! estimate, the PPD's size, the line pulses the firmware saw against the true crossings, and
//! a series of errors every metre of travel (the error-over-time plot of seed 003 Fig 2-25).

use std::time::Instant;

use protocol::{Command, Mode};
use robot_firmware::link::Reply;
use robot_firmware::odometry::Pose as FwPose;
use robot_firmware::robot::LineCorr;
use robot_firmware::Profile;
use serde::Serialize;
use thiserror::Error;

use crate::arena::{Arena, Pose};
use crate::geometry::Point;
use crate::sensors::Noise;
use crate::sim::{Sim, SimConfig, SimError};

/// How a line-correction run is set up. [`LineCorrectOptions::new`] gives the defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct LineCorrectOptions {
    /// Which robot (needs encoders and a line sensor: the Khepera).
    pub profile: &'static Profile,
    /// The run's seed.
    pub seed: u64,
    /// True distance to drive, metres. Default 40 (the host reproduction's runs).
    pub distance_m: f64,
    /// Simulated seconds before giving up.
    pub timeout_s: f64,
    /// Noise levels (line misses and double detections included).
    pub noise: Noise,
    /// Start pose (default: the arena's).
    pub start: Option<Pose>,
    /// Wheel bias (default: drawn and clipped, see the module text).
    pub wheel_bias: Option<[f64; 2]>,
    /// Floor grid pitch, metres. Default 0.10 (seed 003 §2.6.4).
    pub floor_grid_m: f64,
}

impl LineCorrectOptions {
    /// Defaults: seed 0, 40 m, 600 s, the papers' noise, 10 cm grid.
    pub fn new(profile: &'static Profile) -> Self {
        Self {
            profile,
            seed: 0,
            distance_m: 40.0,
            timeout_s: 600.0,
            noise: Noise::default(),
            start: None,
            wheel_bias: None,
            floor_grid_m: crate::world::GRID_PITCH_M,
        }
    }
}

/// One estimate's errors against the truth, millimetres.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct ErrorStats {
    /// Largest position error over the run.
    pub max_mm: f64,
    /// Mean position error over the run's control cycles.
    pub mean_mm: f64,
    /// Position error at the end.
    pub final_mm: f64,
}

/// Errors at one point of the run, millimetres.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ErrorSample {
    /// True distance travelled so far, metres.
    pub distance_m: f64,
    /// Simulated time, seconds.
    pub t_s: f64,
    pub corrected_mm: f64,
    pub uncorrected_mm: f64,
    pub baseline_mm: f64,
}

/// The outcome of a line-correction run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LineCorrectReport {
    pub arena: String,
    pub profile: &'static str,
    pub seed: u64,
    /// Wheel bias in force, relative (left, right).
    pub wheel_bias: [f64; 2],
    /// Floor grid pitch, metres.
    pub floor_grid_m: f64,
    /// Probability of a missed / doubled line detection.
    pub line_miss: f64,
    pub line_double: f64,
    /// True distance travelled, metres.
    pub distance_m: f64,
    pub sim_s: f64,
    pub wall_s: f64,
    pub collisions: u32,
    /// Line-corrected pose (the PPD, seed 003 §2.5).
    pub corrected: ErrorStats,
    /// Plain odometry from the same encoder counts.
    pub uncorrected: ErrorStats,
    /// Nearest-line snapping (the baseline seed 003 §2.2.4 rejects).
    pub baseline: ErrorStats,
    /// Largest heading error of the corrected pose, degrees.
    pub corrected_heading_max_deg: f64,
    /// PPD size (rms radius), largest and mean, millimetres.
    pub ppd_size_max_mm: f64,
    pub ppd_size_mean_mm: f64,
    /// Lines the sensor's centre truly entered.
    pub true_crossings: u32,
    /// Longest run of true crossings without a pulse (missed lines in a row; a crossing of
    /// two lines at once counts as two).
    pub max_missed_run: u32,
    /// Line pulses the firmware saw, corrections it made, pulses it ignored.
    pub pulses: u32,
    pub corrections: u32,
    pub rejected: u32,
    /// The PPD's learnt mean wheel bias (left, right), relative.
    pub learnt_bias: [f64; 2],
    /// Errors every metre of travel.
    pub series: Vec<ErrorSample>,
}

/// Why a line-correction run could not start.
#[derive(Debug, Error)]
pub enum LineCorrectError {
    #[error(transparent)]
    Sim(#[from] SimError),
    #[error("the firmware refused SetMode(Survey): {0:?} (line correction needs encoders and a floor line sensor: --profile khepera)")]
    Refused(protocol::NackReason),
    #[error(
        "arena {arena:?}: its lower-left corner ({x:.3}, {y:.3}) m is not on a line of a \
         {pitch} m grid through the origin, where the firmware assumes the lines; use \
         --arena builtin:floor-grid"
    )]
    GridOffset {
        arena: String,
        x: f64,
        y: f64,
        pitch: f64,
    },
    #[error("--distance {0} and --timeout {1} must be finite and > 0")]
    BadLength(f64, f64),
}

/// Runs the survey for `distance_m` and reports.
pub fn run_line_correct(
    arena: Arena,
    opts: &LineCorrectOptions,
) -> Result<LineCorrectReport, LineCorrectError> {
    let ok = |v: f64| v.is_finite() && v > 0.0;
    if !ok(opts.distance_m) || !ok(opts.timeout_s) {
        return Err(LineCorrectError::BadLength(opts.distance_m, opts.timeout_s));
    }
    let pitch = opts.floor_grid_m;
    let min = arena.bounds.min;
    let off = |v: f64| {
        let r = v.rem_euclid(pitch);
        r.min(pitch - r)
    };
    if off(min.x) > 1e-6 || off(min.y) > 1e-6 {
        return Err(LineCorrectError::GridOffset {
            arena: arena.name.clone(),
            x: min.x,
            y: min.y,
            pitch,
        });
    }
    let name = arena.name.clone();
    // seed 003 §2.3.3: the speed error is at most ±1 % = two sigma; `Sim` draws it clipped.
    let cfg = SimConfig {
        seed: opts.seed,
        noise: opts.noise,
        start: opts.start,
        wheel_bias: opts.wheel_bias,
        floor_grid_m: Some(pitch),
        ..SimConfig::new(opts.profile)
    };
    let mut sim = Sim::new(arena, cfg)?;
    let now_ms = (sim.now_us() / 1000) as u32;
    if let Reply::Nack(r) = sim
        .robot_mut()
        .apply(Command::SetMode(Mode::Survey), now_ms)
    {
        return Err(LineCorrectError::Refused(r));
    }
    let started = Instant::now();
    let timeout_ms = (opts.timeout_s * 1000.0).ceil() as u64;
    let mut acc = Accumulator::default();
    let mut last_cycle = sim.robot().timing().cycles;
    let mut over = sim.world().on_line(truth_point(&sim));
    let mut pulses_seen = sim.robot().line_events();
    let mut run = 0u32;
    let mut next_series_m = 0.0;
    for _ in 0..timeout_ms {
        sim.step();
        let on = sim.world().on_line(truth_point(&sim));
        if on && !over {
            acc.true_crossings += 1;
            run += 1;
        }
        over = on;
        let pulses = sim.robot().line_events();
        if pulses != pulses_seen {
            pulses_seen = pulses;
            // The pulse reports the crossing just entered.
            run = 0;
        }
        acc.max_missed_run = acc.max_missed_run.max(run.saturating_sub(1));
        let cycles = sim.robot().timing().cycles;
        if cycles == last_cycle {
            continue;
        }
        last_cycle = cycles;
        let Some(lc) = sim.robot().linecorr() else {
            return Err(LineCorrectError::Refused(protocol::NackReason::Unsupported));
        };
        let e = acc.sample(&sim, lc);
        if sim.distance_m() >= next_series_m {
            next_series_m += 1.0;
            acc.series.push(e);
        }
        if sim.distance_m() >= opts.distance_m {
            break;
        }
    }
    // Survey was accepted, so the composition has line correction.
    let Some(lc) = sim.robot().linecorr() else {
        return Err(LineCorrectError::Refused(protocol::NackReason::Unsupported));
    };
    let m = lc.report(0);
    let (bl, br) = lc.spps().mean_bias();
    let n = acc.n.max(1) as f64;
    let fin = |s: &mut ErrorStats, sum: f64| s.mean_mm = sum / n;
    fin(&mut acc.corrected, acc.sums[0]);
    fin(&mut acc.uncorrected, acc.sums[1]);
    fin(&mut acc.baseline, acc.sums[2]);
    let noise = opts.noise.sanitised();
    Ok(LineCorrectReport {
        arena: name,
        profile: opts.profile.name,
        seed: opts.seed,
        wheel_bias: sim.wheel_bias(),
        floor_grid_m: pitch,
        line_miss: noise.line_miss,
        line_double: noise.line_double,
        distance_m: sim.distance_m(),
        sim_s: sim.now_us() as f64 * 1e-6,
        wall_s: started.elapsed().as_secs_f64(),
        collisions: sim.collisions(),
        corrected: acc.corrected,
        uncorrected: acc.uncorrected,
        baseline: acc.baseline,
        corrected_heading_max_deg: acc.heading_max_deg,
        ppd_size_max_mm: acc.size_max,
        ppd_size_mean_mm: acc.size_sum / n,
        true_crossings: acc.true_crossings,
        max_missed_run: acc.max_missed_run,
        pulses: u32::from(m.lines),
        corrections: u32::from(m.corrections),
        rejected: u32::from(m.rejected),
        learnt_bias: [f64::from(bl), f64::from(br)],
        series: acc.series,
    })
}

fn truth_point(sim: &Sim) -> Point {
    let t = sim.truth();
    Point::new(t.x, t.y)
}

#[derive(Default)]
struct Accumulator {
    corrected: ErrorStats,
    uncorrected: ErrorStats,
    baseline: ErrorStats,
    sums: [f64; 3],
    n: u64,
    heading_max_deg: f64,
    size_max: f64,
    size_sum: f64,
    true_crossings: u32,
    max_missed_run: u32,
    series: Vec<ErrorSample>,
}

impl Accumulator {
    fn sample(&mut self, sim: &Sim, lc: &LineCorr) -> ErrorSample {
        let t = sim.truth();
        let mm = |p: FwPose| (f64::from(p.x) - t.x).hypot(f64::from(p.y) - t.y) * 1000.0;
        let e = [mm(lc.pose()), mm(lc.uncorrected()), mm(lc.baseline())];
        for ((s, sum), v) in [
            &mut self.corrected,
            &mut self.uncorrected,
            &mut self.baseline,
        ]
        .into_iter()
        .zip(self.sums.iter_mut())
        .zip(e)
        {
            s.max_mm = s.max_mm.max(v);
            s.final_mm = v;
            *sum += v;
        }
        self.n += 1;
        let dh = crate::physics::wrap_pi(f64::from(lc.pose().heading) - t.heading);
        self.heading_max_deg = self.heading_max_deg.max(dh.abs().to_degrees());
        let size = f64::from(lc.spps().size_m()) * 1000.0;
        self.size_max = self.size_max.max(size);
        self.size_sum += size;
        ErrorSample {
            distance_m: sim.distance_m(),
            t_s: sim.now_us() as f64 * 1e-6,
            corrected_mm: e[0],
            uncorrected_mm: e[1],
            baseline_mm: e[2],
        }
    }
}
