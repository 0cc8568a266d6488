//! The README tour's explore -> plan -> execute, with the commands exactly as the station's
//! `E`, `O` and `X` send them (`StartExploration`; `Segment` then `Plan { from: None,
//! to: None }`; `ExecutePlan`), on a robot nobody has briefed, as the served emulator runs it:
//! no beacon position or arena bounds set over the link. The headless scenario runner briefs
//! the robot and names both plan ends itself, so it never met the robot's own defaults.
#![allow(clippy::unwrap_used, clippy::panic)]

use emulator::arena::{Arena, LoadOptions};
use emulator::builtin;
use emulator::sim::{Sim, SimConfig};
use protocol::{Command, NackReason, Pose};
use robot_firmware::link::Reply;
use robot_firmware::nav::Cell;
use robot_firmware::MICRO_RATO;

const TIMEOUT_MS: u64 = 300_000;

fn apply(sim: &mut Sim, cmd: Command) -> Result<(), NackReason> {
    let now_ms = (sim.now_us() / 1000) as u32;
    match sim.robot_mut().apply(cmd, now_ms) {
        Reply::Ack(_) => Ok(()),
        Reply::Nack(r) => Err(r),
    }
}

fn run_until_arrived(sim: &mut Sim) -> bool {
    for _ in 0..TIMEOUT_MS {
        sim.step();
        if sim.robot().arrived() {
            sim.run_for(500);
            return true;
        }
    }
    false
}

fn arena() -> Arena {
    builtin::micro_rato_99(&LoadOptions::default()).unwrap()
}

/// `O` on the robot: segment, then plan from where it is to the map's goal.
fn plan_as_the_station_does(sim: &mut Sim) -> Result<(), NackReason> {
    apply(sim, Command::Segment)?;
    apply(
        sim,
        Command::Plan {
            from: None,
            to: None,
        },
    )
}

#[test]
fn the_emulated_robot_knows_where_the_arenas_beacon_is() {
    let a = arena();
    let beacon = a.beacon().unwrap().position;
    let sim = Sim::new(a, SimConfig::new(&MICRO_RATO)).unwrap();
    let p = sim.robot().dead().params;
    // Micro-Rato'99's beacon is at (3.0, 2.571), not the firmware's default (2.5, 2.5).
    assert!(
        (f64::from(p.beacon.x) - beacon.x).abs() < 1e-4,
        "{:?}",
        p.beacon
    );
    assert!(
        (f64::from(p.beacon.y) - beacon.y).abs() < 1e-4,
        "{:?}",
        p.beacon
    );
    assert!((f64::from(p.bounds.max.x) - 5.0).abs() < 1e-4);
}

#[test]
fn after_exploring_the_robot_plans_to_the_goal_it_found_and_executes_the_plan() {
    for seed in [1, 2] {
        let a = arena();
        let target = *a.target().unwrap();
        let mut cfg = SimConfig::new(&MICRO_RATO);
        cfg.seed = seed;
        let mut sim = Sim::new(a, cfg).unwrap();
        let start = sim.truth();

        apply(&mut sim, Command::StartExploration).unwrap();
        assert!(run_until_arrived(&mut sim), "seed {seed}: exploration");

        // The map's goal is now a free cell the robot stood in when it found the goal area.
        let map = sim.robot_mut().objects_mut().map().unwrap();
        let goal = map.goal.unwrap();
        let grid = sim.robot().objects().nav().grid();
        let (gx, gy) = grid.geometry().to_grid(goal.x_mm, goal.y_mm).cell();
        assert_eq!(
            grid.get(gx as usize, gy as usize),
            Cell::Free,
            "seed {seed}"
        );

        // `O` right after arriving: from its position (in the goal area) to the goal.
        assert_eq!(plan_as_the_station_does(&mut sim), Ok(()), "seed {seed}");

        // Run 2 (seed 004 §7): carried back to the start and told so, `O` then `X`.
        sim.place(start).unwrap();
        let mm = |m: f64| (m * 1000.0).round() as i32;
        let pose = Pose {
            x_mm: mm(start.x),
            y_mm: mm(start.y),
            heading_mrad: (start.heading * 1000.0).round() as i16,
        };
        apply(&mut sim, Command::SetPose { pose }).unwrap();
        assert_eq!(plan_as_the_station_does(&mut sim), Ok(()), "seed {seed}");
        let (plan_id, view) = sim.robot().objects().plan().unwrap();
        let last = view.waypoint(view.waypoint_count() - 1).unwrap();
        // Waypoints go through nav's grid units: within a millimetre or two of the goal.
        let near = (last.x_mm - goal.x_mm).abs() <= 2 && (last.y_mm - goal.y_mm).abs() <= 2;
        assert!(
            near,
            "seed {seed}: the plan ends at {last:?}, not the goal {goal:?}"
        );
        assert!(
            view.waypoint_count() > 4,
            "seed {seed}: a plan through regions"
        );

        apply(&mut sim, Command::ExecutePlan { plan_id }).unwrap();
        assert!(run_until_arrived(&mut sim), "seed {seed}: plan execution");
        let t = sim.truth();
        let off = (t.x - target.centre.x).hypot(t.y - target.centre.y);
        assert!(
            off <= target.radius_m,
            "seed {seed}: stopped {off:.2} m from the target's centre (radius {:.2} m)",
            target.radius_m
        );
    }
}
