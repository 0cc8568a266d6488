//! Seed 000 Fig. 17 (right), as a named scenario: the Khepera's A-to-B navigation through two
//! successive dead ends with the drift behaviour (nearest-point memory, halved drift, pauses
//! that follow the obstacle's edge, 180° turns, seed 000 §4.4-4.5).
//!
//! Paper: one real run; the robot reached B with dx = 2 cm, dy = 1 cm, inside the 5 cm
//! tolerance. The paper does not give the layout; ours (`two_dead_ends`) is a 100 x 70 cm box
//! with a U 12 cm wide and 12 cm deep on the straight line from A to B, opening towards A, and
//! behind it a second U 30 cm wide and 16 cm deep, also opening towards A; B lies behind both.
//! Project (measured over seeds 1-10, 600 simulated s, default noise): the firmware arrives
//! in 10 of 10 runs and its true position is within the 5 cm tolerance in 2 of 10 (seeds 4
//! and 5: 1.8 and 2.5 cm); the other arrivals end 5-27 cm off. Those are odometry errors, not
//! navigation ones: each run's belief is off by about as much as its goal error, after 1.8-8.5
//! m of driving (the longer runs go round the dead ends several times) with the seed's
//! constant wheel speed error (seed 003 §2.3.3: up to ±1 % a wheel), and this box has no
//! landmark or light to correct the pose with (seed 000 §6).
//! History: before the drift's escalation counted 180° turns, 0 of 10 arrived (the robot
//! stayed pressed against the first dead end's back wall); with it, 7 of 10 arrived and 1 of
//! 10 was within 5 cm; since a pause ends once the edge has brought the robot nearer the goal
//! than ever, 10 of 10 arrive and 2 of 10 are within 5 cm.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::PathBuf;

use emulator::arena::{Arena, ArenaFormat, Pose, Wall};
use emulator::geometry::{Aabb, Point};
use emulator::scenarios::task::{
    run_scenario, GoalPoint, ScenarioOptions, Task, KHEPERA_TOLERANCE_M,
};
use robot_firmware::KHEPERA;

/// Wall rectangle from centimetre corners.
fn block(x0: f64, y0: f64, x1: f64, y1: f64) -> Wall {
    Wall::rectangle(
        Aabb::from_corners(
            Point::new(x0 / 100.0, y0 / 100.0),
            Point::new(x1 / 100.0, y1 / 100.0),
        ),
        None,
    )
}

/// A U of 2 cm walls opening towards -x: back wall at `back`, inner width `w`, depth `d`,
/// centred on y = `yc` (all in centimetres).
fn u_trap(back: f64, yc: f64, w: f64, d: f64) -> [Wall; 3] {
    let (y0, y1) = (yc - w / 2.0 - 2.0, yc + w / 2.0 + 2.0);
    [
        block(back, y0, back + 2.0, y1),
        block(back - d, y0, back, y0 + 2.0),
        block(back - d, y1 - 2.0, back, y1),
    ]
}

/// The scenario's arena: two successive dead ends between A (12, 35) and B (88, 35) cm.
fn two_dead_ends() -> Arena {
    let mut walls = Vec::new();
    walls.extend(u_trap(45.0, 35.0, 12.0, 12.0));
    walls.extend(u_trap(72.0, 35.0, 30.0, 16.0));
    Arena {
        name: "fig17 two successive dead ends".into(),
        source: PathBuf::from("test"),
        format: ArenaFormat::AsciiGrid,
        bounds: Aabb::from_corners(Point::new(0.0, 0.0), Point::new(1.0, 0.7)),
        enclosed: true,
        walls,
        raster: None,
        beacons: Vec::new(),
        targets: Vec::new(),
        lights: Vec::new(),
        starts: Vec::new(),
        goal: None,
        unit_m: 0.01,
        warnings: Vec::new(),
    }
}

