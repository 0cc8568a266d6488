//! A keyed fleet under a man in the middle (PROTOCOL.md §13, binding). Two robots of one
//! emulator share one key; the test sits between the stations and the robots' ptys, holding
//! no key, and does what an attacker on the cables can: it forwards every byte, except that
//! the Stop a station sends to robot 2 goes onto robot 1's line, and robot 1's answers go to
//! both stations. Robot 1 is in a session of its own (`station stats`), exploring, so a Stop
//! that verified there would stop it and its Ack would reach robot 2's station.
//!
//! Signatures bound to their session and robot make the relay fail at both ends: robot 1
//! refuses the Stop (it was signed for robot 2's session) and keeps exploring, and `station
//! send` reports no ack and exits 1. Real binaries, real ptys.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command as Process, Stdio};
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use e2e_tests::procs::scratch_dir;
use e2e_tests::workspace_bin;
use emulator::pty::{Pty, ReadState};
use protocol::{Command, Feed, FrameDecoder, Message, Mode};

const KEY: &str = "6b1f0a2c9d8e7f60514233241506f7e8d9cabbac9d8e7f60514233241506f7e8";

/// What the man in the middle saw.
#[derive(Default)]
struct Seen {
    /// Stops from robot 2's station put onto robot 1's line.
    diverted: AtomicU32,
    /// HelloReplies robot 1 sent (each a session some station opened).
    robot_1_replies: AtomicU32,
    /// Robot 1's mode in its telemetry, with the time it was read.
    robot_1_modes: Mutex<Vec<(Instant, Mode)>>,
}

/// Splits a byte stream into whole frames (each with its 0x00 delimiter).
#[derive(Default)]
struct Frames {
    pending: Vec<u8>,
}

impl Frames {
    fn push(&mut self, bytes: &[u8]) -> Vec<Vec<u8>> {
        let mut out = Vec::new();
        for &b in bytes {
            self.pending.push(b);
            if b == 0 {
                out.push(std::mem::take(&mut self.pending));
            }
        }
        out
    }
}

