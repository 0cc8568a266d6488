//! Seed 000 §3.3, Tables 1-2, end to end (emulator/src/scenarios/odometry_laps.rs): a Khepera
//! whose wheels are truly 53.3 mm apart (the firmware keeps the nominal 52 mm) follows the wall
//! on its left for two laps of the 75 x 60 cm box; the runner, as a station, records the
//! encoder counts the robot sends in its Telemetry (u16 on the wire, unwrapped); the counts are
//! re-integrated by the firmware's odometry with each table's d and dl; each entry is the true
//! rotation (the emulator's truth) minus the re-integrated one.
//!
//! Paper: Table 1 (dl 0.076..0.084 mm at d 52) from +18.6 to -55.2 deg, Table 2 (d 48..56 mm
//! at dl 0.080) from -79.8 to +34.4 deg; -18.3 deg at the nominal pair.
//! Seeds 1-12, wheel bias off (the tables put the whole error on d), the rest of the noise on.
//! Tolerances: every run finishes its two laps; the counts re-integrated at the TRUE d give
//! the true rotation within 0.1 deg (pulse rounding); on every run that follows the wall round
//! without turning round at a corner (`clean_laps`, 6 of 12 seeds measured, at least 5 asserted)
//! all 18 entries within 0.75 deg of the paper's (measured 0.36-0.72: 0.3 deg is 53.3 against
//! the 53.33 mm that fits the paper exactly, the rest the run's stop a few degrees off 720,
//! which moves an entry by at most 11 % of it). The other runs turn round once (the 180 deg
//! turn fires on a corner) and so turn 545-1265 deg, not two laps: not the paper's run; they
//! are printed, not compared. Run with `--nocapture` for the table.
#![allow(clippy::unwrap_used, clippy::panic)]

use emulator::scenarios::odometry_laps::{run_odometry_laps, OdometryLapsOptions};

const SEEDS: std::ops::RangeInclusive<u64> = 1..=12;

#[test]
fn two_laps_of_wall_following_reproduce_tables_1_and_2_from_the_counts_the_robot_sends() {
    let mut clean = 0;
    println!("seed | clean | true rot deg | max |ours - paper| deg");
    for seed in SEEDS {
        let r = run_odometry_laps(&OdometryLapsOptions::new(seed)).unwrap();
        println!(
            "{seed:>4} | {:>5} | {:>12.2} | {:>6.3}",
            r.clean_laps, r.true_rotation_deg, r.max_difference_deg
        );
        assert_eq!(r.ended, "laps", "seed {seed}: {r:?}");
        assert_eq!(r.collisions, 0, "seed {seed}");
        // About one moving delta per 80 ms control cycle, all below §3.2's 100 pulses.
        assert!(
            r.moving_deltas as f64 > r.sim_s / 0.080 * 0.9,
            "seed {seed}: {r:?}"
        );
        assert!(r.max_delta < 100, "seed {seed}: {}", r.max_delta);
        assert!(
            (r.true_params_rotation_deg - r.true_rotation_deg).abs() < 0.1,
            "seed {seed}: counts at the true d say {} deg, truth {} deg",
            r.true_params_rotation_deg,
            r.true_rotation_deg
        );
        if !r.clean_laps {
            continue;
        }
        clean += 1;
        // Wall on the left: clockwise laps.
        assert!(
            r.true_rotation_deg < 0.0,
            "seed {seed}: {}",
            r.true_rotation_deg
        );
        for e in &r.tables {
            println!(
                "       table {} d {:.1} dl {:.3}: paper {:+.2} ours {:+.2}",
                e.table, e.d_mm, e.dl_mm, e.paper_deg, e.ours_deg
            );
            assert!(
                (e.ours_deg - e.paper_deg).abs() <= 0.75,
                "seed {seed}: table {} d {} dl {}: ours {} paper {}",
                e.table,
                e.d_mm,
                e.dl_mm,
                e.ours_deg,
                e.paper_deg
            );
        }
    }
    println!("{clean} of {} runs made two clean laps", SEEDS.count());
    assert!(clean >= 5, "{clean} clean runs");
}

#[test]
fn with_the_nominal_wheel_distance_the_counts_say_what_the_robot_turned() {
    // The control: a robot whose wheels are where the firmware believes turns what its counts
    // say, so the -18.3 deg at d = 52 mm of the paper (and of the test above) is the 53.3 mm
    // wheels' doing, not the runner's or the wire's.
    let mut o = OdometryLapsOptions::new(3);
    o.true_wheel_distance_m = 0.052;
    let r = run_odometry_laps(&o).unwrap();
    let nominal = r
        .tables
        .iter()
        .find(|e| e.table == 2 && e.d_mm == 52.0)
        .unwrap();
    assert!(nominal.ours_deg.abs() < 0.2, "{r:?}");
}