#[test]
fn fig17_a_to_b_through_two_successive_dead_ends() {
    const SEEDS: u64 = 10;
    let (mut arrived, mut reached, mut escaped) = (0, 0, 0);
    for seed in 1..=SEEDS {
        let goal = GoalPoint {
            x_m: 0.88,
            y_m: 0.35,
        };
        let mut opts = ScenarioOptions::new(&KHEPERA, Task::GoTo(Some(goal)));
        opts.seed = seed;
        opts.timeout_s = 600.0;
        opts.start = Some(Pose {
            x: 0.12,
            y: 0.35,
            heading: 0.0,
        });
        let r = run_scenario(two_dead_ends(), opts).unwrap();
        assert_eq!(r.tolerance_m, KHEPERA_TOLERANCE_M, "the paper's 5 cm");
        println!(
            "seed {seed}: arrived {} reached {} error {:.3} m after {:.0} s and {:.2} m, true end \
             ({:.2}, {:.2}), belief off by {:.3} m",
            r.arrived,
            r.reached,
            r.goal_error_m,
            r.sim_s,
            r.distance_m,
            r.final_true.x_m,
            r.final_true.y_m,
            r.pose_error_m
        );
        arrived += u32::from(r.arrived);
        reached += u32::from(r.reached);
        // Out of the first dead end (its back wall is at x = 45-47 cm) at the end of the run.
        escaped += u32::from(r.final_true.x_m > 0.5);
    }
    println!(
        "fig17: paper 1 run, reached (dx 2 cm, dy 1 cm, tolerance 5 cm); project {reached}/{SEEDS} \
         reached within 5 cm, {arrived}/{SEEDS} arrived, {escaped}/{SEEDS} past the first dead end"
    );
    assert!(arrived >= 9, "arrived in {arrived} of {SEEDS}");
    assert!(reached >= 2, "reached in {reached} of {SEEDS}");
    assert!(
        escaped >= 9,
        "past the first dead end in {escaped} of {SEEDS}"
    );
}

/// The same A-to-B run by a robot whose owner calibrated its odometry first, in the same box
/// (`station calibrate odometry`; here `scenarios::calibrate_odometry`, as `robot-emulator bench
/// --calibrate-odometry` does): the navigation is unchanged, only parameters 5 and 50 are the
/// calibration's. Paper: one run, 2.2 cm from B (dx 2, dy 1 cm), tolerance 5 cm. Project,
/// seeds 1-10: calibrated in 10 of 10 (ratio within 8-48 ppm of the truth), within 5 cm of B
/// in 10 of 10, 2.1-3.4 cm; asserted: at least 9 of 10. This separates the paper's navigation
/// result from the wheels: with the belief right, the drift behaviour brings the robot within
/// the paper's 5 cm of B, where the uncalibrated robot above reaches it in 2 of 10.
#[test]
fn fig17_with_calibrated_odometry() {
    use emulator::scenarios::calibrate_odometry::{run_calibration, DEFAULT_TIMEOUT_S};
    const SEEDS: u64 = 10;
    let (mut calibrated, mut reached) = (0, 0);
    let mut errors = Vec::new();
    for seed in 1..=SEEDS {
        let goal = GoalPoint {
            x_m: 0.88,
            y_m: 0.35,
        };
        let mut opts = ScenarioOptions::new(&KHEPERA, Task::GoTo(Some(goal)));
        opts.seed = seed;
        opts.timeout_s = 600.0;
        let c = run_calibration(two_dead_ends(), &opts, DEFAULT_TIMEOUT_S).unwrap();
        calibrated += u32::from(c.wheel_ratio_ppm.is_some());
        opts.params = c.params();
        opts.start = Some(Pose {
            x: 0.12,
            y: 0.35,
            heading: 0.0,
        });
        let r = run_scenario(two_dead_ends(), opts).unwrap();
        println!(
            "seed {seed}: ratio {:?} ppm (true {:.0}) reached {} error {:.3} m, belief off by {:.3} m",
            c.wheel_ratio_ppm,
            c.true_ratio_ppm,
            r.reached,
            r.goal_error_m,
            r.pose_error_m
        );
        reached += u32::from(r.reached);
        errors.push(r.goal_error_m);
    }
    println!("fig17 calibrated: {reached}/{SEEDS} within 5 cm, calibrated {calibrated}/{SEEDS}, errors {errors:.3?}");
    // docs/reproductions.md: at least 9 of 10 calibrated and at least 9 of 10 within 5 cm.
    assert!(calibrated >= 9, "calibrated in {calibrated} of {SEEDS}");
    assert!(
        reached >= 9,
        "reached in {reached} of {SEEDS}: {errors:.3?}"
    );
}
