//! One beacon search, traced: the robot's map at the end beside the arena's walls, the true
//! track, and every few seconds what the search was doing. For looking at one benchmark row.
//!
//! `cargo run --release -p emulator --example search_trace -- KIND SEED RUN_SEED [reactive|planned] [EVERY_S] [no-noise]`
//! e.g. `-- real-like 19 0 planned 5` (a run seed of 0 takes the benchmark's, `bench::run_seed(1, SEED - 1, 1)`).
#![allow(clippy::unwrap_used, clippy::panic)]

use emulator::arena::{rasterise, Cell};
use emulator::arena_gen::{generate, Kind};
use emulator::scenarios::task::{apply, set_arrival, ScenarioOptions, Task};
use emulator::sim::Sim;
use protocol::{Command, ParamId};
use robot_firmware::explore::SearchMode;
use robot_firmware::MICRO_RATO;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let kind = match args.get(1).map(String::as_str) {
        Some("micro-rato") => Kind::MicroRato,
        _ => Kind::RealLike,
    };
    let seed: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1);
    let mut run_seed: u64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(0);
    if run_seed == 0 {
        run_seed = emulator::scenarios::bench::run_seed(1, seed as usize - 1, 1);
    }
    let mode = match args.get(4).map(String::as_str) {
        Some("reactive") => SearchMode::Reactive,
        _ => SearchMode::Planned,
    };
    let every_s: f64 = args.get(5).and_then(|s| s.parse().ok()).unwrap_or(10.0);
    let quiet = args.get(6).is_some_and(|a| a == "no-noise");
    let dumps: Vec<f64> = args
        .get(7)
        .map(|a| a.split(',').filter_map(|v| v.parse().ok()).collect())
        .unwrap_or_default();
    let g = generate(kind, seed).unwrap();
    let arena = g.arena.clone();
    let target = *arena.target().unwrap();
    let mut o = ScenarioOptions::new(&MICRO_RATO, Task::ReachBeacon);
    o.seed = run_seed;
    if quiet {
        o.noise = emulator::sensors::Noise::none();
    }
    let mut sim = Sim::new(arena.clone(), o.sim_config()).unwrap();
    set_arrival(&mut sim, None, target.radius_m).unwrap();
    let code = f32::from(mode.code());
    let set = Command::SetParam {
        id: ParamId(robot_firmware::params::id::SEARCH_MODE),
        value: code,
    };
    apply(&mut sim, set, "search mode").unwrap();
    apply(&mut sim, Command::StartExploration, "explore").unwrap();
    let mut track = Vec::new();
    let mut next = 0.0;
    // Time (ms) spinning (wheels opposite), following, driving, reactive.
    let (mut spin, mut follow, mut drive, mut reactive) = (0u64, 0u64, 0u64, 0u64);
    let summary = std::env::var_os("SUMMARY").is_some();
    let mut hits = 0;
    for i in 0..300_000u64 {
        sim.step();
        let t = i as f64 / 1000.0;
        let p = sim.truth();
        if i % 100 == 0 {
            track.push((p.x, p.y));
        }
        if sim.collisions() > hits {
            hits = sim.collisions();
            let r = sim.robot().dom_dinis().unwrap();
            println!(
                "  collision at {t:.2}: true ({:.3},{:.3},{:.2}) ir {:?} motor {:?} {:?} {:?} wp {:?}",
                p.x, p.y, p.heading, &r.core.sensors.ir[..3], r.core.motor,
                r.core.explorer.phase(), r.core.explorer.planned().phase(),
                r.core.explorer.planned().waypoint().map(|w| (w.x, w.y))
            );
        }
        if dumps.iter().any(|&d| (d - t).abs() < 0.0005) {
            println!("--- map at {t:.1} s");
            let w = sim
                .robot()
                .dom_dinis()
                .unwrap()
                .core
                .explorer
                .planned()
                .waypoint();
            print_map(&sim, &arena, &track, w);
        }
        let detail = std::env::var("TRACE_FROM")
            .ok()
            .and_then(|v| v.parse::<f64>().ok())
            .is_some_and(|from| t >= from && t < from + 3.0);
        if detail && i % 50 == 0 {
            let r = sim.robot().dom_dinis().unwrap();
            let b = sim.believed();
            println!(
                "  {t:.2} true ({:.3},{:.3},{:.2}) bel ({:.3},{:.3},{:.2}) ir {:?} motor {:?} {:?} wp {:?}",
                p.x, p.y, p.heading, b.x, b.y, b.heading,
                &r.core.sensors.ir[..3], r.core.motor, r.core.explorer.planned().phase(),
                r.core.explorer.planned().waypoint().map(|w| (w.x, w.y))
            );
        }
        if t >= next && !summary {
            next += every_s;
            let b = sim.believed();
            let r = sim.robot().dom_dinis().unwrap();
            let e = r.core.explorer;
            println!(
                "{t:6.1}s true ({:.2},{:.2}) believed ({:.2},{:.2}) {:?} wp {:?} stats {:?}",
                p.x,
                p.y,
                b.x,
                b.y,
                e.planned().phase(),
                e.planned().waypoint().map(|w| (w.x, w.y)),
                e.stats()
            );
        }
        {
            let r = sim.robot().dom_dinis().unwrap();
            let m = r.core.motor;
            if m.left == -m.right && m.left != 0 {
                spin += 1;
            }
            match (r.core.explorer.phase(), r.core.explorer.planned().phase()) {
                (robot_firmware::explore::ExplorePhase::Follow { .. }, _) => reactive += 1,
                (_, robot_firmware::explore::PlannedPhase::Follow { .. }) => follow += 1,
                _ => drive += 1,
            }
        }
        if sim.robot().arrived() {
            if !summary {
                println!("arrived at {t:.1} s");
            }
            break;
        }
    }
    if summary {
        let e = sim.robot().dom_dinis().unwrap().core.explorer;
        let g = (sim.truth().x - target.centre.x).hypot(sim.truth().y - target.centre.y);
        println!(
            "seed {seed} arrived {} t {:.0} spin {:.0}% follow {:.0}% reactive {:.0}% drive {:.0}% goal {g:.2} pose err {:.2} {:?}",
            sim.robot().arrived(),
            sim.now_us() as f64 * 1e-6,
            100.0 * spin as f64 / (drive + follow + reactive).max(1) as f64,
            100.0 * follow as f64 / (drive + follow + reactive).max(1) as f64,
            100.0 * reactive as f64 / (drive + follow + reactive).max(1) as f64,
            100.0 * drive as f64 / (drive + follow + reactive).max(1) as f64,
            sim.pose_error_m(),
            e.stats()
        );
        return;
    }
    print_map(&sim, &arena, &track, None);
    if std::env::var_os("RUN2").is_some() {
        run2(&mut sim, &arena, track[0]);
    }
    println!(
        "final true ({:.2},{:.2}), collisions {}",
        sim.truth().x,
        sim.truth().y,
        sim.collisions()
    );
}

