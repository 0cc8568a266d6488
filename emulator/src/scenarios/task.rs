//! Headless scenario runs: one task, one arena, as fast as the host allows, and a report.
//!
//! Layer: std, on top of [`Sim`]; used by tests, benchmarks, the paper reproductions and a
//! future `robot-emulator run` subcommand. There is no station and no link session: the task
//! is given to the firmware through its own command path, `Core::apply` (exactly what an
//! accepted `Command` frame does), and the run ends when the firmware reports arrival (plus a
//! short settle so the true pose is taken at rest) or at the timeout.
//!
//! What the firmware is told, and only that, each as a station would over the link: the
//! task's goal; the arrival radius (Khepera: parameter 14, drift arrival; micro-rato:
//! parameter 26, guided arrival); for a robot with a beacon sensor the beacon position
//! (parameters 21/22) and the arena's bounds (the dead reckoning's validation rectangle, seed
//! 004 §4, parameters 27-30). Never the pose, except where an operator would: between the
//! two runs of explore-then-plan the robot is carried back to the start and told so.
//!
//! "Reached" (decided here, documented in [`ScenarioReport::reached`]): the firmware reported
//! arrival AND its TRUE position is within the tolerance of the goal. Default tolerance:
//! Khepera 5 cm (seed 000 §4.4, Fig. 17: target reached with a 5 cm tolerance); micro-rato the
//! radius of the arena's target circle when the goal is that target (seed 004 §2: the goal
//! area), else 0.3 m (seed 004 §4: dead-reckoning accuracy in free motion).
//!
//! The firmware stops as soon as it BELIEVES it is within its arrival radius, so with the
//! arrival radius equal to the tolerance (the Khepera's 5 cm in both roles) the true error
//! lands on the tolerance's edge and "reached" would be a coin toss decided by the sign of the
//! odometry error. The runner therefore tells the firmware to arrive within
//! `min(firmware default, tolerance / 2)`, leaving half the tolerance for odometry error
//! (Khepera: 2.5 cm; the real run of seed 000 Fig. 17 ended 2.2 cm from its target).
//!
//! What can fail: an invalid setup ([`SimError`]), a task without a goal, a command the
//! firmware refuses ([`ScenarioError`]). The run itself cannot fail.

use std::time::Instant;

use protocol::units::{point_mm, OutOfRange};
use protocol::{Command, NackReason, ParamId};
use robot_firmware::link::Reply;
use robot_firmware::params::id as param;
use robot_firmware::Profile;
use serde::Serialize;
use thiserror::Error;

use crate::arena::{Arena, Pose};
use crate::sensors::Noise;
use crate::sim::{Sim, SimConfig, SimError};

/// Settle time after the firmware reports arrival, ms (a few motor time constants).
pub const SETTLE_MS: u64 = 500;
/// Khepera go-to tolerance, metres. seed 000 §4.4 / Fig. 17: 5 cm.
pub const KHEPERA_TOLERANCE_M: f64 = 0.05;
/// Micro-rato tolerance for a goal that is not the arena's target. seed 004 §4: 0.3 m.
pub const RATO_POINT_TOLERANCE_M: f64 = 0.3;
/// The end of a run over which [`RunReport::last_window_span_m`] is measured, seconds.
pub const STUCK_WINDOW_S: f64 = 60.0;
/// Sampling period of that window, ms.
const WINDOW_SAMPLE_MS: u64 = 100;

/// A point in the map frame, metres.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct GoalPoint {
    /// x, metres.
    pub x_m: f64,
    /// y, metres.
    pub y_m: f64,
}

/// What the robot is asked to do.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Task {
    /// Go to a point; `None` = the arena's goal (its marked goal, else its target's centre).
    GoTo(Option<GoalPoint>),
    /// Seed 004 §5, Fig. 4: the reactive goal search (with mapping) from the start to the
    /// goal area, which the ground sensor detects.
    ReachBeacon,
    /// Seed 004 §5-7: run 1 explores as `ReachBeacon`; the robot then segments the map it
    /// built and plans from the start to where it found the goal; it is carried back to the
    /// start and run 2 executes the plan.
    ExploreThenPlan,
    /// Seed 000 §7 foraging: objects from lit sources to the home base
    /// ([`run_forage`](super::forage::run_forage), which has its own report; [`run_scenario`]
    /// refuses it).
    Forage,
}

