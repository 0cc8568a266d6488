//! The simulated serial line: a handshaken session at 50 Hz telemetry never carries more than
//! baud/10 bytes per simulated second, every Telemetry frame is followed by an `EmuTruth`
//! frame with the same time and the true pose of that time, and the robot says it is emulated.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::collections::HashMap;
use std::path::PathBuf;

use emulator::arena::{Arena, ArenaFormat, Pose};
use emulator::geometry::{Aabb, Point};
use emulator::sim::{Sim, SimConfig};
use protocol::{
    caps, encode, Command, Feed, FrameDecoder, Heartbeat, Hello, Message, Mode, FINGERPRINT,
    MAX_FRAME, PROTOCOL_VERSION,
};
use robot_firmware::KHEPERA;

fn open_box() -> Arena {
    Arena {
        name: "box".into(),
        source: PathBuf::from("test"),
        format: ArenaFormat::AsciiGrid,
        bounds: Aabb::from_corners(Point::new(0.0, 0.0), Point::new(0.8, 0.6)),
        enclosed: true,
        walls: Vec::new(),
        raster: None,
        beacons: Vec::new(),
        targets: Vec::new(),
        lights: Vec::new(),
        starts: Vec::new(),
        goal: None,
        unit_m: 0.01,
        warnings: Vec::new(),
    }
}

struct Station {
    seq: u16,
    decoder: FrameDecoder,
}

impl Station {
    fn send(&mut self, sim: &mut Sim, msg: &Message<'_>) {
        let mut buf = [0u8; MAX_FRAME];
        let n = encode(self.seq, msg, &mut buf).unwrap();
        self.seq = self.seq.wrapping_add(1);
        assert_eq!(sim.uart_mut().push_inbound(&buf[..n]), n);
    }
}

/// What the station saw, frame by frame, in order.
#[derive(Debug, PartialEq)]
enum Seen {
    Telemetry(u32),
    Truth {
        time_ms: u32,
        x_mm: i32,
        y_mm: i32,
        collisions: u32,
    },
    HelloReply {
        caps: u32,
    },
    Other,
}

/// True position in millimetres by simulated millisecond.
type TruthMm = HashMap<u32, (i32, i32)>;

/// Runs a 10 s session at `baud` and returns the bytes per simulated second, the frames seen
/// and the true position (mm) at every millisecond.
fn session(baud: u32) -> (Vec<usize>, Vec<Seen>, TruthMm) {
    let cfg = SimConfig {
        seed: 4,
        baud,
        start: Some(Pose {
            x: 0.2,
            y: 0.3,
            heading: 0.2,
        }),
        ..SimConfig::new(&KHEPERA)
    };
    let mut sim = Sim::new(open_box(), cfg).unwrap();
    let mut st = Station {
        seq: 0,
        decoder: FrameDecoder::new(),
    };
    let hello = Hello {
        fingerprint: FINGERPRINT,
        protocol: PROTOCOL_VERSION,
        session: 77,
        station: "uart-test",
    };
    st.send(&mut sim, &Message::Hello(hello));
    st.send(
        &mut sim,
        &Message::Command(Command::SetTelemetryRate { hz: 50 }),
    );
    st.send(&mut sim, &Message::Command(Command::SetMode(Mode::Wander)));
    let mut per_second = Vec::new();
    let mut seen = Vec::new();
    let mut truth = HashMap::new();
    for second in 0..10u32 {
        let mut bytes = 0;
        for ms in 0..1000u32 {
            if ms % 250 == 0 {
                let hb = Heartbeat {
                    time_ms: second * 1000 + ms,
                };
                st.send(&mut sim, &Message::Heartbeat(hb));
            }
            sim.step();
            let t = sim.truth();
            let now_ms = (sim.now_us() / 1000) as u32;
            truth.insert(
                now_ms,
                ((t.x * 1000.0).round() as i32, (t.y * 1000.0).round() as i32),
            );
            let out = sim.uart_mut().take_outbound();
            bytes += out.len();
            let mut input: &[u8] = &out;
            loop {
                match st.decoder.feed(input) {
                    Feed::NeedMore => break,
                    Feed::Error { error, .. } => panic!("bad frame on the wire: {error}"),
                    Feed::Frame { frame, rest } => {
                        seen.push(match frame.message {
                            Message::Telemetry(t) => Seen::Telemetry(t.time_ms),
                            Message::EmuTruth(e) => Seen::Truth {
                                time_ms: e.time_ms,
                                x_mm: e.pose.x_mm,
                                y_mm: e.pose.y_mm,
                                collisions: e.collisions,
                            },
                            Message::HelloReply(r) => Seen::HelloReply {
                                caps: r.capabilities,
                            },
                            _ => Seen::Other,
                        });
                        input = rest;
                    }
                }
            }
        }
        per_second.push(bytes);
    }
    assert!(sim.robot().link().connected(), "the session stayed up");
    (per_second, seen, truth)
}