/// The robot's map over the arena's walls; the robot (R) and the route's next point (o).
fn print_map(
    sim: &Sim,
    arena: &emulator::arena::Arena,
    track: &[(f64, f64)],
    waypoint: Option<robot_firmware::odometry::Point>,
) {
    let target = *arena.target().unwrap();
    let r = sim.robot().dom_dinis().unwrap();
    let grid = r.core.objects.nav().grid();
    let geo = grid.geometry();
    let cell = f64::from(geo.cell_size_m());
    let truth = rasterise(arena, cell, 0.0).unwrap();
    let b = sim.believed();
    println!(
        "map {}x{} cells of {cell} m; # wall both, W wall only truly, x marked only, . free, * track, G goal, R believed robot, o waypoint",
        grid.width(),
        grid.height()
    );
    let (ox, oy) = geo.origin_mm();
    let at = |x: usize, y: usize| {
        (
            f64::from(ox) / 1000.0 + (x as f64 + 0.5) * cell,
            f64::from(oy) / 1000.0 + (y as f64 + 0.5) * cell,
        )
    };
    let near = |cx: f64, cy: f64, px: f64, py: f64| {
        (px - cx).abs() < cell / 2.0 && (py - cy).abs() < cell / 2.0
    };
    for y in (0..grid.height() as usize).rev() {
        let mut line = String::new();
        for x in 0..grid.width() as usize {
            let (cx, cy) = at(x, y);
            let on_track = track.iter().any(|&(tx, ty)| near(cx, cy, tx, ty));
            let wall = truth
                .cell_at(cx, cy)
                .and_then(|(c, r)| truth.get(c, r))
                .is_some_and(|c| c == Cell::Obstacle);
            let goal = (cx - target.centre.x).hypot(cy - target.centre.y) < cell / 1.5;
            let ch = match (grid.get(x, y), wall) {
                _ if near(cx, cy, b.x, b.y) => 'R',
                _ if waypoint.is_some_and(|w| near(cx, cy, f64::from(w.x), f64::from(w.y))) => 'o',
                _ if goal => 'G',
                (Cell::Obstacle, true) => '#',
                (Cell::Obstacle, false) => 'x',
                (_, true) => 'W',
                _ if on_track => '*',
                (Cell::Free, false) => '.',
                _ => ' ',
            };
            line.push(ch);
        }
        println!("{line}");
    }
}

