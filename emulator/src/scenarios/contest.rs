//! The Micro-Rato contest, headless: several robots in one arena, each searching for the
//! beacon at once, each one's result and a ranking.
//!
//! Layer: std, on top of [`Fleet`] and the scenario runner's command path (every robot is
//! given its task exactly as `run_scenario` gives one robot its: `Core::apply`).
//!
//! Scoring. Seed 004 §2 (the paper's text): the robots must go "from a start area to a goal
//! area in the shortest time possible and minimizing collisions with the environment or the
//! other competing robots. Three robots compete simultaneously." The paper gives no formula
//! (no points, no penalty per collision, no time limit). What this runner does, its own
//! choice where the paper is silent:
//! 1. robots that reached the goal area (the firmware reported arrival and the TRUE pose is
//!    in the target, as `run_scenario`'s `reached`) rank before those that did not;
//! 2. among those that reached it: earlier arrival first (the firmware's arrival report, to
//!    the millisecond), then fewer collisions (walls and robots together, each contact once);
//! 3. among the others: nearer the goal's centre at the end first, then fewer collisions;
//! 4. a remaining tie: the lower robot number.
//!
//! The run ends when every robot has arrived (and settled [`SETTLE_MS`]) or at the timeout;
//! a robot that has arrived stays where it stopped, an obstacle for the others, as on the
//! contest floor.
//!
//! What can fail: the fleet's setup, a task other than reach-beacon, a refused command.

use std::collections::VecDeque;
use std::time::Instant;

use protocol::Command;
use serde::Serialize;
use thiserror::Error;

use super::task::{apply, set_arrival, PoseReport, ScenarioError, SETTLE_MS, STUCK_WINDOW_S};
use crate::arena::Arena;
use crate::fleet::{robot_seed, Fleet, FleetError, RobotSpec};
use crate::geometry::Point;
use crate::sensors::Noise;
use crate::sim::SimConfig;

/// The scoring rule, as reports state it.
pub const SCORING: &str =
    "the Dom Dinis paper §2: shortest time, fewest collisions with the environment \
     or the other robots (no formula given). Here: robots in the goal area first, by arrival \
     time, then by collisions (walls + robots); then the others, nearest the goal first, then \
     by collisions; then by robot number";

/// Sampling period of the stuck window, ms (as `run_scenario`).
const WINDOW_SAMPLE_MS: u64 = 100;

/// How a contest is run.
#[derive(Clone, Debug)]
pub struct ContestOptions {
    /// The robots (profiles may be mixed; starts default to the arena's start areas).
    pub robots: Vec<RobotSpec>,
    /// The run's seed (robot `i` draws from `fleet::robot_seed(seed, i)`).
    pub seed: u64,
    /// Simulated seconds before the contest ends.
    pub timeout_s: f64,
    /// Noise levels.
    pub noise: Noise,
}

/// Why a contest could not run.
#[derive(Debug, Error)]
pub enum ContestError {
    /// The fleet could not be set up.
    #[error(transparent)]
    Fleet(#[from] FleetError),
    /// A robot refused its task, or the timeout is bad.
    #[error("robot {robot}: {source}")]
    Robot {
        /// 1-based robot number.
        robot: usize,
        /// Why.
        source: ScenarioError,
    },
    /// A robot that cannot search for the beacon.
    #[error(
        "robot {robot} ({profile}) has no compass and beacon sensor: the contest is seed \
         004's beacon search; use micro-rato robots"
    )]
    Profile {
        /// 1-based robot number.
        robot: usize,
        /// Its profile.
        profile: &'static str,
    },
    /// The arena has no goal area.
    #[error("arena {0:?} has no target area to reach")]
    NoTarget(String),
    /// The timeout is not a finite positive number of seconds.
    #[error("timeout {0} s must be finite and > 0")]
    BadTimeout(f64),
}

