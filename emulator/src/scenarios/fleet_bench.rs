//! The contest benchmark (issue 17): over many arenas, each robot of a Micro-Rato contest
//! against the same robot alone.
//!
//! Layer: std, on top of [`contest`](super::contest) and
//! [`run_scenario`](super::task::run_scenario), sharing [`bench`](super::bench)'s arenas and
//! worker pool; `robot-emulator bench --robots N` only parses and prints.
//!
//! One job per (arena, seed): the contest of N micro-rato robots (reach-beacon, starts by the
//! fleet's rule), then each robot alone from the start it had in the contest, with the seed it
//! had there (`fleet::robot_seed`): the same robot, the same noise draws while nothing differs,
//! the same arena, only the other robots missing. A robot "arrives" when the runner's
//! `reached` holds (arrival reported and the TRUE pose in the goal area), as in `bench`.
//! Robot-robot collisions are each robot's own count (a contact between two robots counts once
//! for each of them).
//!
//! Determinism: a job depends only on (arena, seed); rows come out in (arena, seed) order.

use std::panic::AssertUnwindSafe;
use std::time::Instant;

use serde::Serialize;

use crate::fleet::RobotSpec;
use crate::scenarios::bench::{run_parallel, ArenaSource, BenchOptions, Spread};
use crate::scenarios::contest::{run_contest, ContestOptions};
use crate::scenarios::task::{run_scenario, ScenarioOptions, Task};

/// One robot in one (arena, seed) job.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RobotRow {
    /// 1-based robot number.
    pub robot: usize,
    /// Reached the goal area in the contest.
    pub fleet_reached: bool,
    /// Its arrival time in the contest, simulated seconds.
    pub fleet_s: Option<f64>,
    /// Its place in the contest.
    pub rank: usize,
    /// Wall contacts in the contest.
    pub fleet_wall_collisions: u32,
    /// Contacts with other robots in the contest.
    pub robot_collisions: u32,
    /// Reached it alone (same start, same seed).
    pub solo_reached: bool,
    /// Its time alone, simulated seconds (when it reached).
    pub solo_s: Option<f64>,
    /// Wall contacts alone.
    pub solo_wall_collisions: u32,
}

/// One (arena, seed) job.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FleetRow {
    /// Arena label.
    pub arena: String,
    /// Seed.
    pub seed: u64,
    /// Each robot (empty when the job failed).
    pub robots: Vec<RobotRow>,
    /// Import, setup or panic message.
    pub error: Option<String>,
    /// Wall-clock seconds of the job.
    pub wall_s: f64,
}

/// One robot number's figures over every job.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RobotSummary {
    /// 1-based robot number.
    pub robot: usize,
    /// Jobs where it reached the goal area alone.
    pub solo_reached: usize,
    /// Jobs where it reached it in the contest.
    pub fleet_reached: usize,
    /// Reached alone but not in the contest.
    pub lost_to_contest: usize,
    /// Reached in the contest but not alone.
    pub only_in_contest: usize,
    /// Contests it won.
    pub wins: usize,
    /// Its contacts with other robots, all jobs.
    pub robot_collisions: u64,
}

/// The whole benchmark.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FleetBenchReport {
    /// `reach-beacon`.
    pub task: &'static str,
    /// Robots per contest.
    pub robots: usize,
    /// Arenas.
    pub arenas: usize,
    /// Seeds per arena.
    pub seeds: u64,
    /// Simulated seconds allowed per run.
    pub timeout_s: f64,
    /// Worker threads.
    pub jobs: usize,
    /// Wall-clock seconds.
    pub wall_s: f64,
    /// Jobs that ran (arenas x seeds, less errors).
    pub completed: usize,
    /// Jobs that failed to set up (import, setup, panic).
    pub errors: usize,
    /// Per robot number.
    pub per_robot: Vec<RobotSummary>,
    /// Robot-runs that reached alone, over all robots.
    pub solo_reached: usize,
    /// Robot-runs that reached in the contest.
    pub fleet_reached: usize,
    /// Contests in which at least two robots touched.
    pub contests_with_robot_contact: usize,
    /// Robot-robot contacts per contest (each counted by both robots, halved: contacts).
    pub robot_contacts_per_contest: f64,
    /// Wall contacts per robot-run, alone and in the contest.
    pub wall_collisions_solo_mean: f64,
    /// See `wall_collisions_solo_mean`.
    pub wall_collisions_fleet_mean: f64,
    /// Arrival times of robots that reached, alone and in the contest.
    pub solo_time_s: Option<Spread>,
    /// See `solo_time_s`.
    pub fleet_time_s: Option<Spread>,
    /// Every job, in (arena, seed) order.
    pub rows: Vec<FleetRow>,
}

