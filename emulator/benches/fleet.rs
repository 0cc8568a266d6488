//! Fleet speed: three micro-rato robots searching for the beacon in Micro-Rato'99 at once,
//! against one alone (issue 17). Prints simulated seconds per wall second for the fleet and
//! per robot, e.g. `fleet speed: 3 robots: 2400 sim-s per wall-s (7200 robot-s)`; criterion
//! times 10 simulated seconds of each.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::hint::black_box;
use std::time::Instant;

use criterion::{criterion_group, criterion_main, Criterion};
use emulator::arena::LoadOptions;
use emulator::fleet::{Fleet, RobotSpec};
use emulator::sim::SimConfig;
use protocol::Command;
use robot_firmware::MICRO_RATO;

fn searching(robots: usize) -> Fleet {
    let arena = emulator::builtin::micro_rato_99(&LoadOptions::for_simulation()).unwrap();
    let cfg = SimConfig {
        seed: 1,
        ..SimConfig::new(&MICRO_RATO)
    };
    let specs = vec![
        RobotSpec {
            profile: &MICRO_RATO,
            start: None
        };
        robots
    ];
    let mut fleet = Fleet::new(arena, &cfg, &specs).unwrap();
    for s in fleet.sims_mut() {
        s.robot_mut().apply(Command::StartExploration, 0);
    }
    fleet
}

fn report_speed() {
    let sim_s = 120u64;
    for robots in [1, 3] {
        let mut fleet = searching(robots);
        let t0 = Instant::now();
        fleet.run_for(sim_s * 1000);
        let wall = t0.elapsed().as_secs_f64();
        println!(
            "fleet speed: {robots} robot(s), micro-rato-99 search: {:.0} sim-s per wall-s \
             ({:.0} robot-s per wall-s; {sim_s} s simulated in {wall:.3} s)",
            sim_s as f64 / wall,
            (sim_s * robots as u64) as f64 / wall,
        );
    }
}

fn bench_fleet(c: &mut Criterion) {
    report_speed();
    let mut g = c.benchmark_group("fleet");
    g.sample_size(10);
    for robots in [1, 3] {
        g.bench_function(format!("micro_rato_99_search_{robots}_robots_10s"), |b| {
            b.iter_batched(
                || searching(robots),
                |mut fleet| {
                    fleet.run_for(10_000);
                    black_box(fleet.now_us())
                },
                criterion::BatchSize::LargeInput,
            )
        });
    }
    g.finish();
}

criterion_group!(benches, bench_fleet);
criterion_main!(benches);
