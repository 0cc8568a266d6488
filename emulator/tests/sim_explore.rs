//! Seed 004 end to end in the emulator: the reactive goal search maps the Micro-Rato'99
//! labyrinth on the way to the beacon; the robot then plans on its own map and a second run
//! executes the plan, markedly faster (the paper's plans beat reactive search).
#![allow(clippy::unwrap_used, clippy::panic)]

use emulator::arena::LoadOptions;
use emulator::builtin;
use emulator::scenario::{run_scenario, ScenarioError, ScenarioOptions, ScenarioReport, Task};
use robot_firmware::MICRO_RATO;

fn run(task: Task, seed: u64) -> ScenarioReport {
    try_run(task, seed).unwrap()
}

/// A plan the robot's own map cannot give (its map does not join start and goal) is a failed
/// run 2, not a broken test.
fn try_run(task: Task, seed: u64) -> Result<ScenarioReport, ScenarioError> {
    let arena = builtin::micro_rato_99(&LoadOptions::default()).unwrap();
    let mut o = ScenarioOptions::new(&MICRO_RATO, task);
    o.seed = seed;
    o.timeout_s = 300.0;
    run_scenario(arena, o)
}

#[test]
fn the_reactive_search_reaches_the_goal_area_and_maps_on_the_way() {
    for seed in [1, 2] {
        let r = run(Task::ReachBeacon, seed);
        assert!(r.reached, "seed {seed}: {r:?}");
        let run = &r.runs[0];
        // The 17 x 17 map has 289 cells; the search sees a good part of it, not all.
        let known = run.map_known_cells.unwrap();
        assert!(
            (40..289).contains(&known),
            "seed {seed}: {known} cells known"
        );
        assert!(
            r.pose_error_m < 0.3,
            "seed {seed}: dead reckoning {:.2} m off",
            r.pose_error_m
        );
    }
}

#[test]
fn over_ten_seeds_plans_on_the_explored_map_reach_the_goal_markedly_faster() {
    let mut run1 = Vec::new();
    let mut run2 = Vec::new();
    let mut reached = 0;
    for seed in 1..=10 {
        let r = match try_run(Task::ExploreThenPlan, seed) {
            Err(ScenarioError::Refused { what: "Plan", .. }) => continue,
            other => other.unwrap(),
        };
        let explore = &r.runs[0];
        assert_eq!(explore.kind, "explore");
        assert!(explore.reached, "seed {seed}: exploration failed: {r:?}");
        run1.push(explore.sim_s);
        if let Some(execute) = r.runs.get(1) {
            assert_eq!(execute.kind, "execute_plan");
            assert!(
                execute.plan_regions.unwrap_or(0) > 3,
                "seed {seed}: {execute:?}"
            );
            if r.reached {
                reached += 1;
                run2.push(execute.sim_s);
            }
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let (m1, m2) = (mean(&run1), mean(&run2));
    println!("10 seeds: {reached} reached; run 1 mean {m1:.1} s, run 2 mean {m2:.1} s");
    // The 20-seed report (closing note of the exploration issue) had 20/20; allow one miss.
    assert!(
        reached >= 9,
        "only {reached}/10 plan executions reached the goal area"
    );
    assert!(
        m2 < 0.75 * m1,
        "run 2 ({m2:.1} s) is not markedly faster than run 1 ({m1:.1} s)"
    );
}

#[test]
fn the_same_seed_gives_the_same_exploration() {
    let a = run(Task::ReachBeacon, 7);
    let b = run(Task::ReachBeacon, 7);
    assert_eq!(a.final_true, b.final_true);
    assert_eq!(a.runs[0].map_known_cells, b.runs[0].map_known_cells);
}

#[test]
fn a_search_that_starts_inside_the_target_is_no_success() {
    let arena = builtin::micro_rato_99(&LoadOptions::default()).unwrap();
    let mut o = ScenarioOptions::new(&MICRO_RATO, Task::ReachBeacon);
    o.start = Some(emulator::arena::Pose {
        x: 3.0,
        y: 2.3,
        heading: 0.0,
    });
    let r = run_scenario(arena, o).unwrap();
    assert!(r.started_in_target, "{r:?}");
    assert!(r.arrived && !r.reached, "{r:?}");
}
