//! What the benchmark reports: one row a run with its cause of failure, the summary over the
//! rows, and the table printed for a person.

use serde::Serialize;

use super::breakdown::Breakdown;
use super::{breakdown, BenchTask};

/// Why a run failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Cause {
    /// No arrival; still within a body diameter over the run's last minute.
    Stuck,
    /// No arrival before the timeout, still moving (forage: objects left).
    Timeout,
    /// Arrival reported, true pose outside the target.
    WrongArrival,
    /// The start is already within the goal's tolerance.
    StartedInsideTarget,
    /// No way leads from the start to the goal for this robot (a gap narrower than it):
    /// nothing the robot can do reaches it.
    Unreachable,
    /// The arena could not be generated or loaded.
    ImportError,
    /// Explore-then-plan: the robot's own explored map does not connect the start and the
    /// goal it found, so it refused to plan run 2 (the robot's failure, not the setup's).
    NoPathOnExploredMap,
    /// The runner refused the setup.
    SetupError,
    /// The run panicked (a bug).
    Panic,
}

impl Cause {
    /// Every cause, in report order.
    pub const ALL: [Cause; 9] = [
        Cause::Stuck,
        Cause::Timeout,
        Cause::WrongArrival,
        Cause::NoPathOnExploredMap,
        Cause::StartedInsideTarget,
        Cause::Unreachable,
        Cause::ImportError,
        Cause::SetupError,
        Cause::Panic,
    ];

    /// The name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Cause::Stuck => "stuck",
            Cause::Timeout => "timeout",
            Cause::WrongArrival => "wrong_arrival",
            Cause::NoPathOnExploredMap => "no_path_on_explored_map",
            Cause::StartedInsideTarget => "started_inside_target",
            Cause::Unreachable => "unreachable",
            Cause::ImportError => "import_error",
            Cause::SetupError => "setup_error",
            Cause::Panic => "panic",
        }
    }
}

/// One (arena, seed) run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Row {
    /// Arena label.
    pub arena: String,
    /// The emulator seed ([`run_seed`]; `robot-emulator run --seed` repeats the run).
    pub seed: u64,
    /// Which draw of this arena, 1..=`--seeds`.
    pub draw: u64,
    /// Succeeded (see the module text).
    pub success: bool,
    /// Why not, when it did not.
    pub cause: Option<Cause>,
    /// Simulated seconds (all runs of the task).
    pub sim_s: Option<f64>,
    /// Wall-clock seconds of this run.
    pub wall_s: f64,
    /// Wall contacts.
    pub collisions: Option<u32>,
    /// Final distance from the true position to the goal, metres.
    pub goal_error_m: Option<f64>,
    /// Final distance between true and believed position, metres.
    pub pose_error_m: Option<f64>,
    /// The firmware reported arrival (last run).
    pub arrived: Option<bool>,
    /// The runner's `reached` (last run).
    pub reached: Option<bool>,
    /// The start pose was within the goal's tolerance.
    pub started_inside: Option<bool>,
    /// Explore-then-plan: run 1 and run 2 simulated seconds, and whether each reached.
    pub run1_s: Option<f64>,
    /// See `run1_s`.
    pub run2_s: Option<f64>,
    /// Run 1 reached.
    pub run1_reached: Option<bool>,
    /// Run 2 reached.
    pub run2_reached: Option<bool>,
    /// Forage: objects in play, delivered (truth), delivered (the firmware's count).
    pub objects: Option<usize>,
    /// See `objects`.
    pub delivered: Option<usize>,
    /// See `objects`.
    pub firmware_delivered: Option<u16>,
    /// The error of an import or setup failure, or a panic's message.
    pub error: Option<String>,
    /// The odometry calibration before the run (`--calibrate-odometry`).
    pub calibration: Option<crate::scenarios::calibrate_odometry::CalibrationReport>,
    /// Shortest free path from the start to the goal area for this robot, metres
    /// ([`crate::arena::free_path`]).
    pub free_path_m: Option<f64>,
    /// `free_path_m` over the straight line to the goal area.
    pub detour_ratio: Option<f64>,
    /// The narrowest gap every route passes, metres.
    pub bottleneck_m: Option<f64>,
    /// The last run's ground distance over `free_path_m`.
    pub route_ratio: Option<f64>,
    /// The arena's features ([`breakdown::features_of`]).
    pub features: Vec<&'static str>,
}