/// Runs the contest benchmark.
pub fn run(opts: &BenchOptions) -> FleetBenchReport {
    // The same seeds as the one-robot bench, so robot 1 alone is exactly its run.
    let jobs: Vec<(usize, u64)> =
        crate::scenarios::bench::run_list(opts.arenas.len(), opts.seed, opts.seeds)
            .into_iter()
            .map(|(a, _, seed)| (a, seed))
            .collect();
    let started = Instant::now();
    let workers = opts.jobs.clamp(1, jobs.len().max(1));
    let rows = run_parallel(jobs.len(), workers, opts.progress, |i| {
        let (a, seed) = jobs[i];
        let t0 = Instant::now();
        let source = &opts.arenas[a];
        let result = std::panic::catch_unwind(AssertUnwindSafe(|| one(source, seed, opts)));
        let (robots, error) = match result {
            Ok(Ok(r)) => (r, None),
            Ok(Err(e)) => (Vec::new(), Some(e)),
            Err(p) => {
                let msg = p
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| p.downcast_ref::<&str>().map(|s| (*s).to_string()))
                    .unwrap_or_default();
                (Vec::new(), Some(format!("panic: {msg}")))
            }
        };
        FleetRow {
            arena: source.label(),
            seed,
            robots,
            error,
            wall_s: t0.elapsed().as_secs_f64(),
        }
    });
    summarise(opts, rows, workers, started.elapsed().as_secs_f64())
}

/// One (arena, seed): the contest, then each robot alone.
fn one(source: &ArenaSource, seed: u64, opts: &BenchOptions) -> Result<Vec<RobotRow>, String> {
    let arena = source.load()?;
    let specs = vec![
        RobotSpec {
            profile: opts.profile,
            start: None,
        };
        opts.robots
    ];
    let contest = run_contest(
        arena.clone(),
        &ContestOptions {
            robots: specs,
            seed,
            timeout_s: opts.timeout_s,
            noise: opts.noise,
        },
    )
    .map_err(|e| e.to_string())?;
    let mut rows = Vec::with_capacity(contest.robots.len());
    for r in &contest.robots {
        let mut so = ScenarioOptions::new(opts.profile, Task::ReachBeacon);
        so.seed = r.seed;
        so.timeout_s = opts.timeout_s;
        so.noise = opts.noise;
        so.start = Some(crate::arena::Pose {
            x: r.start.x_m,
            y: r.start.y_m,
            heading: r.start.heading_rad,
        });
        let solo =
            run_scenario(arena.clone(), so).map_err(|e| format!("robot {} alone: {e}", r.robot))?;
        rows.push(RobotRow {
            robot: r.robot,
            fleet_reached: r.reached,
            fleet_s: r.arrival_s.filter(|_| r.reached),
            rank: r.rank,
            fleet_wall_collisions: r.wall_collisions,
            robot_collisions: r.robot_collisions,
            solo_reached: solo.reached,
            solo_s: solo.reached.then_some(solo.sim_s),
            solo_wall_collisions: solo.collisions,
        });
    }
    Ok(rows)
}

