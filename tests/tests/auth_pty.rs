//! Link authentication end to end (PROTOCOL.md §13): the emulator started from its command
//! line with `--key-file` on a real pty, and the station's headless `send` with and without
//! `--key-file`, run through the same parse-and-dispatch as the `station` binary. The right
//! key drives the robot; another key, no key, or a key the robot lacks ends in a clear
//! "link authentication failed" error (the binary's exit status 1), not a timeout.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use clap::Parser;
use e2e_tests::TestStation;
use emulator::link::{spawn_device, RunningEmulator};
use protocol::Command;
use station::link::serial::SerialConnector;
use station::link::{spawn_link, Connection, LinkEvent, LinkOptions};

const KEY: &str = "6b1f0a2c9d8e7f60514233241506f7e8d9cabbac9d8e7f60514233241506f7e8";
const OTHER: &str = "00112233445566778899aabbccddeeff00112233445566778899aabbccddeeff";

/// A private directory for one test's pty link and key files.
fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("auth-e2e-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn key_file(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, format!("{text}\n")).unwrap();
    // A key group or others may read is refused (as ssh refuses such a private key).
    use std::os::unix::fs::PermissionsExt as _;
    std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o600)).unwrap();
    p
}

/// The emulator as `robot-emulator --link PATH [--key-file KEY]` starts it.
fn emulator(link: &Path, key: Option<&Path>) -> RunningEmulator {
    let mut args = vec![
        "robot-emulator".to_string(),
        "--link".into(),
        link.display().to_string(),
        "--seed".into(),
        "5".into(),
    ];
    if let Some(k) = key {
        args.extend(["--key-file".into(), k.display().to_string()]);
    }
    let cli = emulator::cli::Cli::try_parse_from(&args).unwrap();
    let opts = cli.serve.options().unwrap();
    let arena = emulator::builtin::load(&opts.arena, &opts.load).unwrap();
    let sim = emulator::sim::Sim::new(arena, opts.sim.clone()).unwrap();
    spawn_device(move || Ok(sim), opts.serve).unwrap()
}

/// `station send --port LINK [--key-file KEY] --timeout 5 stop`, as the binary runs it: the
/// error is what it prints before exiting 1.
async fn station_send(link: &Path, key: Option<&Path>) -> Result<ExitCode, String> {
    let mut args = vec![
        "station".to_string(),
        "send".into(),
        "--port".into(),
        link.display().to_string(),
        "--timeout".into(),
        "5".into(),
    ];
    if let Some(k) = key {
        args.extend(["--key-file".into(), k.display().to_string()]);
    }
    args.push("stop".into());
    let cli = station::cli::Cli::try_parse_from(&args).unwrap();
    station::headless::dispatch(cli)
        .await
        .map_err(|e| format!("{e:#}"))
}

