//! One station after another on the same emulator pty, as a user runs `station` commands in a
//! row. The robot keeps talking to a station that left until its link timeout (1.5 s), and
//! the pty keeps those bytes for the next station: seconds-old telemetry, or the refusal of
//! the last station's Hello. The next station must take none of it for its own session: not
//! as a clock that runs hundreds of times fast (heartbeats in a burst), not as a refusal of
//! frames it never signed.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::Path;
use std::process::ExitCode;
use std::time::Duration;

use clap::Parser;
use e2e_tests::procs::{emulator_in_process, scratch_dir};
use protocol::sign::{LinkAuth, LinkKey, STATION_LINK};
use protocol::{Hello, Message, FINGERPRINT, MAX_FRAME, PROTOCOL_VERSION};
use station::link::serial::SerialConnector;
use station::link::{spawn_link, Connection, LinkEvent, LinkOptions};

const KEY: &str = "6b1f0a2c9d8e7f60514233241506f7e8d9cabbac9d8e7f60514233241506f7e8";

/// A headless `station` command line, run as the binary runs it; the error is what it prints
/// before exiting 1.
async fn station(args: &[&str]) -> Result<ExitCode, String> {
    let cli =
        station::cli::Cli::try_parse_from(std::iter::once("station").chain(args.iter().copied()))
            .unwrap();
    station::headless::dispatch(cli)
        .await
        .map_err(|e| format!("{e:#}"))
}

/// A keyed station that gives up before the answer to its Hello arrives (as `station stats
/// --key-file` did, told the robot has no key by the unsigned telemetry left by a session
/// before): the robot's refusal of that signed Hello waits in the pty.
fn keyed_hello_left_unanswered(link: &Path) {
    let mut port = serialport::new(link.to_string_lossy(), 115_200)
        .timeout(Duration::from_millis(5))
        .open()
        .unwrap();
    let mut auth = LinkAuth::new(Some(LinkKey::from_hex(KEY).unwrap()), STATION_LINK);
    let hello = Message::Hello(Hello {
        fingerprint: FINGERPRINT,
        protocol: PROTOCOL_VERSION,
        session: 1,
        station: "keyed",
    });
    let mut buf = [0u8; MAX_FRAME];
    let n = auth.encode(0, &hello, 1 << 40, &mut buf).unwrap();
    port.write_all(&buf[..n]).unwrap();
    port.flush().unwrap();
    // The robot reads it and answers within a few ms; no one reads the answer.
    std::thread::sleep(Duration::from_millis(300));
}

#[tokio::test]
async fn a_refusal_left_for_a_keyed_station_is_not_the_next_stations() {
    let d = scratch_dir("after", "refusal");
    let link = d.join("robot");
    let port = link.display().to_string();
    let _emu = emulator_in_process(&link, &["--seed", "5"]);
    keyed_hello_left_unanswered(&link);
    // Without a key: the robot's refusal of signed frames is not about ours.
    assert_eq!(
        station(&["send", "--port", &port, "--timeout", "5", "stop"]).await,
        Ok(ExitCode::SUCCESS)
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[tokio::test]
async fn a_station_after_another_heartbeats_at_the_robots_pace() {
    let d = scratch_dir("after", "heartbeats");
    let link = d.join("robot");
    let port = link.display().to_string();
    let _emu = emulator_in_process(&link, &["--seed", "5"]);
    assert_eq!(
        station(&["send", "--port", &port, "stop"]).await,
        Ok(ExitCode::SUCCESS)
    );
    // The robot sends its telemetry into the pty for 1.5 s more; they wait there, older
    // every second.
    tokio::time::sleep(Duration::from_secs(3)).await;
    let mut running = spawn_link(SerialConnector::new(&link, 115_200), LinkOptions::default());
    let within = tokio::time::Instant::now() + Duration::from_secs(5);
    let s = loop {
        let ev = tokio::time::timeout_at(within, running.events.recv())
            .await
            .expect("two seconds of a session within 5 s")
            .unwrap();
        match ev {
            LinkEvent::Connection(Connection::Refused { message }) => panic!("{message}"),
            LinkEvent::Stats(s) if s.session_ms >= 2_000 => break s,
            _ => {}
        }
    };
    // A heartbeat every 250 ms of the robot's time (real time here): 8 in 2 s, and a Hello.
    // Timed by the backlog, the robot's clock looked hundreds of times fast and the station
    // sent one every 10 ms (about 150 in these 2 s).
    println!(
        "frames to the robot in a {} ms session: {}",
        s.session_ms, s.frames_out
    );
    assert!(
        s.frames_out <= 20,
        "{} frames in {} ms",
        s.frames_out,
        s.session_ms
    );
    running.handle.shutdown();
    let _ = std::fs::remove_dir_all(&d);
}
