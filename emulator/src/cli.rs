//! The `robot-emulator` command line: `serve` (the default) puts the simulated robot on a
//! pseudo-terminal; `run` runs a headless scenario and prints a JSON report.
//!
//! Layer: argument parsing and validation at the edge. Every bad argument is reported with the
//! flag's name and why, and nothing starts.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};
use robot_firmware::{Profile, ALICE, KHEPERA, MICRO_RATO};

use crate::alice::navigation::{Drift, Scene, StepBase, TestMap};
use crate::fault::{FaultConfig, Stall};
use crate::fleet::RobotSpec;
use crate::link::{EmulatorOptions, ServeOptions, Speed};
use crate::scenario::{GoalPoint, ScenarioOptions, Task};
use crate::sensors::Noise;
use crate::sim::SimConfig;

/// The robot's firmware, unchanged, in a simulated world, on a serial port.
#[derive(Debug, Parser)]
#[command(
    name = "robot-emulator",
    version,
    about = "Runs the robot firmware in a simulated arena and exposes its serial link on a \
             pseudo-terminal, so the station (or any serial tool) talks to it as to a real \
             robot on /dev/ttyUSB0.",
    after_help = "Examples:\n  \
        robot-emulator                                   # Micro-Rato'99, micro-rato robot, real time\n  \
        robot-emulator --link /tmp/robot                 # and a stable path to the port\n  \
        station --port /tmp/robot                        # drive it\n  \
        robot-emulator --arena maze.txt --profile khepera --speed 10\n  \
        robot-emulator run --arena lab.xml --profile micro-rato --task go-to --seed 3 --json\n  \
        robot-emulator --profile alice   # ALICE (Zimmer's thesis) in builtin:alice"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    #[command(flatten)]
    pub serve: ServeArgs,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Serve the robot on a pseudo-terminal (the default).
    Serve(ServeArgs),
    /// Run a scenario headless at maximum speed and print a report.
    Run(RunArgs),
    /// Arena files: `arena generate` writes a generated arena.
    Arena(ArenaArgs),
    /// Run one task over many arenas and seeds in parallel and report success rate, times,
    /// collisions, final error and failures by cause (the generalisation benchmark: does a
    /// task succeed in arenas nobody tuned it for?).
    Bench(BenchArgs),
    Hil(crate::hil::args::HilArgs),
}

/// `arena` subcommands.
#[derive(Debug, Clone, Args)]
pub struct ArenaArgs {
    #[command(subcommand)]
    pub command: ArenaCommand,
}

/// What to do with arenas.
#[derive(Debug, Clone, Subcommand)]
pub enum ArenaCommand {
    /// Write a generated arena: CiberRato lab XML (plus its grid file of start positions,
    /// `...Grid.xml` beside a `...Lab.xml`) or micromouse maze text. Same seed, same arena;
    /// every arena is checked solvable at its robot's size before it is written.
    Generate(GenerateArgs),
}

/// `arena generate` options.
#[derive(Debug, Clone, Args)]
pub struct GenerateArgs {
    /// Micro-Rato labyrinth (as Dom Dinis met, Seabra Lopes, Lau, Reis §2), micromouse maze,
    /// or Khepera box (as in the Khepera foraging paper's Fig. 17, Löffler et al.).
    #[arg(long, value_enum)]
    pub kind: crate::arena_gen::Kind,
    /// The arena's seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output file: `...Lab.xml` for micro-rato and box (the grid file goes beside it), any
    /// name for a maze.
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Replace existing files at `--out` (and its grid file); never a device, FIFO or directory.
    #[arg(long)]
    pub force: bool,
}

/// `bench` options.
#[derive(Debug, Clone, Args)]
pub struct BenchArgs {
    /// The task every run does.
    #[arg(long, value_enum)]
    pub task: crate::bench::BenchTask,
    /// Arenas: `generated:N` (N generated arenas, seeds 1..N, of --kind), a directory of
    /// arena files, arena files, or built-in names; several may be given.
    #[arg(long, num_args = 1.., default_value = "generated:200", value_name = "SPEC")]
    pub arenas: Vec<String>,
    /// Kind of generated arena [default: micro-rato for the search tasks, box otherwise].
    #[arg(long, value_enum)]
    pub kind: Option<crate::arena_gen::Kind>,
    /// Noise draws per arena: each run gets its own emulator seed, drawn from --seed and the
    /// arena's index (`bench::run_seed`; a row's `seed` repeats it with `run --seed`), so the
    /// rate measures the noise's distribution, not one draw shared by every arena.
    #[arg(long, default_value_t = 1, value_name = "K")]
    pub seeds: u64,
    /// Base seed of the runs' emulator seeds.
    #[arg(long, default_value_t = 1, value_name = "S")]
    pub seed: u64,
    /// Runs in parallel [default: the number of cores].
    #[arg(long, value_name = "N")]
    pub jobs: Option<usize>,
    /// Robot [default: micro-rato for the search tasks, khepera for goto and forage].
    #[arg(long, value_enum)]
    pub profile: Option<ProfileArg>,
    /// Simulated seconds per run [default: 300; forage: 1200, as `run`].
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub timeout: Option<f64>,
    /// Switch every noise source off.
    #[arg(long)]
    pub no_noise: bool,
    /// Print the whole report, with one row per run, as one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Run each arena as a contest of N robots (reach-beacon only), and each robot alone
    /// from the same start with the same seed: how often each arrives with the others
    /// against alone, and the collisions between robots.
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub robots: usize,
    /// Go-to only: before each run the same robot calibrates its odometry in the arena
    /// (holding the wall both ways, `station calibrate odometry`'s manoeuvre) and starts the
    /// go-to with the measured wheel distance and ratio set.
    #[arg(long)]
    pub calibrate_odometry: bool,
    /// The search tasks: which Dom Dinis search runs (parameter `search_mode`) [default: the
    /// firmware's, planned].
    #[arg(long, value_enum, value_name = "SEARCH")]
    pub search: Option<SearchArg>,
}

/// Which Dom Dinis search a run uses (the firmware parameter `search_mode`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SearchArg {
    /// The Dom Dinis paper's reactive goal search (§5) on a 0.3 m map.
    Reactive,
    /// Plans on its own 0.15 m map as it goes, unknown cells taken as free (the default).
    Planned,
}

impl SearchArg {
    /// The parameter assignment a station would send for it.
    pub fn param(self) -> (u16, f32) {
        let mode = match self {
            SearchArg::Reactive => robot_firmware::explore::SearchMode::Reactive,
            SearchArg::Planned => robot_firmware::explore::SearchMode::Planned,
        };
        (
            robot_firmware::params::id::SEARCH_MODE,
            f32::from(mode.code()),
        )
    }
}

