//! Sensor models against the papers' characteristics: Khepera IR versus distance (seed 000
//! §1.1), encoders at 0.08 mm per pulse (seed 000 §3), floor-line crossings (seed 003), the
//! micro-rato's beacon (seed 004 §3-4) and compass.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};

use emulator::arena::{load, Arena, ArenaFormat, LoadOptions, Pose};
use emulator::geometry::{Aabb, Point, Segment, SegmentSet};
use emulator::rng::SimRng;
use emulator::sensors::ir::IrArray;
use emulator::sensors::rato::BeaconSensor;
use emulator::sensors::Noise;
use emulator::sim::{Sim, SimConfig};
use emulator::world::World;
use protocol::{Command, PointMm};
use robot_firmware::deadreckon::BeaconModel;
use robot_firmware::{KHEPERA, MICRO_RATO};

const R: f64 = 0.0275;

fn open_box(w: f64, h: f64) -> Arena {
    Arena {
        name: "box".into(),
        source: PathBuf::from("test"),
        format: ArenaFormat::AsciiGrid,
        bounds: Aabb::from_corners(Point::new(0.0, 0.0), Point::new(w, h)),
        enclosed: true,
        walls: Vec::new(),
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

/// Readings of sensor S2 (+10 degrees) facing a wall square-on at `d` from the body's edge,
/// one per run seed, with the papers' noise and gain spread.
fn s2_readings(d: f64, runs: u64) -> Vec<u16> {
    let wall_x = 1.0;
    let walls = SegmentSet::new(vec![Segment::new(
        Point::new(wall_x, -1.0),
        Point::new(wall_x, 1.0),
    )]);
    let noise = Noise::default();
    let heading = -10f64.to_radians();
    let pose = Pose {
        x: wall_x - R - d,
        y: 0.0,
        heading,
    };
    (0..runs)
        .map(|seed| {
            let mut ir = IrArray::new(
                &KHEPERA,
                noise.obstacle_counts,
                noise.obstacle_gain_spread,
                &mut SimRng::new(seed, 1),
                SimRng::new(seed, 3),
            );
            ir.read(&walls, pose)[2]
        })
        .collect()
}

fn mean(v: &[u16]) -> f64 {
    v.iter().map(|&x| f64::from(x)).sum::<f64>() / v.len() as f64
}

#[test]
fn khepera_ir_saturates_below_1_7_cm_and_reads_only_noise_beyond_3_3_cm() {
    for d in [0.0, 0.005, 0.010, 0.015] {
        assert!(s2_readings(d, 200).iter().all(|&r| r == 1023), "d = {d}");
    }
    for d in [0.034, 0.04, 0.1] {
        let r = s2_readings(d, 200);
        // Floor of 5 counts plus sigma-3 noise: "a few counts".
        assert!(r.iter().all(|&x| x <= 20), "d = {d}: {r:?}");
        assert!((mean(&r) - 5.0).abs() < 1.0, "d = {d}: {}", mean(&r));
    }
}

#[test]
fn khepera_ir_falls_monotonically_through_the_useful_band() {
    let means: Vec<f64> = (17..=33)
        .map(|mm| mean(&s2_readings(f64::from(mm) / 1000.0, 100)))
        .collect();
    for w in means.windows(2) {
        assert!(w[1] < w[0], "{means:?}");
    }
    assert!(means[0] > 950.0 && means[16] < 30.0, "{means:?}");
}

#[test]
fn khepera_ir_sensors_differ_by_about_100_counts_and_noise_is_about_3_counts() {
    // Gain spread: across runs at the band's middle (~500 counts).
    let r = s2_readings(0.0215, 400);
    let m = mean(&r);
    let sd = (r.iter().map(|&x| (f64::from(x) - m).powi(2)).sum::<f64>() / r.len() as f64).sqrt();
    assert!((400.0..650.0).contains(&m), "{m}");
    // 2 sigma either side ~ 100 counts of spread.
    assert!((15.0..40.0).contains(&sd), "{sd}");
    // Noise alone: one sensor read many times.
    let walls = SegmentSet::new(vec![Segment::new(
        Point::new(1.0, -1.0),
        Point::new(1.0, 1.0),
    )]);
    let mut ir = IrArray::new(
        &KHEPERA,
        3.0,
        0.05,
        &mut SimRng::new(1, 1),
        SimRng::new(1, 3),
    );
    let pose = Pose {
        x: 1.0 - R - 0.0215,
        y: 0.0,
        heading: -10f64.to_radians(),
    };
    let reads: Vec<u16> = (0..2000).map(|_| ir.read(&walls, pose)[2]).collect();
    let m = mean(&reads);
    let sd = (reads
        .iter()
        .map(|&x| (f64::from(x) - m).powi(2))
        .sum::<f64>()
        / reads.len() as f64)
        .sqrt();
    assert!((2.5..3.5).contains(&sd), "{sd}");
}

#[test]
fn encoders_count_0_08_mm_of_wheel_travel_per_pulse() {
    let cfg = SimConfig {
        noise: Noise::none(),
        start: Some(Pose {
            x: 0.1,
            y: 0.3,
            heading: 0.0,
        }),
        ..SimConfig::new(&KHEPERA)
    };
    let mut sim = Sim::new(open_box(1.0, 0.6), cfg).unwrap();
    sim.robot_mut().apply(
        Command::GoTo(PointMm {
            x_mm: 700,
            y_mm: 300,
        }),
        0,
    );
    sim.run_for(5000);
    let body = sim.body();
    let enc = body.encoders().unwrap();
    let rot = body.rotation_m();
    for i in 0..2 {
        assert_eq!(enc[i], (rot[i] / 0.000_08).floor() as i32);
        assert!(enc[i] > 1000, "{enc:?}");
    }
    // No bias, no slip, no wall: wheel travel is ground travel, so odometry is exact to a pulse.
    let travelled = (rot[0] + rot[1]) / 2.0;
    assert!(
        (travelled - sim.distance_m()).abs() < 1e-3,
        "{travelled} vs {}",
        sim.distance_m()
    );
    assert!(sim.pose_error_m() < 0.002, "{}", sim.pose_error_m());
    // The firmware read the same counts at its last control cycle (within one cycle's travel).
    let fw = sim.robot().sensors().encoders.unwrap();
    assert!((fw[0] - enc[0]).abs() < 100, "{fw:?} vs {enc:?}");
}

#[test]
fn wheel_bias_is_what_odometry_cannot_see() {
    let run = |bias: [f64; 2]| {
        let cfg = SimConfig {
            noise: Noise::none(),
            wheel_bias: Some(bias),
            start: Some(Pose {
                x: 0.1,
                y: 0.3,
                heading: 0.0,
            }),
            ..SimConfig::new(&KHEPERA)
        };
        let mut sim = Sim::new(open_box(1.0, 0.6), cfg).unwrap();
        sim.robot_mut().apply(
            Command::GoTo(PointMm {
                x_mm: 800,
                y_mm: 300,
            }),
            0,
        );
        sim.run_for(8000);
        sim
    };
    let straight = run([0.0, 0.0]);
    let biased = run([0.01, -0.01]);
    // Same encoder story, different truth: the biased robot curved right while believing
    // itself on the line.
    assert!(
        biased.truth().y < straight.truth().y - 0.005,
        "{:?}",
        biased.truth()
    );
    assert!(biased.pose_error_m() > 0.005);
}

#[test]
fn the_firmware_counts_one_event_per_floor_line_crossed() {
    let cfg = SimConfig {
        noise: Noise::none(),
        floor_grid_m: Some(0.1),
        start: Some(Pose {
            x: 0.05,
            y: 0.25,
            heading: 0.0,
        }),
        ..SimConfig::new(&KHEPERA)
    };
    let mut sim = Sim::new(open_box(1.0, 0.6), cfg).unwrap();
    sim.robot_mut().apply(
        Command::GoTo(PointMm {
            x_mm: 875,
            y_mm: 250,
        }),
        0,
    );
    sim.run_for(30_000);
    assert!(sim.robot().arrived());
    // Lines at x = 0.1 .. 0.8 lie between start and stop.
    assert_eq!(sim.robot().line_events(), 8, "{:?}", sim.truth());
}

#[test]
fn the_beacon_is_seen_ahead_with_the_firmware_curve_and_not_behind() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/data/arenas/ciberrato/wallsMicRato99.xml");
    let world = World::new(
        load(&path, &LoadOptions::default()).unwrap(),
        Vec::new(),
        None,
    )
    .unwrap();
    let beacon = world.beacon().unwrap();
    let b = beacon.position;
    let mut sensor = BeaconSensor::new(true, 0.0, 0.0, SimRng::new(1, 7));
    let here = Point::new(b.x - 1.0, b.y);
    let ahead = sensor
        .read(
            Some(beacon),
            Pose {
                x: here.x,
                y: here.y,
                heading: 0.2,
            },
        )
        .unwrap();
    assert_eq!(
        u16::from(ahead.strength),
        BeaconModel::default().strength_at(1.0)
    );
    assert!((f64::from(ahead.bearing_rad) + 0.2).abs() < 1e-6);
    let behind = sensor
        .read(
            Some(beacon),
            Pose {
                x: here.x,
                y: here.y,
                heading: 3.0,
            },
        )
        .unwrap();
    assert_eq!(behind.strength, 0);
    // Micro-Rato'99's walls (1 unit) are lower than its beacon (2 units): never hidden.
    assert!(beacon.visible_from(Point::new(0.5, 0.5)));
    let none = BeaconSensor::new(false, 0.0, 0.0, SimRng::new(1, 7));
    let mut none = none;
    assert!(none
        .read(
            Some(beacon),
            Pose {
                x: 0.5,
                y: 0.5,
                heading: 0.0
            }
        )
        .is_none());
}

#[test]
fn the_micro_rato_compass_reads_five_times_a_second_with_two_degrees_of_noise() {
    let cfg = SimConfig {
        seed: 3,
        start: Some(Pose {
            x: 2.5,
            y: 4.0,
            heading: 1.0,
        }),
        ..SimConfig::new(&MICRO_RATO)
    };
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/data/arenas/ciberrato/wallsMicRato99.xml");
    let mut sim = Sim::new(load(&path, &LoadOptions::default()).unwrap(), cfg).unwrap();
    let mut readings = Vec::new();
    let mut last = None;
    for _ in 0..20_000 {
        sim.step();
        let c = sim.robot().sensors().compass;
        let cycle_just_ran = sim.robot().timing().last_cycle_us == Some(sim.now_us() - 1000);
        if let (Some(h), true) = (c, cycle_just_ran) {
            readings.push(f64::from(h));
        }
        last = c.or(last);
    }
    // 20 s at 5 Hz.
    assert!((95..=105).contains(&readings.len()), "{}", readings.len());
    let err: Vec<f64> = readings.iter().map(|h| h - 1.0).collect();
    let rms = (err.iter().map(|e| e * e).sum::<f64>() / err.len() as f64).sqrt();
    assert!(
        (1.2..3.0).contains(&rms.to_degrees()),
        "{}",
        rms.to_degrees()
    );
    assert!(last.is_some());
}
