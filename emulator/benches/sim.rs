//! Simulation speed: simulated seconds per wall-clock second, headless, Khepera profile, in a
//! 2 x 2 m arena with 50 box walls (200 edges plus the boundary, so ray casts go through the
//! bucket grid). The target is 10,000x real time. Besides criterion's timing of a 10 s run,
//! a plain `Instant` measurement over 300 simulated seconds prints the figure, e.g.
//! `sim speed: khepera wander, 50 walls: 25000 sim-s per wall-s`.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::hint::black_box;
use std::path::PathBuf;
use std::time::Instant;

use criterion::{criterion_group, criterion_main, Criterion};
use emulator::arena::{Arena, ArenaFormat, Wall};
use emulator::geometry::{Aabb, Point};
use emulator::sim::{Sim, SimConfig};
use protocol::{Command, Mode, PointMm};
use robot_firmware::KHEPERA;

/// A 2 x 2 m enclosed arena with `n` non-overlapping boxes, 4-12 cm a side, placed by a fixed
/// LCG and kept clear of the start corner.
fn boxes_arena(n: usize) -> Arena {
    let mut seed = 0x2545_F491_4F6C_DD1Du64;
    let mut rnd = move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut boxes: Vec<Aabb> = Vec::new();
    while boxes.len() < n {
        let (w, h) = (0.04 + 0.08 * rnd(), 0.04 + 0.08 * rnd());
        let (x, y) = (0.05 + rnd() * (1.9 - w), 0.05 + rnd() * (1.9 - h));
        let b = Aabb::from_corners(Point::new(x, y), Point::new(x + w, y + h));
        let clear_of_start = b.distance_to_point(Point::new(0.2, 0.2)) > 0.15;
        if clear_of_start && boxes.iter().all(|o| !o.expanded(0.08).overlaps(&b)) {
            boxes.push(b);
        }
    }
    Arena {
        name: format!("{n} boxes"),
        source: PathBuf::from("bench"),
        format: ArenaFormat::AsciiGrid,
        bounds: Aabb::from_corners(Point::new(0.0, 0.0), Point::new(2.0, 2.0)),
        enclosed: true,
        walls: boxes
            .into_iter()
            .map(|b| Wall::rectangle(b, None))
            .collect(),
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

fn wandering_sim(seed: u64) -> Sim {
    let cfg = SimConfig {
        seed,
        start: Some(emulator::arena::Pose {
            x: 0.2,
            y: 0.2,
            heading: 0.7,
        }),
        ..SimConfig::new(&KHEPERA)
    };
    let mut sim = Sim::new(boxes_arena(50), cfg).unwrap();
    let reply = sim.robot_mut().apply(Command::SetMode(Mode::Wander), 0);
    assert!(matches!(reply, robot_firmware::link::Reply::Ack(_)));
    sim
}

/// Go-to back and forth between two corners: a new goal whenever the last is reached, so the
/// robot keeps driving (avoidance, drift, edge following) for the whole run.
fn go_to_shuttle(sim: &mut Sim, seconds: u64) -> u32 {
    let corners = [(1800, 1800), (200, 200)];
    let mut legs = 0u32;
    sim.robot_mut().apply(goal(corners[0]), 0);
    for _ in 0..seconds {
        sim.run_for(1000);
        if sim.robot().arrived() {
            legs += 1;
            let now = (sim.now_us() / 1000) as u32;
            let next = corners[(legs % 2) as usize];
            sim.robot_mut().apply(goal(next), now);
        }
    }
    legs
}

fn goal((x_mm, y_mm): (i32, i32)) -> Command {
    Command::GoTo(PointMm { x_mm, y_mm })
}

fn report_speed() {
    let sim_s = 300u64;
    let mut sim = wandering_sim(1);
    let t0 = Instant::now();
    sim.run_for(sim_s * 1000);
    let wall = t0.elapsed().as_secs_f64();
    println!(
        "sim speed: khepera wander, 50 walls: {:.0} sim-s per wall-s \
         ({sim_s} s simulated in {wall:.3} s; {:.2} m driven, {} collisions)",
        sim_s as f64 / wall,
        sim.distance_m(),
        sim.collisions(),
    );
    let mut sim = wandering_sim(1);
    let t0 = Instant::now();
    let legs = go_to_shuttle(&mut sim, sim_s);
    let wall = t0.elapsed().as_secs_f64();
    println!(
        "sim speed: khepera go-to shuttle, 50 walls: {:.0} sim-s per wall-s \
         ({sim_s} s simulated in {wall:.3} s; {:.2} m driven, {} collisions, {legs} legs)",
        sim_s as f64 / wall,
        sim.distance_m(),
        sim.collisions(),
    );
}

fn bench_sim(c: &mut Criterion) {
    report_speed();
    let mut g = c.benchmark_group("sim");
    g.sample_size(10);
    g.bench_function("khepera_wander_50_walls_10s", |b| {
        b.iter_batched(
            || wandering_sim(2),
            |mut sim| {
                sim.run_for(10_000);
                black_box(sim.truth())
            },
            criterion::BatchSize::LargeInput,
        )
    });
    g.finish();
}

criterion_group!(benches, bench_sim);
criterion_main!(benches);
