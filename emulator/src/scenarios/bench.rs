//! The generalisation benchmark (issue 14): one task over many arenas and seeds, each run
//! headless through the scenario runners ([`run_scenario`](super::task::run_scenario),
//! [`run_forage`](super::forage::run_forage)), in parallel, summarised as success
//! rate, times, collisions, final error and failures by cause.
//!
//! Layer: std, on top of the scenario runners and [`crate::arena_gen`]; the command line
//! (`robot-emulator bench`) only parses arguments and prints.
//!
//! What counts (decided here, from the runner's ground truth, never from the firmware's word):
//! - success: the runner's `reached` (the firmware reported arrival AND the TRUE position is
//!   within the tolerance: inside the target circle for the search tasks, 5 cm for the
//!   Khepera), unless the robot started there; explore-then-plan: run 2 reached; forage:
//!   every object delivered (put down inside the home base, by the emulator's gripper).
//! - failures, one cause each: `started_inside_target` (the start pose is already within the
//!   tolerance of the goal: nothing was shown, whatever the report says), `wrong_arrival` (the
//!   firmware reported arrival but the true pose is not in the target), `stuck` (no arrival,
//!   and in the run's last [`STUCK_WINDOW_S`](super::task::STUCK_WINDOW_S) the robot
//!   stayed within one body diameter),
//!   `timeout` (no arrival, still moving), `import_error` (the arena could not be loaded or
//!   generated), `no_path_on_explored_map` (explore-then-plan: the robot refused to plan
//!   run 2 because its own explored map does not connect start and goal), `setup_error` (the runner refused: start in a wall, a refused command, no
//!   goal), `panic` (a bug; the run is caught so the others finish).
//!
//! Seeds: every run gets its own emulator seed, [`run_seed`]`(--seed, arena index, draw)`, so
//! each arena's run draws its own noise (wheel speed errors, IR gains, ...) and the success
//! rate measures the noise's distribution, not one draw shared by every arena. `--seeds K`
//! runs draws 1..=K of each arena. A row's `seed` is that emulator seed: `robot-emulator run
//! --seed S` with the same arena repeats the run.
//!
//! Determinism: a run depends only on (arena, seed); rows come out in (arena, draw) order
//! whatever the number of jobs. Only `wall_s` varies between runs of the benchmark.

use std::io::IsTerminal as _;
use std::panic::AssertUnwindSafe;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use robot_firmware::Profile;
use serde::Serialize;

use crate::arena::free_path::{free_path, FreePath};
use crate::arena::{Arena, LoadOptions};
use crate::arena_gen::{self, Kind};
use crate::geometry::Point;
use crate::rng::SimRng;
use crate::scenarios::task::{ScenarioOptions, ScenarioReport, Task};
use crate::sensors::Noise;

pub mod breakdown;
pub use breakdown::Breakdown;

/// The tasks the benchmark runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum BenchTask {
    /// The Dom Dinis reactive goal search to the beacon's target circle.
    ReachBeacon,
    /// Dom Dinis: explore, plan on the robot's own map, execute (run 2).
    ExploreThenPlan,
    /// Go to the arena's goal (the Khepera's drift behaviour on boxes and mazes).
    #[value(alias = "go-to")]
    Goto,
    /// Khepera foraging: objects from lamps to home.
    Forage,
}

impl BenchTask {
    /// The arena kind `generated:N` makes for this task unless `--kind` says.
    pub fn default_kind(self) -> Kind {
        match self {
            BenchTask::ReachBeacon | BenchTask::ExploreThenPlan => Kind::MicroRato,
            BenchTask::Goto | BenchTask::Forage => Kind::Box,
        }
    }

    /// The robot unless `--profile` says: the search tasks need compass and beacon sensor
    /// (micro-rato); go-to and foraging are the Khepera's (seed 000).
    pub fn default_profile(self) -> &'static Profile {
        match self {
            BenchTask::ReachBeacon | BenchTask::ExploreThenPlan => &robot_firmware::MICRO_RATO,
            BenchTask::Goto | BenchTask::Forage => &robot_firmware::KHEPERA,
        }
    }

    fn scenario_task(self) -> Task {
        match self {
            BenchTask::ReachBeacon => Task::ReachBeacon,
            BenchTask::ExploreThenPlan => Task::ExploreThenPlan,
            BenchTask::Goto => Task::GoTo(None),
            BenchTask::Forage => Task::Forage,
        }
    }
}

