//! Seed 004 end to end in the emulator: the reactive goal search maps the Micro-Rato'99
//! labyrinth on the way to the beacon; the robot then plans on its own map and a second run
//! executes the plan, markedly faster (the paper's plans beat reactive search).
#![allow(clippy::unwrap_used, clippy::panic)]

use emulator::arena::LoadOptions;
use emulator::builtin;
use emulator::scenarios::task::{
    run_scenario, ScenarioError, ScenarioOptions, ScenarioReport, Task,
};
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
    // Seed 004 §5's reactive search, the paper's (the firmware plans by default, issue 32).
    o.params
        .push((robot_firmware::params::id::SEARCH_MODE, 0.0));
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

/// Seed 004 (Dom Dinis, Micro-Rato'99; /work/shared/design/seed-004-dom-dinis.md): the paper's
/// figure is qualitative, "plans beat the reactive search": run 2, executing the plan made on
/// the robot's own explored map from the start to where run 1 met the goal, is faster than
/// run 1, the reactive beacon search that made the map.
///
/// The project's per-seed figures, seeds 1-10, 300 s timeout (issue 20; release build,
/// `robot-emulator run --task explore-then-plan --seed N --timeout 300 --json`):
///
/// | seed | run 1 s | run 2 s | ratio | reached |
/// |------|---------|---------|-------|---------|
/// | 1    | 129.7   | 75.8    | 0.58  | yes     |
/// | 2    | 127.3   | 84.7    | 0.67  | yes     |
/// | 3    | 196.3   | 54.3    | 0.28  | yes     |
/// | 4    | 123.1   | 47.8    | 0.39  | yes     |
/// | 5    | 196.9   | 45.6    | 0.23  | yes     |
/// | 6    | 121.4   | 80.4    | 0.66  | yes     |
/// | 7    | 228.7   | 58.8    | 0.26  | yes     |
/// | 8    | reached | -       | -     | no: plan refused (`Unreachable`) |
/// | 9    | 125.8   | 51.6    | 0.41  | yes     |
/// | 10   | 121.0   | 45.6    | 0.38  | yes     |
///
/// Paired means (the 9 seeds where both runs reached): run 1 152.2 s, run 2 60.5 s, 0.40.
/// No reached run 2 is slower than its run 1 on these seeds (worst 0.67, seed 2); the 1.16x
/// and 1.34x of the earlier measurement are not reproduced on seeds 1-10 at this firmware.
///
/// Why seed 8 fails: `Segment` segments known-FREE cells only (`Passable::Free`), so a plan
/// never crosses unknown cells; on seed 8 the search's map does not join start and goal in
/// free cells. The start's room (cells x 0-5) joins the corridor along y 2-3 (x 5-12), but
/// the goal room (x 9-11, y 5-7) touches that corridor only through cell (9, 4), still
/// unknown, and diagonally at (12, 4)-(11, 5), and the segmentation's regions join only
/// across edges. A partial explored map, not a bad plan: the refusal counts as a failed
/// run 2 here (it is neither faster nor reached).
///
/// Outside this set, for the record (not asserted): seeds 11-40 give 4 more refusals
/// (11, 22, 28, 36), seed 34 times out in run 2 (plan of 10 regions, 300 s),
/// and seed 21 is the one reached run 2 slower than run 1, 1.16x (139.4 s against 119.9 s,
/// 11.8 m driven and 2 collisions against a typical 8-10 m and 0-1: contact and avoidance
/// during plan execution, not a longer plan).
///
/// What is asserted, per seed and in sum (tolerances leave room for one seed like 21):
/// - at least 9 of 10 run 2s reach the goal area (measured 9: seed 8 refused);
/// - at least 8 of 10 seeds have run 2 faster than run 1 (measured 9); a refused or failed
///   run 2 counts as not faster;
/// - every reached run 2 takes at most 1.5x its own run 1 (measured worst 0.67x);
/// - the paired mean of run 2 is under 0.75x that of run 1 (measured 0.40).
///
/// A broken planner fails it: one that refuses or plans through walls drops the reached
/// count. Checked by mutation (issue 20, not committed): run 2 replaced by a second reactive
/// search from the start (StartExploration instead of ExecutePlan) gives 6 of 10 faster,
/// seed 6 at 1.78x and a paired mean of 0.94; the test fails on the 8-of-10 count, and the
/// 1.5x bound and the 0.75 mean would fail too.
#[test]
fn over_ten_seeds_plans_on_the_explored_map_reach_the_goal_faster_seed_by_seed() {
    const SEEDS: std::ops::RangeInclusive<u64> = 1..=10;
    const MIN_REACHED: usize = 9;
    const MIN_FASTER: usize = 8;
    const MAX_RATIO: f64 = 1.5;
    const MAX_MEAN_RATIO: f64 = 0.75;
    let mut paired = Vec::new();
    let mut faster = 0;
    let mut too_slow = Vec::new();
    println!("seed  run 1 s  run 2 s  ratio  run 2");
    for seed in SEEDS {
        let r = match try_run(Task::ExploreThenPlan, seed) {
            Err(ScenarioError::Refused { what: "Plan", .. }) => {
                println!("{seed:>4}        -        -      -  plan refused");
                continue;
            }
            other => other.unwrap(),
        };
        let explore = &r.runs[0];
        assert_eq!(explore.kind, "explore");
        assert!(explore.reached, "seed {seed}: exploration failed: {r:?}");
        let Some(execute) = r.runs.get(1) else {
            println!("{seed:>4} {:>8.1}        -      -  no run 2", explore.sim_s);
            continue;
        };
        assert_eq!(execute.kind, "execute_plan");
        if execute.no_path_on_map {
            // The robot refused to plan on its own map (the bench's no_path_on_explored_map).
            println!("{seed:>4}        -        -      -  plan refused");
            continue;
        }
        assert!(
            execute.plan_regions.unwrap_or(0) > 3,
            "seed {seed}: {execute:?}"
        );
        let ratio = execute.sim_s / explore.sim_s;
        println!(
            "{seed:>4} {:>8.1} {:>8.1} {ratio:>6.2}  {}",
            explore.sim_s,
            execute.sim_s,
            if r.reached { "reached" } else { "NOT reached" }
        );
        if r.reached {
            paired.push((explore.sim_s, execute.sim_s));
            if ratio < 1.0 {
                faster += 1;
            }
            if ratio > MAX_RATIO {
                too_slow.push((seed, ratio));
            }
        }
    }
    let n = paired.len();
    let m1 = paired.iter().map(|p| p.0).sum::<f64>() / n.max(1) as f64;
    let m2 = paired.iter().map(|p| p.1).sum::<f64>() / n.max(1) as f64;
    println!(
        "{n} of 10 reached, {faster} of 10 faster; paired means run 1 {m1:.1} s, run 2 {m2:.1} s ({:.2})",
        m2 / m1
    );
    assert!(
        n >= MIN_REACHED,
        "only {n}/10 plan executions reached the goal area"
    );
    assert!(
        faster >= MIN_FASTER,
        "run 2 faster than run 1 on only {faster} of 10 seeds (want >= {MIN_FASTER})"
    );
    assert!(
        too_slow.is_empty(),
        "run 2 over {MAX_RATIO}x run 1 (seed, ratio): {too_slow:?}"
    );
    assert!(
        m2 < MAX_MEAN_RATIO * m1,
        "run 2 ({m2:.1} s) is not markedly faster than run 1 ({m1:.1} s) on the paired mean"
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