/// One run of a scenario (explore-then-plan has two).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunReport {
    /// `explore`, `execute_plan` or `go_to`.
    pub kind: &'static str,
    /// The firmware reported arrival in the goal area.
    pub arrived: bool,
    /// Arrived, and the TRUE position is within the tolerance of the goal.
    pub reached: bool,
    /// Simulated seconds of this run.
    pub sim_s: f64,
    /// Wall contacts during this run.
    pub collisions: u32,
    /// Ground distance of this run, metres.
    pub distance_m: f64,
    /// Distance between true and believed position at the end, metres.
    pub pose_error_m: f64,
    /// Known (free or obstacle) cells of the robot's map at the end, if it has one.
    pub map_known_cells: Option<u32>,
    /// Regions and waypoints of the plan run 2 executed.
    pub plan_regions: Option<u32>,
    /// Farthest the TRUE position was from where this run ended during its last
    /// [`STUCK_WINDOW_S`], metres: a run that timed out with this under a body diameter was
    /// stuck, not still searching.
    pub last_window_span_m: f64,
    /// Run 2 of explore-then-plan only: the robot refused to plan (`Unreachable` or
    /// `BadPoint`) because its own explored map does not connect the start and where it
    /// found the goal. The robot's failure (its exploration left no path), not the setup's.
    pub no_path_on_map: bool,
}

/// How a scenario is run. [`ScenarioOptions::new`] gives the defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct ScenarioOptions {
    /// Which robot.
    pub profile: &'static Profile,
    /// The task.
    pub task: Task,
    /// The run's seed.
    pub seed: u64,
    /// Simulated seconds before giving up.
    pub timeout_s: f64,
    /// Noise levels.
    pub noise: Noise,
    /// Start pose (default: as [`SimConfig::start`]).
    pub start: Option<Pose>,
    /// Goal tolerance (default: see the module text).
    pub tolerance_m: Option<f64>,
    /// Arrival radius the firmware is told (default: see the module text).
    pub arrival_m: Option<f64>,
    /// True wheel distance (default nominal).
    pub true_wheel_distance_m: Option<f64>,
    /// Wheel bias (default drawn from the seed).
    pub wheel_bias: Option<[f64; 2]>,
    /// Slip (default none).
    pub slip: f64,
    /// Parameters set before the task, as an operator loads a saved parameter file (e.g. the
    /// odometry calibration's wheel distance and ratio); id and value.
    pub params: Vec<(u16, f32)>,
}

impl ScenarioOptions {
    /// Defaults: seed 0, 120 s, the papers' noise.
    pub fn new(profile: &'static Profile, task: Task) -> ScenarioOptions {
        ScenarioOptions {
            profile,
            task,
            seed: 0,
            timeout_s: 120.0,
            noise: Noise::default(),
            start: None,
            tolerance_m: None,
            arrival_m: None,
            true_wheel_distance_m: None,
            wheel_bias: None,
            slip: 0.0,
            params: Vec::new(),
        }
    }

    /// The simulator's configuration for these options (robot, seed, noise, start, wheels).
    pub fn sim_config(&self) -> SimConfig {
        SimConfig {
            seed: self.seed,
            noise: self.noise,
            start: self.start,
            true_wheel_distance_m: self.true_wheel_distance_m,
            wheel_bias: self.wheel_bias,
            slip: self.slip,
            ..SimConfig::new(self.profile)
        }
    }
}

/// A pose in the report.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PoseReport {
    /// x, metres.
    pub x_m: f64,
    /// y, metres.
    pub y_m: f64,
    /// Heading, radians.
    pub heading_rad: f64,
}

impl From<Pose> for PoseReport {
    fn from(p: Pose) -> Self {
        PoseReport {
            x_m: p.x,
            y_m: p.y,
            heading_rad: p.heading,
        }
    }
}