impl Row {
    pub(super) fn failed(
        arena: String,
        seed: u64,
        cause: Cause,
        error: String,
        wall_s: f64,
    ) -> Row {
        Row {
            arena,
            seed,
            draw: 0,
            success: false,
            cause: Some(cause),
            sim_s: None,
            wall_s,
            collisions: None,
            goal_error_m: None,
            pose_error_m: None,
            arrived: None,
            reached: None,
            started_inside: None,
            run1_s: None,
            run2_s: None,
            run1_reached: None,
            run2_reached: None,
            objects: None,
            delivered: None,
            firmware_delivered: None,
            error: Some(error),
            calibration: None,
            free_path_m: None,
            detour_ratio: None,
            bottleneck_m: None,
            route_ratio: None,
            features: Vec::new(),
        }
    }
}

/// Median and 90th percentile (nearest rank), `None` with no values.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Spread {
    /// Median.
    pub median: f64,
    /// 90th percentile.
    pub p90: f64,
}

/// Median and 90th percentile of `v` (nearest rank).
pub fn spread_of(v: Vec<f64>) -> Option<Spread> {
    spread(v)
}

pub(crate) fn spread(mut v: Vec<f64>) -> Option<Spread> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let rank = |q: f64| v[((q * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1];
    Some(Spread {
        median: rank(0.5),
        p90: rank(0.9),
    })
}

/// Explore-then-plan's figure: run 2 faster than run 1 where both reached.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PlanSummary {
    /// Runs where run 1 and run 2 both reached the target.
    pub both_reached: usize,
    /// Of those, run 2 took less simulated time than run 1.
    pub run2_faster: usize,
    /// `run2_faster / both_reached` (0 with none).
    pub run2_faster_rate: f64,
}

/// Foraging's figures.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ForageSummary {
    /// Objects in play over all runs.
    pub objects: usize,
    /// Objects delivered (truth).
    pub delivered: usize,
    /// `delivered / objects`.
    pub delivered_rate: f64,
    /// Runs where the firmware's delivered count differs from the truth.
    pub miscounted_runs: usize,
}

/// The whole benchmark's figures.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// Runs.
    pub runs: usize,
    /// Successful runs.
    pub successes: usize,
    /// `successes / runs`.
    pub success_rate: f64,
    /// Simulated seconds of the successful runs.
    pub time_s: Option<Spread>,
    /// Mean wall contacts per completed run.
    pub collisions_mean: f64,
    /// Wall contacts over all runs.
    pub collisions_total: u64,
    /// Final true distance to the goal over completed runs, metres.
    pub goal_error_m: Option<Spread>,
    /// Final true-versus-believed position error over completed runs, metres.
    pub pose_error_m: Option<Spread>,
    /// Failures by cause (every cause listed, zeros included).
    pub failures: std::collections::BTreeMap<&'static str, usize>,
    /// Explore-then-plan only.
    pub plan: Option<PlanSummary>,
    /// Forage only.
    pub forage: Option<ForageSummary>,
    /// `--calibrate-odometry` only.
    pub calibration: Option<CalibrationSummary>,
    /// Route driven over the shortest free path, successful runs.
    pub route_ratio: Option<Spread>,
    /// Per detour class of the arenas (shortest free path over straight line).
    pub by_detour: Vec<Breakdown>,
    /// Per arena feature.
    pub by_feature: Vec<Breakdown>,
}

/// The odometry calibrations' figures (`--calibrate-odometry`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct CalibrationSummary {
    /// Calibrations run.
    pub runs: usize,
    /// Calibrations that gave parameters.
    pub succeeded: usize,
    /// Of those, both directions closed a lap.
    pub both_directions: usize,
    /// |true ratio error| before calibration, ppm (the emulator's truth; the robot never sees
    /// it).
    pub true_ratio_ppm: Option<Spread>,
    /// |measured - true ratio error| of the successful calibrations, ppm.
    pub residual_ppm: Option<Spread>,
    /// Simulated seconds of the calibrations.
    pub sim_s: Option<Spread>,
}