/// Run 2 of explore-then-plan as the scenario does it: segment, plan from the start to where
/// the goal was met, carry the robot back, execute; traced like run 1.
fn run2(sim: &mut Sim, arena: &emulator::arena::Arena, start: (f64, f64)) {
    let found = sim.believed();
    apply(sim, Command::Stop, "Stop").unwrap();
    apply(sim, Command::Segment, "Segment").unwrap();
    let mm = |v: f64| (v * 1000.0).round() as i32;
    let plan = Command::Plan {
        from: Some(protocol::PointMm {
            x_mm: mm(start.0),
            y_mm: mm(start.1),
        }),
        to: Some(protocol::PointMm {
            x_mm: mm(found.x),
            y_mm: mm(found.y),
        }),
    };
    apply(sim, plan, "Plan").unwrap();
    let mut pts = [robot_firmware::odometry::Point::new(0.0, 0.0); 64];
    let n = sim.robot().objects().plan_points(&mut pts);
    println!(
        "--- run 2 plan: {:?}",
        pts[..n].iter().map(|p| (p.x, p.y)).collect::<Vec<_>>()
    );
    let heading = sim.truth().heading;
    let s0 = emulator::arena::Pose {
        x: start.0,
        y: start.1,
        heading,
    };
    sim.place(s0).unwrap();
    let pose = protocol::Pose {
        x_mm: mm(start.0),
        y_mm: mm(start.1),
        heading_mrad: (heading * 1000.0).round() as i16,
    };
    apply(sim, Command::SetPose { pose }, "SetPose").unwrap();
    let id = sim.robot().objects().plan().unwrap().0;
    apply(sim, Command::ExecutePlan { plan_id: id }, "ExecutePlan").unwrap();
    let mut track = Vec::new();
    for i in 0..300_000u64 {
        sim.step();
        let p = sim.truth();
        if i % 100 == 0 {
            track.push((p.x, p.y));
        }
        if i % 10_000 == 0 {
            let b = sim.believed();
            println!(
                "run2 {:5.1}s true ({:.2},{:.2}) bel ({:.2},{:.2}) mode {:?} motor {:?}",
                i as f64 / 1000.0,
                p.x,
                p.y,
                b.x,
                b.y,
                sim.robot().mode(),
                sim.robot().dom_dinis().unwrap().core.motor
            );
        }
        if sim.robot().arrived() || sim.robot().mode() == protocol::Mode::Idle {
            println!(
                "run 2 ends at {:.1} s, arrived {}",
                i as f64 / 1000.0,
                sim.robot().arrived()
            );
            break;
        }
    }
    print_map(sim, arena, &track, None);
}