/// The outcome of a run (serialises to JSON for CI and the paper reproductions).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ScenarioReport {
    /// Arena name.
    pub arena: String,
    /// Profile name.
    pub profile: &'static str,
    /// The run's seed.
    pub seed: u64,
    /// The task as given.
    pub task: Task,
    /// The goal actually used.
    pub goal: GoalPoint,
    /// The tolerance actually used, metres.
    pub tolerance_m: f64,
    /// The firmware reported arrival and its TRUE position is within `tolerance_m` of the goal
    /// (for the search tasks: inside the goal's target area); never when the run started
    /// inside it.
    pub reached: bool,
    /// The search task's robot started inside the target area: nothing to search for, so the
    /// run is no success whatever it reports (the summary says "started inside target").
    pub started_in_target: bool,
    /// No way leads from the start to where the run may end for a robot of this size (a gap
    /// narrower than it): the run cannot succeed, and is reported as unreachable, not as a
    /// timeout ([`crate::arena::reach::Reach`] over the arena as given).
    pub unreachable: bool,
    /// The firmware reported arrival (whatever the truth).
    pub arrived: bool,
    /// Simulated seconds.
    pub sim_s: f64,
    /// Wall-clock seconds.
    pub wall_s: f64,
    /// Wall contacts.
    pub collisions: u32,
    /// Final distance between the true and the believed position, metres.
    pub pose_error_m: f64,
    /// Final distance between the true position and the goal, metres.
    pub goal_error_m: f64,
    /// Ground distance travelled, metres.
    pub distance_m: f64,
    /// Final true pose.
    pub final_true: PoseReport,
    /// Final believed pose.
    pub final_believed: PoseReport,
    /// Each run of the task, in order (one for go-to and reach-beacon, two for
    /// explore-then-plan); the top-level figures describe the last.
    pub runs: Vec<RunReport>,
}

/// Why a scenario could not run.
#[derive(Debug, Error)]
pub enum ScenarioError {
    /// The simulation could not be set up.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// A position the link's whole millimetres cannot carry.
    #[error("{0}")]
    Range(#[from] OutOfRange),
    /// No goal in the task and none in the arena.
    #[error("the task names no goal and arena {0:?} has neither a goal nor a target")]
    NoGoal(String),
    /// The firmware refused the task's command.
    #[error("the firmware refused {what}: {reason:?}")]
    Refused {
        /// Which command.
        what: &'static str,
        /// Its reason.
        reason: NackReason,
    },
    /// The timeout is not a finite positive number of seconds.
    #[error("timeout {0} s must be finite and > 0")]
    BadTimeout(f64),
    /// A go-to goal outside the arena: the robot could only run until the timeout.
    #[error(
        "goal ({x:.3}, {y:.3}) m is outside arena {arena:?}, which spans x {x0:.3}..{x1:.3}, \
         y {y0:.3}..{y1:.3} m"
    )]
    GoalOutside {
        x: f64,
        y: f64,
        arena: String,
        x0: f64,
        x1: f64,
        y0: f64,
        y1: f64,
    },
    /// The task has its own runner (foraging: [`run_forage`](super::forage::run_forage)).
    #[error("task {0:?} has its own runner")]
    OtherRunner(Task),
    /// Foraging in an arena with no room for a light source.
    #[error("arena {0:?} has no lamps and no free spot 0.3 m from home for one")]
    NoSources(String),
}

