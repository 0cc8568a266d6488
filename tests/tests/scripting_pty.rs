//! Scripting the robot as a script does: the real `station` binary against a
//! `robot-emulator` process on a real pty (fixed seed), its stdout parsed and its exit codes
//! read.
//!
//! - `station watch --count N` prints N lines of JSON with the pose and exits 0; `--fields`
//!   keeps only the keys asked for; a closed stdout (EPIPE) ends it with 0; a killed emulator
//!   ends it with the link-lost code.
//! - `station status --json` is one JSON object: the robot, its telemetry, the link.
//! - `station send goto X Y --wait`: 0 and "arrived" at a reachable point; the refused code
//!   outside the arena; the gave-up code for a point in a wall; the link-lost code when the
//!   emulator is killed mid-task; a usage error on a command that starts no task.
//! - `station export --csv -` writes to stdout what `--csv FILE` writes to the file.
//!
//! Time limits are generous (the emulator runs in real time on a loaded machine); what is
//! asserted is how each run ended, never how fast.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdout, Command, ExitStatus, Output, Stdio};
use std::time::{Duration, Instant};

use e2e_tests::procs::{emulator_on, record_emulator, scratch_dir};
use e2e_tests::workspace_bin;

/// The exit codes `station send --wait --help` and docs/scripting.md list.
const ARRIVED: i32 = 0;
const USAGE: i32 = 2;
const REFUSED: i32 = 3;
const GAVE_UP: i32 = 4;
const LINK_LOST: i32 = 7;

/// The emulator's seed: the same world and noise every run.
const SEED: &str = "3";

/// An emulator on `DIR/robot`, killed when dropped.
struct Emu {
    child: Child,
    port: PathBuf,
}

impl Emu {
    fn start(d: &Path) -> Emu {
        let port = d.join("robot");
        let child = emulator_on(&port, &["--seed", SEED]);
        Emu { child, port }
    }

    fn port(&self) -> &str {
        self.port.to_str().unwrap()
    }

    fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Drop for Emu {
    fn drop(&mut self) {
        self.kill();
    }
}

fn station(args: &[&str]) -> Command {
    let mut c = Command::new(workspace_bin("station"));
    c.args(args).stdin(Stdio::null());
    c
}

/// Runs `station ARGS` to its end; panics if it takes longer than `limit`.
fn run(args: &[&str], limit: Duration) -> Output {
    let child = station(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    finish(child, limit, args)
}

/// Waits for `child` for up to `limit`, then kills it and panics. Its piped output is read
/// as it comes (a child writing more than a pipe holds would otherwise never end).
fn finish(mut child: Child, limit: Duration, what: &[&str]) -> Output {
    fn drain(r: Option<impl Read + Send + 'static>) -> std::thread::JoinHandle<Vec<u8>> {
        std::thread::spawn(move || {
            let mut buf = Vec::new();
            if let Some(mut r) = r {
                let _ = r.read_to_end(&mut buf);
            }
            buf
        })
    }
    let stdout = drain(child.stdout.take());
    let stderr = drain(child.stderr.take());
    let end = Instant::now() + limit;
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if Instant::now() >= end {
            let _ = child.kill();
            let status = child.wait().unwrap();
            let out = Output {
                status,
                stdout: stdout.join().unwrap(),
                stderr: stderr.join().unwrap(),
            };
            panic!(
                "station {what:?} still running after {limit:?}: {}",
                text(&out)
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    Output {
        status,
        stdout: stdout.join().unwrap(),
        stderr: stderr.join().unwrap(),
    }
}

fn text(o: &Output) -> String {
    format!(
        "status {}; stdout: {}; stderr: {}",
        o.status,
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

fn code(s: ExitStatus) -> i32 {
    s.code().unwrap_or(-1)
}

/// `station ARGS` started, and the first line it wrote; the rest of its stdout is the reader's.
fn first_line(args: &[&str]) -> (Child, String, BufReader<ChildStdout>) {
    let mut child = station(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut first = String::new();
    out.read_line(&mut first).unwrap();
    assert!(!first.is_empty(), "station {args:?} wrote nothing");
    (child, first, out)
}

/// `station ARGS` with stdout a pipe whose reader stops after the first line (`| head -1`):
/// every write after the pipe's buffer is full or the reader gone fails with EPIPE.
fn with_closed_stdout(args: &[&str], limit: Duration) -> ExitStatus {
    let (child, _, out) = first_line(args);
    drop(out);
    finish(child, limit, args).status
}

#[test]
fn watch_prints_json_lines_with_the_pose_and_ends_as_asked() {
    let d = scratch_dir("scripting", "watch");
    let emu = Emu::start(&d);
    let p = emu.port();
    let o = run(
        &["watch", "--port", p, "--count", "5", "--kind", "telemetry"],
        Duration::from_secs(30),
    );
    assert_eq!(code(o.status), 0, "{}", text(&o));
    let lines: Vec<serde_json::Value> = String::from_utf8_lossy(&o.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l:?}")))
        .collect();
    assert_eq!(lines.len(), 5, "{}", text(&o));
    let mut last_robot_time = -1.0;
    for l in &lines {
        assert_eq!(l["kind"], "telemetry", "{l}");
        for key in ["x_m", "y_m", "heading_rad", "time_s"] {
            assert!(l[key].is_f64(), "{key} in {l}");
        }
        // The emulator's start, in the arena.
        let (x, y) = (l["x_m"].as_f64().unwrap(), l["y_m"].as_f64().unwrap());
        assert!((0.0..5.0).contains(&x) && (0.0..5.0).contains(&y), "{l}");
        let t = l["robot_time_s"].as_f64().unwrap();
        assert!(t > last_robot_time, "robot time goes forward: {l}");
        last_robot_time = t;
        // The micro-rato has no encoders: no reading, not a 0.
        assert!(l["enc_left"].is_null(), "{l}");
    }

    // Only the keys asked for, in order, each line with its kind.
    let o = run(
        &["watch", "--port", p, "-n", "3", "--fields", "y_m,x_m"],
        Duration::from_secs(30),
    );
    assert_eq!(code(o.status), 0, "{}", text(&o));
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    assert_eq!(out.lines().count(), 3, "{out}");
    for l in out.lines() {
        assert!(l.starts_with(r#"{"kind":"telemetry","y_m":"#), "{l}");
        let v: serde_json::Value = serde_json::from_str(l).unwrap();
        assert_eq!(v.as_object().unwrap().len(), 3, "{l}");
    }

    // A key no line has is refused before the port is opened, naming the keys there are.
    let o = run(
        &["watch", "--port", "/nonexistent", "--fields", "pose.x"],
        Duration::from_secs(10),
    );
    assert_eq!(code(o.status), USAGE, "{}", text(&o));
    assert!(text(&o).contains("x_m, y_m, heading_rad"), "{}", text(&o));

    // Nobody reads stdout any more (`| head -1`): not an error.
    let s = with_closed_stdout(&["watch", "--port", p], Duration::from_secs(30));
    assert_eq!(code(s), 0, "{s}");

    // --seconds: ends by itself, with what came in that time.
    let o = run(
        &[
            "watch",
            "--port",
            p,
            "--seconds",
            "1",
            "--kind",
            "telemetry",
        ],
        Duration::from_secs(30),
    );
    assert_eq!(code(o.status), 0, "{}", text(&o));
    assert!(!o.stdout.is_empty(), "{}", text(&o));
}

#[test]
fn watch_ends_with_the_link_lost_code_when_the_robot_goes() {
    let d = scratch_dir("scripting", "watch-lost");
    let emu = Emu::start(&d);
    let p = emu.port().to_string();
    let (first, o) = killed_mid_run(emu, &["watch", "--port", &p, "--kind", "telemetry"]);
    assert!(first.starts_with(r#"{"kind":"telemetry""#), "{first}");
    assert_eq!(code(o.status), LINK_LOST, "{}", text(&o));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("link lost"),
        "{}",
        text(&o)
    );
}

/// Runs `station ARGS`, kills the emulator once the first line is out, and returns that line
/// and how the run ended (its stdout still read, so that it ends for the link alone).
fn killed_mid_run(mut emu: Emu, args: &[&str]) -> (String, Output) {
    let (child, first, mut out) = first_line(args);
    let rest = std::thread::spawn(move || {
        let mut buf = Vec::new();
        let _ = out.read_to_end(&mut buf);
    });
    emu.kill();
    let o = finish(child, Duration::from_secs(20), args);
    let _ = rest.join();
    (first, o)
}

#[test]
fn status_is_one_json_object_and_a_few_lines_of_text() {
    let d = scratch_dir("scripting", "status");
    let emu = Emu::start(&d);
    let o = run(
        &["status", "--port", emu.port(), "--json"],
        Duration::from_secs(30),
    );
    assert_eq!(code(o.status), 0, "{}", text(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["peer"]["profile"], "MicroRato", "{v}");
    assert_eq!(v["telemetry"]["mode"], "Idle", "{v}");
    assert!(v["telemetry"]["x_m"].is_f64(), "{v}");
    assert!(v["telemetry"]["battery_v"].is_f64(), "{v}");
    assert!(v["telemetry"].get("kind").is_none(), "{v}");
    assert!(v["progress"].is_null(), "Idle runs no task: {v}");
    assert_eq!(v["stats"]["state"], "connected", "{v}");
    let o = run(&["status", "--port", emu.port()], Duration::from_secs(30));
    assert_eq!(code(o.status), 0, "{}", text(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    for line in [
        "mode        Idle",
        "pose        x ",
        "link        connected",
    ] {
        assert!(out.contains(line), "{line:?} in {out}");
    }
}

#[test]
fn a_go_to_with_wait_ends_with_the_code_of_how_it_ended() {
    let d = scratch_dir("scripting", "wait");
    let emu = Emu::start(&d);
    let p = emu.port();
    let limit = Duration::from_secs(150);

    // Reachable: half a metre up from the start, in the open.
    let o = run(
        &[
            "send",
            "--port",
            p,
            "goto",
            "0.5",
            "1.0",
            "--wait",
            "--timeout",
            "120",
            "--json",
        ],
        limit,
    );
    assert_eq!(code(o.status), ARRIVED, "{}", text(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["outcome"], "ack", "{v}");
    assert_eq!(v["wait"]["outcome"], "arrived", "{v}");
    assert_eq!(v["wait"]["exit_code"], ARRIVED, "{v}");
    let y = v["wait"]["pose"]["y_m"].as_f64().unwrap();
    assert!(
        y > 0.7,
        "arrived near y 1.0 (within the arrival radius): {v}"
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.starts_with("arrived after "), "{err}");

    // Outside the arena: refused, nothing started.
    let o = run(&["send", "--port", p, "goto", "9", "9", "--wait"], limit);
    assert_eq!(code(o.status), REFUSED, "{}", text(&o));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("refused after "),
        "{}",
        text(&o)
    );

    // In a wall (0.6 m right of the start): the robot gives up after stuck_limit_s.
    let o = run(&["params", "--port", p, "set", "stuck_limit_s", "5"], limit);
    assert!(o.status.success(), "{}", text(&o));
    let o = run(
        &[
            "send",
            "--port",
            p,
            "goto",
            "1.1",
            "0.5",
            "--wait",
            "--timeout",
            "120",
        ],
        limit,
    );
    assert_eq!(code(o.status), GAVE_UP, "{}", text(&o));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("go-to gave up: no progress for 5 s"),
        "{}",
        text(&o)
    );

    // A command that starts no task has nothing to wait for.
    let o = run(&["send", "--port", p, "stop", "--wait"], limit);
    assert_eq!(code(o.status), USAGE, "{}", text(&o));
}

#[test]
fn a_wait_ends_with_the_link_lost_code_when_the_emulator_is_killed() {
    let d = scratch_dir("scripting", "wait-lost");
    let emu = Emu::start(&d);
    let p = emu.port().to_string();
    // Two metres up: far longer than the test takes to kill the emulator.
    let args = [
        "send",
        "--port",
        &p,
        "goto",
        "0.5",
        "2.5",
        "--wait",
        "--timeout",
        "120",
    ];
    let (ack, o) = killed_mid_run(emu, &args);
    assert!(ack.starts_with("ack: goto"), "{ack}");
    assert_eq!(code(o.status), LINK_LOST, "{}", text(&o));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("link_lost after "),
        "{}",
        text(&o)
    );
}

#[test]
fn export_csv_to_stdout_is_the_file_export() {
    let d = scratch_dir("scripting", "csv");
    // Four times real time at 50 Hz: more rows (over 90 kB) than a pipe (64 kB) and the
    // reader's buffer (8 kB) hold, so that a reader that stops early makes the export's
    // writes fail.
    let rec = record_emulator(
        &d,
        "run",
        &["--seed", SEED, "--speed", "4"],
        &["rate 50"],
        3.0,
    );
    let file = d.join("run.csv");
    let o = run(
        &[
            "export",
            rec.to_str().unwrap(),
            "--csv",
            file.to_str().unwrap(),
        ],
        Duration::from_secs(30),
    );
    assert!(o.status.success(), "{}", text(&o));
    let o = run(
        &["export", rec.to_str().unwrap(), "--csv", "-"],
        Duration::from_secs(30),
    );
    assert!(o.status.success(), "{}", text(&o));
    let written = std::fs::read(&file).unwrap();
    assert!(written.len() > 90_000, "{} bytes", written.len());
    assert_eq!(o.stdout, written);
    assert!(!d.join("-").exists(), "no file named -");
    // A reader that stops early (`| head -1`) is not a failure.
    let s = with_closed_stdout(
        &["export", rec.to_str().unwrap(), "--csv", "-"],
        Duration::from_secs(30),
    );
    assert_eq!(code(s), 0, "{s}");
}