/// Most seeds per arena `bench --seeds` takes.
pub const MAX_BENCH_SEEDS: u64 = 10_000;
/// Most worker threads `bench --jobs` takes.
pub const MAX_BENCH_JOBS: usize = 1024;

impl BenchArgs {
    /// The benchmark these arguments describe.
    pub fn options(&self) -> Result<crate::bench::BenchOptions, String> {
        use crate::bench::BenchTask;
        if !(1..=MAX_BENCH_SEEDS).contains(&self.seeds) {
            return Err(format!(
                "--seeds {}: must be 1..={MAX_BENCH_SEEDS}",
                self.seeds
            ));
        }
        let jobs = match self.jobs {
            Some(j) if !(1..=MAX_BENCH_JOBS).contains(&j) => {
                return Err(format!("--jobs {j}: must be 1..={MAX_BENCH_JOBS}"))
            }
            Some(j) => j,
            None => std::thread::available_parallelism().map_or(1, usize::from),
        };
        let default_timeout = if self.task == BenchTask::Forage {
            FORAGE_TIMEOUT_S
        } else {
            DEFAULT_TIMEOUT_S
        };
        let timeout_s = match self.timeout {
            None => default_timeout,
            Some(t) if t.is_finite() && t > 0.0 => t,
            Some(t) => return Err(format!("--timeout {t}: must be positive seconds")),
        };
        let profile = match (self.task, self.profile) {
            // The foraging runner is the Khepera's (gripper, light sensors).
            (BenchTask::Forage, _) | (_, None) => self.task.default_profile(),
            (_, Some(p)) => p.profile(),
        };
        let search = matches!(
            self.task,
            BenchTask::ReachBeacon | BenchTask::ExploreThenPlan
        );
        if search && !profile.has(protocol::caps::COMPASS | protocol::caps::BEACON) {
            return Err(format!(
                "--profile {}: the search tasks need compass and beacon sensor (the Dom Dinis search); \
                 use --profile micro-rato",
                profile.name
            ));
        }
        let max = crate::fleet::contact::MAX_ROBOTS;
        if !(1..=max).contains(&self.robots) {
            return Err(format!("--robots {}: must be 1..={max}", self.robots));
        }
        if self.robots > 1 && self.task != BenchTask::ReachBeacon {
            return Err(format!(
                "--robots {}: the contest is the Micro-Rato reach-beacon task (the Dom Dinis paper §2); use --task reach-beacon",
                self.robots
            ));
        }
        if self.calibrate_odometry
            && (self.task != BenchTask::Goto || !profile.has(protocol::caps::ENCODERS))
        {
            return Err(
                "--calibrate-odometry: the odometry calibration is the Khepera go-to's; use \
                 --task goto --profile khepera"
                    .to_string(),
            );
        }
        let kind = self.kind.unwrap_or_else(|| self.task.default_kind());
        let arenas = crate::bench::resolve_arenas(&self.arenas, kind)?;
        Ok(crate::bench::BenchOptions {
            task: self.task,
            profile,
            arenas,
            seeds: self.seeds,
            seed: self.seed,
            jobs,
            timeout_s,
            noise: if self.no_noise {
                Noise::none()
            } else {
                Noise::default()
            },
            progress: !self.json,
            robots: self.robots,
            calibrate_odometry: self.calibrate_odometry,
            params: self.search.map(SearchArg::param).into_iter().collect(),
        })
    }
}

/// Robot and world.
#[derive(Debug, Clone, Args)]
pub struct WorldArgs {
    /// Arena file: CiberRato lab .xml, micromouse maze .txt, ROS map .yaml, or an ASCII grid;
    /// or a built-in one: `builtin:micro-rato-99`, `builtin:forage`, `builtin:floor-grid`,
    /// `builtin:alice` (the default for `--profile alice`), `builtin:alice-navigation` (the
    /// corridors of Zimmer's ALICE thesis §5.3, as it describes them).
    #[arg(long, default_value = crate::builtin::MICRO_RATO_99, value_name = "FILE")]
    pub arena: String,
    /// CiberRato grid file with start poses (default: found beside a `...Lab.xml`).
    #[arg(long, value_name = "FILE")]
    pub grid: Option<PathBuf>,
    /// Robot profile.
    #[arg(long, value_enum, default_value_t = ProfileArg::MicroRato)]
    pub profile: ProfileArg,
    /// Seed for every random draw; the same seed gives the same run.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Start pose `X,Y[,HEADING_DEG]` in metres (default: the arena's start).
    #[arg(long, value_name = "X,Y[,DEG]", value_parser = parse_pose)]
    pub start: Option<[f64; 3]>,
    /// Switch every noise source off (exact sensors, nominal wheels).
    #[arg(long)]
    pub no_noise: bool,
    /// Compass noise, degrees RMS (CiberRato's CompassNoise).
    #[arg(long, value_name = "DEG")]
    pub compass_noise: Option<f64>,
    /// Beacon bearing noise, degrees (BeaconNoise).
    #[arg(long, value_name = "DEG")]
    pub beacon_noise: Option<f64>,
    /// IR proximity noise, counts (ObstacleNoise).
    #[arg(long, value_name = "COUNTS")]
    pub obstacle_noise: Option<f64>,
    /// Per-wheel speed error, relative sigma (MotorsNoise).
    #[arg(long, value_name = "SIGMA")]
    pub motors_noise: Option<f64>,
    /// Probability that the floor sensor misses a line (default 0.02).
    #[arg(long, value_name = "P")]
    pub line_miss: Option<f64>,
    /// Probability that the floor sensor reports a line twice (default 0.02).
    #[arg(long, value_name = "P")]
    pub line_double: Option<f64>,
    /// True wheel distance in metres, if not the profile's nominal one.
    #[arg(long, value_name = "M")]
    pub true_wheel_distance: Option<f64>,
    /// Wheel slip, relative sigma (0 = none).
    #[arg(long, default_value_t = 0.0, value_name = "SIGMA")]
    pub slip: f64,
    /// Floor grid of black lines with this pitch in metres (floor-grid line correction uses 0.10).
    #[arg(long, value_name = "M")]
    pub floor_grid: Option<f64>,
}

