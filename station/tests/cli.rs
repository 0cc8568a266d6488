//! The `station` binary as a user runs it: headless commands against the real firmware on an
//! emulator pty, and bad arguments, each with its exit code and message (never a panic).
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::PathBuf;
use std::process::{Command, Output};

use emulator::link::{spawn_device, Running, ServeOptions};
use station::link::sim::{SimCore, SimOptions};

fn station(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_station"))
        .args(args)
        .output()
        .unwrap()
}

fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// An emulator and the private directory of its symlink, removed when dropped.
struct Robot {
    emu: Option<Running>,
    dir: PathBuf,
}

impl Drop for Robot {
    fn drop(&mut self) {
        drop(self.emu.take());
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// An emulator pty with the real firmware; the returned path is a stable symlink.
fn robot(name: &str) -> (Robot, PathBuf) {
    let dir = std::env::temp_dir().join(format!("station-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let link = dir.join("robot");
    let emu = spawn_device(
        || Ok(SimCore::new(SimOptions::default())),
        ServeOptions {
            link: Some(link.clone()),
            ..ServeOptions::default()
        },
    )
    .unwrap();
    (
        Robot {
            emu: Some(emu),
            dir,
        },
        link,
    )
}

#[test]
fn send_prints_the_ack_with_the_parameter_value_as_json() {
    let (_emu, port) = robot("get");
    let o = station(&[
        "send",
        "--port",
        port.to_str().unwrap(),
        "--json",
        "param",
        "get",
        "failsafe_ms",
    ]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["outcome"], "ack");
    assert_eq!(v["info"]["param"], "failsafe_ms");
    assert_eq!(v["info"]["value"], 300.0);
}

#[test]
fn a_refused_command_prints_the_robots_reason_and_exits_1() {
    let (_emu, port) = robot("nack");
    let p = port.to_str().unwrap();
    let o = station(&["send", "--port", p, "param", "set", "failsafe_ms", "5"]);
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{out}\n{err}");
    assert!(
        err.contains("nack: param set failsafe_ms 5: value out of range"),
        "{err}"
    );
    let o = station(&["send", "--port", p, "--json", "mode", "explore"]);
    let (out, _) = text(&o);
    assert_eq!(o.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["reason"], "Unsupported");
    // And accepted commands of every kind exit 0.
    for args in [
        &["mode", "manual"][..],
        &["teleop", "-100", "200"],
        &["stop"],
        &["rate", "20"],
        &["goto", "1.5", "1.0"],
    ] {
        let mut full = vec!["send", "--port", p];
        full.extend_from_slice(args);
        let o = station(&full);
        let (out, err) = text(&o);
        assert!(o.status.success(), "{args:?}: {out}\n{err}");
        assert!(out.starts_with("ack: "), "{out}");
    }
}

#[test]
fn stats_reports_the_link_as_json() {
    let (_emu, port) = robot("stats");
    let o = station(&[
        "stats",
        "--port",
        port.to_str().unwrap(),
        "--seconds",
        "1.5",
        "--json",
    ]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["stats"]["state"], "connected");
    assert_eq!(v["peer"]["firmware"], "robot-firmware");
    let hz = v["stats"]["telemetry_hz"].as_f64().unwrap();
    assert!((8.0..=12.0).contains(&hz), "{hz}");
    assert_eq!(v["stats"]["decoder"]["crc_errors"], 0);
    // The round trip is measured with a harmless probe (a parameter read), a few a second:
    // without it there was no round trip at all.
    let rt = &v["round_trip"];
    assert!(rt["samples"].as_u64().unwrap() >= 3, "{v}");
    assert!(rt["p50_us"].as_u64().unwrap() > 0, "{v}");
    assert!(rt["p99_us"].as_u64() >= rt["p50_us"].as_u64(), "{v}");
    assert_eq!(v["probe"], "param get failsafe_ms", "{v}");
    assert_eq!(v["probe_failures"].as_array().map(Vec::len), Some(0), "{v}");
    // Harmless: reading changes no state; the robot is still idle.
    assert_eq!(v["stats"]["commands"]["nacked"], 0, "{v}");
}

#[test]
fn stats_prints_the_probed_round_trip() {
    let (_emu, port) = robot("stats-text");
    let o = station(&["stats", "--port", port.to_str().unwrap(), "--seconds", "1"]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    assert!(
        out.lines().any(|l| l.starts_with("round trip  p50 ")
            && l.contains("probes (param get failsafe_ms, every 250 ms)")),
        "{out}"
    );
    assert!(out.contains("commands    "), "{out}");
}

#[test]
fn a_missing_port_is_a_clear_error_with_exit_1() {
    let o = station(&["send", "--port", "/dev/ttyNOPE9", "stop"]);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(1));
    assert!(err.contains("/dev/ttyNOPE9 does not exist"), "{err}");
}

#[tokio::test(flavor = "current_thread")]
async fn a_busy_port_names_the_process_holding_it() {
    let (_emu, port) = robot("busy");
    let held = station::link::serial::open_exclusive(&port, 115_200).unwrap();
    let p = port.to_str().unwrap().to_string();
    let o = tokio::task::spawn_blocking(move || station(&["send", "--port", &p, "stop"]))
        .await
        .unwrap();
    drop(held);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(1));
    assert!(err.contains("is in use by pid"), "{err}");
    assert!(
        err.contains(&format!("pid {}", std::process::id())),
        "{err}"
    );
}

#[test]
fn bad_arguments_exit_2_with_a_message_and_never_panic() {
    for args in [
        &["send", "--port", "/dev/null", "param", "get", "warp"][..],
        &["send", "--port", "/dev/null", "rate", "51"],
        &["send", "--port", "/dev/null", "teleop", "1"],
        &["send", "stop"],
        &["stats", "--port", "/dev/null", "--seconds", "x"],
        &["--baud", "9"],
        &["nonsense"],
    ] {
        let o = station(args);
        let (_, err) = text(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.starts_with("error:"), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

#[test]
fn the_tui_refuses_to_start_without_a_terminal() {
    let o = station(&[]);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(1));
    assert!(err.contains("needs a terminal"), "{err}");
}

#[test]
fn ports_lists_without_failing() {
    let o = station(&["ports", "--json"]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(v["serial"].is_array() && v["pty"].is_array());
}

#[test]
fn a_reader_that_goes_away_ends_the_output_quietly_as_with_sigpipe() {
    // `station plan ... | head -1`: the reader has gone before the first line is written.
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let out = Command::new(env!("CARGO_BIN_EXE_station"))
        .args(["plan", "--map", "builtin:micro-rato-99"])
        .stdout(writer)
        .stderr(std::process::Stdio::piped())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(out.status.code(), Some(141), "{stderr}");
}