fn check_session(baud: u32) -> (usize, usize) {
    let (per_second, seen, truth) = session(baud);
    let budget = baud as usize / 10;
    for (s, &b) in per_second.iter().enumerate() {
        // A byte straddling the second boundary may count in the earlier second.
        assert!(b <= budget + 1, "second {s}: {b} bytes > {budget}");
    }
    assert!(per_second.iter().sum::<usize>() <= budget * 10);
    assert!(matches!(seen.first(), Some(Seen::HelloReply { caps: c }) if c & caps::EMULATED != 0));
    // Each truth frame is about a telemetry frame sent before it: the oldest still owed, or a
    // later one when the emulator dropped older truth the robot's bytes left no room for.
    // Robot frames may come between a telemetry frame and its truth (truth waits for them).
    let mut owed = std::collections::VecDeque::new();
    let (mut telemetry, mut truths) = (0, 0);
    for frame in &seen {
        match frame {
            Seen::Telemetry(t) => {
                telemetry += 1;
                owed.push_back(*t);
            }
            Seen::Truth {
                time_ms,
                x_mm,
                y_mm,
                collisions,
            } => {
                truths += 1;
                while owed.front().is_some_and(|t| t != time_ms) {
                    owed.pop_front();
                }
                assert_eq!(owed.pop_front(), Some(*time_ms), "truth for no telemetry");
                assert_eq!(truth.get(time_ms), Some(&(*x_mm, *y_mm)));
                assert_eq!(*collisions, 0);
            }
            _ => {}
        }
    }
    println!("{baud} baud: {truths} truth frames for {telemetry} telemetry frames");
    assert!(truths <= telemetry);
    if baud >= 115_200 {
        // A line a third busy leaves room for every truth frame (the last may be in flight).
        assert!(truths + 2 >= telemetry, "{truths} of {telemetry}");
    }
    (telemetry, per_second.iter().sum())
}

#[test]
fn at_115200_baud_50_hz_telemetry_flows_with_truth_frames_within_the_budget() {
    let (telemetry, bytes) = check_session(115_200);
    // 50 Hz for ~10 s: nearly every frame is sent at this rate.
    assert!(telemetry >= 480, "{telemetry}");
    println!("115200 baud: {telemetry} telemetry frames, {bytes} bytes in 10 s");
}

#[test]
fn at_9600_baud_the_line_saturates_but_never_exceeds_baud_over_ten() {
    let (telemetry, bytes) = check_session(9600);
    // The firmware skips telemetry it cannot send; the line runs close to full, with the
    // robot's own bytes: truth, which a real robot does not send, only gets what they leave.
    assert!(telemetry < 480, "{telemetry}");
    assert!(bytes > 9600 * 10 / 10 * 8 / 10, "{bytes}");
    // ... but it gets some: a robot filling the line does not starve truth for good.
    let (_, seen, _) = session(9600);
    let truths = seen
        .iter()
        .filter(|f| matches!(f, Seen::Truth { .. }))
        .count();
    assert!(
        truths * 4 >= telemetry,
        "{truths} truth frames for {telemetry} telemetry"
    );
    println!("9600 baud: {telemetry} telemetry frames, {bytes} bytes in 10 s");
}