/// Several robots in one arena (issue 17): `--robots N` of `--profile`, or `--robot` once per
/// robot. Robot 1 starts at `--start` if given; the others at the arena's start areas.
#[derive(Debug, Clone, Args)]
pub struct FleetArgs {
    /// Robots in the arena, each its own firmware, sensors and serial port (1..=16)
    /// [default: 1].
    #[arg(long, value_name = "N", conflicts_with = "robot")]
    pub robots: Option<usize>,
    /// One robot, `PROFILE[@X,Y,DEG]` (metres, degrees); repeat for each robot (profiles may
    /// be mixed). Without a pose it starts at the arena's next start area.
    #[arg(long, value_name = "PROFILE[@X,Y,DEG]", value_parser = parse_robot)]
    pub robot: Vec<RobotArg>,
}

/// One `--robot` value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobotArg {
    /// Its profile.
    pub profile: ProfileArg,
    /// Its start, metres and degrees.
    pub start: Option<[f64; 3]>,
}

impl FleetArgs {
    /// The fleet asked for, or `None` for one robot as before (`--robots 1`, or nothing).
    /// One `--robot` is a fleet of one (served as robot 1 of the fleet loop; `run` makes it a
    /// contest of one), which behaves as the single robot with that profile and pose.
    pub fn specs(&self, world: &WorldArgs) -> Result<Option<Vec<RobotSpec>>, String> {
        let max = crate::fleet::contact::MAX_ROBOTS;
        let pose = |[x, y, deg]: [f64; 3]| crate::arena::Pose {
            x,
            y,
            heading: deg.to_radians(),
        };
        if !self.robot.is_empty() {
            if self.robot.len() > max {
                return Err(format!(
                    "--robot given {} times: a fleet has at most {max} robots",
                    self.robot.len()
                ));
            }
            if world.start.is_some() {
                return Err(
                    "--start is for a single robot; give each robot's pose with \
                            --robot PROFILE@X,Y,DEG"
                        .to_string(),
                );
            }
            return Ok(Some(
                self.robot
                    .iter()
                    .map(|r| RobotSpec {
                        profile: r.profile.profile(),
                        start: r.start.map(pose),
                    })
                    .collect(),
            ));
        }
        match self.robots {
            None | Some(1) => Ok(None),
            Some(n) if n == 0 || n > max => Err(format!("--robots {n}: must be 1..={max}")),
            Some(n) => Ok(Some(
                (0..n)
                    .map(|i| RobotSpec {
                        profile: world.profile.profile(),
                        start: if i == 0 { world.start.map(pose) } else { None },
                    })
                    .collect(),
            )),
        }
    }
}

/// A value for every robot (`VALUE`) or for one (`ROBOT:VALUE`, robots numbered from 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PerRobot<T> {
    /// The robot, 1-based; `None` = every robot.
    pub robot: Option<usize>,
    /// The value.
    pub value: T,
}

/// The value in force for `robot` (1-based): the last `ROBOT:VALUE` naming it, else the last
/// plain `VALUE`.
pub fn for_robot<T: Copy>(list: &[PerRobot<T>], robot: usize) -> Option<T> {
    list.iter()
        .rev()
        .find(|p| p.robot == Some(robot))
        .or_else(|| list.iter().rev().find(|p| p.robot.is_none()))
        .map(|p| p.value)
}

/// Refuses a `ROBOT:` prefix naming a robot the run does not have.
fn check_robots<T>(flag: &str, list: &[PerRobot<T>], robots: usize) -> Result<(), String> {
    match list.iter().find_map(|p| p.robot.filter(|&r| r > robots)) {
        Some(r) => Err(format!(
            "{flag} {r}:...: robot {r} does not exist; this run has {robots} robot(s), \
             numbered from 1"
        )),
        None => Ok(()),
    }
}

/// Splits `ROBOT:REST` (`ROBOT` a whole number from 1) from a per-robot value.
fn split_robot(s: &str) -> Result<(Option<usize>, &str), String> {
    match s.split_once(':') {
        None => Ok((None, s)),
        Some((r, rest)) => match r.trim().parse::<usize>() {
            Ok(n) if n >= 1 => Ok((Some(n), rest)),
            _ => Err(format!(
                "`{r}` in `{s}` is not a robot number (1, 2, ...): expected [ROBOT:]VALUE"
            )),
        },
    }
}

fn parse_per_robot_number(s: &str) -> Result<PerRobot<f64>, String> {
    let (robot, rest) = split_robot(s)?;
    let value = rest
        .trim()
        .parse::<f64>()
        .map_err(|_| format!("`{rest}` in `{s}` is not a number"))?;
    Ok(PerRobot { robot, value })
}

fn parse_per_robot_stall(s: &str) -> Result<PerRobot<Stall>, String> {
    let (robot, rest) = split_robot(s)?;
    Ok(PerRobot {
        robot,
        value: parse_stall(rest)?,
    })
}

/// `PROFILE[@X,Y,DEG]` (`--robot`).
fn parse_robot(s: &str) -> Result<RobotArg, String> {
    let (name, pose) = match s.split_once('@') {
        Some((n, p)) => (n, Some(parse_pose(p)?)),
        None => (s, None),
    };
    let profile = ProfileArg::from_str(name.trim(), true).map_err(|_| {
        format!("unknown profile `{name}` in `{s}`: expected khepera, micro-rato or alice")
    })?;
    Ok(RobotArg {
        profile,
        start: pose,
    })
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ProfileArg {
    Khepera,
    MicroRato,
    /// ALICE, the robot of Zimmer's thesis: 24 whiskers, 24 photoresistors, situations
    /// (kind 16); in `builtin:alice` unless --arena names another.
    Alice,
}

impl ProfileArg {
    pub fn profile(self) -> &'static Profile {
        match self {
            ProfileArg::Khepera => &KHEPERA,
            ProfileArg::MicroRato => &MICRO_RATO,
            ProfileArg::Alice => &ALICE,
        }
    }
}

