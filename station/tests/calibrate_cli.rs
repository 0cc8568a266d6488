//! `station calibrate` on a recording made from the in-process emulator: a Khepera 1 cm from
//! a lamp in `Mode::CalibrateLight`, its telemetry at 10 Hz written through the recording
//! code (`record::synth`) exactly as `station record` frames it. The station trains seed 000
//! §5.3's network on it with the firmware's code (labels from each turn, as the robot makes
//! them, or from the lamp's position); the held-out error is compared with the
//! paper (mean 1.52 deg, max 6.52 deg: mean within +25 %, max within +35 %, as the firmware's
//! tests), and the written map is read back and checked against the emulator's truth.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use emulator::arena::{Arena, Light, Pose};
use emulator::geometry::Point;
use emulator::sim::{Sim, SimConfig};
use protocol::{Message, Mode};
use robot_firmware::KHEPERA;
use station::calibrate::decode;
use station::record::synth::Synth;
use station::record::Meta;

const LAMP: (f64, f64) = (0.4, 0.3);

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("calibrate-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn station(args: &[&str], cwd: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_station"))
        .args(args)
        .current_dir(cwd)
        .stdin(Stdio::null())
        .output()
        .unwrap()
}

fn open_box() -> Arena {
    emulator::arena::walled_box("open box", "test", 0.75, 0.6)
}

fn spot(gap: f64) -> Point {
    let r = f64::from(KHEPERA.body_diameter_m) / 2.0;
    Point::new(LAMP.0 - r - gap, LAMP.1)
}

fn sim(seed: u64, mode: Mode, wheel_bias: Option<[f64; 2]>) -> Sim {
    let at = spot(0.01);
    let cfg = SimConfig {
        seed,
        wheel_bias,
        start: Some(Pose {
            x: at.x,
            y: at.y,
            heading: 0.7,
        }),
        lights: vec![Light {
            position: Point::new(LAMP.0, LAMP.1),
            height_m: 0.0,
            intensity: 1.0,
        }],
        ..SimConfig::new(&KHEPERA)
    };
    let mut sim = Sim::new(open_box(), cfg).unwrap();
    sim.robot_mut().apply(protocol::Command::SetMode(mode), 0);
    sim
}

/// A recording of the robot's telemetry at 10 Hz for `seconds` (or until it leaves
/// `Mode::CalibrateLight`).
fn record(sim: &mut Sim, seconds: u64) -> Vec<u8> {
    let mut synth = Synth::new(&Meta::now("in-process emulator", 115_200));
    for step in 0..seconds * 10 {
        sim.run_for(100);
        let now_ms = (sim.now_us() / 1000) as u32;
        let t = sim.robot().telemetry(now_ms);
        synth.from_robot(sim.now_us(), &Message::Telemetry(t));
        if step > 0 && sim.robot().mode() != Mode::CalibrateLight {
            break;
        }
    }
    synth.finish(sim.now_us(), "test")
}

/// Mean and max error of a map against the emulator's truth, the robot carried round the
/// lamp at 1 cm (as emulator/tests/sim_calibrate.rs).
fn truth_errors(sim: &mut Sim, som: &robot_firmware::som::LightSom) -> (f64, f64) {
    let at = spot(0.01);
    let mut e = Vec::new();
    for a in -90..=90 {
        sim.place(Pose {
            x: at.x,
            y: at.y,
            heading: -f64::from(a).to_radians(),
        })
        .unwrap();
        sim.run_for(90);
        let amb = sim.robot().sensors().ambient;
        let front: [u16; 6] = std::array::from_fn(|k| amb[k]);
        let inputs = robot_firmware::som::rescale(front.map(f32::from), 50.0, 500.0);
        let got = f64::from(som.recall(&inputs).unwrap()) - 90.0;
        e.push((got - f64::from(a)).abs());
    }
    (
        e.iter().sum::<f64>() / e.len() as f64,
        e.iter().copied().fold(0.0, f64::max),
    )
}

