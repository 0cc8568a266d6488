//! Retracing (seed 001 §3.1.2) end to end: a `robot-emulator --hal-trace` process on a pty, the
//! real `station record` binary recording its link while it runs a task (`--send`), then the
//! real `station retrace` re-running the firmware's own code over the recorded hardware trace.
//!
//! - Each profile's tasks (Dom Dinis reach-beacon search; Khepera go-to and foraging), fixed
//!   seeds: the retraced frames and motor commands equal the recorded ones bit for bit.
//! - A trace switched on mid-run cannot be retraced: reported, exit 1, with the first
//!   divergence.
//! - Seed 000 Tables 1-2 re-integrated from a recording by changing the odometry's d and dl
//!   (`--param`): the Khepera follows the wall of the paper's 75 x 60 cm box with its wheels
//!   truly 53.3 mm apart (as in emulator/src/scenarios/odometry_laps.rs); the retrace stops
//!   where the true position has gone twice round the box; each entry is the true rotation
//!   minus the retraced one, compared with robot_firmware::odometry::paper_000.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use e2e_tests::procs::{record_emulator, scratch_dir};
use e2e_tests::workspace_bin;
use protocol::{Feed, FrameDecoder, Message};
use robot_firmware::odometry::paper_000::{TABLE_1, TABLE_2};
use station::record::{RecordKind, Recording};

fn dir(name: &str) -> PathBuf {
    scratch_dir("retrace", name)
}

/// Records `seconds` of the emulator started with `emu_args`, sending `send` once connected.
fn record(d: &Path, name: &str, emu_args: &[&str], send: &[&str], seconds: f64) -> PathBuf {
    let mut all = vec!["serve"];
    all.extend_from_slice(emu_args);
    record_emulator(d, name, &all, send, seconds)
}

/// `station retrace REC ARGS --json`: exit code and report.
fn retrace(rec: &Path, args: &[&str]) -> (i32, serde_json::Value) {
    let out = Command::new(workspace_bin("station"))
        .arg("retrace")
        .arg(rec)
        .args(args)
        .arg("--json")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    let report = serde_json::from_str(&text).unwrap_or_else(|e| {
        panic!(
            "retrace {}: {e}: {text} {}",
            rec.display(),
            String::from_utf8_lossy(&out.stderr)
        )
    });
    (out.status.code().unwrap_or(-1), report)
}

fn assert_identical(name: &str, rec: &Path) {
    let (code, r) = retrace(rec, &[]);
    println!(
        "{name}: {} cycles, {} frames compared, believed {:.2} m / {:.0} deg, trace {:.0} B a \
         cycle (max {}), {:.1} % of 115200 baud beside telemetry's {:.1} %",
        r["cycles"],
        r["frames_compared"],
        r["believed_distance_m"].as_f64().unwrap(),
        r["believed_rotation_deg"].as_f64().unwrap(),
        r["link"]["trace_bytes_per_cycle_mean"].as_f64().unwrap(),
        r["link"]["trace_bytes_per_cycle_max"],
        r["link"]["trace_percent_of_115200"].as_f64().unwrap(),
        r["link"]["telemetry_percent_of_115200"].as_f64().unwrap(),
    );
    assert_eq!(r["identical"], true, "{name}: {r:#}");
    assert_eq!(code, 0, "{name}");
    assert_eq!(r["trace_complete_from_power_up"], true, "{name}");
    assert_eq!(r["trace_dropped_steps"], 0, "{name}");
    assert!(r["cycles"].as_u64().unwrap() > 100, "{name}: {r:#}");
    // Telemetry, the trace's own frames, replies: many frames, every one the trace covers
    // compared: the retrace ran to the trace's end, and what was not compared is only what
    // the robot sent after the last pass whose trace was recorded (a pass or two: its frames
    // and, at most, the trace chunk behind them).
    assert!(
        r["frames_compared"].as_u64().unwrap() > 150,
        "{name}: {r:#}"
    );
    assert_eq!(r["stopped"], "end of the trace", "{name}: {r:#}");
    assert!(
        r["frames_not_compared"].as_u64().unwrap() <= 8,
        "{name}: {r:#}"
    );
    // The task ran: the robot moved or turned.
    let moved = r["believed_distance_m"].as_f64().unwrap() > 0.05
        || r["believed_rotation_deg"].as_f64().unwrap().abs() > 45.0;
    assert!(moved, "{name}: the robot did not move: {r:#}");
}

