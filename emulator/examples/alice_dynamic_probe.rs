//! Seed 001 §4.5.4's dynamic wall over seeds 1-10 with any QT parameters, with ALICE's drift
//! or exact odometry: the numbers the dynamic tests' doc comments quote for runs the
//! `robot-emulator` tasks do not make (exact odometry with the correlations on).
//!
//! `cargo run --release -p emulator --example alice_dynamic_probe -- [drift] [NAME=VALUE ...]`
//! prints, per seed, the edges across the standing wall at its removal, the cells that won on
//! both of its sides, and when the gap closed (-1: never), and how many seeds meet the
//! thesis's "clear gap, closed within about 1500" (at most 1 edge across, closed by 1500).

use emulator::scenarios::alice::experiments::dynamic_with;
use world_model::Params;

fn main() {
    if let Err(e) = probe() {
        eprintln!("alice_dynamic_probe: {e}");
        std::process::exit(2);
    }
}

fn probe() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let drift = args.iter().any(|a| a == "drift");
    let mut p = Params::default();
    for kv in args.iter().filter(|a| *a != "drift") {
        p.assign(kv).map_err(|e| format!("{e} (or drift)"))?;
    }
    let (mut edges, mut two, mut closed, mut clear) = (vec![], vec![], vec![], 0);
    for seed in 1..=10 {
        let r = dynamic_with(seed, &p, drift)?;
        let ok = r.gap_clear() && r.gap_closed_in_time();
        clear += usize::from(ok);
        edges.push(r.gap_edges_at_removal.map_or(-1, |g| g as i64));
        two.push(r.gap_two_sided_at_removal.map_or(-1, |g| g as i64));
        closed.push(r.gap_closed_after.map_or(-1, |a| a as i64));
    }
    let odometry = if drift {
        "ALICE's drift"
    } else {
        "exact odometry"
    };
    println!(
        "{odometry} {args:?}: edges across {edges:?}, two-sided cells {two:?}, closed after \
         {closed:?}; clear gap closed in time in {clear} of 10 seeds"
    );
    Ok(())
}
