//! Issue 15: where a command's round trip goes with telemetry on the line, in simulated time.
//! A handshaken robot sends telemetry at 50 Hz (and the emulator a truth frame after each);
//! Stop commands come at pseudo-random moments 20-60 ms apart, as
//! `tests/tools/min_client_rtt.py` sends them. A Stop finding the line free is answered in
//! its own and its Ack's bytes' time (the robot acts on it the moment its last bit arrives);
//! one finding a frame on the line waits for it. docs/performance.md's "minimal client" row cites the
//! share. Simulated time only: the wall-clock figure is the client's benchmark.
#![allow(clippy::unwrap_used, clippy::panic)]

use emulator::link::Device;
use emulator::sim::{Sim, SimConfig};
use protocol::{
    encode, Ack, AckInfo, Command, Feed, FrameDecoder, Hello, Message, FINGERPRINT, MAX_FRAME,
    PROTOCOL_VERSION,
};

/// For each Stop: its round trip (µs, from its first bit to its Ack's last) and the time of
/// the two frames' bytes.
fn round_trips(hz: u8, commands: u16) -> Vec<(f64, f64)> {
    let arena = emulator::builtin::micro_rato_99(&emulator::arena::LoadOptions::default()).unwrap();
    let cfg = SimConfig::new(&robot_firmware::MICRO_RATO);
    let byte_us = 10.0 * 1e6 / f64::from(cfg.baud);
    let mut sim = Sim::new(arena, cfg).unwrap();
    let mut buf = [0u8; MAX_FRAME];
    let hello = Hello {
        fingerprint: FINGERPRINT,
        protocol: PROTOCOL_VERSION,
        session: 7,
        station: "busy-line",
    };
    let n = encode(0, &Message::Hello(hello), &mut buf).unwrap();
    Device::push_inbound_at(&mut sim, &buf[..n], 0);
    sim.run_for(50);
    let rate = Message::Command(Command::SetTelemetryRate { hz });
    let n = encode(1, &rate, &mut buf).unwrap();
    let now = sim.now_us();
    Device::push_inbound_at(&mut sim, &buf[..n], now);
    sim.run_for(300);
    let mut out = Vec::new();
    Device::take_outbound_until(&mut sim, u64::MAX, &mut out);
    let mut decoder = FrameDecoder::new();
    let _ = decoder.feed(&out);
    let mut lcg: u64 = 0x5EED_0015;
    let mut trips = Vec::new();
    for seq in 2..2 + commands {
        lcg = lcg
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        let at = sim.now_us() + 20_000 + (lcg >> 33) % 40_000;
        while sim.now_us() <= at {
            sim.step();
        }
        let n = encode(seq, &Message::Command(Command::Stop), &mut buf).unwrap();
        Device::push_inbound_at(&mut sim, &buf[..n], at);
        let ack = Message::Ack(Ack {
            cmd_seq: seq,
            info: AckInfo::Done,
        });
        let ack_len = encode(0, &ack, &mut [0u8; MAX_FRAME]).unwrap();
        let mut answered = None;
        let mut t = at;
        while answered.is_none() {
            // Look when the next frame towards the station ends, as the serving loop does.
            t = Device::next_frame_end_us(&sim)
                .unwrap_or(t + 1000)
                .max(t + 1);
            while sim.now_us() <= t {
                sim.step();
            }
            out.clear();
            Device::take_outbound_until(&mut sim, t, &mut out);
            let mut rest = &out[..];
            loop {
                match decoder.feed(rest) {
                    Feed::Frame { frame, rest: r } => {
                        if let Message::Ack(a) = frame.message {
                            if a.cmd_seq == seq {
                                answered = Some(t);
                            }
                        }
                        rest = r;
                    }
                    Feed::Error { rest: r, .. } => rest = r,
                    Feed::NeedMore => break,
                }
            }
            assert!(t < at + 100_000, "no answer to Stop {seq}");
        }
        let took = (answered.unwrap() - at) as f64;
        trips.push((took, (n + ack_len) as f64 * byte_us));
    }
    trips
}

#[test]
fn at_50_hz_a_stop_finding_the_line_free_is_answered_in_its_bytes_time() {
    let trips = round_trips(50, 400);
    // Each frame starts at a whole bit of the line's clock: up to a bit each.
    let bit_us = 1e6 / 115_200.0;
    let free = trips
        .iter()
        .filter(|&&(took, wire)| took <= wire + 2.0 * bit_us + 2.0)
        .count();
    let mut sorted: Vec<f64> = trips.iter().map(|t| t.0).collect();
    sorted.sort_by(f64::total_cmp);
    let q = |f: f64| sorted[((sorted.len() - 1) as f64 * f).round() as usize] / 1000.0;
    println!(
        "50 Hz, 400 Stops: {free} answered in their bytes' time; p50 {:.2} ms, p90 {:.2} ms, \
         p99 {:.2} ms, max {:.2} ms",
        q(0.5),
        q(0.9),
        q(0.99),
        q(1.0)
    );
    for &(took, wire) in &trips {
        assert!(
            took >= wire - 1.0,
            "{took} us: faster than its bytes ({wire:.0} us)"
        );
        // The longest wait: a telemetry frame (at most 80 bytes) and its truth frame just
        // begun, about 9 ms of line.
        assert!(
            took <= wire + 9_500.0,
            "{took} us for {wire:.0} us of bytes"
        );
    }
    // The robot's telemetry and the emulator's truth frame after it fill 7-8.5 ms of every
    // 20 ms at 50 Hz, and a Stop's Ack must wait for any frame begun before the Stop (0.95 ms
    // of bytes) is complete: 40-50 % of Stops at random moments find the line busy (46 % with
    // this seed), the rest are answered in their bytes' time.
    assert!(
        (trips.len() * 50 / 100..=trips.len() * 70 / 100).contains(&free),
        "{free} of {} answered in their bytes' time",
        trips.len()
    );
}
