//! The live ALICE (seed 001) in the emulator's `Sim`: the firmware's ALICE composition with the
//! scenarios' whisker and photoresistor models (`sensors::alice`) in `builtin:alice`. Over its
//! serial port it sends a situation (kind 16) three times a second built from what its sensors
//! and odometry gave it; wandering, it touches walls and turns away, and sees the lamps; the
//! same seed gives the same bytes.
#![allow(clippy::unwrap_used, clippy::panic)]

use emulator::builtin::alice::alice;
use emulator::sim::{Sim, SimConfig};
use protocol::{
    encode, AliceSituation, Command, Feed, FrameDecoder, Hello, Message, Mode, FINGERPRINT,
    MAX_FRAME, PROTOCOL_VERSION,
};
use robot_firmware::ALICE;

fn frame(seq: u16, m: &Message<'_>) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME];
    let n = encode(seq, m, &mut buf).unwrap();
    buf[..n].to_vec()
}

/// `secs` seconds of ALICE wandering from power-up; every byte it sent, and the sim.
fn wander(seed: u64, secs: u64) -> (Vec<u8>, Sim) {
    let cfg = SimConfig {
        seed,
        ..SimConfig::new(&ALICE)
    };
    let mut sim = Sim::new(alice(), cfg).unwrap();
    let hello = Message::Hello(Hello {
        fingerprint: FINGERPRINT,
        protocol: PROTOCOL_VERSION,
        session: 1,
        station: "test",
    });
    sim.uart_mut().push_inbound(&frame(0, &hello));
    sim.run_for(100);
    sim.uart_mut()
        .push_inbound(&frame(1, &Message::Command(Command::SetMode(Mode::Wander))));
    let mut wire = Vec::new();
    for s in 0..secs * 5 {
        // Heartbeats keep the link up (the station's would).
        let hb = Message::Heartbeat(protocol::Heartbeat { time_ms: 0 });
        sim.uart_mut().push_inbound(&frame(2 + s as u16, &hb));
        sim.run_for(200);
        wire.extend(sim.uart_mut().take_outbound());
    }
    (wire, sim)
}

fn situations(bytes: &[u8]) -> Vec<AliceSituation> {
    let mut dec = FrameDecoder::new();
    let mut out = Vec::new();
    let mut input = bytes;
    loop {
        match dec.feed(input) {
            Feed::Frame { frame, rest } => {
                if let Message::AliceSituation(s) = frame.message {
                    out.push(s);
                }
                input = rest;
            }
            Feed::Error { rest, .. } => input = rest,
            Feed::NeedMore => break,
        }
    }
    out
}

#[test]
fn a_wandering_alice_sends_its_situations_at_3_hz_touching_walls_and_seeing_lamps() {
    let secs = 120;
    let (wire, sim) = wander(3, secs);
    let s = situations(&wire);
    let rate = s.len() as f64 / secs as f64;
    let touching = s.iter().filter(|s| s.whiskers != 0).count();
    eprintln!(
        "{} situations, {touching} touching, {:.1} m, {} contacts",
        s.len(),
        sim.distance_m(),
        sim.collisions()
    );
    assert!(
        (2.9..=3.05).contains(&rate),
        "{} situations in {secs} s",
        s.len()
    );
    for w in s.windows(2) {
        assert_eq!(
            w[1].seq,
            w[0].seq.wrapping_add(1),
            "none lost at 115200 baud"
        );
    }
    assert!(
        touching > 5,
        "{touching} situations with a whisker touching"
    );
    assert!(touching < s.len() / 2, "{touching} of {} touching", s.len());
    let lit = s.iter().filter(|s| s.light.iter().any(|&l| l > 50)).count();
    assert!(lit > s.len() / 2, "{lit} of {} see a lamp", s.len());
    // It covers the arena: 25 cm/s for most of the time.
    assert!(sim.distance_m() > 10.0, "{} m", sim.distance_m());
    // The whiskers touch before the body does (17 cm reach): few wall contacts.
    assert!(sim.collisions() < 10, "{} contacts", sim.collisions());
    // The odometry in the situations is the robot's belief.
    let last = s.last().unwrap();
    let b = sim.believed();
    assert!((f64::from(last.odometry.x_mm) / 1000.0 - b.x).abs() < 0.15);
}

#[test]
fn the_same_seed_gives_the_same_situations_and_another_seed_others() {
    let (a, _) = wander(7, 20);
    let (b, _) = wander(7, 20);
    assert_eq!(a, b, "same seed, same bytes");
    let (c, _) = wander(8, 20);
    assert_ne!(situations(&a), situations(&c));
}
