//! Seed 000 §7 foraging end to end: the unchanged firmware in `builtin:forage` finds the lit
//! sources, grips their objects, carries them home and puts them down, over several seeds.
#![allow(clippy::unwrap_used, clippy::panic)]

use emulator::builtin;
use emulator::scenarios::forage::run_forage;
use emulator::scenarios::task::{ScenarioOptions, Task};
use robot_firmware::KHEPERA;

/// Seeds run; each with the papers' noise (IR, light, wheel bias drawn from the seed).
const SEEDS: [u64; 10] = [1, 2, 3, 4, 5, 6, 7, 8, 9, 10];
/// Simulated time per run: 20 minutes (the paper's autonomy with both turrets is about a
/// third of the Khepera's, some 20-30 minutes).
const TIMEOUT_S: f64 = 1200.0;
/// Objects that must be home over the ten seeds (three per run). The paper's result is
/// qualitative (seed 000 §7: one real run, two sources); the project's target (issue 14) is
/// 90 %, 27 of 30, asserted as is. Measured: 29 of 30 (seed 5 brings 2), so the tolerance
/// is two objects below the measurement; seeds 11-20 give 27 of 30. Before the approach and
/// leaving fixes of issue 14: 17 of 30 (a delivery rate this test would fail).
const MIN_DELIVERED: usize = 27;
/// Largest true-versus-believed position error when an object is put down at home, metres
/// (measured at most 27 mm): the landmark fix at home (seed 000 §6.2) bounds it, where plain
/// odometry is tens of centimetres and tens of degrees off after a search.
const MAX_RETURN_ERROR_M: f64 = 0.05;

#[test]
fn the_khepera_carries_the_objects_home_over_several_seeds() {
    let mut delivered = 0;
    let mut objects = 0;
    for seed in SEEDS {
        let arena = builtin::forage().unwrap();
        let mut o = ScenarioOptions::new(&KHEPERA, Task::Forage);
        o.seed = seed;
        o.timeout_s = TIMEOUT_S;
        let r = run_forage(arena, o).unwrap();
        eprintln!(
            "seed {seed}: {}/{} delivered in {:.0} s, returns {:?}",
            r.delivered,
            r.objects,
            r.sim_s,
            r.returns
                .iter()
                .map(|h| (h.time_s.round(), (h.pose_error_m * 1000.0).round()))
                .collect::<Vec<_>>()
        );
        assert_eq!(r.objects, 3);
        delivered += r.delivered;
        objects += r.objects;
        assert!(
            usize::from(r.firmware_grasped) >= r.delivered,
            "seed {seed}: every object home was reported gripped"
        );
        // The firmware counts a delivery when the object leaves its fingers, so it never
        // reports fewer than are home, even when the run stops right after the last one
        // lands (it counted once the arm was back up, 1 s later: seed 6 reported 2 of 3).
        assert!(
            usize::from(r.firmware_delivered) >= r.delivered,
            "seed {seed}: firmware counted {} delivered, {} are home",
            r.firmware_delivered,
            r.delivered
        );
        assert!(
            r.firmware_delivered >= 1,
            "seed {seed}: nothing reported delivered"
        );
        for h in &r.returns {
            assert!(h.delivered, "seed {seed}: put down outside home: {h:?}");
            assert!(
                h.pose_error_m <= MAX_RETURN_ERROR_M,
                "seed {seed}: pose error {:.3} m at a return home",
                h.pose_error_m
            );
        }
    }
    assert!(
        delivered >= MIN_DELIVERED,
        "only {delivered} of {objects} objects delivered"
    );
}

#[test]
fn the_same_seed_forages_the_same_way() {
    let run = || {
        let mut o = ScenarioOptions::new(&KHEPERA, Task::Forage);
        o.seed = 7;
        o.timeout_s = 60.0;
        let r = run_forage(builtin::forage().unwrap(), o).unwrap();
        (r.distance_m, r.collisions, r.returns.len(), r.pose_error_m)
    };
    assert_eq!(run(), run());
}

#[test]
fn a_robot_without_a_gripper_is_refused() {
    let o = ScenarioOptions::new(&robot_firmware::MICRO_RATO, Task::Forage);
    let e = run_forage(builtin::forage().unwrap(), o).unwrap_err();
    assert!(e.to_string().contains("refused"), "{e}");
}

#[test]
fn on_an_arena_whose_target_is_elsewhere_the_home_base_is_the_start() {
    // A generated box's target is the go-to goal, metres from the start; the firmware's home
    // is where it starts. With the home at the target every object was put down outside it
    // (bench, 20 boxes: 0 of 54 delivered).
    let g = emulator::arena_gen::generate(emulator::arena_gen::Kind::Box, 1).unwrap();
    let start = g.arena.starts[0];
    let target = *g.arena.target().unwrap();
    assert!(
        ((start.x - target.centre.x).powi(2) + (start.y - target.centre.y).powi(2)).sqrt()
            > target.radius_m,
        "the test needs a start outside the target"
    );
    let mut o = ScenarioOptions::new(&KHEPERA, Task::Forage);
    o.timeout_s = 1.0;
    let r = run_forage(g.arena, o).unwrap();
    assert!(
        (r.home[0] - start.x).abs() < 1e-9 && (r.home[1] - start.y).abs() < 1e-9,
        "home {:?}, start ({}, {})",
        r.home,
        start.x,
        start.y
    );
}

/// `bench --task forage --arenas builtin:forage --seeds 10`, draw 8: the third object was put
/// down 0.49 m from home (the belief 0.46 m and 62° off after the search) and the firmware
/// counted it delivered (3) where the emulator's truth has 2 home: at home the landmark scans
/// gave no fix it could trust, and "no fix" counted as home. Only a drop the robot has
/// confirmed home counts now, so its count is the truth's.
#[test]
fn the_firmware_counts_only_drops_it_has_confirmed_at_home() {
    let mut o = ScenarioOptions::new(&KHEPERA, Task::Forage);
    o.seed = emulator::scenarios::bench::run_seed(1, 0, 8);
    o.timeout_s = TIMEOUT_S;
    let r = run_forage(builtin::forage().unwrap(), o).unwrap();
    assert_eq!(
        usize::from(r.firmware_delivered),
        r.delivered,
        "firmware and truth disagree: {:?}",
        r.returns
    );
}
