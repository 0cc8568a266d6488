//! `station calibrate odometry` against the real `robot-emulator` binary over a pty, as an
//! operator runs it on a Khepera: a generated box, the robot follows its walls and closes
//! laps from the telemetry the station receives, the two odometry parameters are set, and
//! `station params get` reads them back. The emulator's drawn wheels (its `--json` report on
//! exit) judge the measured ratio; the station never sees them.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdout, Command, Output, Stdio};

use e2e_tests::procs::scratch_dir;
use e2e_tests::workspace_bin;

fn dir(name: &str) -> PathBuf {
    scratch_dir("calibrate-odometry", name)
}

/// The emulator, killed if the test fails before asking it to stop.
struct Emulator {
    child: Child,
    out: BufReader<ChildStdout>,
}

impl Drop for Emulator {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Emulator {
    /// Serves a khepera in `arena` at 10 x real time (the fastest at which the station's
    /// real-time link timers and the robot's simulated ones still agree).
    fn start(arena: &Path, seed: u64) -> (Emulator, PathBuf) {
        let mut child = Command::new(workspace_bin("robot-emulator"))
            .args(["--profile", "khepera", "--arena"])
            .arg(arena)
            .args(["--speed", "10", "--json", "--seed", &seed.to_string()])
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let mut out = BufReader::new(child.stdout.take().unwrap());
        let mut line = String::new();
        out.read_line(&mut line).unwrap();
        let pty = PathBuf::from(line.trim());
        assert!(pty.exists(), "no pty: {line:?}");
        (Emulator { child, out }, pty)
    }

