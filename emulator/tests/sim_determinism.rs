//! Determinism: the same seed and inputs give the same run bit for bit (true trace, firmware
//! belief, serial bytes); different seeds give different runs.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};

use emulator::arena::{load, Arena, ArenaFormat, Light, LoadOptions, Pose, Wall};
use emulator::geometry::{Aabb, Point};
use emulator::sim::{Sim, SimConfig};
use protocol::{
    encode, Command, Hello, Message, Mode, PointMm, FINGERPRINT, MAX_FRAME, PROTOCOL_VERSION,
};
use robot_firmware::{KHEPERA, MICRO_RATO};

fn cluttered_box() -> Arena {
    let pillar = |x: f64, y: f64| {
        Wall::rectangle(
            Aabb::from_corners(Point::new(x, y), Point::new(x + 0.08, y + 0.06)),
            None,
        )
    };
    Arena {
        name: "clutter".into(),
        source: PathBuf::from("test"),
        format: ArenaFormat::AsciiGrid,
        bounds: Aabb::from_corners(Point::new(0.0, 0.0), Point::new(0.75, 0.6)),
        enclosed: true,
        walls: vec![pillar(0.3, 0.2), pillar(0.5, 0.4), pillar(0.15, 0.42)],
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

/// Everything observable of a run: the true pose every 10 ms (as bits), the believed pose, the
/// collisions and every byte the robot sent.
#[derive(Debug, PartialEq)]
struct Trace {
    truth: Vec<[u64; 3]>,
    believed: Vec<[u64; 3]>,
    collisions: u32,
    wire: Vec<u8>,
}

fn khepera_run(seed: u64) -> Trace {
    let cfg = SimConfig {
        seed,
        start: Some(Pose {
            x: 0.1,
            y: 0.1,
            heading: 0.5,
        }),
        floor_grid_m: Some(0.1),
        slip: 0.01,
        lights: vec![Light {
            position: Point::new(0.6, 0.5),
            height_m: 0.0,
            intensity: 1.0,
        }],
        ..SimConfig::new(&KHEPERA)
    };
    let mut sim = Sim::new(cluttered_box(), cfg).unwrap();
    let hello = Hello {
        fingerprint: FINGERPRINT,
        protocol: PROTOCOL_VERSION,
        session: 1,
        station: "det",
    };
    let mut buf = [0u8; MAX_FRAME];
    let n = encode(0, &Message::Hello(hello), &mut buf).unwrap();
    sim.uart_mut().push_inbound(&buf[..n]);
    let n = encode(
        1,
        &Message::Command(Command::SetMode(Mode::Wander)),
        &mut buf,
    )
    .unwrap();
    sim.uart_mut().push_inbound(&buf[..n]);
    trace(&mut sim, 20_000)
}

fn trace(sim: &mut Sim, ms: u32) -> Trace {
    trace_with(sim, ms, |_| {})
}

/// `trace`, calling `each_ms` before every step.
fn trace_with(sim: &mut Sim, ms: u32, mut each_ms: impl FnMut(&mut Sim)) -> Trace {
    let bits = |p: Pose| [p.x.to_bits(), p.y.to_bits(), p.heading.to_bits()];
    let mut t = Trace {
        truth: Vec::new(),
        believed: Vec::new(),
        collisions: 0,
        wire: Vec::new(),
    };
    for _ in 0..ms / 10 {
        for _ in 0..10 {
            each_ms(sim);
            sim.step();
        }
        t.truth.push(bits(sim.truth()));
        t.believed.push(bits(sim.believed()));
        t.wire.extend(sim.uart_mut().take_outbound());
    }
    t.collisions = sim.collisions();
    t
}

#[test]
fn the_same_seed_gives_the_same_khepera_run_bit_for_bit() {
    let (a, b) = (khepera_run(21), khepera_run(21));
    assert!(!a.wire.is_empty());
    assert_eq!(a, b);
    // It did move, and the truth and the belief parted ways (noise and bias are on).
    assert_ne!(a.truth.first(), a.truth.last());
    assert_ne!(a.truth.last(), a.believed.last());
}

#[test]
fn different_seeds_give_different_runs() {
    let (a, b) = (khepera_run(21), khepera_run(22));
    assert_ne!(a.truth, b.truth);
}

#[test]
fn the_same_seed_gives_the_same_micro_rato_run() {
    let run = |seed: u64| {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../shared/data/arenas/ciberrato/wallsMicRato99.xml");
        let arena = load(&path, &LoadOptions::default()).unwrap();
        let cfg = SimConfig {
            seed,
            start: Some(Pose {
                x: 0.5,
                y: 0.5,
                heading: 0.0,
            }),
            ..SimConfig::new(&MICRO_RATO)
        };
        let mut sim = Sim::new(arena, cfg).unwrap();
        let goal = Command::GoTo(PointMm {
            x_mm: 2500,
            y_mm: 4500,
        });
        sim.robot_mut().apply(goal, 0);
        trace(&mut sim, 15_000)
    };
    let (a, b, c) = (run(5), run(5), run(6));
    assert_eq!(a, b);
    assert_ne!(a.truth, c.truth);
}

/// A robot with no station (a headless run) does nothing between control cycles, and the
/// simulation skips those passes of its main loop (`Robot::idle_until_us`). The run must be
/// the one a pass every millisecond gives, bit for bit: here the other run gets a pass every
/// millisecond because `robot_mut` tells the simulation the robot may have changed.
#[test]
fn skipping_the_idle_passes_between_control_cycles_changes_nothing() {
    let arena = || {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../shared/data/arenas/ciberrato/wallsMicRato99.xml");
        load(&path, &LoadOptions::default()).unwrap()
    };
    let run = |every_ms: bool, profile, arena: Arena, command: Command| {
        let cfg = SimConfig {
            seed: 9,
            start: Some(Pose {
                x: 0.5,
                y: 0.5,
                heading: 0.3,
            }),
            slip: 0.01,
            ..SimConfig::new(profile)
        };
        let mut sim = Sim::new(arena, cfg).unwrap();
        sim.robot_mut().apply(command, 0);
        trace_with(&mut sim, 12_000, |sim| {
            if every_ms {
                let _ = sim.robot_mut();
            }
        })
    };
    let goal = Command::GoTo(PointMm {
        x_mm: 2500,
        y_mm: 4500,
    });
    let a = run(false, &MICRO_RATO, arena(), goal);
    assert_ne!(a.truth.first(), a.truth.last(), "the robot drove");
    assert_eq!(a, run(true, &MICRO_RATO, arena(), goal));
    let wander = Command::SetMode(Mode::Wander);
    let a = run(false, &KHEPERA, cluttered_box(), wander);
    assert_ne!(a.truth.first(), a.truth.last(), "the robot wandered");
    assert_eq!(a, run(true, &KHEPERA, cluttered_box(), wander));
}
