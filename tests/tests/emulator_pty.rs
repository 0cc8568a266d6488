//! The emulator over a real pseudo-terminal: handshake, telemetry at the configured rate, the
//! baud rate honoured, teleop moving the simulated robot, and reopening the port.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::time::Duration;

use e2e_tests::{Received, TestStation};
use emulator::link::{spawn, EmulatorOptions};
use protocol::{caps, Command, Heartbeat, Message};

fn start(baud: u32) -> emulator::link::RunningEmulator {
    let mut opts = EmulatorOptions::builtin_default();
    opts.sim.baud = baud;
    opts.sim.seed = 4;
    spawn(opts).expect("emulator starts")
}

#[test]
fn handshake_then_telemetry_at_the_configured_rate_within_the_baud_rate() {
    let baud = 115_200;
    let mut emu = start(baud);
    let mut st = TestStation::open(emu.path(), baud).unwrap();
    let caps_seen = st.handshake(Duration::from_secs(3)).expect("handshake");
    assert!(
        caps_seen & caps::EMULATED != 0,
        "the emulator says it is one"
    );
    assert!(caps_seen & caps::COMPASS != 0, "micro-rato profile");
    st.command(Command::SetTelemetryRate { hz: 50 }).unwrap();
    st.collect(Duration::from_millis(300));
    let before = st.bytes_in;
    let mut telemetry = 0;
    let mut truth = 0;
    // Rates over the time the loop really took: on a loaded machine eight 250 ms windows
    // plus the sends take longer than 2 s, and more frames arrive in them.
    let started = std::time::Instant::now();
    for _ in 0..8 {
        st.send(&Message::Heartbeat(Heartbeat { time_ms: 0 }))
            .unwrap();
        for (_, r) in st.collect(Duration::from_millis(250)) {
            match r {
                Received::Telemetry(_) => telemetry += 1,
                Received::Truth(_) => truth += 1,
                _ => {}
            }
        }
    }
    let secs = started.elapsed().as_secs_f64();
    let bytes_per_s = (st.bytes_in - before) as f64 / secs;
    let hz = f64::from(telemetry) / secs;
    println!(
        "{secs:.2} s at 50 Hz: {telemetry} telemetry ({hz:.1} Hz), {truth} truth frames, {bytes_per_s:.0} B/s"
    );
    assert!(
        (42.5..=52.5).contains(&hz),
        "{telemetry} telemetry frames in {secs:.2} s: {hz:.1} Hz at 50 Hz"
    );
    assert!(truth >= telemetry - 2, "EmuTruth follows telemetry");
    assert!(
        bytes_per_s <= f64::from(baud) / 10.0,
        "{bytes_per_s} B/s over {baud} baud"
    );
    assert_eq!(st.decoder_stats().bad_crc, 0);
}

#[test]
fn a_slow_baud_rate_throttles_the_link() {
    // 9600 baud carries 960 B/s: 50 Hz telemetry (~74 B) plus truth frames cannot all fit.
    let baud = 9600;
    let mut emu = start(baud);
    let mut st = TestStation::open(emu.path(), baud).unwrap();
    st.handshake(Duration::from_secs(3)).expect("handshake");
    st.command(Command::SetTelemetryRate { hz: 50 }).unwrap();
    st.collect(Duration::from_millis(300));
    let before = st.bytes_in;
    let t0 = std::time::Instant::now();
    for _ in 0..16 {
        st.send(&Message::Heartbeat(Heartbeat { time_ms: 0 }))
            .unwrap();
        st.collect(Duration::from_millis(250));
    }
    let secs = t0.elapsed().as_secs_f64();
    let bytes = (st.bytes_in - before) as f64;
    println!(
        "9600 baud: {bytes} bytes in {secs:.3} s = {:.0} B/s",
        bytes / secs
    );
    // The UART sends at most 960 B/s; what sat in the pty buffer when the window opened
    // (at most one 256-byte frame plus the 64-byte FIFO) may arrive inside it.
    assert!(
        bytes <= 960.0 * secs + 320.0,
        "{bytes} bytes in {secs} s over 9600 baud"
    );
    assert!(bytes / secs > 600.0, "the link is used");
}