/// Where one benchmark arena comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum ArenaSource {
    /// `arena_gen::generate(kind, seed)`.
    Generated(Kind, u64),
    /// A file or a built-in arena name, loaded as `--arena` would.
    Named(String),
}

impl ArenaSource {
    /// The arena's label in reports.
    pub fn label(&self) -> String {
        match self {
            ArenaSource::Generated(k, s) => arena_gen::arena_name(*k, *s),
            ArenaSource::Named(n) => n.clone(),
        }
    }

    /// The arena: generated, or loaded as `--arena` would.
    pub fn load(&self) -> Result<Arena, String> {
        self.load_with_features().map(|(a, _)| a)
    }

    /// The arena and the features its generator drew it with (none for a file).
    pub fn load_with_features(&self) -> Result<(Arena, Vec<&'static str>), String> {
        match self {
            ArenaSource::Generated(k, s) => arena_gen::generate(*k, *s)
                .map(|g| (g.arena, g.features))
                .map_err(|e| e.to_string()),
            ArenaSource::Named(n) => crate::builtin::load(n, &LoadOptions::for_simulation())
                .map(|a| (a, Vec::new()))
                .map_err(|e| e.to_string()),
        }
    }
}

/// Stream of the benchmark's base seed from which each run's emulator seed is drawn (beyond
/// the per-component streams of `rng::stream` and the fleet's).
const BENCH_SEED_STREAM: u64 = 0x0042_656e_6368; // "Bench"

/// The emulator seed of draw `draw` (1-based, `--seeds K` runs 1..=K) on the arena at
/// `arena_index` (0-based, the order of `--arenas` after expansion: `generated:N` is
/// arenas 1..N at indices 0..N-1) of a benchmark with base seed `base` (`--seed`): the
/// `draw`-th value of the generator seeded with `base` on stream "Bench" + `arena_index`.
/// Different arenas and draws get independent noise; the same triple always the same seed.
pub fn run_seed(base: u64, arena_index: usize, draw: u64) -> u64 {
    run_seeds(base, arena_index, draw)
        .last()
        .copied()
        .unwrap_or_default()
}

/// Draws 1..=`draws` of [`run_seed`] for one arena.
fn run_seeds(base: u64, arena_index: usize, draws: u64) -> Vec<u64> {
    let mut rng = SimRng::new(base, BENCH_SEED_STREAM.wrapping_add(arena_index as u64));
    (0..draws).map(|_| rng.next_u64()).collect()
}

/// Every (arena index, draw, emulator seed) of a benchmark, in report order.
pub(crate) fn run_list(arenas: usize, base: u64, draws: u64) -> Vec<(usize, u64, u64)> {
    (0..arenas)
        .flat_map(|a| {
            run_seeds(base, a, draws)
                .into_iter()
                .zip(1..)
                .map(move |(seed, draw)| (a, draw, seed))
        })
        .collect()
}

/// Most arenas `generated:N` may ask for.
pub const MAX_GENERATED: u64 = 100_000;

/// Resolves `--arenas` values: `generated:N` (N arenas of `kind`, seeds 1..=N), a directory
/// (every arena file in it, sorted by name; grid files are not arenas), or a file or
/// built-in name.
pub fn resolve_arenas(specs: &[String], kind: Kind) -> Result<Vec<ArenaSource>, String> {
    let mut out = Vec::new();
    for spec in specs {
        if let Some(n) = spec.strip_prefix("generated:") {
            let n: u64 = n
                .parse()
                .ok()
                .filter(|n| (1..=MAX_GENERATED).contains(n))
                .ok_or_else(|| {
                    format!(
                        "--arenas {spec}: expected generated:N with N a whole number in \
                         1..={MAX_GENERATED}"
                    )
                })?;
            out.extend((1..=n).map(|s| ArenaSource::Generated(kind, s)));
        } else if Path::new(spec).is_dir() {
            let files = arena_files(Path::new(spec))?;
            if files.is_empty() {
                return Err(format!(
                    "--arenas {spec}: the directory holds no arena files (.xml labs, .txt \
                     mazes or grids, .yaml maps)"
                ));
            }
            out.extend(
                files
                    .into_iter()
                    .map(|p| ArenaSource::Named(p.to_string_lossy().into_owned())),
            );
        } else {
            out.push(ArenaSource::Named(spec.clone()));
        }
    }
    Ok(out)
}