/// `serve` options.
#[derive(Debug, Clone, Args)]
pub struct ServeArgs {
    #[command(flatten)]
    pub world: WorldArgs,
    #[command(flatten)]
    pub fleet: FleetArgs,
    /// Also create this symlink to the pty (like socat's link=), replaced on restart. With
    /// several robots, robot K's is PATH followed by K (`/tmp/robot` gives `/tmp/robot1`,
    /// `/tmp/robot2`, ...).
    #[arg(long, value_name = "PATH")]
    pub link: Option<PathBuf>,
    /// Serial line rate the robot's UART runs at (8N1).
    #[arg(long, default_value_t = 115_200)]
    pub baud: u32,
    /// Stream the robot's hardware trace (parameter 34 hal_trace, message kind 15) from
    /// power-up; the robot powers up at the station's first byte, so the whole trace reaches
    /// it and `station retrace` can re-run the firmware over it (single robot).
    #[arg(long)]
    pub hal_trace: bool,
    /// Simulation speed: a factor (1 = real time) or `max`.
    #[arg(long, default_value = "1", value_parser = parse_speed)]
    pub speed: Speed,
    /// Probability of losing a byte, both directions. `ROBOT:P` faults only that robot's link
    /// (robots numbered from 1); repeat for several.
    #[arg(long, value_name = "[ROBOT:]P", allow_negative_numbers = true, value_parser = parse_per_robot_number)]
    pub drop_rate: Vec<PerRobot<f64>>,
    /// Probability of flipping a bit, both directions (`ROBOT:P`: one robot's link).
    #[arg(long, value_name = "[ROBOT:]P", allow_negative_numbers = true, value_parser = parse_per_robot_number)]
    pub flip_rate: Vec<PerRobot<f64>>,
    /// Only fault the station-to-robot direction.
    #[arg(long, conflicts_with = "only_from_robot")]
    pub only_to_robot: bool,
    /// Only fault the robot-to-station direction.
    #[arg(long)]
    pub only_from_robot: bool,
    /// Stall the link every PERIOD seconds for DURATION seconds: `PERIOD,DURATION`
    /// (`ROBOT:PERIOD,DURATION`: one robot's link).
    #[arg(long, value_name = "PERIOD,DURATION", value_parser = parse_per_robot_stall)]
    pub stall: Vec<PerRobot<Stall>>,
    /// Unplug the port after this many simulated seconds (`ROBOT:S`: only that robot's,
    /// while the others run on).
    #[arg(long, value_name = "S", allow_negative_numbers = true, value_parser = parse_per_robot_number)]
    pub disconnect_after: Vec<PerRobot<f64>>,
    /// Plug it back in (a new pty; --link follows it) this many seconds after unplugging
    /// (`ROBOT:S`: that robot's).
    #[arg(long, value_name = "S", requires = "disconnect_after", allow_negative_numbers = true, value_parser = parse_per_robot_number)]
    pub reconnect_after: Vec<PerRobot<f64>>,
    /// On exit, print what the run measured (bytes, faults, cycle jitter) as JSON.
    #[arg(long)]
    pub json: bool,
    /// Link authentication key: a file holding 64 hex digits (PROTOCOL.md §13). The robot
    /// then signs every frame and accepts only frames signed with this key.
    #[arg(long, value_name = "PATH")]
    pub key_file: Option<PathBuf>,
}

/// `run` options.
#[derive(Debug, Clone, Args)]
pub struct RunArgs {
    #[command(flatten)]
    pub world: WorldArgs,
    #[command(flatten)]
    pub fleet: FleetArgs,
    /// What the robot does.
    #[arg(long, value_enum, default_value_t = TaskArg::GoTo)]
    pub task: TaskArg,
    /// Goal `X,Y` in metres for go-to (default: the arena's goal or target).
    #[arg(long, value_name = "X,Y", value_parser = parse_point)]
    pub goal: Option<[f64; 2]>,
    /// Simulated seconds before giving up [default: 300; forage: 1200, since the first
    /// object comes home after about 6 minutes; line-correct: 1.5 x the survey's time at
    /// 0.1 m/s, e.g. 600 s for 40 m].
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub timeout: Option<f64>,
    /// Print the report as one JSON object (otherwise a readable summary).
    #[arg(long)]
    pub json: bool,
    /// reach-beacon, explore-then-plan: which Dom Dinis search runs (parameter `search_mode`)
    /// [default: the firmware's, planned].
    #[arg(long, value_enum, value_name = "SEARCH")]
    pub search: Option<SearchArg>,
    /// go-to (khepera): before the run the same robot calibrates its odometry in the arena
    /// (`bench --calibrate-odometry`'s manoeuvre) and the go-to starts with the measured wheel
    /// distance and ratio set.
    #[arg(long)]
    pub calibrate_odometry: bool,
    /// line-correct: true distance to drive, metres.
    #[arg(long, default_value_t = 40.0, value_name = "M")]
    pub distance: f64,
    /// alice-*: set a QT world-model parameter (repeatable), e.g. `--qt-param eps_o=0.05`.
    #[arg(long = "qt-param", value_name = "NAME=VALUE")]
    pub qt_param: Vec<String>,
    /// alice-navigation: §5.3's static drift during the test runs, degrees per metre
    /// (default 5, the thesis's "up to 5"; 0 separates its effect).
    #[arg(long = "static-drift", value_name = "DEG_PER_M")]
    pub static_drift: Option<f64>,
    /// alice-navigation: the control, a path-execution memory that never learns (the
    /// first-over-fifth factors without any learning).
    #[arg(long = "no-learning")]
    pub no_learning: bool,
    /// alice-navigation: what the map does during the test runs: `frozen` (the default:
    /// no adaptation or insertion, but winner changes still refresh and create edges),
    /// `static` (nothing of the map changes; localisation still runs) or `adapting` (it keeps
    /// learning as while exploring).
    #[arg(long = "test-map", value_enum, default_value_t = TestMap::Frozen)]
    pub test_map: TestMap,
    /// alice-navigation: the same as `--test-map adapting`.
    #[arg(long = "adapting-map", conflicts_with = "test_map")]
    pub adapting_map: bool,
    /// alice-navigation: a counterfactual to judge the navigator: during the test runs the
    /// internal pose is held at the truth (carried into the map's frame) after every sample.
    #[arg(long = "true-pose")]
    pub true_pose: bool,
    /// alice-navigation: what a step's geometric command is measured from: the map's edge from
    /// the winner cell (`cell`, the default) or the internal pose (`pose`).
    #[arg(long = "step-from", value_enum, default_value_t = StepBase::Cell)]
    pub step_from: StepBase,
    /// alice-navigation: the odometry's own drift: `alice` (the default: ALICE's 20-25 %
    /// translational and up to 0.5 deg/m rotational drift, as in the §4.5 scenarios) or
    /// `static` (§5.3's simulator: only the static drift of the test runs, `--static-drift`).
    #[arg(long = "drift", value_enum, default_value_t = Drift::Alice)]
    pub drift: Drift,
    /// alice-navigation: where it runs: `pillar` (the default: the §4.5 test scene) or
    /// `corridors` (§5.3's scene as the thesis describes it: a narrow corridor to a pocket
    /// upper left, a narrowing one lower left, a rough right wall, jagged obstacles).
    #[arg(long = "scene", value_enum, default_value_t = Scene::Pillar)]
    pub scene: Scene,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum TaskArg {
    /// Drive to --goal (default: the arena's target).
    GoTo,
    /// The Dom Dinis reactive goal search (Seabra Lopes, Lau, Reis §5), start to goal area,
    /// mapping on the way.
    ReachBeacon,
    /// Dom Dinis (Seabra Lopes, Lau, Reis §5-7): run 1 explores; the robot plans on its own
    /// map; run 2 executes the plan.
    ExploreThenPlan,
    /// Survey a floor grid for --distance metres; report line-corrected, plain-odometry and
    /// nearest-line errors against the truth (floor-grid line correction, Mächler's thesis
    /// ch. 2; use --arena builtin:floor-grid).
    LineCorrect,
    /// Carry the objects at the lit sources to the home base (Khepera foraging, Löffler,
    /// Klahold, Rückert §7). Runs the khepera
    /// (the profile with a gripper) in `builtin:forage` unless --arena names another arena
    /// (which then gets three lamps with objects drawn from --seed, home at the start).
    Forage,
    /// Khepera light-source mapping (Löffler et al. §6.1): calibrate the light sensors, then map one lamp in the paper's 75 x 60
    /// cm box, once without and once with local correction; reports the recognitions of
    /// each (paper: 5 without, 24+ with). Its own arena and the khepera: --arena and
    /// --profile are ignored.
    LightMap,
    /// Khepera odometry, the foraging paper's Tables 1-2 (Löffler et al. §3.3): a Khepera with 53.3 mm wheels wall-follows two laps of the
    /// 75 x 60 cm box; the encoder counts it sends are re-integrated with the tables' swept
    /// wheel distance and pulse length. Its own arena and the khepera: --arena and --profile
    /// are ignored.
    OdometryLaps,
    /// Unsupervised landmarks and places (Mächler's thesis ch. 3): the thesis's simulated
    /// Khepera wanders in a generated arena (--arena unstructured|structured, from --seed),
    /// resets its odometry on landmark matches; reports corrected vs plain odometry error in
    /// robot diameters. --timeout is the run length [default 1200 s].
    UnsupervisedPlaces,
    /// ALICE's QT world model (Zimmer's thesis §4.5.4): one 8000-situation run in builtin:alice;
    /// when the cell count settles (thesis: about 5000). Own arena and robot; --seed.
    AliceEquilibrium,
    /// ALICE's QT model, eps_o at 0.1 / 0.03 / 0.005 (§4.5.1).
    AliceEpsO,
    /// ALICE's QT model with both correlations, without position, without orientation
    /// (§4.5.3).
    AliceCorrelation,
    /// ALICE's QT model with a wall below the pillar removed at situation 3500 (§4.5.4).
    AliceDynamic,
    /// ALICE's QT model, eps_o at 0.03 and 0.005 continued to 20000 situations (§4.5.1).
    AliceEpsOContinued,
    /// ALICE's navigation (§5.3): map by exploring, then five test runs out and back with A*
    /// planning, the reinforcement-trained path execution and 5 deg/m static drift; the first
    /// run against the fifth.
    AliceNavigation,
}

impl WorldArgs {
    /// The arena to load: `--arena`, except that ALICE replaces the default (Micro-Rato'99)
    /// with its own scene, `builtin:alice` (seed 001 §4.5), as foraging does with its own.
    pub fn arena(&self) -> &str {
        if self.profile == ProfileArg::Alice && self.arena == crate::builtin::MICRO_RATO_99 {
            crate::alice::arena::BUILTIN_ALICE
        } else {
            &self.arena
        }
    }