/// Runs one scenario to arrival or timeout.
pub fn run_scenario(arena: Arena, opts: ScenarioOptions) -> Result<ScenarioReport, ScenarioError> {
    if !(opts.timeout_s.is_finite() && opts.timeout_s > 0.0) {
        return Err(ScenarioError::BadTimeout(opts.timeout_s));
    }
    let target = arena.target().copied();
    let given = match opts.task {
        Task::GoTo(g) => g,
        Task::ReachBeacon | Task::ExploreThenPlan => None,
        Task::Forage => return Err(ScenarioError::OtherRunner(opts.task)),
    };
    if let Some(g) = given {
        let b = arena.bounds;
        if !b.contains(crate::geometry::Point::new(g.x_m, g.y_m)) {
            return Err(ScenarioError::GoalOutside {
                x: g.x_m,
                y: g.y_m,
                arena: arena.name.clone(),
                x0: b.min.x,
                x1: b.max.x,
                y0: b.min.y,
                y1: b.max.y,
            });
        }
    }
    let goal = given
        .or_else(|| {
            // The goal area's centre for the search tasks; a marked goal for go-to.
            let marked = arena.goal.filter(|_| matches!(opts.task, Task::GoTo(_)));
            marked.map(|g| GoalPoint { x_m: g.x, y_m: g.y })
        })
        .or_else(|| {
            target.map(|t| GoalPoint {
                x_m: t.centre.x,
                y_m: t.centre.y,
            })
        })
        .ok_or_else(|| ScenarioError::NoGoal(arena.name.clone()))?;
    let tolerance_m = opts.tolerance_m.unwrap_or_else(|| {
        if opts.profile.has(protocol::caps::ENCODERS) {
            KHEPERA_TOLERANCE_M
        } else {
            match target {
                Some(t) if (t.centre.x - goal.x_m).hypot(t.centre.y - goal.y_m) < 1e-6 => {
                    t.radius_m
                }
                _ => RATO_POINT_TOLERANCE_M,
            }
        }
    });
    let name = arena.name.clone();
    let any_goal_target = matches!(opts.task, Task::ReachBeacon | Task::ExploreThenPlan);
    let reach_goal = (goal, tolerance_m, any_goal_target);
    let unreachable = !goal_reachable(&arena, &opts, reach_goal);
    let mut sim = Sim::new(arena, opts.sim_config())?;
    // In any target the search may end in (a lab with several beacons has several): the
    // ground sensor sees it from the start, and nothing was searched for.
    let started_in_target = matches!(opts.task, Task::ReachBeacon | Task::ExploreThenPlan) && {
        let s = sim.truth();
        sim.world().in_target(crate::geometry::Point::new(s.x, s.y))
    };
    set_arrival(&mut sim, opts.arrival_m, tolerance_m)?;
    set_params(&mut sim, &opts.params)?;
    let started = Instant::now();
    let timeout_ms = (opts.timeout_s * 1000.0).ceil() as u64;
    // A beacon search sent to a target's centre ends well in any goal target (CiberRato: the
    // robot must reach a target area; a lab may have several).
    let any_target = matches!(opts.task, Task::ReachBeacon | Task::ExploreThenPlan)
        && tolerance_m == target.map_or(f64::NAN, |t| t.radius_m);
    let judge = Judge {
        goal,
        tolerance_m,
        any_target,
    };
    let mut runs = Vec::new();
    match opts.task {
        Task::GoTo(_) => {
            let cmd = Command::GoTo(point_mm(["goal x", "goal y"], (goal.x_m, goal.y_m))?);
            apply(&mut sim, cmd, "GoTo")?;
            runs.push(run_until_arrived(&mut sim, "go_to", timeout_ms, &judge));
        }
        Task::ReachBeacon => {
            apply(&mut sim, Command::StartExploration, "StartExploration")?;
            runs.push(run_until_arrived(&mut sim, "explore", timeout_ms, &judge));
        }
        Task::ExploreThenPlan => {
            let start = sim.truth();
            apply(&mut sim, Command::StartExploration, "StartExploration")?;
            let first = run_until_arrived(&mut sim, "explore", timeout_ms, &judge);
            let explored = first.arrived;
            runs.push(first);
            if explored {
                runs.push(plan_and_execute(&mut sim, start, timeout_ms, &judge)?);
            }
        }
        Task::Forage => return Err(ScenarioError::OtherRunner(opts.task)),
    }
    let wall_s = started.elapsed().as_secs_f64();
    let t = sim.truth();
    let last = runs.last().cloned();
    let goal_error_m = (t.x - goal.x_m).hypot(t.y - goal.y_m);
    let (arrived, reached) = match (&last, opts.task) {
        (Some(r), Task::ExploreThenPlan) => (r.arrived, runs.len() == 2 && r.reached),
        (Some(r), _) => (r.arrived, r.reached),
        (None, _) => (false, false),
    };
    let reached = reached && !started_in_target;
    Ok(ScenarioReport {
        arena: name,
        profile: opts.profile.name,
        seed: opts.seed,
        task: opts.task,
        goal,
        tolerance_m,
        reached,
        started_in_target,
        unreachable,
        arrived,
        sim_s: sim.now_us() as f64 * 1e-6,
        wall_s,
        collisions: sim.collisions(),
        pose_error_m: sim.pose_error_m(),
        goal_error_m,
        distance_m: sim.distance_m(),
        final_true: t.into(),
        final_believed: sim.believed().into(),
        runs,
    })
}

