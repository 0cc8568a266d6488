//! `robot-emulator serve` (the default): the simulated robot on a pseudo-terminal, its link
//! faults, its speed.

use std::path::PathBuf;

use clap::Args;

use super::fleet::{
    check_robots, for_robot, parse_per_robot_number, parse_per_robot_stall, FleetArgs, PerRobot,
};
use super::parse::parse_speed;
use super::world::WorldArgs;
use crate::fault::{FaultConfig, Stall};
use crate::fleet::RobotSpec;
use crate::link::{EmulatorOptions, ServeOptions, Speed};

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