    fn noise(&self) -> Result<Noise, String> {
        let mut n = if self.no_noise {
            Noise::none()
        } else {
            Noise::default()
        };
        let set = |v: Option<f64>, name: &str, slot: &mut f64| -> Result<(), String> {
            if let Some(v) = v {
                if !(v.is_finite() && v >= 0.0) {
                    return Err(format!("--{name} {v}: must be a finite number >= 0"));
                }
                *slot = v;
            }
            Ok(())
        };
        set(self.compass_noise, "compass-noise", &mut n.compass_deg)?;
        set(self.beacon_noise, "beacon-noise", &mut n.beacon_deg)?;
        set(
            self.obstacle_noise,
            "obstacle-noise",
            &mut n.obstacle_counts,
        )?;
        set(self.motors_noise, "motors-noise", &mut n.motors)?;
        for (v, name, slot) in [
            (self.line_miss, "line-miss", &mut n.line_miss),
            (self.line_double, "line-double", &mut n.line_double),
        ] {
            if v.is_some_and(|p| !(0.0..=1.0).contains(&p)) {
                return Err(format!(
                    "--{name} {}: must be a probability in [0, 1]",
                    v.unwrap_or_default()
                ));
            }
            set(v, name, slot)?;
        }
        Ok(n)
    }

    /// How `--arena` is loaded: for simulation (the emulator's world limit), with `--grid`.
    pub fn load_options(&self) -> crate::arena::LoadOptions {
        let mut load = crate::arena::LoadOptions::for_simulation();
        if let Some(g) = &self.grid {
            load.ciberrato_grid = crate::arena::GridFile::Path(g.clone());
        }
        load
    }

    fn check(&self) -> Result<(), String> {
        if let Some(d) = self.true_wheel_distance {
            if !(d.is_finite() && d > 0.0 && d < 2.0) {
                return Err(format!(
                    "--true-wheel-distance {d}: must be in (0, 2) metres"
                ));
            }
        }
        if !(self.slip.is_finite() && (0.0..1.0).contains(&self.slip)) {
            return Err(format!("--slip {}: must be in [0, 1)", self.slip));
        }
        if let Some(g) = self.floor_grid {
            if !(g.is_finite() && g > 0.02) {
                return Err(format!("--floor-grid {g}: must be more than 0.02 m"));
            }
        }
        Ok(())
    }

    fn start_pose(&self) -> Option<crate::arena::Pose> {
        self.start.map(|[x, y, deg]| crate::arena::Pose {
            x,
            y,
            heading: deg.to_radians(),
        })
    }