/// The arena files in a directory, sorted: labs (not their grid files), mazes/grids, maps.
fn arena_files(dir: &Path) -> Result<Vec<PathBuf>, String> {
    let entries = std::fs::read_dir(dir).map_err(|e| format!("--arenas {}: {e}", dir.display()))?;
    let mut files: Vec<PathBuf> = entries
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_file())
        .filter(|p| {
            let ext = p
                .extension()
                .and_then(|e| e.to_str())
                .map(str::to_ascii_lowercase);
            let stem = p
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("")
                .to_ascii_lowercase();
            match ext.as_deref() {
                // A grid (start poses) or parameter file beside the labs is none.
                Some("xml") => {
                    !stem.ends_with("grid")
                        && !matches!(
                            crate::arena::ciberrato::root_element(p).as_deref(),
                            Some("Grid" | "Parameters")
                        )
                }
                Some("txt" | "yaml" | "yml") => true,
                _ => false,
            }
        })
        .collect();
    files.sort();
    Ok(files)
}

/// How the benchmark runs.
#[derive(Clone, Debug)]
pub struct BenchOptions {
    /// The task.
    pub task: BenchTask,
    /// The robot.
    pub profile: &'static Profile,
    /// The arenas.
    pub arenas: Vec<ArenaSource>,
    /// Noise draws per arena (`--seeds`): draws 1..=seeds, each with its own [`run_seed`].
    pub seeds: u64,
    /// The base seed (`--seed`) every run's emulator seed is derived from.
    pub seed: u64,
    /// Worker threads.
    pub jobs: usize,
    /// Simulated seconds per run.
    pub timeout_s: f64,
    /// Noise levels.
    pub noise: Noise,
    /// Draw a progress bar on stderr (only when it is a terminal).
    pub progress: bool,
    /// Robots per contest; above 1 the benchmark is `fleet_bench`'s.
    pub robots: usize,
    /// Go-to: before each run, the same robot (same seed) calibrates its odometry in the same
    /// arena ([`calibrate_odometry`](super::calibrate_odometry)) and the go-to run
    /// starts with the result set, as an operator who calibrated once and loads the parameter
    /// file.
    pub calibrate_odometry: bool,
    /// Parameters set before every run (id, value), as a station loading a parameter file
    /// (e.g. `--search`'s `search_mode`).
    pub params: Vec<(u16, f32)>,
}

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
    fn failed(arena: String, seed: u64, cause: Cause, error: String, wall_s: f64) -> Row {
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

/// Runs the benchmark.
pub fn run(opts: &BenchOptions) -> BenchReport {
    let jobs = run_list(opts.arenas.len(), opts.seed, opts.seeds);
    let started = Instant::now();
    let workers = opts.jobs.clamp(1, jobs.len().max(1));
    let rows = run_parallel(jobs.len(), workers, opts.progress, |i| {
        let (a, draw, seed) = jobs[i];
        let mut row = run_one(&opts.arenas[a], seed, opts);
        row.draw = draw;
        row
    });
    BenchReport {
        task: opts.task,
        profile: opts.profile.name,
        arenas: opts.arenas.len(),
        seeds: opts.seeds,
        seed: opts.seed,
        timeout_s: opts.timeout_s,
        jobs: workers,
        wall_s: started.elapsed().as_secs_f64(),
        summary: summarise(opts.task, &rows),
        rows,
    }
}

/// Runs `job(0..n)` on `workers` threads and returns the results in index order, whatever
/// order they finish in; with `progress`, a bar on stderr when it is a terminal.
pub(crate) fn run_parallel<T: Send>(
    n: usize,
    workers: usize,
    progress: bool,
    job: impl Fn(usize) -> T + Sync,
) -> Vec<T> {
    let started = Instant::now();
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<T>>> = Mutex::new((0..n).map(|_| None).collect());
    let workers = workers.clamp(1, n.max(1));
    let bar = progress && std::io::stderr().is_terminal();
    std::thread::scope(|scope| {
        for _ in 0..workers {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                if i >= n {
                    break;
                }
                let out = job(i);
                if let Ok(mut r) = results.lock() {
                    r[i] = Some(out);
                }
                done.fetch_add(1, Ordering::Relaxed);
            });
        }
        if bar {
            while done.load(Ordering::Relaxed) < n {
                draw_bar(done.load(Ordering::Relaxed), n, started.elapsed());
                std::thread::sleep(Duration::from_millis(200));
            }
            draw_bar(n, n, started.elapsed());
            eprintln!();
        }
    });
    results
        .into_inner()
        .unwrap_or_default()
        .into_iter()
        .flatten()
        .collect()
}