/// Whether a robot of the run's size can drive from its start to within `tolerance` of
/// `goal` (or, with `any_target`, into any goal target): [`crate::arena::free_path`], whose
/// cell-centre clearance finds a gap a little wider than the robot (the generator's
/// conservative raster would not). Yes when the start cannot be worked out here (the
/// simulator then refuses the run with its own error).
fn goal_reachable(
    arena: &Arena,
    opts: &ScenarioOptions,
    (goal, tolerance_m, any_target): (GoalPoint, f64, bool),
) -> bool {
    use crate::arena::free_path::free_path;
    use crate::geometry::Point;
    let radius = f64::from(opts.profile.body_diameter_m) / 2.0;
    let Ok(world) = crate::world::World::new(arena.clone(), Vec::new(), None) else {
        return true;
    };
    let Ok(start) = crate::sim::start_pose(&world, opts.start, radius) else {
        return true;
    };
    let s = Point::new(start.x, start.y);
    let mut areas = vec![(Point::new(goal.x_m, goal.y_m), tolerance_m)];
    if any_target {
        areas.extend(world.goal_targets().map(|t| (t.centre, t.radius_m)));
    }
    areas
        .into_iter()
        .any(|(c, r)| free_path(arena, s, c, r, radius).is_some())
}

/// What "reached" means for a run.
struct Judge {
    goal: GoalPoint,
    tolerance_m: f64,
    /// Inside any of the world's goal targets also counts.
    any_target: bool,
}

/// Steps until the firmware reports arrival (then settles) or the timeout.
fn run_until_arrived(
    sim: &mut Sim,
    kind: &'static str,
    timeout_ms: u64,
    judge: &Judge,
) -> RunReport {
    let (t0, c0, d0) = (sim.now_us(), sim.collisions(), sim.distance_m());
    let mut arrived = false;
    let samples = (STUCK_WINDOW_S * 1000.0) as usize / WINDOW_SAMPLE_MS as usize;
    let mut window = std::collections::VecDeque::with_capacity(samples + 1);
    for i in 0..timeout_ms {
        sim.step();
        if sim.robot().arrived() {
            arrived = true;
            sim.run_for(SETTLE_MS);
            break;
        }
        if i % WINDOW_SAMPLE_MS == 0 {
            if window.len() == samples {
                window.pop_front();
            }
            let p = sim.truth();
            window.push_back((p.x, p.y));
        }
    }
    let t = sim.truth();
    let last_window_span_m = window
        .iter()
        .map(|&(x, y)| (x - t.x).hypot(y - t.y))
        .fold(0.0, f64::max);
    let goal_error = (t.x - judge.goal.x_m).hypot(t.y - judge.goal.y_m);
    let known = sim.robot().objects().nav().grid();
    let map_known_cells = sim.robot().objects().has_map().then(|| {
        (0..usize::from(known.height()))
            .flat_map(|y| (0..usize::from(known.width())).map(move |x| (x, y)))
            .filter(|&(x, y)| known.get(x, y) != crate::arena::Cell::Unknown)
            .count() as u32
    });
    RunReport {
        kind,
        arrived,
        reached: arrived
            && (goal_error <= judge.tolerance_m
                || (judge.any_target
                    && sim.world().in_target(crate::geometry::Point::new(t.x, t.y)))),
        sim_s: (sim.now_us() - t0) as f64 * 1e-6,
        collisions: sim.collisions() - c0,
        distance_m: sim.distance_m() - d0,
        pose_error_m: sim.pose_error_m(),
        map_known_cells,
        plan_regions: None,
        last_window_span_m,
        no_path_on_map: false,
    }
}