    /// The simulation these arguments describe (one robot; a fleet shares all but profile and start).
    pub fn sim_config(&self, baud: u32) -> Result<SimConfig, String> {
        self.check()?;
        let mut cfg = SimConfig::new(self.profile.profile());
        cfg.seed = self.seed;
        cfg.noise = self.noise()?;
        cfg.start = self.start_pose();
        cfg.true_wheel_distance_m = self.true_wheel_distance;
        cfg.slip = self.slip;
        cfg.floor_grid_m = self
            .floor_grid
            .or_else(|| crate::builtin::floor_grid_pitch(self.arena()));
        cfg.baud = baud;
        Ok(cfg)
    }
}

impl ServeArgs {
    /// The emulator these arguments describe, for one robot (robot 1's link options).
    pub fn options(&self) -> Result<EmulatorOptions, String> {
        let sim = self.world.sim_config(self.baud)?;
        let serve = self.link_options(1, 1)?;
        Ok(EmulatorOptions {
            arena: self.world.arena().to_string(),
            load: self.world.load_options(),
            sim,
            serve,
        })
    }

    /// The robots `--robots`/`--robot` ask for; `None` for today's single robot.
    pub fn robots(&self) -> Result<Option<Vec<RobotSpec>>, String> {
        self.fleet.specs(&self.world)
    }

    /// Robot `robot`'s (1-based, of `robots`) link: speed, its faults, its `--link` path
    /// ([`crate::fleet::serve::link_for`]), its seed ([`crate::fleet::robot_seed`]), the key.
    pub fn link_options(&self, robot: usize, robots: usize) -> Result<ServeOptions, String> {
        if self.baud == 0 || self.baud > 4_000_000 {
            return Err(format!("--baud {}: must be 1..=4000000", self.baud));
        }
        if let Speed::Factor(f) = self.speed {
            if !(f.is_finite() && f > 0.0) {
                return Err(format!("--speed {f}: must be a positive factor or `max`"));
            }
        }
        for (name, list) in [
            ("--drop-rate", &self.drop_rate),
            ("--flip-rate", &self.flip_rate),
            ("--disconnect-after", &self.disconnect_after),
            ("--reconnect-after", &self.reconnect_after),
        ] {
            check_robots(name, list, robots)?;
        }
        check_robots("--stall", &self.stall, robots)?;
        let faults = FaultConfig {
            drop_rate: for_robot(&self.drop_rate, robot).unwrap_or(0.0),
            flip_rate: for_robot(&self.flip_rate, robot).unwrap_or(0.0),
            stall: for_robot(&self.stall, robot),
        };
        faults.validate("--drop-rate/--flip-rate/--stall")?;
        let disconnect_after_s = for_robot(&self.disconnect_after, robot);
        let reconnect_after_s = for_robot(&self.reconnect_after, robot);
        for (name, v) in [
            ("--disconnect-after", disconnect_after_s),
            ("--reconnect-after", reconnect_after_s),
        ] {
            if let Some(v) = v {
                if !(v.is_finite() && v >= 0.0) {
                    return Err(format!("{name} {v}: must be a number of seconds >= 0"));
                }
            }
        }
        if reconnect_after_s.is_some() && disconnect_after_s.is_none() {
            return Err(format!(
                "--reconnect-after: robot {robot} is plugged back in but never unplugged; \
                 give it --disconnect-after {robot}:S"
            ));
        }
        let clean = FaultConfig::default();
        Ok(ServeOptions {
            speed: self.speed,
            to_robot: if self.only_from_robot { clean } else { faults },
            from_robot: if self.only_to_robot { clean } else { faults },
            disconnect_after_s,
            reconnect_after_s,
            link: self
                .link
                .as_deref()
                .map(|l| crate::fleet::serve::link_for(l, robot, robots)),
            seed: crate::fleet::robot_seed(self.world.seed, robot - 1),
            key: match &self.key_file {
                Some(p) => Some(crate::link::read_key_file(p)?),
                None => None,
            },
        })
    }
}

impl RunArgs {
    /// The arena to load: `--arena`, except that foraging replaces the default
    /// (Micro-Rato'99) with `builtin:forage`.
    pub fn arena(&self) -> &str {
        if self.task == TaskArg::Forage && self.world.arena == crate::builtin::MICRO_RATO_99 {
            crate::forage::BUILTIN_FORAGE
        } else {
            self.world.arena()
        }
    }

    /// `--timeout`, or the task's `default`; refused unless finite and positive.
    fn timeout_s(&self, default: f64) -> Result<f64, String> {
        match self.timeout {
            None => Ok(default),
            Some(t) if t.is_finite() && t > 0.0 => Ok(t),
            Some(t) => Err(format!("--timeout {t}: must be positive seconds")),
        }
    }

