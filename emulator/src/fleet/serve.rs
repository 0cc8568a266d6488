//! Serving a fleet: one pseudo-terminal per robot, one simulated world, one loop.
//!
//! Layer: the fleet's I/O loop, the multi-robot form of `link::serve`. Each robot has its
//! own [`Endpoint`] (pty, `--link` symlink, fault injectors, unplug and replug times, byte
//! counters), so one robot's link can be cut, corrupted or stalled while the others run; the
//! world steps all robots together against the wall clock (times `speed`).
//!
//! Ports: with `--link PATH` robot `k` (1-based) of a fleet of two or more gets
//! `PATH` followed by `k` ([`link_for`]: `/tmp/robot` gives `/tmp/robot1`, `/tmp/robot2`,
//! ...); a single robot keeps `PATH` itself.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use serde::Serialize;

use super::Fleet;
use crate::link::{
    CycleClock, Device, Endpoint, RealTime, ServeOptions, ServeStats, Speed, MAX_CATCH_UP_MS,
    MAX_SPEED_BATCH_MS,
};
use crate::pty::{Pty, PtyError};

/// The path of robot `robot`'s (1-based) `--link` symlink in a fleet of `robots`.
pub fn link_for(base: &Path, robot: usize, robots: usize) -> PathBuf {
    if robots <= 1 {
        return base.to_path_buf();
    }
    let mut name = base.as_os_str().to_owned();
    name.push(robot.to_string());
    PathBuf::from(name)
}

/// What one robot's link measured, with its collisions.
#[derive(Clone, Debug, Serialize)]
pub struct RobotServeStats {
    /// 1-based robot number.
    pub robot: usize,
    /// Profile name.
    pub profile: &'static str,
    /// Its `--link` symlink, if any.
    pub link: Option<String>,
    /// Wall contacts.
    pub wall_collisions: u32,
    /// Contacts with other robots.
    pub robot_collisions: u32,
    /// Its link's counters and real-time jitter.
    #[serde(flatten)]
    pub serve: ServeStats,
}

/// What a fleet's serving run measured.
#[derive(Clone, Debug, Serialize)]
pub struct FleetServeStats {
    /// Robots served.
    pub robots: usize,
    /// Simulated seconds.
    pub sim_s: f64,
    /// Wall-clock seconds.
    pub wall_s: f64,
    /// Real-time mode: the largest p99 of the robots' control-cycle periods, microseconds
    /// (0 at maximum speed).
    pub worst_cycle_p99_us: f64,
    /// Each robot, in order.
    pub per_robot: Vec<RobotServeStats>,
}

/// Serves every robot of `fleet` on its own pty until `stop` is set; `links[i]` is robot
/// `i`'s link options (its faults, symlink, seed, key). `speed` is taken from the first.
/// `on_ready(i, path)` reports each robot's pty (again after each replug).
pub fn serve(
    fleet: &mut Fleet,
    links: &[ServeOptions],
    stop: &AtomicBool,
    on_ready: &mut dyn FnMut(usize, &Path),
) -> Result<FleetServeStats, PtyError> {
    let n = fleet.len().min(links.len());
    let speed = links.first().map_or(Speed::Factor(1.0), |o| o.speed);
    let mut ends = Vec::with_capacity(n);
    for (i, (sim, opts)) in fleet.sims_mut().iter_mut().zip(links).enumerate() {
        sim.set_link_key(opts.key.as_ref());
        ends.push(Endpoint::open(opts, &mut |p| on_ready(i, p))?);
    }
    let wall0 = Instant::now();
    let sim0 = fleet.now_us();
    let mut clocks: Vec<CycleClock> = fleet
        .sims()
        .iter()
        .map(|s| CycleClock::new(s.cycles()))
        .collect();

    let real_time = match speed {
        Speed::Factor(f) => {
            crate::link::precise_wake_ups();
            Some(RealTime::new(wall0, sim0, f))
        }
        Speed::Max => None,
    };
    while !stop.load(Ordering::Relaxed) {
        // As the one-robot loop (`link::serve`): every step whose start the clock has reached,
        // each robot's wire moved on to it first.
        let now_us = match &real_time {
            Some(rt) => {
                let now = rt.sim_now();
                let mut steps = 0;
                while fleet.now_us() <= now && steps < MAX_CATCH_UP_MS {
                    let t = fleet.now_us();
                    for s in fleet.sims_mut() {
                        s.sync_line(t);
                    }
                    fleet.step();
                    for (c, s) in clocks.iter_mut().zip(fleet.sims()) {
                        c.observe(s.cycles());
                    }
                    steps += 1;
                }
                now
            }
            None => {
                for _ in 0..MAX_SPEED_BATCH_MS {
                    fleet.step();
                }
                fleet.now_us()
            }
        };
        let t_s = (fleet.now_us() - sim0) as f64 * 1e-6;
        for (i, (end, sim)) in ends.iter_mut().zip(fleet.sims_mut()).enumerate() {
            end.plug(t_s, &mut |p| on_ready(i, p))?;
            let (line_us, take_until) = crate::link::exchange_clock(real_time.as_ref(), now_us);
            end.exchange(sim, t_s, line_us, take_until);
        }
        if let Some(rt) = &real_time {
            let due = fleet
                .sims()
                .iter()
                .map(|s| {
                    s.next_due_us()
                        .min(s.next_frame_end_us().unwrap_or(u64::MAX))
                })
                .min()
                .unwrap_or(now_us + 1000);
            let wait = rt.wall_at(due).saturating_duration_since(Instant::now());
            let ptys: Vec<&Pty> = ends.iter().filter_map(Endpoint::pty).collect();
            Pty::wait_any(&ptys, wait);
        }
    }
    let sim_s = (fleet.now_us() - sim0) as f64 * 1e-6;
    let wall_s = wall0.elapsed().as_secs_f64();
    let per_robot: Vec<RobotServeStats> = ends
        .into_iter()
        .zip(clocks)
        .zip(fleet.sims())
        .zip(links)
        .enumerate()
        .map(|(i, (((end, clock), sim), opts))| {
            let mut serve = end.finish(sim);
            serve.sim_s = sim_s;
            serve.wall_s = wall_s;
            serve.cycle_period_us = clock.jitter(sim.cycle_us());
            RobotServeStats {
                robot: i + 1,
                profile: sim.robot().profile().name,
                link: opts.link.as_ref().map(|l| l.display().to_string()),
                wall_collisions: sim.collisions(),
                robot_collisions: sim.robot_collisions(),
                serve,
            }
        })
        .collect();
    Ok(FleetServeStats {
        robots: n,
        sim_s,
        wall_s,
        worst_cycle_p99_us: per_robot
            .iter()
            .map(|r| r.serve.cycle_period_us.p99_us)
            .fold(0.0, f64::max),
        per_robot,
    })
}
