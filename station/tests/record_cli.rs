//! `station record` and `station replay` as a user runs them: against the real firmware on an
//! emulator pty, interrupted by Ctrl-C and killed outright, and with bad arguments and bad
//! files, each with its exit code and message, never a panic, and never a stray output file.
//! Nothing here waits a fixed time or judges a wall-clock rate: the tests move on when the
//! recording holds what they wait for, and judge telemetry rates on the robot's own clock.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use emulator::link::{spawn_device, Running, ServeOptions};
use protocol::{Feed, FrameDecoder, Message};
use station::link::sim::{SimCore, SimOptions};
use station::record::synth::demo;
use station::record::{RecordKind, Recording};

fn station(args: &[&str], cwd: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_station"))
        .args(args)
        .current_dir(cwd)
        .stdin(Stdio::null())
        .output()
        .unwrap()
}

fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("record-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn files(d: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n != "robot")
        .collect();
    v.sort();
    v
}

/// The real firmware on an emulator pty, reached through a symlink in `d`.
fn robot(d: &Path) -> (Running, PathBuf) {
    let link = d.join("robot");
    let emu = spawn_device(
        || Ok(SimCore::new(SimOptions::default())),
        ServeOptions {
            link: Some(link.clone()),
            ..ServeOptions::default()
        },
    )
    .unwrap();
    (emu, link)
}

/// `station record` of `port` into `d/run.rec` for two seconds with `args`, which succeeds; its
/// stdout and stderr.
fn record_two_seconds(d: &Path, port: &Path, args: &[&str]) -> (String, String) {
    let p = port.to_str().unwrap();
    let base = ["record", "--port", p, "--out", "run.rec", "--seconds", "2"];
    let o = station(&[&base[..], args].concat(), d);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    (out, err)
}

#[test]
fn record_then_replay_json_against_the_firmware_on_a_pty() {
    let d = dir("pty");
    let (_emu, port) = robot(&d);
    let (out, _) = record_two_seconds(&d, &port, &["--rate", "20", "--json"]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["connected"], true);
    assert_eq!(v["end"], "time limit");
    assert!(v["bytes_to_robot"].as_u64().unwrap() > 50);
    assert_eq!(files(&d), ["run.rec"], "no .partial left");

    let o = station(&["replay", "run.rec", "--json"], &d);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    let s: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(s["end"], "time limit");
    assert_eq!(s["sessions"], 1);
    assert_eq!(s["frames_to_robot"]["Hello"], 1);
    assert_eq!(s["frames_to_robot"]["Command"], 1, "the --rate command");
    assert_eq!(s["commands"]["acked"], 1);
    // 20 Hz from the rate command on (sent as the session starts, so at most the first
    // frame comes before it): on the robot's clock the frames are 50 ms apart (the station's
    // clock would measure this machine's load too).
    let times = telemetry_times(&d.join("run.rec"));
    let steps: Vec<u32> = times.windows(2).map(|w| w[1].wrapping_sub(w[0])).collect();
    assert!(steps.len() >= 10, "telemetry over 2 s: {times:?}");
    assert!(
        steps.iter().skip(1).all(|&dt| dt == 50),
        "telemetry steps (ms) on the robot's clock: {steps:?}"
    );
    assert_eq!(s["errors"]["crc_errors"], 0);
    let _ = std::fs::remove_dir_all(&d);
}

