//! The odometry calibration alone over the go-to benchmark's generated boxes, with each
//! arena's own noise draw (the same seeds as `robot-emulator bench --task goto --profile
//! khepera --kind box --calibrate-odometry`): the wheel-ratio error against the emulator's
//! truth, its distribution and how many gave nothing. For measuring what a change to the
//! calibration does without running the go-to after it:
//! `cargo run --release -p emulator --example calibration_bench -- [FIRST LAST [JOBS]]`
//! (default 1 200 2); `VERBOSE=1` prints each box.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use emulator::arena_gen::{generate, Kind};
use emulator::scenarios::bench::run_seed;
use emulator::scenarios::calibrate_odometry::{run_calibration, DEFAULT_TIMEOUT_S};
use emulator::scenarios::task::{ScenarioOptions, Task};

fn main() {
    if let Some(b) = std::env::var("TRACE").ok().and_then(|v| v.parse().ok()) {
        trace(b);
        return;
    }
    let a: Vec<String> = std::env::args().collect();
    let first: u64 = a.get(1).map_or(1, |s| s.parse().unwrap());
    let last: u64 = a.get(2).map_or(200, |s| s.parse().unwrap());
    let jobs: usize = a.get(3).map_or(2, |s| s.parse().unwrap());
    let verbose = std::env::var("VERBOSE").is_ok_and(|v| !v.is_empty());
    let boxes: Vec<u64> = (first..=last).collect();
    let next = AtomicUsize::new(0);
    let out = Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..jobs.max(1) {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(&b) = boxes.get(i) else { break };
                let arena = generate(Kind::Box, b).expect("generates").arena;
                let mut so = ScenarioOptions::new(&robot_firmware::KHEPERA, Task::GoTo(None));
                // The bench's seed for arena index b - 1, draw 1, base seed 1.
                so.seed = run_seed(1, (b - 1) as usize, 1);
                let r = run_calibration(arena, &so, DEFAULT_TIMEOUT_S).expect("runs");
                if verbose {
                    eprintln!(
                        "box {b:>3}: true {:>7.0} measured {:>7.0} err {:>6.0} dist err {:>6.3} mm laps {:?} both {} straight {} {:.2} m rej {} {:.0} s {}",
                        r.true_ratio_ppm,
                        r.wheel_ratio_ppm.unwrap_or(f32::NAN),
                        r.wheel_ratio_ppm.map_or(f64::NAN, |m| (f64::from(m) - r.true_ratio_ppm).abs()),
                        r.wheel_distance_mm.map_or(f64::NAN, |d| f64::from(d) - r.true_distance_mm),
                        r.lap_length_m,
                        r.both_directions,
                        r.straight_stretches,
                        r.straight_m,
                        r.straight_rejected,
                        r.sim_s,
                        r.error.as_deref().unwrap_or("")
                    );
                }
                out.lock().unwrap().push((b, r));
            });
        }
    });
    let mut rows = out.into_inner().unwrap();
    rows.sort_by_key(|r| r.0);
    let mut err: Vec<f64> = rows
        .iter()
        .filter_map(|(_, r)| {
            r.wheel_ratio_ppm
                .map(|m| (f64::from(m) - r.true_ratio_ppm).abs())
        })
        .collect();
    let none = rows.len() - err.len();
    err.sort_by(f64::total_cmp);
    let rank = |q: f64| {
        err.get(((q * err.len() as f64).ceil() as usize).clamp(1, err.len().max(1)) - 1)
            .copied()
            .unwrap_or(f64::NAN)
    };
    let under = |x: f64| err.iter().filter(|e| **e < x).count();
    let sim: f64 = rows.iter().map(|(_, r)| r.sim_s).sum::<f64>() / rows.len().max(1) as f64;
    println!(
        "{} boxes: nothing {none}; error < 500 ppm {} ({:.1} %), < 1500 {}; median {:.0} p90 {:.0} p95 {:.0} max {:.0} ppm; mean {:.0} s simulated",
        rows.len(),
        under(500.0),
        100.0 * under(500.0) as f64 / rows.len().max(1) as f64,
        under(1500.0),
        rank(0.5),
        rank(0.9),
        rank(0.95),
        err.last().copied().unwrap_or(f64::NAN),
        sim
    );
}

/// `TRACE=B`: one box's calibration sample by sample (travel, believed and true heading, side
/// and front IR, the mode), to see what the manoeuvre sees.
fn trace(b: u64) {
    use emulator::sim::Sim;
    use robot_firmware::odometry_calibration::CalibrationParams;
    use robot_firmware::odometry_manoeuvre::{Manoeuvre, Observation};
    let arena = generate(Kind::Box, b).expect("generates").arena;
    let mut so = ScenarioOptions::new(&robot_firmware::KHEPERA, Task::GoTo(None));
    so.seed = run_seed(1, (b - 1) as usize, 1);
    let mut sim = Sim::new(arena, so.sim_config()).expect("sim");
    eprintln!("bias {:?}", sim.wheel_bias());
    let p = &robot_firmware::KHEPERA;
    let mut m = Manoeuvre::new(
        CalibrationParams::default(),
        p.pulse_m * 1000.0,
        p.wheel_distance_m * 1000.0,
    );
    let now = |sim: &Sim| (sim.now_us() / 1000) as u32;
    let c = m.start();
    let t = now(&sim);
    let _ = sim.robot_mut().apply(c, t);
    let mut seq = 0u16;
    while sim.now_us() < 600_000_000 {
        let mut buf = [0u8; protocol::MAX_FRAME];
        let hb = protocol::Message::Heartbeat(protocol::Heartbeat { time_ms: 0 });
        let n = protocol::encode(seq, &hb, &mut buf).unwrap();
        seq = seq.wrapping_add(1);
        sim.uart_mut().push_inbound(&buf[..n]);
        let _ = sim.uart_mut().take_outbound();
        sim.run_for(40);
        let core = sim.robot();
        let enc = core.sensors().encoders.expect("encoders");
        let ir = core.sensors().ir;
        let h = core.pose().heading;
        let tr = sim.truth();
        println!(
            "{:.2} {} {} {:.4} {:.4} {} {} {} {} {:.4} {:.4}",
            sim.now_us() as f64 * 1e-6,
            enc[0],
            enc[1],
            h,
            tr.heading,
            ir[5],
            ir[0],
            ir[2],
            ir[3],
            tr.x,
            tr.y
        );
        let step = m.step(Observation {
            pulses: [i64::from(enc[0]), i64::from(enc[1])],
            heading_rad: h,
            ir,
        });
        for c in step.commands() {
            let t = now(&sim);
            let _ = sim.robot_mut().apply(c, t);
        }
        if step.done.is_some() {
            break;
        }
    }
    for st in m.straight_walls().stretches() {
        eprintln!("stretch {st:?}");
    }
    let rejected = m.straight_walls().rejected;
    eprintln!("rejected {rejected} result {:?}", m.finish());
}
