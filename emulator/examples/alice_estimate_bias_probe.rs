//! Where seed 001 §4.2.4's position estimate p_est leans: its error against the truth along
//! the direction away from the nearest obstacle, by the robot's clearance from it: a likely
//! source of the map's shrink with exact odometry (see the doc comment of
//! `the_map_is_larger_than_the_world_by_the_odometrys_drift`, which says what it leaves open).
//!
//! `cargo run --release -p emulator --example alice_estimate_bias_probe -- [NAME=VALUE ...]`
//! runs the §4.5 scene (pillar, ALICE's body, the wanderer) for 6000 situations with exact
//! odometry (but for the turns' 1 %) and the correlations as good as off (eps_or 0, eps_pos
//! 1e-9: the estimate is made every situation but moves the pose by a nanometre per metre of
//! its error), so the map stays in the world's frame and p_est can be held against the truth.
//! From situation 1000 on, seeds 1-10, it prints per seed and pooled the mean error away
//! from the nearest wall or the pillar in 0.2 m bins of the centre's clearance from it
//! (positive: the estimate lies farther from the obstacle than the robot), and the mean
//! distance between estimate and truth.

use emulator::builtin::alice::alice;
use emulator::geometry::Point;
use emulator::scenarios::alice::scenario::{run_with, RunOptions};
use world_model::Params;

/// Clearance bins, 0.2 m wide; the last takes everything beyond.
const BINS: usize = 6;
const BIN_M: f64 = 0.2;
/// The map forms first.
const FROM: u64 = 1000;

fn main() {
    if let Err(e) = probe() {
        eprintln!("alice_estimate_bias_probe: {e}");
        std::process::exit(2);
    }
}

fn probe() -> Result<(), String> {
    let mut p = Params {
        eps_or: 0.0,
        eps_pos: 1e-9,
        ..Params::default()
    };
    for kv in std::env::args().skip(1) {
        p.assign(&kv).map_err(|e| e.to_string())?;
    }
    // The scene `run_with` drives in (no gap wall: `remove_wall_at` stays None).
    let obstacles = alice().segment_set();
    println!("p_est's error away from the nearest obstacle, metres, by clearance bins of {BIN_M} m (count)");
    let mut pooled = [(0.0f64, 0u64); BINS];
    let (mut dist, mut n) = (0.0f64, 0u64);
    for seed in 1..=10u64 {
        let mut o = RunOptions::new(seed, 6000);
        o.drift = false;
        o.params = p.clone();
        let mut bins = [(0.0f64, 0u64); BINS];
        run_with(&o, |t, model, truth| {
            let (Some(est), true) = (model.last_estimate(), t >= FROM) else {
                return;
            };
            let at = Point::new(truth.0, truth.1);
            // The body keeps its centre off every wall, so the direction away is defined.
            let Some(near) = obstacles
                .nearest(at, f64::INFINITY)
                .filter(|n| n.distance > 0.0)
            else {
                return;
            };
            let away = at - near.point;
            let along = ((est.0 - truth.0) * away.x + (est.1 - truth.1) * away.y) / near.distance;
            let b = ((near.distance / BIN_M) as usize).min(BINS - 1);
            bins[b].0 += along;
            bins[b].1 += 1;
            dist += (est.0 - truth.0).hypot(est.1 - truth.1);
            n += 1;
        })?;
        for (all, b) in pooled.iter_mut().zip(bins) {
            all.0 += b.0;
            all.1 += b.1;
        }
        println!("seed {seed:2}: {}", line(&bins));
    }
    if n == 0 {
        return Err("no position estimate was made: eps_pos must stay above 0".into());
    }
    println!("pooled:  {}", line(&pooled));
    println!(
        "mean |p_est - truth| {:.3} m over {n} situations",
        dist / n as f64
    );
    Ok(())
}

fn line(bins: &[(f64, u64)]) -> String {
    bins.iter()
        .enumerate()
        .map(|(i, (s, k))| {
            let lo = i as f64 * BIN_M;
            if *k == 0 {
                return format!("{lo:.1}-: none");
            }
            format!("{lo:.1}-: {:+.3} ({k})", s / *k as f64)
        })
        .collect::<Vec<_>>()
        .join("  ")
}
