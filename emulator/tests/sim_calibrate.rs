//! Seed 000 §5.3 done by the robot itself: `Mode::CalibrateLight` in the emulator. The
//! Khepera is set down 1 cm from a lamp (the paper's calibration distance) in an open box and
//! told to calibrate; it turns on the spot, labels its readings with its own odometry heading
//! and trains its network online (robot-firmware/src/robot/calibrate.rs). Then it is carried
//! round the lamp, 1 deg at a time from the lamp on its right (-90 deg) to its left (+90), and
//! its `light_bearing()` is compared with the TRUE bearing from the simulation.
//!
//! Paper (offline, errors against odometry labels on the training rotation): mean 1.52 deg,
//! max 6.52 deg. Here the errors are against the truth, on fresh readings, so they include the
//! robot's own heading reference (found from the first turn) and its odometry. Tolerances,
//! one-sided because an error against the truth below the paper's is no failure: the
//! seed-averaged mean at most 1.52 deg + 25 %, the seed-averaged max at most 6.52 deg + 35 %,
//! the 4 cm mean above the 1 cm mean. Seeds 1-6.
//!
//! Where label noise would come from: the labels are the odometry's angle turned (times the
//! measured turn ratio) from the turn's reference. The test measures, from the emulator's
//! truth, how far that angle is from the true angle turned at every training cycle
//! (label error): robot-firmware/tests/paper_000_som.rs ASSUMES 2 deg (1 sigma) of it to
//! land on the paper's 1.52 deg. Measured: with nominal wheels 0.00-0.18 deg RMS per seed
//! (asserted < 0.5); with 53.3 mm wheels 0.03-1.33 deg RMS (max 8.3 deg, a turn whose drift
//! estimate is off; asserted RMS < 2), and the seeds with more label error have the larger
//! bearing errors (0.03 -> 0.84 deg mean, 1.33 -> 1.53 deg): the noise comes from the
//! robot's estimate of its turn-rate error. The reference's own error (the light's direction
//! from the sweeps) is not in this measure. Run with `--nocapture`.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::f64::consts::PI;

use emulator::arena::{Arena, Light, Pose};
use emulator::geometry::Point;
use emulator::sim::{Sim, SimConfig};
use protocol::{Command, Mode};
use robot_firmware::link::Reply;
use robot_firmware::KHEPERA;

const SEEDS: u64 = 6;
const LAMP: (f64, f64) = (0.4, 0.3);

fn lamp() -> Point {
    Point::new(LAMP.0, LAMP.1)
}

fn open_box() -> Arena {
    emulator::arena::walled_box("open box", "test", 0.75, 0.6)
}

/// The robot's centre with the lamp `gap` from its rim, due west of the lamp.
fn spot(gap: f64) -> Point {
    let r = f64::from(KHEPERA.body_diameter_m) / 2.0;
    Point::new(LAMP.0 - r - gap, LAMP.1)
}

struct Outcome {
    sim_s: f64,
    /// RMS and max of (odometry angle turned x turn ratio - true angle turned) within each
    /// training turn, degrees.
    label_rms: f64,
    label_max: f64,
    drift_deg: f64,
    mean: f64,
    max: f64,
    far_mean: f64,
}

fn calibrate(seed: u64, true_wheel_distance_m: Option<f64>, start_heading: f64) -> Outcome {
    let at = spot(0.01);
    let cfg = SimConfig {
        seed,
        start: Some(Pose {
            x: at.x,
            y: at.y,
            heading: start_heading,
        }),
        lights: vec![Light {
            position: lamp(),
            height_m: 0.0,
            intensity: 1.0,
        }],
        true_wheel_distance_m,
        ..SimConfig::new(&KHEPERA)
    };
    let mut sim = Sim::new(open_box(), cfg).unwrap();
    let reply = sim
        .robot_mut()
        .apply(Command::SetMode(Mode::CalibrateLight), 0);
    assert_eq!(reply, Reply::Ack(protocol::AckInfo::Done));
    // 21 turns of about 20 s; give it 600 s. Each control cycle (80 ms): the angle turned
    // since the epoch began, by odometry (scaled by the robot's measured turn ratio) and by
    // the truth.
    let wrap = |a: f64| emulator::physics::wrap_pi(a);
    let (mut turn, mut odo_turn, mut true_turn) = ((u32::MAX, false), 0.0f64, 0.0f64);
    let (mut prev_odo, mut prev_true) = (0.0f64, 0.0f64);
    let mut label_errors = Vec::new();
    for ms in 0..600_000u32 {
        sim.step();
        if sim.robot().mode() != Mode::CalibrateLight {
            break;
        }
        if ms % 80 != 0 {
            continue;
        }
        let core = &sim.robot().khepera().expect("a khepera").core;
        let (odo, truth) = (f64::from(core.pose().heading), sim.truth().heading);
        let training = core.light_cal.phase() == robot_firmware::robot::CalPhase::Train;
        // A training turn is one epoch; the align turns before it are not labelled.
        if (core.light_cal.epoch(), training) != turn {
            (turn, odo_turn, true_turn) = ((core.light_cal.epoch(), training), 0.0, 0.0);
        } else {
            odo_turn += wrap(odo - prev_odo);
            true_turn += wrap(truth - prev_true);
            if training {
                let drift = f64::from(core.light_cal.drift_per_turn());
                let scale = 2.0 * PI / (2.0 * PI - drift);
                label_errors.push((odo_turn * scale - true_turn).to_degrees());
            }
        }
        (prev_odo, prev_true) = (odo, truth);
    }
    let core = &sim.robot().khepera().expect("a khepera").core;
    assert_eq!(core.mode, Mode::Idle, "seed {seed}: still calibrating");
    assert!(core.light_cal.trained, "seed {seed}: calibration failed");
    let sim_s = sim.now_us() as f64 * 1e-6;
    let drift = core.light_cal.drift_per_turn().to_degrees();
    let (mean, max) = sweep(&mut sim, 0.01);
    let (far_mean, _) = sweep(&mut sim, 0.04);
    let n = label_errors.len().max(1) as f64;
    Outcome {
        sim_s,
        label_rms: (label_errors.iter().map(|e| e * e).sum::<f64>() / n).sqrt(),
        label_max: label_errors.iter().map(|e| e.abs()).fold(0.0, f64::max),
        drift_deg: f64::from(drift),
        mean,
        max,
        far_mean,
    }
}