/// Seed 004 §6-7 after an exploration run: segment the robot's own map, plan from the start
/// to where it found the goal, carry it back to the start, and execute the plan.
fn plan_and_execute(
    sim: &mut Sim,
    start: Pose,
    timeout_ms: u64,
    judge: &Judge,
) -> Result<RunReport, ScenarioError> {
    // Where the robot believes it met the goal area: a free cell it has visited.
    let found = sim.believed();
    apply(sim, Command::Stop, "Stop")?;
    apply(sim, Command::Segment, "Segment")?;
    let from = point_mm(["start x", "start y"], (start.x, start.y))?;
    let to = point_mm(["goal found x", "goal found y"], (found.x, found.y))?;
    let plan = Command::Plan {
        from: Some(from),
        to: Some(to),
    };
    match apply(sim, plan, "Plan") {
        Ok(()) => {}
        Err(ScenarioError::Refused {
            reason: NackReason::Unreachable | NackReason::BadPoint,
            ..
        }) => return Ok(no_path_run(sim)),
        Err(e) => return Err(e),
    }
    let (plan_id, regions) = match sim.robot().objects().plan() {
        Some((id, view)) => (id, view.waypoint_count().saturating_sub(2)),
        None => {
            return Err(ScenarioError::Refused {
                what: "Plan",
                reason: NackReason::NoPlan,
            })
        }
    };
    // The operator carries the robot back and tells it where it is (seed 004: the start is
    // known); the compass gives the heading.
    sim.place(start)?;
    let pose = protocol::Pose {
        x_mm: from.x_mm,
        y_mm: from.y_mm,
        heading_mrad: (start.heading * 1000.0).round() as i16,
    };
    apply(sim, Command::SetPose { pose }, "SetPose")?;
    apply(sim, Command::ExecutePlan { plan_id }, "ExecutePlan")?;
    let mut run = run_until_arrived(sim, "execute_plan", timeout_ms, judge);
    run.plan_regions = Some(u32::from(regions));
    Ok(run)
}

/// Run 2 when the robot's explored map has no path from the start to where it found the
/// goal: nothing is driven, the run fails as the robot's own.
fn no_path_run(sim: &Sim) -> RunReport {
    RunReport {
        kind: "execute_plan",
        arrived: false,
        reached: false,
        sim_s: 0.0,
        collisions: 0,
        distance_m: 0.0,
        pose_error_m: sim.pose_error_m(),
        map_known_cells: None,
        plan_regions: None,
        last_window_span_m: 0.0,
        no_path_on_map: true,
    }
}

/// Tells the firmware its arrival radius: the option, else `min(default, tolerance / 2)`.
pub fn set_arrival(
    sim: &mut Sim,
    arrival_m: Option<f64>,
    tolerance_m: f64,
) -> Result<(), ScenarioError> {
    let core = sim.robot();
    let (id, default) = if core.profile().has(protocol::caps::ENCODERS) {
        (
            param::DRIFT_ARRIVAL_RADIUS_M,
            f64::from(core.arbiter().params.drift.arrival_radius_m),
        )
    } else {
        (param::GUIDED_ARRIVAL_M, f64::from(core.guided().arrival_m))
    };
    let value = arrival_m.unwrap_or_else(|| default.min(tolerance_m / 2.0));
    let cmd = Command::SetParam {
        id: ParamId(id),
        value: value as f32,
    };
    apply(sim, cmd, "SetParam(arrival radius)")
}

/// Sets each (id, value) as `SetParam`, as a station loading a parameter file does.
pub(crate) fn set_params(sim: &mut Sim, params: &[(u16, f32)]) -> Result<(), ScenarioError> {
    for &(id, value) in params {
        let cmd = Command::SetParam {
            id: ParamId(id),
            value,
        };
        apply(sim, cmd, "SetParam(saved parameter)")?;
    }
    Ok(())
}

pub fn apply(sim: &mut Sim, cmd: Command, what: &'static str) -> Result<(), ScenarioError> {
    let now_ms = (sim.now_us() / 1000) as u32;
    match sim.robot_mut().apply(cmd, now_ms) {
        Reply::Ack(_) => Ok(()),
        Reply::Nack(reason) => Err(ScenarioError::Refused { what, reason }),
    }
}