fn summarise(
    opts: &BenchOptions,
    rows: Vec<FleetRow>,
    workers: usize,
    wall_s: f64,
) -> FleetBenchReport {
    let done: Vec<&FleetRow> = rows.iter().filter(|r| r.error.is_none()).collect();
    let all: Vec<&RobotRow> = done.iter().flat_map(|r| r.robots.iter()).collect();
    let per_robot = (1..=opts.robots)
        .map(|k| {
            let mine: Vec<&&RobotRow> = all.iter().filter(|r| r.robot == k).collect();
            RobotSummary {
                robot: k,
                solo_reached: mine.iter().filter(|r| r.solo_reached).count(),
                fleet_reached: mine.iter().filter(|r| r.fleet_reached).count(),
                lost_to_contest: mine
                    .iter()
                    .filter(|r| r.solo_reached && !r.fleet_reached)
                    .count(),
                only_in_contest: mine
                    .iter()
                    .filter(|r| !r.solo_reached && r.fleet_reached)
                    .count(),
                wins: mine
                    .iter()
                    .filter(|r| r.rank == 1 && r.fleet_reached)
                    .count(),
                robot_collisions: mine.iter().map(|r| u64::from(r.robot_collisions)).sum(),
            }
        })
        .collect();
    let mean = |v: u64, n: usize| if n == 0 { 0.0 } else { v as f64 / n as f64 };
    let robot_contacts: u64 = all.iter().map(|r| u64::from(r.robot_collisions)).sum();
    let spread = |v: Vec<f64>| crate::scenarios::bench::spread_of(v);
    FleetBenchReport {
        task: "reach-beacon",
        robots: opts.robots,
        arenas: opts.arenas.len(),
        seeds: opts.seeds,
        timeout_s: opts.timeout_s,
        jobs: workers,
        wall_s,
        completed: done.len(),
        errors: rows.len() - done.len(),
        per_robot,
        solo_reached: all.iter().filter(|r| r.solo_reached).count(),
        fleet_reached: all.iter().filter(|r| r.fleet_reached).count(),
        contests_with_robot_contact: done
            .iter()
            .filter(|r| r.robots.iter().any(|x| x.robot_collisions > 0))
            .count(),
        robot_contacts_per_contest: mean(robot_contacts, done.len()) / 2.0,
        wall_collisions_solo_mean: mean(
            all.iter().map(|r| u64::from(r.solo_wall_collisions)).sum(),
            all.len(),
        ),
        wall_collisions_fleet_mean: mean(
            all.iter().map(|r| u64::from(r.fleet_wall_collisions)).sum(),
            all.len(),
        ),
        solo_time_s: spread(all.iter().filter_map(|r| r.solo_s).collect()),
        fleet_time_s: spread(all.iter().filter_map(|r| r.fleet_s).collect()),
        rows,
    }
}

/// The report as text for a terminal.
pub fn render(r: &FleetBenchReport) -> String {
    let n = r.completed;
    let mut out = format!(
        "bench reach-beacon contest: {} robots, {} arenas x {} seeds = {} contests ({} failed \
         to set up), {:.0} s timeout ({} jobs, {:.1} s wall)\n\
         robot  alone      in contest  lost to contest  only in contest  wins  robot contacts\n",
        r.robots, r.arenas, r.seeds, n, r.errors, r.timeout_s, r.jobs, r.wall_s
    );
    let pct = |a: usize| {
        if n == 0 {
            0.0
        } else {
            a as f64 * 100.0 / n as f64
        }
    };
    for p in &r.per_robot {
        out += &format!(
            "{:>5}  {:>4} {:>5.1}%  {:>4} {:>5.1}%  {:>15}  {:>15}  {:>4}  {:>14}\n",
            p.robot,
            p.solo_reached,
            pct(p.solo_reached),
            p.fleet_reached,
            pct(p.fleet_reached),
            p.lost_to_contest,
            p.only_in_contest,
            p.wins,
            p.robot_collisions
        );
    }
    let t = |s: Option<Spread>| {
        s.map_or_else(
            || "none".to_string(),
            |s| format!("median {:.1} s, p90 {:.1} s", s.median, s.p90),
        )
    };
    out += &format!(
        "all    {} alone, {} in the contest, of {} robot-runs\n\
         robot-robot contacts: {:.2} per contest; {} of {} contests had one\n\
         wall contacts per robot-run: {:.2} alone, {:.2} in the contest\n\
         arrival time: alone {}; in the contest {}\n",
        r.solo_reached,
        r.fleet_reached,
        n * r.robots,
        r.robot_contacts_per_contest,
        r.contests_with_robot_contact,
        n,
        r.wall_collisions_solo_mean,
        r.wall_collisions_fleet_mean,
        t(r.solo_time_s),
        t(r.fleet_time_s)
    );
    out
}