#[test]
fn teleop_moves_the_simulated_robot_and_truth_shows_it() {
    let mut emu = start(115_200);
    let mut st = TestStation::open(emu.path(), 115_200).unwrap();
    st.handshake(Duration::from_secs(3)).expect("handshake");
    let first_truth = |frames: &[(std::time::Instant, Received)]| {
        frames.iter().rev().find_map(|(_, r)| match r {
            Received::Truth(t) => Some(t.pose),
            _ => None,
        })
    };
    let before = first_truth(&st.collect(Duration::from_millis(300))).expect("truth frames");
    let mut acked = false;
    for _ in 0..10 {
        let s = st
            .command(Command::Teleop {
                v_mm_s: 200,
                w_mrad_s: 0,
            })
            .unwrap();
        for (_, r) in st.collect(Duration::from_millis(100)) {
            acked |= r == Received::Ack { cmd_seq: s };
        }
    }
    assert!(acked, "teleop acknowledged");
    let after = first_truth(&st.collect(Duration::from_millis(100))).expect("truth frames");
    let moved = f64::from(after.x_mm - before.x_mm).hypot(f64::from(after.y_mm - before.y_mm));
    println!("moved {moved} mm in ~1 s of teleop at 200 mm/s");
    assert!(moved > 80.0, "the robot moved {moved} mm");
}

#[test]
fn the_station_can_close_and_reopen_the_port() {
    let mut emu = start(115_200);
    let path = emu.path().to_path_buf();
    for round in 0..3 {
        let mut st = TestStation::open(&path, 115_200).unwrap();
        st.handshake(Duration::from_secs(3))
            .unwrap_or_else(|| panic!("handshake on round {round}"));
        let frames = st.collect(Duration::from_millis(300));
        assert!(frames
            .iter()
            .any(|(_, r)| matches!(r, Received::Telemetry(_))));
        drop(st);
        std::thread::sleep(Duration::from_millis(100));
    }
}

/// A 1 MiB burst from the station once queued whole in front of the robot's UART and drained
/// at the baud rate, so the emulator stopped answering for 91 s. Its serial port now holds
/// what a real one holds (a 4 KB line buffer, clear in 0.36 s of line time) and the rest is
/// dropped and counted: that count is the verdict. The robot then answers a Hello and a Stop;
/// the wait for them is bounded (10 s) only so that a failure ends, and the time it took is
/// printed, not judged (wall time on a loaded machine).
#[test]
fn a_one_mebibyte_burst_is_dropped_beyond_the_ports_buffer_and_the_robot_answers_after_it() {
    let baud = 115_200;
    let mut emu = start(baud);
    let mut st = TestStation::open(emu.path(), baud).unwrap();
    st.handshake(Duration::from_secs(3)).expect("handshake");
    // Garbage without a frame delimiter: one undecodable frame as long as the burst.
    let burst = vec![0x55u8; 1 << 20];
    let written = st.write_raw(&burst, Duration::from_secs(20));
    assert_eq!(written, burst.len(), "the pty took the burst");
    let t0 = std::time::Instant::now();
    st.handshake(Duration::from_secs(10))
        .expect("the robot answers a Hello soon after the burst");
    let answered_s = t0.elapsed().as_secs_f64();
    let seq = st.command(Command::Stop).unwrap();
    let acked = st
        .collect(Duration::from_secs(2))
        .iter()
        .any(|(_, r)| *r == Received::Ack { cmd_seq: seq });
    assert!(acked, "the Stop after the burst is answered");
    println!("Hello answered {answered_s:.2} s after a 1 MiB burst");
    let stats = emu.stop().expect("the loop ran").expect("no pty error");
    assert!(
        stats.bytes_to_robot_dropped >= (1 << 20) - 8192,
        "dropped {} of the burst's bytes",
        stats.bytes_to_robot_dropped
    );
}
