//! The foraging scenario (seed 000 §7): `robot-emulator run --task forage`.
//!
//! Layer: on top of [`Sim`], beside the go-to and search scenarios. The site is the arena's
//! own (`builtin:forage`, the default for this task) or one drawn from the seed for any
//! other arena (`ForageSite::for_arena`: home at the start, three lamps with objects). The
//! robot is told only what a station would: `SetMode(Forage)`; it starts at its home base.
//! The run ends when every object is delivered (plus a settle, so the last drop is seen) or
//! at the timeout.
//!
//! What the report measures, from the emulator's ground truth: objects delivered (put down
//! inside the home base), when, and at each put-down ("return home") the distance between
//! the robot's true and believed position and heading, plus how far from the home centre the
//! object landed. What can fail: the setup ([`ScenarioError`]); the run itself cannot.

use std::time::Instant;

use protocol::{Command, Mode};
use serde::Serialize;

use super::task::{apply, ScenarioError, ScenarioOptions, SETTLE_MS};
use crate::arena::Arena;
use crate::forage::ForageSite;
use crate::geometry::Point;
use crate::sim::{Sim, SimConfig};
use crate::world::World;

/// One object put down.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HomeReturn {
    /// Simulated seconds since the start.
    pub time_s: f64,
    /// Inside the home base.
    pub delivered: bool,
    /// True-versus-believed position error at the put-down, metres.
    pub pose_error_m: f64,
    /// True-versus-believed heading error, degrees.
    pub heading_error_deg: f64,
    /// Distance from the object to the home base's centre, metres.
    pub from_home_m: f64,
}

/// The outcome of a foraging run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ForageReport {
    /// Arena name.
    pub arena: String,
    /// Profile name.
    pub profile: &'static str,
    /// The run's seed.
    pub seed: u64,
    /// Always `forage`.
    pub task: &'static str,
    /// Home base centre and radius, metres.
    pub home: [f64; 3],
    /// The lamps (each with one object), metres.
    pub sources: Vec<[f64; 2]>,
    /// Objects in play.
    pub objects: usize,
    /// Objects put down inside the home base.
    pub delivered: usize,
    /// Every object was delivered before the timeout.
    pub all_delivered: bool,
    /// Objects the firmware reported gripped (`ObjectGrasped`).
    pub firmware_grasped: u16,
    /// Objects the firmware reported delivered (`ObjectDelivered`).
    pub firmware_delivered: u16,
    /// Sources the firmware remembers as emptied.
    pub firmware_sources: usize,
    /// Each put-down, in order.
    pub returns: Vec<HomeReturn>,
    /// Largest position error at a put-down, metres (0 with none).
    pub max_return_error_m: f64,
    /// Simulated seconds.
    pub sim_s: f64,
    /// Wall-clock seconds.
    pub wall_s: f64,
    /// Wall contacts.
    pub collisions: u32,
    /// Ground distance travelled, metres.
    pub distance_m: f64,
    /// Final true-versus-believed position error, metres.
    pub pose_error_m: f64,
}

/// Runs the foraging task on `arena`.
pub fn run_forage(arena: Arena, opts: ScenarioOptions) -> Result<ForageReport, ScenarioError> {
    if !(opts.timeout_s.is_finite() && opts.timeout_s > 0.0) {
        return Err(ScenarioError::BadTimeout(opts.timeout_s));
    }
    let name = arena.name.clone();
    // The site is drawn in the bare world (no added lights) the run will extend.
    let probe = World::new(arena.clone(), Vec::new(), None).map_err(crate::sim::SimError::from)?;
    let start = opts
        .start
        .or_else(|| arena.starts.first().copied())
        .map(|p| Point::new(p.x, p.y))
        .or_else(|| probe.free_spot(f64::from(opts.profile.body_diameter_m) / 2.0))
        .unwrap_or(arena.bounds.min);
    let site = ForageSite::for_arena(&probe, start, opts.seed);
    if site.sources.is_empty() {
        return Err(ScenarioError::NoSources(name));
    }
    let home = site.home;
    let cfg = SimConfig {
        forage: Some(site.clone()),
        ..opts.sim_config()
    };
    let mut sim = Sim::new(arena, cfg)?;
    apply(&mut sim, Command::SetMode(Mode::Forage), "SetMode(Forage)")?;
    let started = Instant::now();
    let timeout_ms = (opts.timeout_s * 1000.0).ceil() as u64;
    let objects = sim.gripper().objects().len();
    let mut returns = Vec::new();
    let mut seen = 0;
    for _ in 0..timeout_ms {
        sim.step();
        let drops = sim.gripper().drops();
        let dropped = drops.len() > seen;
        if dropped {
            let d = drops[drops.len() - 1];
            seen = drops.len();
            let (t, b) = (sim.truth(), sim.believed());
            let dh = crate::physics::wrap_pi(t.heading - b.heading);
            returns.push(HomeReturn {
                time_s: d.time_ms as f64 / 1000.0,
                delivered: d.delivered,
                pose_error_m: sim.pose_error_m(),
                heading_error_deg: dh.to_degrees(),
                from_home_m: (d.position - home.centre).norm(),
            });
        }
        // Only a drop can deliver (counting the objects every step was 4 % of a run); a site
        // without objects is done at once.
        if (dropped || objects == 0) && sim.gripper().delivered() == objects {
            sim.run_for(SETTLE_MS);
            break;
        }
    }
    // (0, 0, 0) cannot happen: SetMode(Forage) was accepted, so the composition forages.
    let (firmware_grasped, firmware_delivered, firmware_sources) = sim
        .robot()
        .forage()
        .map_or((0, 0, 0), |f| (f.grasped, f.delivered, f.sources().len()));
    let delivered = sim.gripper().delivered();
    Ok(ForageReport {
        arena: name,
        profile: opts.profile.name,
        seed: opts.seed,
        task: "forage",
        home: [home.centre.x, home.centre.y, home.radius_m],
        sources: site
            .sources
            .iter()
            .map(|l| [l.position.x, l.position.y])
            .collect(),
        objects,
        delivered,
        all_delivered: delivered == objects,
        firmware_grasped,
        firmware_delivered,
        firmware_sources,
        max_return_error_m: returns.iter().map(|r| r.pose_error_m).fold(0.0, f64::max),
        returns,
        sim_s: sim.now_us() as f64 * 1e-6,
        wall_s: started.elapsed().as_secs_f64(),
        collisions: sim.collisions(),
        distance_m: sim.distance_m(),
        pose_error_m: sim.pose_error_m(),
    })
}