#[tokio::test]
async fn the_right_key_drives_the_robot_and_every_frame_verifies() {
    let d = dir("right");
    let link = d.join("robot");
    let key = key_file(&d, "robot.key", KEY);
    let _emu = emulator(&link, Some(&key));
    assert_eq!(station_send(&link, Some(&key)).await, Ok(ExitCode::SUCCESS));

    // The station's link task with the key drives the robot (teleop, seen moving in the
    // emulator's signed EmuTruth), and nothing is refused.
    let opts = LinkOptions {
        key: station::commands::args::load_key(Some(&key)).unwrap(),
        ..LinkOptions::default()
    };
    let mut running = spawn_link(SerialConnector::new(&link, 115_200), opts);
    let end = tokio::time::Instant::now() + Duration::from_secs(5);
    loop {
        let ev = tokio::time::timeout_at(end, running.events.recv())
            .await
            .expect("a handshake within 5 s")
            .unwrap();
        match ev {
            LinkEvent::Connection(Connection::Connected(_)) => break,
            LinkEvent::Connection(Connection::Refused { message }) => panic!("{message}"),
            _ => {}
        }
    }
    for _ in 0..10 {
        let teleop = Command::Teleop {
            v_mm_s: 200,
            w_mrad_s: 0,
        };
        assert!(running.handle.call(teleop).await.is_ack());
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    assert!(running.handle.call(Command::Stop).await.is_ack());
    let (mut first, mut last, mut stats) = (None, None, None);
    while let Ok(ev) = running.events.try_recv() {
        match ev {
            LinkEvent::Truth(t) => {
                first = first.or(Some(t.pose));
                last = Some(t.pose);
            }
            LinkEvent::Stats(s) => stats = Some(s),
            _ => {}
        }
    }
    let (a, b) = (first.expect("signed EmuTruth frames"), last.unwrap());
    let moved = f64::from(b.x_mm - a.x_mm).hypot(f64::from(b.y_mm - a.y_mm));
    assert!(moved > 80.0, "the robot moved {moved} mm");
    let s = stats.expect("statistics");
    println!("keyed link: moved {moved:.0} mm; auth counts {:?}", s.auth);
    assert!(s.auth.keyed);
    assert!(s.auth.verified > 10, "{:?}", s.auth);
    assert_eq!(s.auth.refused(), 0, "{:?}", s.auth);
    running.handle.shutdown();
    let _ = std::fs::remove_dir_all(&d);
}

#[tokio::test]
async fn another_key_fails_with_a_clear_error() {
    let d = dir("wrong");
    let link = d.join("robot");
    let _emu = emulator(&link, Some(&key_file(&d, "robot.key", KEY)));
    let err = station_send(&link, Some(&key_file(&d, "other.key", OTHER)))
        .await
        .unwrap_err();
    println!("station: {err}");
    assert!(err.contains("link authentication failed"), "{err}");
    assert!(err.contains("another key"), "{err}");
    assert!(err.contains("check --key-file"), "{err}");
    let _ = std::fs::remove_dir_all(&d);
}

#[tokio::test]
async fn no_key_against_a_keyed_robot_fails_clearly() {
    let d = dir("nokey");
    let link = d.join("robot");
    let _emu = emulator(&link, Some(&key_file(&d, "robot.key", KEY)));
    let err = station_send(&link, None).await.unwrap_err();
    println!("station: {err}");
    assert!(err.contains("link authentication failed"), "{err}");
    assert!(err.contains("this station has no key"), "{err}");
    let _ = std::fs::remove_dir_all(&d);
}

#[tokio::test]
async fn a_key_against_a_robot_without_one_fails_clearly() {
    let d = dir("robotnokey");
    let link = d.join("robot");
    let _emu = emulator(&link, None);
    let err = station_send(&link, Some(&key_file(&d, "robot.key", KEY)))
        .await
        .unwrap_err();
    println!("station: {err}");
    assert!(err.contains("link authentication failed"), "{err}");
    assert!(err.contains("the robot does not sign"), "{err}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn an_unsigned_station_gets_no_session_from_a_keyed_robot() {
    let d = dir("raw");
    let link = d.join("robot");
    let _emu = emulator(&link, Some(&key_file(&d, "robot.key", KEY)));
    let mut raw = TestStation::open(&link, 115_200).unwrap();
    assert_eq!(raw.handshake(Duration::from_millis(1500)), None);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn bad_key_files_are_refused_naming_the_file_and_the_fault() {
    let d = dir("badfile");
    let short = key_file(&d, "short.key", "abc123");
    let nothex = key_file(&d, "nothex.key", &format!("{}zz", &KEY[..62]));
    let missing = d.join("missing.key");
    let emu = |k: &Path| {
        let args = ["robot-emulator", "--key-file", &k.display().to_string()].map(String::from);
        emulator::cli::Cli::try_parse_from(&args)
            .unwrap()
            .serve
            .options()
            .map(|_| ())
            .unwrap_err()
    };
    let e = emu(&short);
    assert!(
        e.contains("short.key") && e.contains("64 hex digits"),
        "{e}"
    );
    let e = emu(&nothex);
    assert!(
        e.contains("nothex.key") && e.contains("character 63"),
        "{e}"
    );
    let e = emu(&missing);
    assert!(
        e.contains("missing.key") && e.contains("cannot read"),
        "{e}"
    );
    let e = station::commands::args::load_key(Some(&short)).unwrap_err();
    assert!(e.contains("--key-file") && e.contains("short.key"), "{e}");
    // A good key that others may read: refused by both, with the mode and the fix.
    let open = key_file(&d, "open.key", KEY);
    use std::os::unix::fs::PermissionsExt as _;
    std::fs::set_permissions(&open, std::fs::Permissions::from_mode(0o644)).unwrap();
    let fix = format!("chmod 600 {}", open.display());
    let e = emu(&open);
    assert!(e.contains("(mode 0644)") && e.contains(&fix), "{e}");
    let e = station::commands::args::load_key(Some(&open)).unwrap_err();
    assert!(e.contains("--key-file") && e.contains(&fix), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn the_station_binary_exits_1_with_the_message_on_a_wrong_key() {
    let d = dir("binary");
    let link = d.join("robot");
    let _emu = emulator(&link, Some(&key_file(&d, "robot.key", KEY)));
    let run = |key: &Path| {
        std::process::Command::new(e2e_tests::workspace_bin("station"))
            .arg("send")
            .arg("--port")
            .arg(&link)
            .arg("--key-file")
            .arg(key)
            .arg("stop")
            .output()
            .expect("the station binary runs")
    };
    let out = run(&key_file(&d, "other.key", OTHER));
    let stderr = String::from_utf8_lossy(&out.stderr);
    println!("{stderr}");
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("link authentication failed"), "{stderr}");
    let out = run(&d.join("robot.key"));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// `station record --key-file K` without --port gives the built-in emulator the same key: the
/// keyed station would get no session from an unkeyed robot ("a key against a robot without
/// one"), so a connected recording shows both ends signed with K.
#[test]
fn the_built_in_emulator_shares_the_stations_key() {
    let d = dir("builtin");
    let out_file = d.join("keyed.rec");
    let out = std::process::Command::new(e2e_tests::workspace_bin("station"))
        .arg("record")
        .arg("--key-file")
        .arg(key_file(&d, "robot.key", KEY))
        .arg("--out")
        .arg(&out_file)
        .args(["--seconds", "2", "--json"])
        .output()
        .expect("the station binary runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("\"connected\": true"), "{stdout}");
    assert!(!stdout.contains("\"bytes_from_robot\": 0,"), "{stdout}");
    let _ = std::fs::remove_dir_all(&d);
}
