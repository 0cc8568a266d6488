//! One port, several programs: the TUI in tmux holds a `robot-emulator`'s pty (fixed seed),
//! and other `station` commands given the same `--port` go through the TUI's shared link.
//!
//! - `station send stop` is acked to its sender while `station watch` prints telemetry from
//!   the same robot at the same time;
//! - `station send goto --wait` arrives through it (events reach the client);
//! - a client driving by hand that goes away stops the robot, which the holder's heartbeats
//!   alone would not (the robot's failsafe listens for any station frame);
//! - `--via SOCKET` names the shared link itself; the socket is the user's alone (0600) and
//!   is gone when the TUI ends.
//!
//! Time limits are generous (real time on a loaded machine); what is asserted is how each
//! run ended and what the robot did.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::io::{BufRead, BufReader};
use std::os::unix::fs::PermissionsExt;
use std::path::Path;
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

use e2e_tests::procs::{emulator_on, scratch_dir};
use e2e_tests::tmux::Tmux;
use e2e_tests::workspace_bin;

fn station(args: &[&str]) -> Command {
    let mut c = Command::new(workspace_bin("station"));
    c.args(args).stdin(Stdio::null());
    c
}

/// Runs `station ARGS` to its end within `limit`.
fn run(args: &[&str], limit: Duration) -> Output {
    let mut child = station(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            return child.wait_with_output().unwrap();
        }
        if t0.elapsed() > limit {
            let _ = child.kill();
            panic!("station {args:?} took more than {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// The robot's mode as `station status --json` reports it through the shared link.
fn mode(port: &str) -> String {
    let o = run(
        &["status", "--port", port, "--json"],
        Duration::from_secs(20),
    );
    let (out, err) = text(&o);
    assert!(o.status.success(), "status: {err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    v["telemetry"]["mode"]
        .as_str()
        .unwrap_or_default()
        .to_string()
}

struct Rig {
    _emu: KillOnDrop,
    tui: Tmux,
    port: String,
}

struct KillOnDrop(Child);

impl Drop for KillOnDrop {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn rig(name: &str) -> Option<Rig> {
    if !Tmux::require(name) {
        return None;
    }
    let d = scratch_dir("shared-link", name);
    let port = d.join("robot");
    let emu = KillOnDrop(emulator_on(&port, &["--seed", "3"]));
    let p = port.to_str().unwrap().to_string();
    let tui = Tmux::start(
        name,
        120,
        40,
        &d,
        &workspace_bin("station"),
        &["--port", &p],
    );
    tui.wait_text("connected: robot-firmware", Duration::from_secs(30));
    tui.wait_text("shared:", Duration::from_secs(5));
    Some(Rig {
        _emu: emu,
        tui,
        port: p,
    })
}

#[test]
fn commands_and_watch_go_through_the_tui_holding_the_port() {
    let Some(r) = rig("send-watch") else { return };
    let mut watch = station(&[
        "watch",
        "--port",
        &r.port,
        "--kind",
        "telemetry",
        "--count",
        "20",
    ])
    .stdout(Stdio::piped())
    .stderr(Stdio::piped())
    .spawn()
    .unwrap();
    // The first line of the watch: it is attached and reading.
    let mut lines = BufReader::new(watch.stdout.take().unwrap()).lines();
    let first = lines.next().unwrap().unwrap();
    assert!(first.contains("\"kind\":\"telemetry\""), "{first}");

    let o = run(
        &["send", "--port", &r.port, "stop"],
        Duration::from_secs(20),
    );
    let (out, err) = text(&o);
    assert!(o.status.success(), "send: {out} {err}");
    assert!(out.contains("ack: stop"), "{out}");
    assert!(
        err.contains("shared link"),
        "says it goes through the TUI: {err}"
    );

    // The watch goes on to its count, its lines valid JSON with the pose.
    let rest: Vec<String> = lines.map(|l| l.unwrap()).collect();
    assert_eq!(rest.len(), 19, "{rest:?}");
    for l in &rest {
        let v: serde_json::Value = serde_json::from_str(l).unwrap();
        assert!(v["x_m"].is_number(), "{l}");
    }
    assert!(watch.wait().unwrap().success());

    // A go-to through the shared link arrives, and --wait hears it.
    let o = run(
        &[
            "send",
            "--port",
            &r.port,
            "goto",
            "0.5",
            "1.3",
            "--wait",
            "--timeout",
            "90",
        ],
        Duration::from_secs(120),
    );
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{out} {err}");
    assert!(err.contains("arrived"), "{err}");
    // The TUI saw the robot do it.
    r.tui.wait_text("arrived", Duration::from_secs(10));
}

#[test]
fn a_client_driving_by_hand_that_goes_away_stops_the_robot() {
    let Some(r) = rig("driver") else { return };
    let o = run(
        &["send", "--port", &r.port, "teleop", "100", "0"],
        Duration::from_secs(20),
    );
    let (out, err) = text(&o);
    assert!(o.status.success(), "teleop: {out} {err}");
    // The client has exited; the holder stops the robot for it.
    let t0 = Instant::now();
    loop {
        let m = mode(&r.port);
        if m == "Idle" {
            break;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(10),
            "the robot is still in {m} after its driver left"
        );
        std::thread::sleep(Duration::from_millis(200));
    }
}

#[test]
fn via_names_the_socket_which_is_private_and_gone_with_the_tui() {
    let Some(r) = rig("via") else { return };
    let screen = r.tui.screen().join("\n");
    // The log names the socket; find it in the runtime directory instead of parsing the
    // wrapped line: the one whose name ends with the emulator's pty.
    let dev = std::fs::canonicalize(&r.port).unwrap();
    let dir = match std::env::var_os("XDG_RUNTIME_DIR") {
        Some(d) if !d.is_empty() => Path::new(&d).join("station"),
        _ => {
            let uid = std::fs::metadata("/proc/self")
                .map(|m| std::os::unix::fs::MetadataExt::uid(&m))
                .unwrap();
            Path::new(&format!("/tmp/station-{uid}")).to_path_buf()
        }
    };
    let name = dev.display().to_string().replace('/', "%2F") + ".sock";
    let sock = dir.join(&name);
    assert!(sock.exists(), "{} in {screen}", sock.display());
    let mode = std::fs::metadata(&sock).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode, 0o600, "the socket is the user's alone");
    let dmode = std::fs::metadata(&dir).unwrap().permissions().mode() & 0o777;
    assert_eq!(dmode, 0o700);

    let s = sock.to_str().unwrap();
    let o = run(
        &["send", "--port", "/nonexistent/tty", "--via", s, "stop"],
        Duration::from_secs(20),
    );
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out} {err}");
    assert!(out.contains("ack: stop"), "{out}");

    r.tui.keys(&["q"]);
    let t0 = Instant::now();
    while sock.exists() {
        assert!(
            t0.elapsed() < Duration::from_secs(10),
            "the socket outlived the TUI"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
}
