//! `robot-emulator bench`: one task over many arenas and seeds, and what it takes to check
//! them.

use clap::Args;

use super::run::{SearchArg, DEFAULT_TIMEOUT_S, FORAGE_TIMEOUT_S};
use super::world::ProfileArg;
use crate::sensors::Noise;

/// `bench` options.
#[derive(Debug, Clone, Args)]
pub struct BenchArgs {
    /// The task every run does.
    #[arg(long, value_enum)]
    pub task: crate::scenarios::bench::BenchTask,
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

/// Most seeds per arena `bench --seeds` takes.
pub const MAX_BENCH_SEEDS: u64 = 10_000;
/// Most worker threads `bench --jobs` takes.
pub const MAX_BENCH_JOBS: usize = 1024;

impl BenchArgs {
    /// The benchmark these arguments describe.
    pub fn options(&self) -> Result<crate::scenarios::bench::BenchOptions, String> {
        use crate::scenarios::bench::BenchTask;
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
        let arenas = crate::scenarios::bench::resolve_arenas(&self.arenas, kind)?;
        Ok(crate::scenarios::bench::BenchOptions {
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
