//! Several robots in one world (issue 17; seed 004 §2: "Three robots compete
//! simultaneously").
//!
//! Layer: std, on top of [`Sim`]. A [`Fleet`] is one [`Sim`] per robot, each its own firmware
//! instance, sensors, noise, battery and UART, over the same arena, stepped in lockstep one
//! millisecond at a time. Before robot `i` steps it is told where the others are now
//! ([`Sim::set_neighbours`]): its IR sensors see their bodies (and its bump, the firmware's
//! IR contact threshold, fires on them), their bodies can hide the beacon, and its body
//! cannot enter theirs ([`contact`]). Robots step in index order, so robot `i` sees robots
//! before it at this millisecond and after it at the last: a millisecond's lag, a quarter of a
//! millimetre at the micro-rato's 0.23 m/s.
//!
//! Determinism: robot `i`'s runs draw from [`robot_seed`]`(seed, i)`: robot 1 (index 0) keeps
//! the run's seed, so a fleet of one is today's single robot bit for bit, and every other
//! robot gets its own independent streams. Nothing reads the wall clock.
//!
//! What can fail: [`Fleet::new`] (a robot's setup, starts that overlap or no room: see
//! [`starts`]). Stepping cannot fail.

pub mod contact;
pub mod serve;
pub mod starts;

use robot_firmware::Profile;
use thiserror::Error;

use crate::arena::{Arena, Pose};
use crate::rng::SimRng;
use crate::sim::{Sim, SimConfig, SimError};
use crate::world::World;
use contact::{Neighbour, MAX_ROBOTS};

/// Stream from which robots 2.. derive their seeds (beyond the per-component streams of
/// `rng::stream`).
const FLEET_SEED_STREAM: u64 = 0x0046_6c65_6574; // "Fleet"

/// The seed of robot `index` (0-based) in a run seeded with `seed`: robot 1 keeps `seed`;
/// each other robot gets its own, drawn from a stream of `seed`, so its noise is independent
/// of the others' and the same in every run with that seed.
pub fn robot_seed(seed: u64, index: usize) -> u64 {
    if index == 0 {
        seed
    } else {
        SimRng::new(seed, FLEET_SEED_STREAM.wrapping_add(index as u64)).next_u64()
    }
}

/// One robot of a fleet: which robot, and where it starts (default: [`starts`]'s rule).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RobotSpec {
    /// Its profile (profiles may be mixed).
    pub profile: &'static Profile,
    /// Its start pose.
    pub start: Option<Pose>,
}

/// Why a fleet cannot start.
#[derive(Debug, Error)]
pub enum FleetError {
    /// No robots, or more than the world holds.
    #[error("a fleet has 1 to {MAX_ROBOTS} robots, not {0}")]
    Count(usize),
    /// The arena or a robot's configuration.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// The start poses.
    #[error(transparent)]
    Start(#[from] starts::StartError),
    /// One robot's simulation.
    #[error("robot {robot}: {source}")]
    Robot {
        /// 1-based robot number.
        robot: usize,
        /// Why.
        source: SimError,
    },
}

/// Several robots in one world.
pub struct Fleet {
    sims: Vec<Sim>,
    /// Reused every step: the bodies of all robots.
    scratch: Vec<Neighbour>,
}

impl Fleet {
    /// Builds one simulation per robot over `arena`. `base` gives what the robots share
    /// (seed, noise, baud, lights, floor grid; its `profile` and `start` are replaced by each
    /// robot's); robot `i` is seeded with [`robot_seed`].
    pub fn new(arena: Arena, base: &SimConfig, robots: &[RobotSpec]) -> Result<Fleet, FleetError> {
        if robots.is_empty() || robots.len() > MAX_ROBOTS {
            return Err(FleetError::Count(robots.len()));
        }
        let world = World::new(arena.clone(), base.lights.clone(), None).map_err(SimError::from)?;
        let radii: Vec<f64> = robots
            .iter()
            .map(|r| f64::from(r.profile.body_diameter_m) / 2.0)
            .collect();
        let given: Vec<Option<Pose>> = robots.iter().map(|r| r.start).collect();
        let poses = starts::start_poses(&world, &given, &radii)?;
        let mut sims = Vec::with_capacity(robots.len());
        for (i, (spec, pose)) in robots.iter().zip(poses).enumerate() {
            let cfg = SimConfig {
                profile: spec.profile,
                seed: robot_seed(base.seed, i),
                start: Some(pose),
                ..base.clone()
            };
            let mut sim = Sim::new(arena.clone(), cfg).map_err(|source| FleetError::Robot {
                robot: i + 1,
                source,
            })?;
            // Robot k is robot id k (MAX_ROBOTS is far below 255), as `--link` names its
            // pty k: the station can tell the robots apart from the handshake on.
            sim.robot_mut().config_mut().robot_id = u8::try_from(i + 1).unwrap_or(u8::MAX);
            sims.push(sim);
        }
        let mut fleet = Fleet {
            scratch: Vec::with_capacity(sims.len()),
            sims,
        };
        fleet.tell_neighbours_all();
        Ok(fleet)
    }

    /// Number of robots.
    pub fn len(&self) -> usize {
        self.sims.len()
    }

    /// Always false: a fleet has at least one robot.
    pub fn is_empty(&self) -> bool {
        self.sims.is_empty()
    }

    /// Every robot's simulation, in robot order.
    pub fn sims(&self) -> &[Sim] {
        &self.sims
    }

    /// Every robot's simulation, mutably (its firmware, its UART).
    pub fn sims_mut(&mut self) -> &mut [Sim] {
        &mut self.sims
    }

    /// Simulated time, microseconds (the same for every robot).
    pub fn now_us(&self) -> u64 {
        self.sims.first().map_or(0, Sim::now_us)
    }

    /// Advances every robot one millisecond, in robot order, each seeing the others where
    /// they are at that moment.
    pub fn step(&mut self) {
        if self.sims.len() == 1 {
            if let Some(s) = self.sims.first_mut() {
                s.step();
            }
            return;
        }
        for i in 0..self.sims.len() {
            self.scratch.clear();
            self.scratch
                .extend(
                    self.sims
                        .iter()
                        .enumerate()
                        .filter(|(j, _)| *j != i)
                        .map(|(j, s)| Neighbour {
                            id: j,
                            body: s.disc(),
                        }),
                );
            if let Some(s) = self.sims.get_mut(i) {
                s.set_neighbours(self.scratch.iter().copied());
                s.step();
            }
        }
    }

    /// Advances `ms` milliseconds.
    pub fn run_for(&mut self, ms: u64) {
        for _ in 0..ms {
            self.step();
        }
    }

    /// Tells every robot where the others are (after building, and after a robot is
    /// carried somewhere), so the first readings already see them.
    pub fn tell_neighbours_all(&mut self) {
        let bodies: Vec<Neighbour> = self
            .sims
            .iter()
            .enumerate()
            .map(|(j, s)| Neighbour {
                id: j,
                body: s.disc(),
            })
            .collect();
        for (i, s) in self.sims.iter_mut().enumerate() {
            s.set_neighbours(bodies.iter().filter(|n| n.id != i).copied());
        }
    }
}