/// One robot's contest.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RobotResult {
    /// 1-based robot number (its pty is `--link` followed by this number).
    pub robot: usize,
    /// Profile name.
    pub profile: &'static str,
    /// Its own seed (`fleet::robot_seed`): the same robot alone is `run` with this seed and
    /// this start.
    pub seed: u64,
    /// Where it started.
    pub start: PoseReport,
    /// Its place in the ranking, 1 = winner.
    pub rank: usize,
    /// The firmware reported arrival.
    pub arrived: bool,
    /// Arrived and the true pose is in the goal area (not when it started there).
    pub reached: bool,
    /// It started inside the goal area (no success, whatever it reports).
    pub started_in_target: bool,
    /// Simulated seconds from the start to the firmware's arrival report.
    pub arrival_s: Option<f64>,
    /// Wall contacts.
    pub wall_collisions: u32,
    /// Contacts with other robots.
    pub robot_collisions: u32,
    /// Both.
    pub collisions: u32,
    /// Ground distance travelled, metres.
    pub distance_m: f64,
    /// Final true distance to the goal's centre, metres.
    pub goal_error_m: f64,
    /// Final distance between true and believed position, metres.
    pub pose_error_m: f64,
    /// How far it moved in the last [`STUCK_WINDOW_S`] of the contest, metres.
    pub last_window_span_m: f64,
    /// Final true pose.
    pub final_true: PoseReport,
}

/// A contest's outcome.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ContestReport {
    /// Arena name.
    pub arena: String,
    /// `reach-beacon`.
    pub task: &'static str,
    /// The run's seed.
    pub seed: u64,
    /// Simulated seconds allowed.
    pub timeout_s: f64,
    /// The scoring rule used ([`SCORING`]).
    pub scoring: &'static str,
    /// Simulated seconds the contest ran.
    pub sim_s: f64,
    /// Wall-clock seconds.
    pub wall_s: f64,
    /// Each robot, in robot order.
    pub robots: Vec<RobotResult>,
    /// Robot numbers, winner first.
    pub ranking: Vec<usize>,
}

/// Runs a contest to the last arrival or the timeout.
pub fn run_contest(arena: Arena, opts: &ContestOptions) -> Result<ContestReport, ContestError> {
    if !(opts.timeout_s.is_finite() && opts.timeout_s > 0.0) {
        return Err(ContestError::BadTimeout(opts.timeout_s));
    }
    let sensors = protocol::caps::COMPASS | protocol::caps::BEACON;
    for (i, r) in opts.robots.iter().enumerate() {
        if !r.profile.has(sensors) {
            return Err(ContestError::Profile {
                robot: i + 1,
                profile: r.profile.name,
            });
        }
    }
    let target = arena
        .target()
        .copied()
        .ok_or_else(|| ContestError::NoTarget(arena.name.clone()))?;
    let goal = target.centre;
    let name = arena.name.clone();
    let base = SimConfig {
        seed: opts.seed,
        noise: opts.noise,
        ..SimConfig::new(&robot_firmware::MICRO_RATO)
    };
    let mut fleet = Fleet::new(arena, &base, &opts.robots)?;
    let n = fleet.len();
    let starts: Vec<_> = fleet.sims().iter().map(|s| s.truth()).collect();
    // In any target the search may end in, as `run_scenario` judges a start.
    let started_in: Vec<bool> = fleet
        .sims()
        .iter()
        .zip(&starts)
        .map(|(sim, s)| sim.world().in_target(crate::geometry::Point::new(s.x, s.y)))
        .collect();
    for (i, sim) in fleet.sims_mut().iter_mut().enumerate() {
        let robot = i + 1;
        let fail = |source| ContestError::Robot { robot, source };
        set_arrival(sim, None, target.radius_m).map_err(fail)?;
        apply(sim, Command::StartExploration, "StartExploration").map_err(fail)?;
    }
    let started = Instant::now();
    let timeout_ms = (opts.timeout_s * 1000.0).ceil() as u64;
    let mut arrival_ms: Vec<Option<u64>> = vec![None; n];
    let samples = (STUCK_WINDOW_S * 1000.0) as usize / WINDOW_SAMPLE_MS as usize;
    let mut windows: Vec<VecDeque<(f64, f64)>> = vec![VecDeque::with_capacity(samples + 1); n];
    for t in 0..timeout_ms {
        fleet.step();
        let now_ms = t + 1;
        for (i, sim) in fleet.sims().iter().enumerate() {
            if arrival_ms[i].is_none() && sim.robot().arrived() {
                arrival_ms[i] = Some(now_ms);
            }
        }
        if t % WINDOW_SAMPLE_MS == 0 {
            for (w, sim) in windows.iter_mut().zip(fleet.sims()) {
                if w.len() == samples {
                    w.pop_front();
                }
                let p = sim.truth();
                w.push_back((p.x, p.y));
            }
        }
        let last = arrival_ms.iter().copied().collect::<Option<Vec<u64>>>();
        if last.is_some_and(|a| a.iter().all(|&ms| now_ms >= ms + SETTLE_MS)) {
            break;
        }
    }
    let wall_s = started.elapsed().as_secs_f64();
    let mut robots: Vec<RobotResult> = fleet
        .sims()
        .iter()
        .enumerate()
        .map(|(i, sim)| {
            let t = sim.truth();
            let here = Point::new(t.x, t.y);
            let goal_error_m = (here - goal).norm();
            let arrived = arrival_ms[i].is_some();
            let inside = goal_error_m <= target.radius_m || sim.world().in_target(here);
            let last_window_span_m = windows[i]
                .iter()
                .map(|&(x, y)| (x - t.x).hypot(y - t.y))
                .fold(0.0, f64::max);
            RobotResult {
                robot: i + 1,
                profile: sim.robot().profile().name,
                seed: robot_seed(opts.seed, i),
                start: starts[i].into(),
                rank: 0,
                arrived,
                reached: arrived && inside && !started_in[i],
                started_in_target: started_in[i],
                arrival_s: arrival_ms[i].map(|ms| ms as f64 * 1e-3),
                wall_collisions: sim.collisions(),
                robot_collisions: sim.robot_collisions(),
                collisions: sim.collisions().saturating_add(sim.robot_collisions()),
                distance_m: sim.distance_m(),
                goal_error_m,
                pose_error_m: sim.pose_error_m(),
                last_window_span_m,
                final_true: t.into(),
            }
        })
        .collect();
    let ranking = rank(&robots);
    for (place, &robot) in ranking.iter().enumerate() {
        if let Some(r) = robots.get_mut(robot - 1) {
            r.rank = place + 1;
        }
    }
    Ok(ContestReport {
        arena: name,
        task: "reach-beacon",
        seed: opts.seed,
        timeout_s: opts.timeout_s,
        scoring: SCORING,
        sim_s: fleet.now_us() as f64 * 1e-6,
        wall_s,
        robots,
        ranking,
    })
}