/// Carries the robot round the lamp at `gap`, -90..=90 deg in 1 deg steps; (mean, max)
/// absolute error of the robot's bearing against the truth, degrees.
fn sweep(sim: &mut Sim, gap: f64) -> (f64, f64) {
    let at = spot(gap);
    let mut errors = Vec::new();
    for a in -90..=90 {
        // The lamp is due east: bearing a means heading -a.
        let heading = -f64::from(a).to_radians();
        sim.place(Pose {
            x: at.x,
            y: at.y,
            heading,
        })
        .unwrap();
        // One control cycle reads the sensors.
        sim.run_for(90);
        let t = sim.truth();
        let truth = ((LAMP.1 - t.y).atan2(LAMP.0 - t.x) - t.heading).to_degrees();
        let got = sim
            .robot()
            .light_bearing()
            .unwrap_or_else(|| panic!("no bearing at {a} deg, {gap} m"));
        errors.push((f64::from(got.to_degrees()) - truth).abs());
    }
    let mean = errors.iter().sum::<f64>() / errors.len() as f64;
    (mean, errors.iter().copied().fold(0.0, f64::max))
}

fn experiment(label: &str, wheel: Option<f64>) -> (f64, f64, f64, f64) {
    println!("\nonline calibration, {label}");
    println!("seed | sim s | drift deg/turn | label err rms  max | 1 cm mean   max | 4 cm mean");
    let mut acc = (0.0, 0.0, 0.0);
    let mut label_rms: f64 = 0.0;
    for seed in 1..=SEEDS {
        // Start facing anywhere: the first turn finds the lamp.
        let o = calibrate(seed, wheel, seed as f64 * 1.1);
        println!(
            "{seed:>4} | {:>5.0} | {:>14.2} | {:>13.2} {:>4.2} | {:>9.2} {:>5.2} | {:>9.2}",
            o.sim_s, o.drift_deg, o.label_rms, o.label_max, o.mean, o.max, o.far_mean
        );
        label_rms = label_rms.max(o.label_rms);
        acc = (acc.0 + o.mean, acc.1 + o.max, acc.2 + o.far_mean);
    }
    let n = SEEDS as f64;
    let out = (acc.0 / n, acc.1 / n, acc.2 / n);
    println!(
        "average: mean {:.2} deg (paper 1.52), max {:.2} deg (paper 6.52), 4 cm mean {:.2}",
        out.0, out.1, out.2
    );
    (out.0, out.1, out.2, label_rms)
}

#[test]
fn the_robot_calibrates_itself_to_the_papers_accuracy() {
    let (mean, max, far, label_rms) = experiment("nominal wheels", None);
    assert!(label_rms < 0.5, "label error rms up to {label_rms} deg");
    assert!(mean <= 1.52 * 1.25, "mean {mean}");
    assert!(max <= 6.52 * 1.35, "max {max}");
    assert!(far > mean, "4 cm {far} vs 1 cm {mean}");
}

#[test]
fn a_robot_whose_wheels_are_53_mm_apart_calibrates_as_well() {
    // seed 000 §3: the real Khepera behaves as if its wheels were 53.3 mm apart while the
    // odometry uses 52 mm: odometry over-reports every turn by 2.5 % (the light drifts about
    // -9 deg per turn through the odometry frame). The robot measures that drift and scales
    // its labels, so the paper's tolerances hold here too.
    let (mean, max, _, label_rms) = experiment("true wheel distance 53.3 mm", Some(0.0533));
    assert!(label_rms < 2.0, "label error rms up to {label_rms} deg");
    assert!(mean <= 1.52 * 1.25, "mean {mean}");
    assert!(max <= 6.52 * 1.35, "max {max}");
}

#[test]
fn calibration_far_from_any_light_fails_cleanly() {
    let cfg = SimConfig {
        seed: 3,
        start: Some(Pose {
            x: 0.2,
            y: 0.3,
            heading: 0.0,
        }),
        ..SimConfig::new(&KHEPERA)
    };
    let mut sim = Sim::new(open_box(), cfg).unwrap();
    sim.robot_mut()
        .apply(Command::SetMode(Mode::CalibrateLight), 0);
    // One turn is about 20 s.
    sim.run_for(40_000);
    let core = &sim.robot().khepera().expect("a khepera").core;
    assert_eq!(core.mode, Mode::Idle);
    assert!(!core.light_cal.trained);
    assert_eq!(core.light_bearing(), None);
}