    /// Stops it as Ctrl-C does and returns its --json report.
    fn stop(mut self) -> serde_json::Value {
        let pid = self.child.id().to_string();
        assert!(Command::new("kill")
            .args(["-INT", &pid])
            .status()
            .unwrap()
            .success());
        let mut rest = String::new();
        self.out.read_to_string(&mut rest).unwrap();
        let last = rest.lines().last().unwrap_or_default().to_string();
        serde_json::from_str(&last).unwrap_or_else(|e| panic!("{e}: {rest:?}"))
    }
}

fn station(args: &[&str]) -> Output {
    Command::new(workspace_bin("station"))
        .args(args)
        .stdin(Stdio::null())
        .output()
        .unwrap()
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

fn get(pty: &str, name: &str) -> f64 {
    let o = station(&["params", "--port", pty, "--json", "get", name]);
    assert!(o.status.success(), "{}", text(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    v["value"].as_f64().unwrap()
}

#[test]
#[ignore = "timing-sensitive: the station samples the robot's telemetry at 25 Hz in wall time \
            against an emulator at --speed 10, so a loaded machine changes the laps it closes; \
            at a load of 12 it measured -4478 ppm against the true -3647 (tolerance 729). \
            Run with --ignored on a quiet machine; the emulator scenario's bench test checks \
            the same calibrator deterministically"]
fn calibrates_on_a_generated_box_and_sets_the_parameters() {
    let d = dir("box");
    let arena = d.join("box3Lab.xml");
    let o = Command::new(workspace_bin("robot-emulator"))
        .args(["arena", "generate", "--kind", "box", "--seed", "3", "--out"])
        .arg(&arena)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let (emu, pty) = Emulator::start(&arena, 1);
    let port = pty.to_str().unwrap();
    assert_eq!(get(port, "odo_wheel_ratio_ppm"), 0.0);

    let o = station(&[
        "calibrate",
        "odometry",
        "--port",
        port,
        "--timeout",
        "120",
        "--json",
    ]);
    let all = text(&o);
    assert!(o.status.success(), "{all}");
    // Progress on stderr, the report on stdout.
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("lap 1 closed"),
        "{all}"
    );
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(r["error"].is_null(), "{all}");
    assert!(!r["laps"].as_array().unwrap().is_empty(), "{all}");
    let changes = r["changes"].as_array().unwrap();
    let change = |name: &str| {
        changes
            .iter()
            .find(|c| c["name"] == name)
            .unwrap_or_else(|| panic!("{name}: {all}"))
            .clone()
    };
    let ratio = change("odo_wheel_ratio_ppm");
    let distance = change("odo_wheel_distance_mm");
    assert_eq!(ratio["before"], 0.0);
    // Set with `params set` semantics: what the robot put in force is what reads back.
    let measured = ratio["after"].as_f64().unwrap_or_else(|| panic!("{all}"));
    // (Both are f32 on the robot; the two JSON writers print them at different widths.)
    assert_eq!(get(port, "odo_wheel_ratio_ppm") as f32, measured as f32);
    assert_eq!(
        get(port, "odo_wheel_distance_mm") as f32,
        distance["after"].as_f64().unwrap() as f32
    );
    let truth = emu.stop();
    let t = truth["true_ratio_ppm"].as_f64().unwrap();
    // The emulator scenario's own tolerance (emulator/tests/bench.rs): within 20 % of the
    // true ratio, or 500 ppm where the true one is small.
    assert!(
        (measured - t).abs() <= 0.2 * t.abs().max(2500.0),
        "measured {measured} ppm, true {t} ppm: {all}"
    );
}

#[test]
fn dry_run_measures_but_sets_nothing_and_a_robot_without_encoders_is_refused() {
    let d = dir("dry");
    let arena = d.join("box5Lab.xml");
    let o = Command::new(workspace_bin("robot-emulator"))
        .args(["arena", "generate", "--kind", "box", "--seed", "5", "--out"])
        .arg(&arena)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let (emu, pty) = Emulator::start(&arena, 2);
    let port = pty.to_str().unwrap();
    // A short timeout: whatever laps closed are used, nothing is set either way.
    let o = station(&[
        "calibrate",
        "odometry",
        "--port",
        port,
        "--timeout",
        "15",
        "--dry-run",
    ]);
    let all = text(&o);
    assert!(all.contains("following the wall on the right"), "{all}");
    assert_eq!(get(port, "odo_wheel_ratio_ppm"), 0.0, "{all}");
    assert_eq!(get(port, "odo_wheel_distance_mm"), 52.0, "{all}");
    drop(emu);

    // The micro-rato has no encoders: refused before the robot moves.
    let mut child = Command::new(workspace_bin("robot-emulator"))
        .args(["--profile", "micro-rato", "--speed", "10"])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut line = String::new();
    out.read_line(&mut line).unwrap();
    let emu = Emulator { child, out };
    let o = station(&["calibrate", "odometry", "--port", line.trim()]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("no wheel encoders"), "{}", text(&o));
    drop(emu);
}

/// Ctrl-C mid-lap: the robot is stopped, nothing is set, exit status 1.
#[test]
fn ctrl_c_stops_and_sets_nothing() {
    let d = dir("ctrlc");
    let arena = d.join("box1Lab.xml");
    let o = Command::new(workspace_bin("robot-emulator"))
        .args(["arena", "generate", "--kind", "box", "--seed", "1", "--out"])
        .arg(&arena)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let (emu, pty) = Emulator::start(&arena, 1);
    let port = pty.to_str().unwrap();
    let mut child = Command::new(workspace_bin("station"))
        .args(["calibrate", "odometry", "--port", port])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut line = String::new();
    out.read_line(&mut line).unwrap();
    assert!(line.contains("following the wall"), "{line:?}");
    // Let it drive a little first.
    std::thread::sleep(std::time::Duration::from_secs(2));
    assert!(Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap()
        .success());
    let status = child.wait().unwrap();
    let mut err = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    assert_eq!(status.code(), Some(1), "{err}");
    assert!(err.contains("interrupted (Ctrl-C): nothing set"), "{err}");
    assert!(
        !err.contains("warning: stop"),
        "the stop was not acknowledged: {err}"
    );
    assert_eq!(get(port, "odo_wheel_ratio_ppm"), 0.0);
    drop(emu);
}