/// `station record --send` keeps what the station says of its commands' outcomes and of the
/// robot's events (station log records), and the export carries them on `/log` beside an
/// accepted go-to's marker on `/plan`.
#[test]
fn record_keeps_the_stations_words_and_the_export_marks_the_goal() {
    let d = dir("words");
    let (_emu, port) = robot(&d);
    record_two_seconds(&d, &port, &["--send", "goto 1.0 0.5"]);
    let rec = Recording::open(&d.join("run.rec")).unwrap();
    let lines: Vec<_> = rec.records.iter().filter_map(|r| r.station_log()).collect();
    assert!(
        lines
            .iter()
            .any(|l| l.text.starts_with("ok: goto 1.000 0.500 m")
                && l.level == protocol::LogLevel::Info),
        "{lines:?}"
    );
    assert!(
        lines.iter().any(|l| l.text == "mode changed to GoTo"),
        "{lines:?}"
    );

    let o = station(&["export", "run.rec", "--mcap", "run.mcap"], &d);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    let bytes = std::fs::read(d.join("run.mcap")).unwrap();
    let mut logged = Vec::new();
    let mut goal = None;
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        let v: serde_json::Value = match m.channel.topic.as_str() {
            "/log" | "/plan" => serde_json::from_slice(&m.data).unwrap(),
            _ => continue,
        };
        if m.channel.topic == "/log" {
            logged.push((v["name"].clone(), v["message"].clone()));
        } else if v["entities"][0]["id"] == "goal" {
            goal = Some(v["entities"][0]["spheres"][0]["pose"]["position"].clone());
        }
    }
    assert!(
        logged.iter().any(|(n, t)| n == "station/command"
            && t.as_str().unwrap().starts_with("ok: goto 1.000 0.500 m")),
        "{logged:?}"
    );
    let goal = goal.expect("a goal marker");
    assert_eq!(
        (goal["x"].as_f64(), goal["y"].as_f64()),
        (Some(1.0), Some(0.5))
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// The robot clock (`time_ms`) of every telemetry frame in a recording (finished or not).
fn telemetry_times(path: &Path) -> Vec<u32> {
    let Ok(rec) = Recording::open(path) else {
        return Vec::new();
    };
    let mut dec = FrameDecoder::new();
    let mut times = Vec::new();
    for r in rec
        .records
        .iter()
        .filter(|r| r.kind == RecordKind::FromRobot)
    {
        let mut input = r.data.as_slice();
        loop {
            match dec.feed(input) {
                Feed::NeedMore => break,
                Feed::Error { rest, .. } => input = rest,
                Feed::Frame { frame, rest } => {
                    if let Message::Telemetry(t) = frame.message {
                        times.push(t.time_ms);
                    }
                    input = rest;
                }
            }
        }
    }
    times
}

/// Waits until the unfinished recording at `partial` holds more than `frames` telemetry
/// frames (the station flushes it every second); a bound only for a failure.
fn wait_for_telemetry(partial: &Path, frames: usize) {
    let t0 = Instant::now();
    while telemetry_times(partial).len() <= frames {
        assert!(
            t0.elapsed() < Duration::from_secs(20),
            "{partial:?} never held {frames} telemetry frames"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn ctrl_c_finishes_the_recording_and_a_kill_leaves_a_readable_partial() {
    let d = dir("signals");
    let (_emu, port) = robot(&d);
    let p = port.to_str().unwrap().to_string();
    let spawn = |out: &str| {
        Command::new(env!("CARGO_BIN_EXE_station"))
            .args(["record", "--port", &p, "--out", out])
            .current_dir(&d)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let kill = |pid: u32, sig: &str| {
        let ok = Command::new("kill")
            .args([sig, &pid.to_string()])
            .status()
            .unwrap();
        assert!(ok.success());
    };
    // Ctrl-C: a clean end under the final name.
    let child = spawn("int.rec");
    wait_for_telemetry(&d.join("int.rec.partial"), 5);
    kill(child.id(), "-INT");
    let o = child.wait_with_output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = station(&["replay", "int.rec", "--json"], &d);
    let s: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(s["end"], "interrupted");
    assert!(s["telemetry"]["frames"].as_u64().unwrap() > 5);

    // A kill: the .partial keeps everything up to the last flush (each second).
    let child = spawn("kill.rec");
    wait_for_telemetry(&d.join("kill.rec.partial"), 5);
    kill(child.id(), "-KILL");
    let _ = child.wait_with_output().unwrap();
    assert!(!d.join("kill.rec").exists());
    let o = station(&["replay", "kill.rec", "--json"], &d);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        err.contains("kill.rec.partial"),
        "a hint to the partial: {err}"
    );
    let o = station(&["replay", "kill.rec.partial", "--json"], &d);
    let s: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(s["end"], serde_json::Value::Null, "no end record");
    assert!(s["telemetry"]["frames"].as_u64().unwrap() > 5);
    // A new recording does not overwrite the unfinished one.
    let o = station(&["record", "--port", &p, "--out", "kill.rec"], &d);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(1));
    assert!(err.contains("unfinished recording"), "{err}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn bad_arguments_and_files_exit_non_zero_without_creating_files() {
    let d = dir("bad");
    std::fs::write(d.join("keep.rec"), b"precious").unwrap();
    let good = demo(2, 10);
    std::fs::write(d.join("good.rec"), &good).unwrap();
    std::fs::write(d.join("torn.rec"), &good[..good.len() - 5]).unwrap();
    let before = files(&d);
    let cases: &[(&[&str], i32, &str)] = &[
        (&["record", "--port", "/dev/null"], 2, "--out <FILE>"),
        (
            &["record", "--port", "/nonexistent/tty", "--out", "x.rec"],
            1,
            "does not exist",
        ),
        (
            &["record", "--port", "/dev/null", "--out", "keep.rec"],
            1,
            "exists; pass --force to overwrite it",
        ),
        (
            &[
                "record",
                "--port",
                "/dev/null",
                "--out",
                "no/such/dir/x.rec",
            ],
            1,
            "does not exist",
        ),
        (
            &["record", "--out", "x.rec", "--seconds", "0"],
            2,
            "out of range",
        ),
        (&["record", "--out", "x.rec", "--rate", "99"], 2, "99"),
        (&["replay"], 2, "<FILE>"),
        (&["replay", "missing.rec", "--json"], 1, "does not exist"),
        (
            &["replay", "keep.rec", "--json"],
            1,
            "not a station recording",
        ),
        (&["replay", "good.rec", "--speed", "0"], 2, "out of range"),
        (&["replay", "good.rec"], 1, "needs a terminal"),
        (&["replay", "torn.rec", "--json"], 1, "truncated at byte"),
        (&["export", "good.rec"], 2, "--mcap"),
        (
            &["export", "good.rec", "--csv", "good.rec"],
            1,
            "is the input",
        ),
        (
            &["export", "good.rec", "--csv", "nodir/x.csv"],
            1,
            "does not exist",
        ),
    ];
    for (args, code, needle) in cases {
        let o = station(args, &d);
        let (out, err) = text(&o);
        assert_eq!(o.status.code(), Some(*code), "{args:?}: {out}\n{err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert_eq!(files(&d), before, "{args:?} created a file");
    }
    assert_eq!(std::fs::read(d.join("keep.rec")).unwrap(), b"precious");
    // A torn recording's summary is still printed, with the damage named.
    let o = station(&["replay", "torn.rec", "--json"], &d);
    let s: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(s["damage"]["offset"].as_u64().unwrap() > 0);
    assert_eq!(s["telemetry"]["frames"], 20);
    let _ = std::fs::remove_dir_all(&d);
}
