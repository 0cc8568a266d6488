//! The robot and its world, as every subcommand that simulates one takes them (`serve`,
//! `run`, `hil`): profile, arena, start, seed, noise, wheel errors, floor grid.

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use robot_firmware::{Profile, ALICE, KHEPERA, MICRO_RATO};

use super::parse::parse_pose;
use crate::sensors::Noise;
use crate::sim::SimConfig;

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

impl WorldArgs {
    /// The arena to load: `--arena`, except that ALICE replaces the default (Micro-Rato'99)
    /// with its own scene, `builtin:alice` (seed 001 §4.5), as foraging does with its own.
    pub fn arena(&self) -> &str {
        if self.profile == ProfileArg::Alice && self.arena == crate::builtin::MICRO_RATO_99 {
            crate::builtin::alice::BUILTIN_ALICE
        } else {
            &self.arena
        }
    }

    pub(super) fn noise(&self) -> Result<Noise, String> {
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

    pub(super) fn check(&self) -> Result<(), String> {
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

    pub(super) fn start_pose(&self) -> Option<crate::arena::Pose> {
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