    /// The scenario these arguments describe.
    pub fn options(&self) -> Result<ScenarioOptions, String> {
        self.world.check()?;
        let timeout_s = self.timeout_s(if self.task == TaskArg::Forage {
            FORAGE_TIMEOUT_S
        } else {
            DEFAULT_TIMEOUT_S
        })?;
        let task = match self.task {
            TaskArg::GoTo => Task::GoTo(self.goal.map(|[x, y]| GoalPoint { x_m: x, y_m: y })),
            TaskArg::ReachBeacon | TaskArg::ExploreThenPlan if self.goal.is_some() => {
                return Err("--goal is for --task go-to; the search tasks head for the \
                            arena's beacon"
                    .to_string())
            }
            TaskArg::ReachBeacon => Task::ReachBeacon,
            TaskArg::ExploreThenPlan => Task::ExploreThenPlan,
            TaskArg::Forage if self.goal.is_some() => {
                return Err("--goal is for --task go-to; foraging heads for the lamps".to_string())
            }
            TaskArg::Forage => Task::Forage,
            TaskArg::OdometryLaps => {
                return Err("--task odometry-laps is run by `scenario::odometry_laps`".to_string())
            }
            TaskArg::LightMap => {
                return Err("--task light-map is run by `scenario::lightmap`".to_string())
            }
            TaskArg::UnsupervisedPlaces => {
                return Err(
                    "--task unsupervised-places is run by `unsupervised_places_options`"
                        .to_string(),
                )
            }
            TaskArg::LineCorrect => {
                return Err("--task line-correct is run by `line_correct_options`".to_string())
            }
            TaskArg::AliceEquilibrium
            | TaskArg::AliceEpsO
            | TaskArg::AliceCorrelation
            | TaskArg::AliceDynamic
            | TaskArg::AliceEpsOContinued
            | TaskArg::AliceNavigation => {
                return Err("the alice-* tasks are run by `alice::experiments`".to_string())
            }
        };
        let profile = if task == Task::Forage {
            &KHEPERA
        } else {
            self.world.profile.profile()
        };
        // Seed 004's search steers by compass and beacon; say so before the firmware refuses.
        let search = matches!(task, Task::ReachBeacon | Task::ExploreThenPlan);
        let sensors = protocol::caps::COMPASS | protocol::caps::BEACON;
        if search && !profile.has(sensors) {
            return Err(format!(
                "--task {} searches for the beacon by compass and beacon sensor (the Dom Dinis search), \
                 which the {} profile lacks; use --profile micro-rato",
                self.task
                    .to_possible_value()
                    .map_or_else(String::new, |v| v.get_name().to_string()),
                profile.name
            ));
        }
        let mut o = ScenarioOptions::new(profile, task);
        o.seed = self.world.seed;
        o.timeout_s = timeout_s;
        o.noise = self.world.noise()?;
        o.start = self.world.start_pose();
        o.true_wheel_distance_m = self.world.true_wheel_distance;
        o.slip = self.world.slip;
        o.params.extend(self.search.map(SearchArg::param));
        if self.calibrate_odometry
            && (!matches!(task, Task::GoTo(_)) || !profile.has(protocol::caps::ENCODERS))
        {
            return Err(
                "--calibrate-odometry: the odometry calibration is the Khepera go-to's; use \
                 --task go-to --profile khepera"
                    .to_string(),
            );
        }
        Ok(o)
    }
}

impl RunArgs {
    /// The contest `--robots N` / `--robot` ask for (`None`: one robot, `options`).
    pub fn contest_options(
        &self,
    ) -> Result<Option<crate::scenario::contest::ContestOptions>, String> {
        let Some(robots) = self.fleet.specs(&self.world)? else {
            return Ok(None);
        };
        if self.task != TaskArg::ReachBeacon {
            return Err(format!(
                "--robots/--robot: several robots run the Micro-Rato contest, --task \
                 reach-beacon (the Dom Dinis paper §2), not --task {}",
                self.task
                    .to_possible_value()
                    .map_or_else(String::new, |v| v.get_name().to_string())
            ));
        }
        if self.goal.is_some() {
            return Err("--goal is for --task go-to; the contest heads for the beacon".into());
        }
        self.world.check()?;
        Ok(Some(crate::scenario::contest::ContestOptions {
            robots,
            seed: self.world.seed,
            timeout_s: self.timeout_s(DEFAULT_TIMEOUT_S)?,
            noise: self.world.noise()?,
        }))
    }

    /// The unsupervised-places run these arguments describe: `--arena` names the generated
    /// arena kind, `--seed` its seed, `--timeout` the run length.
    pub fn unsupervised_places_options(
        &self,
    ) -> Result<crate::unsupervised_places::PlacesOptions, String> {
        use crate::unsupervised_places::{ArenaKind, PlacesOptions};
        if self.goal.is_some() {
            return Err("--goal is for --task go-to; unsupervised-places wanders".to_string());
        }
        let kind = ArenaKind::parse(&self.world.arena)?;
        let mut o = PlacesOptions::new(kind, self.world.seed);
        o.duration_s = self.timeout_s(o.duration_s)?;
        if o.duration_s > crate::unsupervised_places::MAX_DURATION_S {
            return Err(format!(
                "--timeout {}: unsupervised-places runs at most {} s (its report keeps a series)",
                o.duration_s,
                crate::unsupervised_places::MAX_DURATION_S
            ));
        }
        o.noise = self.world.noise()?;
        Ok(o)
    }

    /// The line-correction run these arguments describe (`--task line-correct`).
    pub fn line_correct_options(&self) -> Result<crate::line_correct::LineCorrectOptions, String> {
        self.world.check()?;
        if self.goal.is_some() {
            return Err("--goal is for --task go-to; line-correct surveys the grid".to_string());
        }
        if !(self.distance.is_finite() && self.distance > 0.0) {
            return Err(format!(
                "--distance {}: must be positive metres",
                self.distance
            ));
        }
        // A 40 m survey at 0.1 m/s takes 400 s: the go-to default (300 s) would cut it.
        let timeout_s = self.timeout_s(self.distance / 0.1 * 1.5)?;
        let mut o = crate::line_correct::LineCorrectOptions::new(self.world.profile.profile());
        o.seed = self.world.seed;
        o.distance_m = self.distance;
        o.timeout_s = timeout_s;
        o.noise = self.world.noise()?;
        o.start = self.world.start_pose();
        if let Some(g) = self.world.floor_grid {
            o.floor_grid_m = g;
        }
        Ok(o)
    }
}

/// Simulated seconds a scenario runs before giving up, unless `--timeout` says.
const DEFAULT_TIMEOUT_S: f64 = 300.0;
/// Foraging's: 20 simulated minutes, in which seeds 1-6 bring 1-3 of the 3 objects home (the
/// first after 4-13 minutes of searching); 300 s would end most runs with none.
const FORAGE_TIMEOUT_S: f64 = 1200.0;

fn numbers(s: &str, what: &str, min: usize, max: usize) -> Result<Vec<f64>, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() < min || parts.len() > max {
        return Err(format!("expected {what}, got `{s}`"));
    }
    parts
        .iter()
        .map(|p| {
            p.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("`{p}` in `{s}` is not a finite number ({what})"))
        })
        .collect()
}

fn parse_point(s: &str) -> Result<[f64; 2], String> {
    let v = numbers(s, "X,Y in metres", 2, 2)?;
    Ok([v[0], v[1]])
}

/// `X,Y[,HEADING_DEG]` in metres and degrees (`--start`).
pub fn parse_pose(s: &str) -> Result<[f64; 3], String> {
    let v = numbers(s, "X,Y or X,Y,HEADING_DEG", 2, 3)?;
    Ok([v[0], v[1], v.get(2).copied().unwrap_or(0.0)])
}

pub fn parse_stall(s: &str) -> Result<Stall, String> {
    let v = numbers(s, "PERIOD,DURATION in seconds", 2, 2)?;
    Ok(Stall {
        period_s: v[0],
        duration_s: v[1],
    })
}

fn parse_speed(s: &str) -> Result<Speed, String> {
    if s.eq_ignore_ascii_case("max") {
        return Ok(Speed::Max);
    }
    match s.parse::<f64>() {
        Ok(f) if f.is_finite() && f > 0.0 => Ok(Speed::Factor(f)),
        _ => Err(format!("`{s}` is neither a positive factor nor `max`")),
    }
}

