//! Issue 14's odometry calibration on a fixed subset of the go-to benchmark's generated
//! boxes, each with its bench seed (`bench::run_seed(1, index, 1)`, default noise: each box
//! draws its own wheel speed errors, sigma 0.5 % a wheel): the wheel-ratio error against the
//! emulator's truth (which the calibration never sees). Measured over all 200 boxes
//! (`cargo run --release -p emulator --example calibration_bench`): median 10 ppm, p95 41
//! ppm, 193 of 200 under 500 ppm, 3 with no result. Before the wall holder and the straight
//! walls (seed 000's edge follower, laps only), these ten boxes gave 3 under 500 ppm.

use emulator::arena_gen::{generate, Kind};
use emulator::scenarios::bench::run_seed;
use emulator::scenarios::calibrate_odometry::{
    run_calibration, CalibrationReport, DEFAULT_TIMEOUT_S,
};
use emulator::scenarios::task::{ScenarioOptions, Task};

/// Box `b`'s calibration with its bench seed: the report and the ratio error, ppm.
fn calibrate(b: u64) -> (CalibrationReport, Option<f64>) {
    let arena = generate(Kind::Box, b).expect("generates").arena;
    let mut so = ScenarioOptions::new(&robot_firmware::KHEPERA, Task::GoTo(None));
    so.seed = run_seed(1, (b - 1) as usize, 1);
    let r = run_calibration(arena, &so, DEFAULT_TIMEOUT_S).expect("runs");
    let err = r
        .wheel_ratio_ppm
        .map(|m| (f64::from(m) - r.true_ratio_ppm).abs());
    (r, err)
}

#[test]
fn the_wheel_ratio_comes_within_500_ppm_in_nine_boxes_of_ten() {
    let mut errors = Vec::new();
    for b in 1..=10u64 {
        let (r, err) = calibrate(b);
        errors.push((b, err, r.straight_m, r.error.clone()));
    }
    let mut ok: Vec<f64> = errors.iter().filter_map(|e| e.1).collect();
    assert!(ok.len() >= 9, "{errors:?}");
    ok.sort_by(f64::total_cmp);
    let under = ok.iter().filter(|e| **e < 500.0).count();
    assert!(under >= 9, "{errors:?}");
    // The median: far inside the target, the straight walls' own resolution.
    assert!(ok[ok.len() / 2] < 100.0, "{errors:?}");
    // Every result here came from straight walls (a metre or more of them).
    assert!(errors.iter().all(|e| e.2 >= 1.0), "{errors:?}");
}

/// Issue 32: a post beside the start. The holder ran straight into it and followed it round;
/// the side sensor lost the post at every corner, so the lap calibrator never closed a lap
/// and the robot circled it for the whole 600 s ("NoLap"): boxes 63, 81, 111 and 168 of the
/// 200 (before: no result in each; after: within 60 ppm in each). Now a whole turn the wrong
/// way for the side leaves the block, and the box's walls give the ratio.
#[test]
fn a_post_beside_the_start_is_left_and_the_boxs_walls_calibrate() {
    for b in [63u64, 81, 111, 168] {
        let (r, err) = calibrate(b);
        assert!(
            err.is_some_and(|e| e < 500.0) && r.straight_m >= 1.0,
            "box {b}: {:?} ({err:?} ppm, {:.2} m of straight walls)",
            r.error,
            r.straight_m
        );
    }
}
