//! `robot-emulator run`: a headless scenario and its JSON report.

use clap::{Args, ValueEnum};
use robot_firmware::KHEPERA;

use super::fleet::FleetArgs;
use super::parse::parse_point;
use super::world::WorldArgs;
use crate::scenarios::alice::navigation::{Drift, Scene, StepBase, TestMap};
use crate::scenarios::task::{GoalPoint, ScenarioOptions, Task};

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
    pub(super) fn timeout_s(&self, default: f64) -> Result<f64, String> {
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
                return Err("--task odometry-laps is run by `scenarios::odometry_laps`".to_string())
            }
            TaskArg::LightMap => {
                return Err("--task light-map is run by `scenarios::lightmap`".to_string())
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
    ) -> Result<Option<crate::scenarios::contest::ContestOptions>, String> {
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
        Ok(Some(crate::scenarios::contest::ContestOptions {
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
    ) -> Result<crate::scenarios::unsupervised_places::PlacesOptions, String> {
        use crate::scenarios::unsupervised_places::{ArenaKind, PlacesOptions};
        if self.goal.is_some() {
            return Err("--goal is for --task go-to; unsupervised-places wanders".to_string());
        }
        let kind = ArenaKind::parse(&self.world.arena)?;
        let mut o = PlacesOptions::new(kind, self.world.seed);
        o.duration_s = self.timeout_s(o.duration_s)?;
        if o.duration_s > crate::scenarios::unsupervised_places::MAX_DURATION_S {
            return Err(format!(
                "--timeout {}: unsupervised-places runs at most {} s (its report keeps a series)",
                o.duration_s,
                crate::scenarios::unsupervised_places::MAX_DURATION_S
            ));
        }
        o.noise = self.world.noise()?;
        Ok(o)
    }

    /// The line-correction run these arguments describe (`--task line-correct`).
    pub fn line_correct_options(
        &self,
    ) -> Result<crate::scenarios::line_correct::LineCorrectOptions, String> {
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
        let mut o =
            crate::scenarios::line_correct::LineCorrectOptions::new(self.world.profile.profile());
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
pub(super) const DEFAULT_TIMEOUT_S: f64 = 300.0;
/// Foraging's: 20 simulated minutes, in which seeds 1-6 bring 1-3 of the 3 objects home (the
/// first after 4-13 minutes of searching); 300 s would end most runs with none.
pub(super) const FORAGE_TIMEOUT_S: f64 = 1200.0;

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
