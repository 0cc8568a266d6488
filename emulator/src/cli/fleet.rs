//! Several robots in one arena (`serve --robots`/`--robot`), and the per-robot values
//! (`ROBOT:VALUE`) of the link faults.

use clap::{Args, ValueEnum};

use super::parse::{parse_pose, parse_stall};
use super::world::{ProfileArg, WorldArgs};
use crate::fault::Stall;
use crate::fleet::RobotSpec;

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
pub(super) fn check_robots<T>(
    flag: &str,
    list: &[PerRobot<T>],
    robots: usize,
) -> Result<(), String> {
    match list.iter().find_map(|p| p.robot.filter(|&r| r > robots)) {
        Some(r) => Err(format!(
            "{flag} {r}:...: robot {r} does not exist; this run has {robots} robot(s), \
             numbered from 1"
        )),
        None => Ok(()),
    }
}

/// Splits `ROBOT:REST` (`ROBOT` a whole number from 1) from a per-robot value.
pub(super) fn split_robot(s: &str) -> Result<(Option<usize>, &str), String> {
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

pub(super) fn parse_per_robot_number(s: &str) -> Result<PerRobot<f64>, String> {
    let (robot, rest) = split_robot(s)?;
    let value = rest
        .trim()
        .parse::<f64>()
        .map_err(|_| format!("`{rest}` in `{s}` is not a number"))?;
    Ok(PerRobot { robot, value })
}

pub(super) fn parse_per_robot_stall(s: &str) -> Result<PerRobot<Stall>, String> {
    let (robot, rest) = split_robot(s)?;
    Ok(PerRobot {
        robot,
        value: parse_stall(rest)?,
    })
}

/// `PROFILE[@X,Y,DEG]` (`--robot`).
pub(super) fn parse_robot(s: &str) -> Result<RobotArg, String> {
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
