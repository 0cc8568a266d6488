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
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use robot_firmware::Profile;
use serde::Serialize;

use crate::arena::free_path::{free_path, FreePath};
use crate::arena::Arena;
use crate::arena_gen::Kind;
use crate::geometry::Point;
use crate::scenarios::task::{ScenarioOptions, ScenarioReport, Task};
use crate::sensors::Noise;

mod arenas;
pub mod breakdown;
mod report;

pub(crate) use arenas::run_list;
pub use arenas::{resolve_arenas, run_seed, ArenaSource, MAX_GENERATED};
pub use breakdown::Breakdown;
pub(crate) use report::spread;
pub use report::{
    render, spread_of, summarise, BenchReport, CalibrationSummary, Cause, ForageSummary,
    PlanSummary, Row, Spread, Summary,
};

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
