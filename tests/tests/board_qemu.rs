//! The robot firmware's own image on a Cortex-M4 (QEMU mps2-an386, `robot-firmware/board`)
//! driven by the real station through a pty, its sensors and motors served by
//! `robot-emulator hil` in lockstep (docs/hil.md): boot, a signed handshake, a teleop whose
//! wheels the failsafe stops when the station leaves, another stopped by a Stop, telemetry, a
//! map upload, a station without the key refused; then the board's own measures (RAM within
//! the Dom Dinis board's 32 KB, no byte dropped by the station FIFO). CI's smoke test of the
//! image (needs qemu-system-arm).
#![allow(clippy::unwrap_used, clippy::panic)]

use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use e2e_tests::workspace_bin;

const KEY: &str = "6b1f0a2c9d8e7f60514233241506f7e8d9cabbac9d8e7f60514233241506f7e8";
const TARGET: &str = "thumbv7em-none-eabihf";

/// The board image, built if missing (CI builds it with the firmware's Cortex-M4 step).
fn image() -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let target_dir = exe.ancestors().nth(3).unwrap().to_path_buf();
    let path = target_dir.join(TARGET).join("release").join("robot-board");
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let status = Command::new(cargo)
        .args([
            "build",
            "-q",
            "-p",
            "robot-board",
            "--release",
            "--target",
            TARGET,
        ])
        .arg("--target-dir")
        .arg(&target_dir)
        .status()
        .unwrap();
    assert!(status.success(), "the board image builds");
    assert!(path.is_file(), "{} missing", path.display());
    path
}

fn station(args: &[&str]) -> (bool, String) {
    let out = Command::new(workspace_bin("station"))
        .args(args)
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    (out.status.success(), text)
}