/// Robot numbers in ranking order by the [`SCORING`] rule.
pub fn rank(robots: &[RobotResult]) -> Vec<usize> {
    let mut order: Vec<&RobotResult> = robots.iter().collect();
    order.sort_by(|a, b| {
        b.reached
            .cmp(&a.reached)
            .then_with(|| {
                if a.reached && b.reached {
                    let (ta, tb) = (
                        a.arrival_s.unwrap_or(f64::MAX),
                        b.arrival_s.unwrap_or(f64::MAX),
                    );
                    ta.total_cmp(&tb)
                } else {
                    std::cmp::Ordering::Equal
                }
            })
            .then_with(|| {
                if a.reached {
                    a.collisions.cmp(&b.collisions)
                } else {
                    a.goal_error_m
                        .total_cmp(&b.goal_error_m)
                        .then(a.collisions.cmp(&b.collisions))
                }
            })
            .then(a.robot.cmp(&b.robot))
    });
    order.into_iter().map(|r| r.robot).collect()
}

/// The report as text for a terminal: one line per robot in ranking order, then the rule.
pub fn render(r: &ContestReport) -> String {
    let mut out = format!(
        "{}: Micro-Rato contest, {} robots, reach-beacon, seed {}, {:.1} s simulated ({:.2} s wall)\n\
         rank robot profile     result         arrival   walls robots  dist m  goal m\n",
        r.arena,
        r.robots.len(),
        r.seed,
        r.sim_s,
        r.wall_s
    );
    for &n in &r.ranking {
        let Some(x) = r.robots.get(n - 1) else {
            continue;
        };
        let result = if x.started_in_target {
            "started inside"
        } else if x.reached {
            "reached"
        } else if x.arrived {
            "wrong arrival"
        } else {
            "not reached"
        };
        let arrival = x
            .arrival_s
            .map_or_else(|| "-".to_string(), |s| format!("{s:.1} s"));
        out += &format!(
            "{:>4} {:>5} {:<10} {:<14} {:>8} {:>6} {:>6} {:>7.2} {:>7.2}\n",
            x.rank,
            x.robot,
            x.profile,
            result,
            arrival,
            x.wall_collisions,
            x.robot_collisions,
            x.distance_m,
            x.goal_error_m
        );
    }
    out += &format!("scoring: {}\n", r.scoring);
    out
}