/// Ends the process quietly, status 141 (128 + SIGPIPE, what a shell expects), when printing
/// to stdout fails because the reader went away (`robot-emulator run --json | head -1`):
/// Rust ignores SIGPIPE, so `println!` would panic with "failed printing to stdout" instead
/// of the program ending as `cat` does. Every other panic goes to the hook before it.
pub fn exit_quietly_on_broken_pipe() {
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let text = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if text.starts_with("failed printing to stdout") && text.contains("Broken pipe") {
            std::process::exit(141);
        }
        previous(info);
    }));
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(args: &[&str]) -> Result<Cli, clap::Error> {
        Cli::try_parse_from(std::iter::once("robot-emulator").chain(args.iter().copied()))
    }

    #[test]
    fn defaults_serve_micro_rato_99_in_real_time() {
        let cli = parse(&[]).expect("no arguments is valid");
        assert!(cli.command.is_none());
        let o = cli.serve.options().expect("valid");
        assert_eq!(o.arena, crate::builtin::MICRO_RATO_99);
        assert_eq!(o.serve.speed, Speed::Factor(1.0));
        assert_eq!(o.sim.baud, 115_200);
    }

    #[test]
    fn bad_values_name_the_flag() {
        let cli = parse(&["--drop-rate", "2"]).expect("parses");
        assert!(cli.serve.options().unwrap_err().contains("drop rate"));
        assert!(parse(&["--speed", "fast"]).is_err());
        assert!(parse(&["--speed", "-1"]).is_err());
        assert!(parse(&["run", "--goal", "1"]).is_err());
        assert!(parse(&["run", "--goal", "1,nan"]).is_err());
        assert!(parse(&["--profile", "roomba"]).is_err());
        let cli = parse(&["--baud", "0"]).expect("parses");
        assert!(cli.serve.options().unwrap_err().contains("--baud"));
        assert!(
            parse(&["--reconnect-after", "1"]).is_err(),
            "needs --disconnect-after"
        );
    }

    #[test]
    fn line_correct_takes_distance_and_line_faults() {
        let cli = parse(&[
            "run",
            "--task",
            "line-correct",
            "--profile",
            "khepera",
            "--arena",
            "builtin:floor-grid",
            "--line-miss",
            "0.3",
            "--distance",
            "12",
        ])
        .expect("valid");
        let Some(Command::Run(r)) = cli.command else {
            panic!("run subcommand")
        };
        let o = r.line_correct_options().expect("valid");
        assert_eq!((o.distance_m, o.noise.line_miss), (12.0, 0.3));
        assert!(r.options().is_err(), "not a go-to scenario");
        let cli = parse(&["run", "--task", "line-correct", "--line-miss", "2"]).expect("parses");
        let Some(Command::Run(r)) = cli.command else {
            panic!("run subcommand")
        };
        let e = r.line_correct_options().unwrap_err();
        assert!(e.contains("--line-miss"), "{e}");
        // Serving the floor-grid arena lays its grid.
        let cli = parse(&["--arena", "builtin:floor-grid", "--profile", "khepera"]).expect("ok");
        let o = cli.serve.options().expect("valid");
        assert_eq!(o.sim.floor_grid_m, Some(0.1));
    }

    #[test]
    fn run_takes_task_goal_and_seed() {
        let cli = parse(&[
            "run",
            "--profile",
            "khepera",
            "--goal",
            "0.4,0.2",
            "--seed",
            "9",
        ])
        .expect("valid");
        let Some(Command::Run(r)) = cli.command else {
            panic!("run subcommand")
        };
        let o = r.options().expect("valid");
        assert_eq!(o.seed, 9);
        assert_eq!(o.task, Task::GoTo(Some(GoalPoint { x_m: 0.4, y_m: 0.2 })));
    }

    #[test]
    fn robots_get_numbered_links_and_their_own_faults_and_seeds() {
        let cli = parse(&[
            "--robots",
            "3",
            "--link",
            "/tmp/robot",
            "--drop-rate",
            "0.01",
            "--drop-rate",
            "2:0.5",
            "--disconnect-after",
            "2:5",
            "--reconnect-after",
            "2:1",
        ])
        .expect("valid");
        let a = &cli.serve;
        assert_eq!(a.robots().expect("valid").map(|r| r.len()), Some(3));
        let l1 = a.link_options(1, 3).expect("valid");
        let l2 = a.link_options(2, 3).expect("valid");
        assert_eq!(
            l1.link.as_deref(),
            Some(std::path::Path::new("/tmp/robot1"))
        );
        assert_eq!(
            l2.link.as_deref(),
            Some(std::path::Path::new("/tmp/robot2"))
        );
        assert_eq!((l1.to_robot.drop_rate, l2.to_robot.drop_rate), (0.01, 0.5));
        assert_eq!(
            (l1.disconnect_after_s, l2.disconnect_after_s),
            (None, Some(5.0))
        );
        assert_eq!(l2.reconnect_after_s, Some(1.0));
        assert_eq!(l1.seed, 1, "robot 1 keeps the run's seed");
        assert_ne!(l2.seed, l1.seed);
        // One robot keeps today's path and faults.
        let one = parse(&["--link", "/tmp/robot", "--drop-rate", "0.2"]).expect("valid");
        assert!(one.serve.robots().expect("valid").is_none());
        let o = one.serve.options().expect("valid");
        assert_eq!(
            o.serve.link.as_deref(),
            Some(std::path::Path::new("/tmp/robot"))
        );
        assert_eq!(o.serve.to_robot.drop_rate, 0.2);
    }

    #[test]
    fn robot_takes_a_profile_and_an_optional_pose_and_profiles_mix() {
        let cli = parse(&[
            "run",
            "--task",
            "reach-beacon",
            "--robot",
            "micro-rato@0.5,0.5,90",
            "--robot",
            "micro-rato",
        ])
        .expect("valid");
        let Some(Command::Run(r)) = cli.command else {
            panic!("run subcommand")
        };
        let c = r.contest_options().expect("valid").expect("a contest");
        assert_eq!(c.robots.len(), 2);
        let s = c.robots[0].start.expect("a pose");
        assert!((s.heading - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert!(c.robots[1].start.is_none());
        let mixed = parse(&["--robot", "khepera", "--robot", "micro-rato@1,1"]).expect("valid");
        let specs = mixed.serve.robots().expect("valid").expect("a fleet");
        assert_eq!(specs[0].profile.name, KHEPERA.name);
        assert_eq!(specs[1].profile.name, MICRO_RATO.name);
        assert!(parse(&["--robot", "roomba"]).is_err());
        assert!(parse(&["--robots", "2", "--robot", "khepera"]).is_err());
    }
}