#[test]
fn a_recorded_calibration_trains_a_map_to_the_papers_accuracy() {
    let d = dir("train");
    let mut totals = (0.0, 0.0, 0.0, 0.0);
    let seeds = [1u64, 2, 3];
    for seed in seeds {
        // With --light the labels come from the recorded pose, so its heading must not drift
        // over the 20 turns: that run has unbiased wheels. The per-turn reference (the
        // default, as on the robot) copes with the drawn wheel bias.
        for (out, extra) in [("som.json", None), ("som.bin", Some("0.40,0.30"))] {
            let bias = extra.map(|_| [0.0, 0.0]);
            let mut s = sim(seed, Mode::CalibrateLight, bias);
            let rec = record(&mut s, 600);
            let path = d.join(format!("cal-{seed}-{out}.rec"));
            std::fs::write(&path, rec).unwrap();
            let mut args = vec!["calibrate", path.to_str().unwrap(), "--out", out, "--json"];
            if let Some(l) = extra {
                args.extend(["--light", l]);
            }
            if seed > seeds[0] {
                // The last seed's map is there: kept unless asked to replace it.
                let o = station(&args, &d);
                assert!(!o.status.success());
                let e = String::from_utf8_lossy(&o.stderr);
                assert!(e.contains("exists; pass --force"), "{e}");
                args.push("--force");
            }
            let o = station(&args, &d);
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
            println!("seed {seed} {out}: {report}");
            let mean = report["mean_deg"].as_f64().unwrap();
            let max = report["max_deg"].as_f64().unwrap();
            let som = decode(&std::fs::read(d.join(out)).unwrap()).unwrap();
            let (tmean, tmax) = truth_errors(&mut s, &som);
            println!("  against the truth: mean {tmean:.2} max {tmax:.2}");
            assert_eq!(
                report["reference"],
                if extra.is_some() { "light" } else { "turns" }
            );
            assert!(report["held_out"].as_u64().unwrap() > 100, "{report}");
            totals = (
                totals.0 + mean,
                totals.1 + max,
                totals.2 + tmean,
                totals.3 + tmax,
            );
        }
    }
    let n = (2 * seeds.len()) as f64;
    let avg = (totals.0 / n, totals.1 / n, totals.2 / n, totals.3 / n);
    println!(
        "average held-out mean {:.2} max {:.2}; against truth mean {:.2} max {:.2} (paper 1.52 / 6.52)",
        avg.0, avg.1, avg.2, avg.3
    );
    assert!(avg.0 <= 1.52 * 1.25 && avg.2 <= 1.52 * 1.25, "{avg:?}");
    assert!(avg.1 <= 6.52 * 1.35 && avg.3 <= 6.52 * 1.35, "{avg:?}");
    let names: Vec<String> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(names.is_empty(), "temporary files left: {names:?}");
}

#[test]
fn bad_recordings_and_arguments_are_refused_with_a_reason_and_no_output() {
    let d = dir("bad");
    // The robot idle: no frame in calibrate-light.
    let mut s = sim(4, Mode::Idle, None);
    let mut synth = Synth::new(&Meta::now("in-process emulator", 115_200));
    for _ in 0..20 {
        s.run_for(100);
        let t = s.robot().telemetry((s.now_us() / 1000) as u32);
        synth.from_robot(s.now_us(), &Message::Telemetry(t));
    }
    std::fs::write(d.join("idle.rec"), synth.finish(s.now_us(), "test")).unwrap();
    let o = station(&["calibrate", "idle.rec", "--out", "som.json"], &d);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("calibrate-light"), "{err}");
    // --any-mode: frames, but the robot never turned.
    let o = station(
        &["calibrate", "idle.rec", "--out", "som.json", "--any-mode"],
        &d,
    );
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("full turn"), "{err}");
    // Not a recording.
    std::fs::write(d.join("junk.rec"), b"hello").unwrap();
    let o = station(&["calibrate", "junk.rec", "--out", "som.bin"], &d);
    assert!(!o.status.success());
    // A bad point.
    let o = station(
        &["calibrate", "idle.rec", "--out", "som.bin", "--light", "x"],
        &d,
    );
    assert!(!o.status.success());
    assert!(!d.join("som.json").exists() && !d.join("som.bin").exists());
    // The map would replace the recording it is trained from.
    let before = std::fs::read(d.join("idle.rec")).unwrap();
    let o = station(&["calibrate", "idle.rec", "--out", "idle.rec"], &d);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--out") && err.contains("is the input"),
        "{err}"
    );
    assert_eq!(std::fs::read(d.join("idle.rec")).unwrap(), before);
}

#[test]
fn damaged_map_files_are_refused() {
    let mut rng = robot_firmware::behaviour::XorShift32::new(3);
    let som = robot_firmware::som::LightSom::random(&mut rng, (50.0, 500.0), (0.0, 180.0));
    let mut bin = station::calibrate::encode_bin(&som);
    assert_eq!(bin.len(), 854);
    assert_eq!(decode(&bin).unwrap(), som);
    bin[100] ^= 1;
    assert!(format!("{}", decode(&bin).unwrap_err()).contains("CRC"));
    assert!(decode(b"{\"format\": \"x\"}").is_err());
}

#[test]
fn a_calibration_run_far_from_any_lamp_is_refused_saying_so() {
    let d = dir("dark");
    // No lamp in this world: every reading stays dark.
    let cfg = SimConfig {
        seed: 5,
        start: Some(Pose {
            x: 0.2,
            y: 0.3,
            heading: 0.0,
        }),
        ..SimConfig::new(&KHEPERA)
    };
    let mut s = Sim::new(open_box(), cfg).unwrap();
    s.robot_mut()
        .apply(protocol::Command::SetMode(Mode::CalibrateLight), 0);
    std::fs::write(d.join("dark.rec"), record(&mut s, 30)).unwrap();
    let o = station(&["calibrate", "dark.rec", "--out", "som.json"], &d);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("no lamp near the robot"), "{err}");
    assert!(!d.join("som.json").exists());
}