/// The message of one whole frame, signature unchecked (the relay holds no key).
fn decoded<T>(frame: &[u8], f: impl FnOnce(&Message<'_>) -> T) -> Option<T> {
    let mut dec = FrameDecoder::new();
    match dec.feed(frame) {
        Feed::Frame { frame, .. } => Some(f(&frame.message)),
        _ => None,
    }
}

fn open_robot(path: &Path) -> Box<dyn serialport::SerialPort> {
    serialport::new(path.to_string_lossy(), 115_200)
        .timeout(Duration::from_millis(2))
        .open()
        .unwrap()
}

fn read_port(port: &mut dyn serialport::SerialPort, buf: &mut [u8]) -> usize {
    port.read(buf).unwrap_or(0)
}

fn read_pty(pty: &Pty, buf: &mut [u8]) -> usize {
    match pty.read(buf) {
        ReadState::Data(n) => n,
        _ => 0,
    }
}

/// Relays station 1 <-> robot 1 and station 2 <-> robot 2 until `stop`, moving station 2's
/// Stop commands onto robot 1's line and copying robot 1's Acks and Nacks to station 2.
fn relay(via: [Pty; 2], robots: [PathBuf; 2], seen: Arc<Seen>, stop: Arc<AtomicBool>) {
    let [via_1, via_2] = via;
    let mut robot_1 = open_robot(&robots[0]);
    let mut robot_2 = open_robot(&robots[1]);
    let (mut from_station_2, mut from_robot_1) = (Frames::default(), Frames::default());
    let mut buf = [0u8; 4096];
    while !stop.load(Ordering::Relaxed) {
        let n = read_pty(&via_1, &mut buf);
        robot_1.write_all(&buf[..n]).unwrap();
        let n = read_port(robot_2.as_mut(), &mut buf);
        via_2.write(&buf[..n]);

        let n = read_pty(&via_2, &mut buf);
        for frame in from_station_2.push(&buf[..n]) {
            let is_stop =
                decoded(&frame, |m| matches!(m, Message::Command(Command::Stop))) == Some(true);
            if is_stop {
                seen.diverted.fetch_add(1, Ordering::Relaxed);
                robot_1.write_all(&frame).unwrap();
            } else {
                robot_2.write_all(&frame).unwrap();
            }
        }
        let n = read_port(robot_1.as_mut(), &mut buf);
        for frame in from_robot_1.push(&buf[..n]) {
            via_1.write(&frame);
            let kind = decoded(&frame, |m| match m {
                Message::Ack(_) | Message::Nack(_) => Some(true),
                Message::HelloReply(_) => {
                    seen.robot_1_replies.fetch_add(1, Ordering::Relaxed);
                    None
                }
                Message::Telemetry(t) => {
                    seen.robot_1_modes
                        .lock()
                        .unwrap()
                        .push((Instant::now(), t.mode));
                    None
                }
                _ => None,
            });
            if kind.flatten() == Some(true) {
                via_2.write(&frame);
            }
        }
        via_1.wait_input(Duration::from_millis(1));
    }
}

fn station(args: &[&str]) -> Process {
    let mut p = Process::new(workspace_bin("station"));
    p.args(args).stdin(Stdio::null());
    p
}

fn wait_until(what: &str, within: Duration, mut done: impl FnMut() -> bool) {
    let end = Instant::now() + within;
    while !done() {
        assert!(Instant::now() < end, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn a_stop_for_robot_2_moved_onto_robot_1s_line_is_refused_and_not_acked() {
    let dir = scratch_dir("relay", "stop");
    let key = dir.join("fleet.key");
    std::fs::write(&key, format!("{KEY}\n")).unwrap();
    use std::os::unix::fs::PermissionsExt as _;
    std::fs::set_permissions(&key, std::fs::Permissions::from_mode(0o600)).unwrap();
    let key = key.display().to_string();
    let robots = [dir.join("robot1"), dir.join("robot2")];
    let mut emu = Process::new(workspace_bin("robot-emulator"))
        .args(["--robots", "2", "--seed", "3", "--key-file", &key, "--link"])
        .arg(dir.join("robot"))
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    wait_until("the fleet's ptys", Duration::from_secs(10), || {
        robots.iter().all(|r| r.exists())
    });
    let via_paths = [dir.join("via1"), dir.join("via2")];
    let via = [
        Pty::open(Some(&via_paths[0])).unwrap(),
        Pty::open(Some(&via_paths[1])).unwrap(),
    ];
    let seen = Arc::new(Seen::default());
    let stop = Arc::new(AtomicBool::new(false));
    let relay_thread = {
        let (seen, stop) = (seen.clone(), stop.clone());
        std::thread::spawn(move || relay(via, robots, seen, stop))
    };
    let via_1 = via_paths[0].display().to_string();
    let via_2 = via_paths[1].display().to_string();

    // Both robots explore; the relay passes everything but Stops through as it is.
    for via in [&via_1, &via_2] {
        let out = station(&["send", "--port", via, "--key-file", &key, "explore"])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "explore through {via}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    // Robot 1 in a session of its own for the rest of the test.
    let replies_before = seen.robot_1_replies.load(Ordering::Relaxed);
    let mut holder = station(&[
        "stats",
        "--port",
        &via_1,
        "--key-file",
        &key,
        "--seconds",
        "15",
    ])
    .stdout(Stdio::null())
    .stderr(Stdio::null())
    .spawn()
    .unwrap();
    wait_until(
        "robot 1's session with station stats",
        Duration::from_secs(10),
        || seen.robot_1_replies.load(Ordering::Relaxed) > replies_before,
    );

    let attack_at = Instant::now();
    let out = station(&["send", "--port", &via_2, "--key-file", &key, "stop"])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    // Robot 1's telemetry for a second more: still exploring, the Stop refused.
    std::thread::sleep(Duration::from_secs(1));
    stop.store(true, Ordering::Relaxed);
    relay_thread.join().unwrap();
    let _ = holder.kill();
    let _ = holder.wait();
    let _ = emu.kill();
    let _ = emu.wait();

    assert!(
        seen.diverted.load(Ordering::Relaxed) >= 1,
        "the relay never saw the Stop: {stdout} {stderr}"
    );
    assert!(
        !out.status.success(),
        "station send stop exited 0 on a relayed line: {stdout} {stderr}"
    );
    assert!(
        !stdout.contains("ack"),
        "robot 1's Ack was taken for robot 2's: {stdout}"
    );
    let modes = seen.robot_1_modes.lock().unwrap();
    let after: Vec<Mode> = modes
        .iter()
        .filter(|(t, _)| *t > attack_at)
        .map(|(_, m)| *m)
        .collect();
    assert!(
        !after.is_empty(),
        "no telemetry from robot 1 after the Stop"
    );
    assert!(
        after.iter().all(|m| *m == Mode::Explore),
        "robot 1 obeyed robot 2's Stop: modes after it {after:?}"
    );
}