fn draw_bar(done: usize, total: usize, elapsed: Duration) {
    const WIDTH: usize = 30;
    let filled = done * WIDTH / total.max(1);
    let eta = if done > 0 && done < total {
        let per = elapsed.as_secs_f64() / done as f64;
        format!(", about {:.0} s left", per * (total - done) as f64)
    } else {
        String::new()
    };
    eprint!(
        "\r[{}{}] {done}/{total} runs, {:.0} s{eta}   ",
        "#".repeat(filled),
        " ".repeat(WIDTH - filled),
        elapsed.as_secs_f64()
    );
}

/// One (arena, seed) run, whatever happens in it.
fn run_one(source: &ArenaSource, seed: u64, opts: &BenchOptions) -> Row {
    let t0 = Instant::now();
    let label = source.label();
    let result = std::panic::catch_unwind(AssertUnwindSafe(|| run_checked(source, seed, opts)));
    match result {
        Ok(Ok(mut row)) => {
            row.wall_s = t0.elapsed().as_secs_f64();
            row
        }
        Ok(Err((cause, e))) => Row::failed(label, seed, cause, e, t0.elapsed().as_secs_f64()),
        Err(p) => {
            let msg = p
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| (*s).to_string()))
                .unwrap_or_default();
            Row::failed(label, seed, Cause::Panic, msg, t0.elapsed().as_secs_f64())
        }
    }
}

fn run_checked(
    source: &ArenaSource,
    seed: u64,
    opts: &BenchOptions,
) -> Result<Row, (Cause, String)> {
    let (arena, declared) = source
        .load_with_features()
        .map_err(|e| (Cause::ImportError, e))?;
    let mut so = ScenarioOptions::new(opts.profile, opts.task.scenario_task());
    so.seed = seed;
    so.timeout_s = opts.timeout_s;
    so.noise = opts.noise;
    so.params.extend(opts.params.iter().copied());
    let setup = |e: crate::scenarios::task::ScenarioError| (Cause::SetupError, e.to_string());
    let mut row = Row::failed(source.label(), seed, Cause::Timeout, String::new(), 0.0);
    row.error = None;
    if opts.calibrate_odometry {
        let c = crate::scenarios::calibrate_odometry::calibrate_before(&arena, &mut so)
            .map_err(setup)?;
        row.calibration = Some(c);
    }
    if opts.task == BenchTask::Forage {
        let r = crate::scenarios::forage::run_forage(arena, so).map_err(setup)?;
        row.success = r.all_delivered;
        row.cause = (!r.all_delivered).then_some(Cause::Timeout);
        row.sim_s = Some(r.sim_s);
        row.collisions = Some(r.collisions);
        row.pose_error_m = Some(r.pose_error_m);
        row.objects = Some(r.objects);
        row.delivered = Some(r.delivered);
        row.firmware_delivered = Some(r.firmware_delivered);
        return Ok(row);
    }
    let start = start_point(&arena, opts.profile).map_err(|e| (Cause::SetupError, e))?;
    let measured = arena.clone();
    let r = crate::scenarios::task::run_scenario(arena, so).map_err(setup)?;
    let (to_goal, ended) = routes(&measured, start, &r, opts.profile);
    let diameter = f64::from(opts.profile.body_diameter_m);
    row.features = breakdown::features_of(&measured, to_goal.as_ref(), &declared, diameter);
    if let Some(f) = to_goal {
        row.free_path_m = Some(f.length_m);
        row.detour_ratio = Some(f.detour_ratio);
        row.bottleneck_m = Some(f.bottleneck_m);
    }
    if let Some(f) = ended.filter(|f| f.length_m > 0.0) {
        let driven = r.runs.last().map_or(r.distance_m, |x| x.distance_m);
        row.route_ratio = Some(driven / f.length_m);
    }
    let started_inside =
        r.started_in_target || (start - Point::new(r.goal.x_m, r.goal.y_m)).norm() <= r.tolerance_m;
    row.cause = cause_of(&r, started_inside, diameter);
    row.success = row.cause.is_none();
    row.sim_s = Some(r.sim_s);
    row.collisions = Some(r.collisions);
    row.goal_error_m = Some(r.goal_error_m);
    row.pose_error_m = Some(r.pose_error_m);
    row.arrived = Some(r.arrived);
    row.reached = Some(r.reached);
    row.started_inside = Some(started_inside);
    if opts.task == BenchTask::ExploreThenPlan {
        let run = |i: usize| r.runs.get(i);
        row.run1_s = run(0).map(|x| x.sim_s);
        row.run2_s = run(1).map(|x| x.sim_s);
        row.run1_reached = run(0).map(|x| x.reached);
        row.run2_reached = Some(run(1).is_some_and(|x| x.reached));
    }
    Ok(row)
}