fn wait_for(path: &Path, within: Duration) {
    let end = Instant::now() + within;
    while std::fs::metadata(path).is_err() {
        assert!(
            Instant::now() < end,
            "no {} within {within:?}",
            path.display()
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn the_image_boots_and_the_station_drives_it_through_a_pty() {
    assert!(
        Command::new("qemu-system-arm")
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success()),
        "qemu-system-arm is needed (Debian: apt-get install qemu-system-arm)"
    );
    let started = Instant::now();
    let image = image();
    let dir = std::env::temp_dir().join(format!("board-qemu-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let key = dir.join("link.key");
    std::fs::write(&key, format!("{KEY}\n")).unwrap();
    use std::os::unix::fs::PermissionsExt as _;
    std::fs::set_permissions(&key, std::fs::Permissions::from_mode(0o600)).unwrap();
    let link = dir.join("robot");
    let key_s = key.display().to_string();
    let port = link.display().to_string();

    let mut world = Command::new(workspace_bin("robot-emulator"))
        .args(["hil", "--seed", "3", "--json", "--image"])
        .arg(&image)
        .args(["--key-file", &key_s, "--link", &port])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdout = BufReader::new(world.stdout.take().unwrap());
    let mut pty = String::new();
    stdout.read_line(&mut pty).unwrap();
    assert!(
        pty.starts_with("/dev/"),
        "the station's port is printed first: {pty:?}"
    );
    wait_for(&link, Duration::from_secs(10));
    let boot = started.elapsed();

    // A signed handshake and a teleop; the wheels turn; a Stop.
    let with_key = |cmd: &[&str]| {
        let mut a = vec!["send", "--port", &port, "--key-file", &key_s];
        a.extend_from_slice(cmd);
        station(&a)
    };
    // The station's `send` leaves at once: its link falls silent, and the manual-mode
    // failsafe (failsafe_ms, 300 ms) must stop the wheels on the image.
    let (ok, out) = with_key(&["teleop", "150", "0"]);
    assert!(ok && out.contains("ack: teleop"), "{out}");
    std::thread::sleep(Duration::from_millis(1000));
    let (ok, out) = with_key(&["teleop", "150", "0"]);
    assert!(ok && out.contains("ack: teleop"), "{out}");
    std::thread::sleep(Duration::from_millis(150));
    let (ok, out) = with_key(&["stop"]);
    assert!(ok && out.contains("ack: stop"), "{out}");

    // Telemetry, over a session of its own.
    let (ok, out) = station(&[
        "stats",
        "--port",
        &port,
        "--key-file",
        &key_s,
        "-s",
        "1.5",
        "--json",
    ]);
    assert!(ok, "{out}");
    let stats: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(stats["peer"]["profile"], "MicroRato", "{out}");
    let caps = stats["peer"]["capabilities"].as_u64().unwrap();
    assert_eq!(
        caps & u64::from(protocol::caps::EMULATED),
        0,
        "a board is no emulator"
    );
    let telemetry = stats["stats"]["telemetry_frames"]
        .as_u64()
        .or_else(|| stats["stats"]["telemetry"]["frames"].as_u64());
    let frames_in = stats["stats"]["frames_in"].as_u64().unwrap();
    assert!(
        telemetry.unwrap_or(frames_in) > 5 && frames_in > 5,
        "telemetry comes: {out}"
    );

    // A map upload, windowed chunks, CRC-checked, installed.
    let (ok, out) = station(&[
        "upload-map",
        "--port",
        &port,
        "--key-file",
        &key_s,
        "--map",
        "builtin:micro-rato-99",
        "--json",
    ]);
    assert!(ok && out.contains("\"ok\": true"), "{out}");

    // Without the key the image refuses the station.
    let (ok, out) = station(&["send", "--port", &port, "stop"]);
    assert!(!ok && out.contains("link authentication failed"), "{out}");

    // The world's summary: the wheels turned and stopped; the board's own measures.
    let pid = world.id().to_string();
    Command::new("kill").args(["-INT", &pid]).status().unwrap();
    let mut rest = String::new();
    stdout.read_to_string(&mut rest).unwrap();
    let status = world.wait().unwrap();
    let mut err = String::new();
    world
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    assert!(status.success(), "robot-emulator hil: {status}\n{err}");
    let summary: serde_json::Value =
        serde_json::from_str(rest.lines().last().unwrap_or("")).unwrap();
    eprintln!("board in the loop: {summary}");
    assert!(summary["fault"].is_null(), "{summary}");
    assert_eq!(summary["power_ons"], 1, "{summary}");
    assert_eq!(summary["frame_errors"], 0, "{summary}");
    assert!(
        summary["moving_exchanges"].as_u64().unwrap() > 0,
        "teleop moved: {summary}"
    );
    assert!(summary["distance_m"].as_f64().unwrap() > 0.0, "{summary}");
    // Two teleops, two stops: the failsafe's after the first, the Stop's after the second.
    let stops = summary["motor_stops_monotonic_s"].as_array().unwrap();
    assert!(
        stops.len() >= 2,
        "the failsafe and the Stop stopped the wheels: {summary}"
    );
    let t = |i: usize| stops[i].as_f64().unwrap();
    assert!(t(1) - t(0) > 0.5, "one stop each: {summary}");
    let b = &summary["board"];
    let ram = b["static_ram"].as_u64().unwrap() + b["stack_used"].as_u64().unwrap();
    assert!(b["stack_used"].as_u64().unwrap() > 512, "{summary}");
    assert!(
        ram <= 32 * 1024,
        "state + stack {ram} B over the Dom Dinis board's 32 KB"
    );
    assert_eq!(b["rx_dropped"], 0, "{summary}");
    assert!(b["rx_bytes"].as_u64().unwrap() > 100, "{summary}");
    assert_eq!(b["hil_errors"], 0, "{summary}");
    eprintln!(
        "booted in {boot:?}, whole smoke test {:?}, state + stack {ram} B",
        started.elapsed()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Lockstep: the same seed gives the same run however fast the board executes. The robot
/// searches from power-on (no station), once with QEMU in real time and once with every
/// instruction taking 8 ns (`-icount shift=3`): the exchanges' digest (every sensor frame
/// sent, every motor command received) is the same.
#[test]
fn a_seed_gives_the_same_run_however_fast_the_image_executes() {
    let image = image();
    let run = |extra: &[&str]| {
        let out = Command::new(workspace_bin("robot-emulator"))
            .args([
                "hil",
                "--seed",
                "5",
                "--power-on-mode",
                "explore",
                "--seconds",
                "4",
            ])
            .arg("--json")
            .arg("--image")
            .arg(&image)
            .args(extra)
            .stdin(Stdio::null())
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = String::from_utf8_lossy(&out.stdout).to_string();
        let v: serde_json::Value = serde_json::from_str(text.lines().last().unwrap()).unwrap();
        v
    };
    let fast = run(&[]);
    let slow = run(&["--icount", "3"]);
    assert_eq!(fast["exchanges"], 80, "{fast}");
    assert!(
        fast["distance_m"].as_f64().unwrap() > 0.2,
        "the robot searched: {fast}"
    );
    assert_eq!(fast["digest"], slow["digest"], "{fast}\n{slow}");
    assert_eq!(fast["distance_m"], slow["distance_m"]);
    // The instruction counts differ (the slow run's timer counts 8 ns instructions), the run
    // does not.
    assert_ne!(
        fast["board"]["cycle_ticks_max"],
        slow["board"]["cycle_ticks_max"]
    );
}

/// The station link through the world (`--line-baud`, `--drop-rate`): the emulator's seeded
/// link faults between the station and the image, a paced 115200-baud line; the station
/// still handshakes and reads telemetry through the losses, and the relay counts them.
#[test]
fn the_station_link_through_the_world_takes_the_emulators_faults() {
    let image = image();
    let dir = std::env::temp_dir().join(format!("board-qemu-relay-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let link = dir.join("robot");
    let port = link.display().to_string();
    let mut world = Command::new(workspace_bin("robot-emulator"))
        .args(["hil", "--seed", "2", "--json", "--line-baud", "115200"])
        .args(["--drop-rate", "0.003", "--link", &port, "--image"])
        .arg(&image)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    wait_for(&link, Duration::from_secs(10));
    let (ok, out) = station(&["stats", "--port", &port, "-s", "3", "--json"]);
    assert!(ok, "{out}");
    let stats: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(stats["stats"]["frames_in"].as_u64().unwrap() > 10, "{out}");
    let pid = world.id().to_string();
    Command::new("kill").args(["-INT", &pid]).status().unwrap();
    let mut rest = String::new();
    world
        .stdout
        .take()
        .unwrap()
        .read_to_string(&mut rest)
        .unwrap();
    assert!(world.wait().unwrap().success());
    let summary: serde_json::Value =
        serde_json::from_str(rest.lines().last().unwrap_or("")).unwrap();
    let relay = &summary["relay"];
    assert!(
        relay["from_robot_bytes"].as_u64().unwrap() > 1000,
        "{summary}"
    );
    let dropped =
        relay["to_robot_dropped"].as_u64().unwrap() + relay["from_robot_dropped"].as_u64().unwrap();
    assert!(dropped > 0, "the faults were applied: {summary}");
    assert!(summary["fault"].is_null(), "{summary}");
    let _ = std::fs::remove_dir_all(&dir);
}
