//! Seed 001 §4.5.3's correlation ablation over seeds 1-10 with any QT parameters, under
//! ALICE's drift or with exact odometry: the numbers the paper tests' doc comments quote for
//! runs the `robot-emulator` tasks do not make (what each correlation costs where the
//! odometry is good).
//!
//! `cargo run --release -p emulator --example alice_correlation_probe -- [exact] [NAME=VALUE ...]`
//! prints, per seed and in the mean over the seeds, the late absolute position error (metres)
//! and the late aligned heading error (degrees) with both correlations, without the position
//! one and without the orientation one, and the plain odometry's position error.

use emulator::scenarios::alice::experiments::correlation_with;
use world_model::Params;

fn main() {
    if let Err(e) = probe() {
        eprintln!("alice_correlation_probe: {e}");
        std::process::exit(2);
    }
}

fn probe() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let exact = args.iter().any(|a| a == "exact");
    let mut p = Params::default();
    for kv in args.iter().filter(|a| *a != "exact") {
        p.assign(kv).map_err(|e| format!("{e} (or exact)"))?;
    }
    let odometry = if exact {
        "exact odometry"
    } else {
        "ALICE's drift"
    };
    println!("{odometry} {args:?}: position m / heading deg, late (samples 5000-8000)");
    let seeds = 1..=10u64;
    let mut sums = [0.0f64; 7];
    for seed in seeds.clone() {
        let r = correlation_with(seed, &p, !exact)?;
        let mut line = format!("seed {seed:2}:");
        for (i, run) in r.runs.iter().enumerate() {
            line += &format!(
                "  {} {:.2}/{:.1}",
                run.variant, run.late_absolute_error_m, run.late_heading_error_deg
            );
            sums[2 * i] += run.late_absolute_error_m;
            sums[2 * i + 1] += run.late_heading_error_deg;
        }
        let odo = r.runs.first().map_or(f64::NAN, |b| b.late_odometry_error_m);
        sums[6] += odo;
        println!("{line}  odometry {odo:.2}");
    }
    let n = seeds.count() as f64;
    let m: Vec<String> = sums.iter().map(|s| format!("{:.2}", s / n)).collect();
    println!(
        "mean: both {}/{}  no-position {}/{}  no-orientation {}/{}  odometry {}",
        m[0], m[1], m[2], m[3], m[4], m[5], m[6]
    );
    Ok(())
}