#[test]
fn runs_of_each_profile_retrace_bit_for_bit() {
    let d = dir("tasks");
    // Dom Dinis, Micro-Rato'99: the reactive search for the beacon (seed 004 §5).
    let dd = record(
        &d,
        "dom-dinis-explore",
        &["--hal-trace", "--seed", "5"],
        &["explore"],
        10.0,
    );
    assert_identical("Dom Dinis reach-beacon", &dd);
    let khepera = ["--hal-trace", "--profile", "khepera", "--seed", "7"];
    let goto = record(&d, "khepera-goto", &khepera, &["goto 1.0 1.0"], 10.0);
    assert_identical("Khepera go-to", &goto);
    let forage_args = [&khepera[..], &["--arena", "builtin:forage"]].concat();
    let forage = record(&d, "khepera-forage", &forage_args, &["mode forage"], 10.0);
    assert_identical("Khepera forage", &forage);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_trace_switched_on_mid_run_is_reported_and_its_first_divergence_named() {
    let d = dir("midrun");
    // Without --hal-trace: the robot runs from power-up untraced, the station switches the
    // trace on after the handshake.
    let rec = record(
        &d,
        "midrun",
        &["--seed", "3"],
        &["param set hal_trace 1", "mode wander"],
        4.0,
    );
    let (code, r) = retrace(&rec, &[]);
    assert_eq!(code, 1, "{r:#}");
    assert_eq!(r["trace_complete_from_power_up"], false, "{r:#}");
    assert_eq!(r["identical"], false, "{r:#}");
    let div = &r["first_divergence"];
    assert!(
        div["step"].as_u64().is_some() && div["field"].is_string(),
        "{r:#}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// The emulator's truth in a recording: (robot time ms, x m, y m, heading rad).
fn truth(rec: &Path) -> Vec<(u32, f64, f64, f64)> {
    let bytes = std::fs::read(rec).unwrap();
    let recording = Recording::parse(&bytes).unwrap();
    let mut dec = FrameDecoder::new();
    let mut out = Vec::new();
    for r in recording
        .records
        .iter()
        .filter(|r| r.kind == RecordKind::FromRobot)
    {
        let mut input = &r.data[..];
        loop {
            match dec.feed(input) {
                Feed::Frame { frame, rest } => {
                    if let Message::EmuTruth(t) = frame.message {
                        out.push((
                            t.time_ms,
                            f64::from(t.pose.x_mm) / 1000.0,
                            f64::from(t.pose.y_mm) / 1000.0,
                            f64::from(t.pose.heading_mrad) / 1000.0,
                        ));
                    }
                    input = rest;
                }
                Feed::Error { rest, .. } => input = rest,
                Feed::NeedMore => break,
            }
        }
    }
    out
}

fn wrap(a: f64) -> f64 {
    (a + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI) - std::f64::consts::PI
}

/// When the true heading has turned `deg` (either way): (time ms, true rotation deg, how far
/// the robot went round the box centre meanwhile, deg).
fn turned(truth: &[(u32, f64, f64, f64)], centre: (f64, f64), deg: f64) -> Option<(u32, f64, f64)> {
    let around = |x: f64, y: f64| (y - centre.1).atan2(x - centre.0);
    let (mut circled, mut rotation) = (0.0f64, 0.0f64);
    for w in truth.windows(2) {
        let (a, b) = (w[0], w[1]);
        circled += wrap(around(b.1, b.2) - around(a.1, a.2));
        rotation += wrap(b.3 - a.3);
        if rotation.abs().to_degrees() >= deg {
            return Some((b.0, rotation.to_degrees(), circled.to_degrees()));
        }
    }
    None
}

#[test]
fn changing_d_and_dl_in_a_retrace_reproduces_seed_000_tables_1_and_2() {
    let d = dir("tables");
    // The paper's box, 75 x 60 cm inside, as an ASCII grid of 1 cm cells.
    let (w, h) = (75, 60);
    let mut grid =
        String::from("# name Khepera box 75 x 60 cm\n# cell 0.01\n# origin -0.01 -0.01\n");
    grid.push_str(&"#".repeat(w + 2));
    grid.push('\n');
    for _ in 0..h {
        grid.push_str(&format!("#{}#\n", ".".repeat(w)));
    }
    grid.push_str(&"#".repeat(w + 2));
    grid.push('\n');
    let arena = d.join("box.txt");
    std::fs::write(&arena, grid).unwrap();
    let arena = arena.to_str().unwrap().to_string();
    // As the Tables scenario: along the bottom wall heading west, the wall on the left, 39 mm
    // from it; wheels truly 53.3 mm apart; no wheel bias (--motors-noise 0); 4x real time.
    let mut clean = None;
    for seed in ["3", "1", "2", "4", "5"] {
        let args = [
            "--hal-trace",
            "--profile",
            "khepera",
            "--arena",
            &arena,
            "--start",
            "0.375,0.039,180",
            "--true-wheel-distance",
            "0.0533",
            "--motors-noise",
            "0",
            "--seed",
            seed,
            "--speed",
            "4",
        ];
        let rec = record(&d, &format!("box-{seed}"), &args, &["mode edge-left"], 50.0);
        let t = truth(&rec);
        // The Tables' end: two laps' rotation, 720 deg.
        let done = turned(&t, (0.375, 0.30), 720.0);
        println!("seed {seed}: {done:?} (ms, true rotation, circled round the centre, deg)");
        // A run that turned round at a corner went back round the box: it turned 720 deg
        // without going twice round the centre the same way (the scenario's `clean_laps`).
        if let Some((ms, rot, circled)) = done.filter(|(_, r, c)| r * c > 0.0 && c.abs() > 600.0) {
            clean = Some((rec, ms, rot, circled));
            break;
        }
    }
    let (rec, until, _, _) = clean.expect("a seed of five follows the wall round twice");
    let until = until.to_string();
    let mut worst: f64 = 0.0;
    for (table, rows, name) in [
        (1, &TABLE_1, "odo_mm_per_pulse"),
        (2, &TABLE_2, "odo_wheel_distance_mm"),
    ] {
        for &(value, paper_deg) in rows.iter() {
            let param = format!("{name}={value}");
            let (code, r) = retrace(&rec, &["--until-ms", &until, "--param", &param]);
            assert_eq!(code, 0, "{r:#}");
            // With the recorded parameters the retrace is the recorded run.
            assert_eq!(r["identical"], true, "{r:#}");
            let rot = &r["rotation"];
            let truth = rot["truth_deg"].as_f64().unwrap();
            let retraced = rot["retraced_deg"].as_f64().unwrap();
            // The paper's sign: how far the integrated rotation falls short of the true one.
            let ours = truth.abs() - retraced.abs();
            println!(
                "table {table} {name} {value}: paper {paper_deg:+.1} deg, retraced {ours:+.2}"
            );
            worst = worst.max((ours - paper_deg).abs());
        }
    }
    // The Tables scenario's tolerance is 0.75 deg, with 53.3 mm against the 53.33 that fits
    // the paper exactly and the robot's stop a few degrees off 720; here the retrace stops
    // where the true rotation reaches 720 deg; measured 0.37 deg at worst (seed 3).
    assert!(worst < 0.75, "worst |retraced - paper| = {worst:.2} deg");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn the_replay_overlays_the_retraced_track_and_says_what_differed() {
    if !e2e_tests::tmux::Tmux::require(
        "the_replay_overlays_the_retraced_track_and_says_what_differed",
    ) {
        return;
    }
    let d = dir("overlay");
    let args = ["--hal-trace", "--profile", "khepera", "--seed", "7"];
    let rec = record(&d, "goto", &args, &["goto 1.0 1.0"], 5.0);
    let t = e2e_tests::tmux::Tmux::start(
        "retrace-overlay",
        200,
        50,
        &d,
        &workspace_bin("station"),
        &[
            "replay",
            rec.to_str().unwrap(),
            "--retrace",
            "--param",
            "odo_wheel_distance_mm=40",
            "--speed",
            "16",
        ],
    );
    // The log's first line: the retrace, its parameter, the thesis's limit.
    t.wait_text(
        "retrace (odo_wheel_distance_mm=40)",
        Duration::from_secs(20),
    );
    // The retraced robot's marker on the map once the replay has run.
    t.wait_text("◇", Duration::from_secs(20));
    let _ = std::fs::remove_dir_all(&d);
}