/// The benchmark's report (`--json` prints it whole).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BenchReport {
    /// The task.
    pub task: BenchTask,
    /// Profile name.
    pub profile: &'static str,
    /// Arenas run.
    pub arenas: usize,
    /// Noise draws per arena (`--seeds`).
    pub seeds: u64,
    /// The base seed (`--seed`) of every run's [`run_seed`].
    pub seed: u64,
    /// Simulated seconds allowed per run.
    pub timeout_s: f64,
    /// Worker threads.
    pub jobs: usize,
    /// Wall-clock seconds for the whole benchmark.
    pub wall_s: f64,
    /// The figures.
    pub summary: Summary,
    /// Every run, in (arena, seed) order.
    pub rows: Vec<Row>,
}

/// The figures over a set of rows.
pub fn summarise(task: BenchTask, rows: &[Row]) -> Summary {
    let runs = rows.len();
    let successes = rows.iter().filter(|r| r.success).count();
    let ratio = |a: usize, b: usize| if b == 0 { 0.0 } else { a as f64 / b as f64 };
    let completed: Vec<&Row> = rows.iter().filter(|r| r.sim_s.is_some()).collect();
    let collisions_total: u64 = completed
        .iter()
        .map(|r| u64::from(r.collisions.unwrap_or(0)))
        .sum();
    let mut failures = std::collections::BTreeMap::new();
    for c in Cause::ALL {
        failures.insert(c.name(), rows.iter().filter(|r| r.cause == Some(c)).count());
    }
    let plan = (task == BenchTask::ExploreThenPlan).then(|| {
        let both: Vec<&Row> = rows
            .iter()
            .filter(|r| r.run1_reached == Some(true) && r.run2_reached == Some(true))
            .collect();
        let faster = both
            .iter()
            .filter(|r| matches!((r.run1_s, r.run2_s), (Some(a), Some(b)) if b < a))
            .count();
        PlanSummary {
            both_reached: both.len(),
            run2_faster: faster,
            run2_faster_rate: ratio(faster, both.len()),
        }
    });
    let cals: Vec<&crate::scenarios::calibrate_odometry::CalibrationReport> =
        rows.iter().filter_map(|r| r.calibration.as_ref()).collect();
    let calibration = (!cals.is_empty()).then(|| {
        let ok: Vec<_> = cals
            .iter()
            .filter(|c| c.wheel_ratio_ppm.is_some())
            .collect();
        CalibrationSummary {
            runs: cals.len(),
            succeeded: ok.len(),
            both_directions: ok.iter().filter(|c| c.both_directions).count(),
            true_ratio_ppm: spread(cals.iter().map(|c| c.true_ratio_ppm.abs()).collect()),
            residual_ppm: spread(
                ok.iter()
                    .filter_map(|c| c.wheel_ratio_ppm)
                    .zip(ok.iter().map(|c| c.true_ratio_ppm))
                    .map(|(m, t)| (f64::from(m) - t).abs())
                    .collect(),
            ),
            sim_s: spread(cals.iter().map(|c| c.sim_s).collect()),
        }
    });
    let forage = (task == BenchTask::Forage).then(|| {
        let objects = rows.iter().filter_map(|r| r.objects).sum();
        let delivered = rows.iter().filter_map(|r| r.delivered).sum();
        ForageSummary {
            objects,
            delivered,
            delivered_rate: ratio(delivered, objects),
            miscounted_runs: rows
                .iter()
                .filter(|r| {
                    matches!((r.delivered, r.firmware_delivered),
                        (Some(d), Some(f)) if d != usize::from(f))
                })
                .count(),
        }
    });
    Summary {
        runs,
        successes,
        success_rate: ratio(successes, runs),
        time_s: spread(
            rows.iter()
                .filter(|r| r.success)
                .filter_map(|r| r.sim_s)
                .collect(),
        ),
        collisions_mean: if completed.is_empty() {
            0.0
        } else {
            collisions_total as f64 / completed.len() as f64
        },
        collisions_total,
        goal_error_m: spread(completed.iter().filter_map(|r| r.goal_error_m).collect()),
        pose_error_m: spread(completed.iter().filter_map(|r| r.pose_error_m).collect()),
        failures,
        plan,
        forage,
        calibration,
        route_ratio: spread(
            rows.iter()
                .filter(|r| r.success)
                .filter_map(|r| r.route_ratio)
                .collect(),
        ),
        by_detour: breakdown::by_detour(rows),
        by_feature: breakdown::by_feature(rows),
    }
}