/// The shortest free path from `start` to the runner's goal within its tolerance (the goal's
/// target area for a beacon search), and, when the run ended in another goal target (a lab
/// with several beacons: any counts), the one to that target, which the route is judged by.
fn routes(
    arena: &Arena,
    start: Point,
    r: &ScenarioReport,
    profile: &Profile,
) -> (Option<FreePath>, Option<FreePath>) {
    let radius = f64::from(profile.body_diameter_m) / 2.0;
    let goal = Point::new(r.goal.x_m, r.goal.y_m);
    let to_goal = free_path(arena, start, goal, r.tolerance_m, radius);
    let end = Point::new(r.final_true.x_m, r.final_true.y_m);
    let search = matches!(r.task, Task::ReachBeacon | Task::ExploreThenPlan);
    let ended_elsewhere = arena
        .goal_targets()
        .find(|t| (end - t.centre).norm() <= t.radius_m)
        .filter(|t| search && (t.centre - goal).norm() > 1e-6);
    let ended = match ended_elsewhere {
        Some(t) => free_path(arena, start, t.centre, t.radius_m, radius),
        None => to_goal,
    };
    (to_goal, ended)
}

/// Why a scenario run failed (None: it succeeded), from the runner's ground truth:
/// `started_inside` is whether the start was already within the goal's tolerance,
/// `diameter_m` the robot's body diameter (a run that stayed within it over its last
/// window was stuck, not still searching).
pub fn cause_of(r: &ScenarioReport, started_inside: bool, diameter_m: f64) -> Option<Cause> {
    let last = r.runs.last();
    if started_inside {
        Some(Cause::StartedInsideTarget)
    } else if r.unreachable && !r.reached {
        Some(Cause::Unreachable)
    } else if r.reached {
        None
    } else if r.arrived {
        Some(Cause::WrongArrival)
    } else if last.is_some_and(|l| l.no_path_on_map) {
        Some(Cause::NoPathOnExploredMap)
    } else if last.is_some_and(|l| l.last_window_span_m < diameter_m) {
        Some(Cause::Stuck)
    } else {
        Some(Cause::Timeout)
    }
}

/// Where the runner will start the robot (the same rule: `sim::start_pose`).
fn start_point(arena: &Arena, profile: &Profile) -> Result<Point, String> {
    let world =
        crate::world::World::new(arena.clone(), Vec::new(), None).map_err(|e| e.to_string())?;
    let radius = f64::from(profile.body_diameter_m) / 2.0;
    let p = crate::sim::start_pose(&world, None, radius).map_err(|e| e.to_string())?;
    Ok(Point::new(p.x, p.y))
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_is_nearest_rank() {
        let s = spread((1..=10).map(f64::from).collect()).expect("values");
        assert_eq!((s.median, s.p90), (5.0, 9.0));
        assert!(spread(Vec::new()).is_none());
    }

    #[test]
    fn every_arena_and_draw_gets_its_own_seed_and_the_same_base_the_same_ones() {
        let list = run_list(3, 1, 2);
        assert_eq!(list.len(), 6);
        let seeds: std::collections::BTreeSet<u64> = list.iter().map(|x| x.2).collect();
        assert_eq!(seeds.len(), 6, "{list:?}");
        assert_eq!(
            list.iter().map(|x| (x.0, x.1)).collect::<Vec<_>>(),
            vec![(0, 1), (0, 2), (1, 1), (1, 2), (2, 1), (2, 2)]
        );
        assert_eq!(list, run_list(3, 1, 2));
        assert_eq!(run_seed(1, 2, 2), list[5].2);
        // More draws keep the first ones: --seeds 5 extends --seeds 2.
        assert_eq!(run_list(3, 1, 5)[0..2], list[0..2]);
        assert_ne!(run_list(3, 2, 2), list, "another base seed, other draws");
    }

    #[test]
    fn generated_specs_resolve_and_bad_ones_name_the_flag() {
        let a = resolve_arenas(&["generated:3".into()], Kind::Maze).expect("valid");
        assert_eq!(a[2], ArenaSource::Generated(Kind::Maze, 3));
        for bad in ["generated:0", "generated:x", "generated:-1"] {
            let e = resolve_arenas(&[bad.into()], Kind::Box).unwrap_err();
            assert!(e.starts_with("--arenas"), "{e}");
        }
    }
}
