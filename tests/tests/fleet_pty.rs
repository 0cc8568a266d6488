//! Three robots in one emulator process, one pty each (issue 17): robot 2's link is cut and
//! plugged back in (`--disconnect-after 2:S --reconnect-after 2:S`) while robots 1 and 3 keep
//! their sessions and their telemetry flowing, and robot 2 handshakes again on its new pty.
//! On Ctrl-C the emulator prints its `--json` report: each robot's link counters and
//! real-time jitter (printed here as a figure, not asserted).
#![allow(clippy::unwrap_used, clippy::panic)]

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command as Process, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use e2e_tests::procs::scratch_dir;
use e2e_tests::{workspace_bin, Received, TestStation};
use protocol::{Command, Heartbeat, Message};

/// Simulated (= wall, at --speed 1) seconds after which robot 2 is unplugged, and for how long.
const CUT_AT_S: f64 = 4.0;
const CUT_FOR_S: f64 = 3.0;

fn dir() -> PathBuf {
    scratch_dir("fleet", "run")
}

struct Emulator {
    child: Child,
    lines: mpsc::Receiver<String>,
}

impl Drop for Emulator {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn start(link: &Path) -> Emulator {
    let mut child = Process::new(workspace_bin("robot-emulator"))
        .args(["--robots", "3", "--seed", "3", "--json", "--link"])
        .arg(link)
        .args(["--disconnect-after", &format!("2:{CUT_AT_S}")])
        .args(["--reconnect-after", &format!("2:{CUT_FOR_S}")])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("robot-emulator starts");
    let out = child.stdout.take().unwrap();
    let (tx, lines) = mpsc::channel();
    std::thread::spawn(move || {
        for l in BufReader::new(out).lines().map_while(Result::ok) {
            if tx.send(l).is_err() {
                break;
            }
        }
    });
    Emulator { child, lines }
}

fn link_of(base: &Path, k: usize) -> PathBuf {
    PathBuf::from(format!("{}{k}", base.display()))
}

/// Heartbeats every robot still open and counts telemetry per robot over `dur`.
fn tick(stations: &mut [Option<TestStation>; 3], dur: Duration) -> [u32; 3] {
    let mut counts = [0u32; 3];
    for (st, c) in stations.iter_mut().zip(&mut counts) {
        let Some(st) = st else { continue };
        let _ = st.send(&Message::Heartbeat(Heartbeat { time_ms: 0 }));
        for (_, r) in st.collect(dur) {
            if matches!(r, Received::Telemetry(_)) {
                *c += 1;
            }
        }
    }
    counts
}

#[test]
fn one_robots_link_is_cut_and_restored_while_the_other_two_run_on() {
    let d = dir();
    let base = d.join("robot");
    let emu = start(&base);
    // The first three lines are the three ptys, in robot order.
    let first: Vec<String> = (0..3)
        .map(|_| emu.lines.recv_timeout(Duration::from_secs(20)).unwrap())
        .collect();
    let t0 = Instant::now();
    for (k, path) in first.iter().enumerate() {
        let link = link_of(&base, k + 1);
        assert_eq!(std::fs::read_link(&link).unwrap(), PathBuf::from(path));
    }
    let mut stations: [Option<TestStation>; 3] = [None, None, None];
    for (k, st) in stations.iter_mut().enumerate() {
        let mut s = TestStation::open(&link_of(&base, k + 1), 115_200).unwrap();
        s.handshake(Duration::from_secs(3)).expect("handshake");
        s.command(Command::SetTelemetryRate { hz: 20 }).unwrap();
        *st = Some(s);
    }
    // Until well past the reconnection, in 100 ms slots per robot.
    let mut history: Vec<(f64, [u32; 3])> = Vec::new();
    let mut replugged: Option<(f64, String)> = None;
    let mut reopened = false;
    while t0.elapsed().as_secs_f64() < CUT_AT_S + CUT_FOR_S + 2.0 {
        let counts = tick(&mut stations, Duration::from_millis(100));
        let t = t0.elapsed().as_secs_f64();
        history.push((t, counts));
        if replugged.is_none() {
            if let Ok(path) = emu.lines.try_recv() {
                replugged = Some((t, path));
            }
        }
        // Robot 2's new pty: reopen its link and handshake again.
        if let (Some((_, path)), false) = (&replugged, reopened) {
            if std::fs::read_link(link_of(&base, 2)).ok() == Some(PathBuf::from(path)) {
                let mut s = TestStation::open(&link_of(&base, 2), 115_200).unwrap();
                s.handshake(Duration::from_secs(3))
                    .expect("robot 2 handshakes on its new pty");
                s.command(Command::SetTelemetryRate { hz: 20 }).unwrap();
                stations[1] = Some(s);
                reopened = true;
            }
        }
    }
    let (back_at, _) = replugged.expect("robot 2 was plugged back in (a 4th pty line)");
    println!("robot 2 back at {back_at:.1} s; per-slot telemetry:");
    // Robots 1 and 3: telemetry in every second of the run, outage included.
    for robot in [0, 2] {
        for second in 1..(history.last().unwrap().0 as usize) {
            let n: u32 = history
                .iter()
                .filter(|(t, _)| *t >= second as f64 && *t < second as f64 + 1.0)
                .map(|(_, c)| c[robot])
                .sum();
            assert!(
                n >= 5,
                "robot {} sent {n} telemetry frames in second {second} (20 Hz asked)",
                robot + 1
            );
        }
    }
    // Robot 2: nothing while unplugged, telemetry again after.
    let during: u32 = history
        .iter()
        .filter(|(t, _)| *t > CUT_AT_S + 0.5 && *t < CUT_AT_S + CUT_FOR_S - 0.5)
        .map(|(_, c)| c[1])
        .sum();
    let after: u32 = history
        .iter()
        .filter(|(t, _)| *t > back_at + 0.5)
        .map(|(_, c)| c[1])
        .sum();
    println!("robot 2: {during} frames while unplugged, {after} after");
    assert_eq!(during, 0, "robot 2's link was cut");
    assert!(after >= 5, "robot 2 talks again after its replug");

    // Ctrl-C: the emulator prints its report and removes its links.
    let pid = emu.child.id().to_string();
    let _ = Process::new("kill").args(["-INT", &pid]).status();
    let report = emu
        .lines
        .recv_timeout(Duration::from_secs(10))
        .expect("the --json report");
    let v: serde_json::Value = serde_json::from_str(&report).unwrap();
    assert_eq!(v["robots"], 3);
    let per = v["per_robot"].as_array().unwrap();
    assert_eq!(per[1]["disconnects"], 1);
    assert_eq!(per[0]["disconnects"], 0);
    assert_eq!(per[2]["disconnects"], 0);
    for r in per {
        println!(
            "robot {}: cycle period p50 {:.0} us, p99 {:.0} us, max error {:.0} us ({} samples)",
            r["robot"],
            r["cycle_period_us"]["p50_us"].as_f64().unwrap_or(0.0),
            r["cycle_period_us"]["p99_us"].as_f64().unwrap_or(0.0),
            r["cycle_period_us"]["max_abs_error_us"]
                .as_f64()
                .unwrap_or(0.0),
            r["cycle_period_us"]["samples"]
        );
    }
    drop(emu);
    let _ = std::fs::remove_dir_all(&d);
}