/// The report as text for a terminal.
pub fn render(r: &BenchReport) -> String {
    let s = &r.summary;
    let pct = |x: f64| x * 100.0;
    let mut out = format!(
        "bench {}: {} arenas x {} noise draws (base seed {}) = {} runs, {} robot, {:.0} s timeout ({} jobs, {:.1} s wall)\n",
        task_name(r.task),
        r.arenas,
        r.seeds,
        r.seed,
        s.runs,
        r.profile,
        r.timeout_s,
        r.jobs,
        r.wall_s
    );
    let what = match r.task {
        BenchTask::Forage => "every object delivered",
        BenchTask::ExploreThenPlan => "run 2 reached, true pose in the target",
        _ => "true pose in the target",
    };
    out += &format!(
        "  success        {}/{} ({:.1} %; {what})\n",
        s.successes,
        s.runs,
        pct(s.success_rate)
    );
    let fmt_spread = |x: Option<Spread>, unit: &str| match x {
        Some(v) => format!("median {:.2} {unit}, p90 {:.2} {unit}", v.median, v.p90),
        None => "none".to_string(),
    };
    out += &format!(
        "  time           {} simulated (successful runs)\n",
        fmt_spread(s.time_s, "s")
    );
    out += &format!(
        "  collisions     {:.1} per run ({} in all)\n",
        s.collisions_mean, s.collisions_total
    );
    if r.task != BenchTask::Forage {
        out += &format!(
            "  final error    {} from the goal (true pose)\n",
            fmt_spread(s.goal_error_m, "m")
        );
    }
    out += &format!(
        "  pose error     {} (true vs believed, at the end)\n",
        fmt_spread(s.pose_error_m, "m")
    );
    if let Some(x) = s.route_ratio {
        out += &format!(
            "  route          median {:.2}x, p90 {:.2}x the shortest free path (successful runs)\n",
            x.median, x.p90
        );
    }
    let causes: Vec<String> = Cause::ALL
        .iter()
        .map(|c| {
            let n = s.failures.get(c.name()).copied().unwrap_or(0);
            format!("{} {n}", c.name().replace('_', " "))
        })
        .collect();
    out += &format!("  failures       {}\n", causes.join(", "));
    if let Some(p) = s.plan {
        out += &format!(
            "  plan           both runs reached in {}; run 2 faster in {} ({:.1} %)\n",
            p.both_reached,
            p.run2_faster,
            pct(p.run2_faster_rate)
        );
    }
    if let Some(c) = s.calibration {
        let ppm = |x: Option<Spread>| match x {
            Some(v) => format!("median {:.0} ppm, p90 {:.0} ppm", v.median, v.p90),
            None => "none".to_string(),
        };
        out += &format!(
            "  calibration    {} of {} gave parameters ({} both directions); wheel ratio error \
             {} before, residual {}\n",
            c.succeeded,
            c.runs,
            c.both_directions,
            ppm(c.true_ratio_ppm),
            ppm(c.residual_ppm)
        );
    }
    if s.by_detour.iter().any(|b| b.runs > 0) {
        out += &breakdown::render(
            "by detour (shortest free path / straight line):",
            &s.by_detour,
        );
    }
    if !s.by_feature.is_empty() {
        out += &breakdown::render("by feature:", &s.by_feature);
    }
    if let Some(f) = s.forage {
        out += &format!(
            "  forage         {} of {} objects delivered ({:.1} %); firmware count differs from \
             the truth in {} runs\n",
            f.delivered,
            f.objects,
            pct(f.delivered_rate),
            f.miscounted_runs
        );
    }
    out
}

fn task_name(t: BenchTask) -> &'static str {
    match t {
        BenchTask::ReachBeacon => "reach-beacon",
        BenchTask::ExploreThenPlan => "explore-then-plan",
        BenchTask::Goto => "goto",
        BenchTask::Forage => "forage",
    }
}
