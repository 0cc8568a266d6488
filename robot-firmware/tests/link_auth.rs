//! Link authentication on the robot (PROTOCOL.md §13): with a key it acts only on frames that
//! verify; unsigned, forged, replayed and reflected frames change nothing (no motor moves, no
//! failsafe held off), a frame signed for another robot or session (a fleet shares one key)
//! is refused like a forgery, and a refused Hello is answered with its reason.
#![allow(clippy::unwrap_used, clippy::panic)]

use protocol::sign::{LinkAuth, LinkKey, ANY_ROBOT, ROBOT_LINK, STATION_LINK};
use protocol::*;
use robot_firmware::scripted::ScriptedHal;
use robot_firmware::{AnyRobot, MotorCommand, RobotOptions, MICRO_RATO};

const KEY: [u8; 32] = [0x42; 32];
const OTHER: [u8; 32] = [0x24; 32];
/// The station's clock at the start of a test, in signing ticks (2026-01-01).
const T0: u64 = 0x1f92_d63c_e000;

/// What the station saw: each frame's message (owned enough) and its verdict.
#[derive(Clone, Debug, PartialEq)]
enum Seen {
    HelloReply { accepted: bool },
    Ack(u16),
    Nack(u16, NackReason),
    Event(Event),
    Other,
}

struct Station {
    robot: AnyRobot,
    hal: ScriptedHal,
    seq: u16,
    dec: FrameDecoder,
    /// The station's own signing and verifying state (the key it believes in).
    auth: LinkAuth,
    clock: u64,
}

impl Station {
    fn new(robot_key: Option<&[u8; 32]>, station_key: Option<&[u8; 32]>) -> Self {
        let mut robot = AnyRobot::new(RobotOptions {
            profile: &MICRO_RATO,
            seed: 1,
            start: robot_firmware::odometry::Pose::new(0.5, 0.5, 0.0),
            emulated: false,
            firmware_version: "test",
        });
        robot.link_mut().set_key(robot_key);
        Station {
            robot,
            hal: ScriptedHal {
                compass: Some(0.0),
                ..ScriptedHal::default()
            },
            seq: 0,
            dec: FrameDecoder::new(),
            auth: LinkAuth::new(station_key.map(LinkKey::new), STATION_LINK),
            clock: T0,
        }
    }

    /// Encodes as the station would (signed when it has a key), returns the wire bytes.
    fn frame(&mut self, msg: &Message<'_>) -> Vec<u8> {
        let mut buf = [0u8; MAX_FRAME];
        self.clock += 100;
        self.bind_hello(msg);
        let n = self
            .auth
            .encode(self.seq, msg, self.clock, &mut buf)
            .unwrap();
        self.seq = self.seq.wrapping_add(1);
        buf[..n].to_vec()
    }

    fn push(&mut self, wire: &[u8]) {
        assert_eq!(self.hal.push_rx(wire), wire.len());
    }

    fn send(&mut self, msg: &Message<'_>) -> Vec<u8> {
        let wire = self.frame(msg);
        self.push(&wire);
        wire
    }

    /// An unsigned frame, whatever the station's key.
    fn send_unsigned(&mut self, msg: &Message<'_>) {
        let mut buf = [0u8; MAX_FRAME];
        let n = encode(self.seq, msg, &mut buf).unwrap();
        self.seq = self.seq.wrapping_add(1);
        self.push(&buf[..n]);
    }

    /// A frame signed with another key.
    fn send_forged(&mut self, msg: &Message<'_>) {
        let binding = self.auth.binding().for_message(msg);
        self.send_signed_as(&LinkKey::new(&OTHER), binding, msg);
    }

    /// As the station does: a Hello opens its session, no robot named yet.
    fn bind_hello(&mut self, msg: &Message<'_>) {
        if let Message::Hello(h) = msg {
            self.auth.bind(Binding::new(h.session, ANY_ROBOT));
        }
    }

    /// A frame signed with `key` and bound to `binding`, whatever the station's own.
    fn send_signed_as(&mut self, key: &LinkKey, binding: Binding, msg: &Message<'_>) {
        let mut buf = [0u8; MAX_FRAME];
        self.clock += 100;
        self.bind_hello(msg);
        let n = encode_signed(
            self.seq,
            msg,
            key,
            &binding,
            STATION_LINK,
            self.clock,
            &mut buf,
        )
        .unwrap();
        self.push(&buf[..n]);
    }

    fn hello(&mut self) -> Vec<Seen> {
        let hello = Message::Hello(Hello {
            fingerprint: FINGERPRINT,
            protocol: PROTOCOL_VERSION,
            session: 7,
            station: "test",
        });
        self.send(&hello);
        self.run(20)
    }

    /// Steps the robot `ms` milliseconds; returns what it sent, each frame checked by the
    /// station's authentication (a frame that does not verify is a test failure).
    fn run(&mut self, ms: u64) -> Vec<Seen> {
        let mut seen = Vec::new();
        for _ in 0..ms {
            self.robot.step(&mut self.hal);
            self.hal.now_us += 1000;
            let mut buf = [0u8; 4096];
            let n = self.hal.take_tx(&mut buf);
            let mut input = &buf[..n];
            loop {
                match self.dec.feed(input) {
                    Feed::NeedMore => break,
                    Feed::Error { error, .. } => panic!("robot sent a bad frame: {error}"),
                    Feed::Frame { frame, rest } => {
                        input = rest;
                        if let Err(e) = self.auth.verify(&frame) {
                            panic!("robot frame {:?} refused: {e}", frame.header.kind);
                        }
                        if let Message::HelloReply(r) = &frame.message {
                            if r.accepted {
                                self.auth.bind(Binding::new(r.session, r.robot_id));
                            }
                        }
                        seen.push(match frame.message {
                            Message::HelloReply(r) => Seen::HelloReply {
                                accepted: r.accepted,
                            },
                            Message::Ack(a) => Seen::Ack(a.cmd_seq),
                            Message::Nack(n) => Seen::Nack(n.cmd_seq, n.reason),
                            Message::Event(e) => Seen::Event(e),
                            _ => Seen::Other,
                        });
                    }
                }
            }
        }
        seen
    }

    fn replies(seen: &[Seen]) -> Vec<&Seen> {
        seen.iter()
            .filter(|s| matches!(s, Seen::Ack(_) | Seen::Nack(..)))
            .collect()
    }
}

fn teleop() -> Message<'static> {
    Message::Command(Command::Teleop {
        v_mm_s: 200,
        w_mrad_s: 0,
    })
}

/// A keyed robot and station in a session, the robot in manual mode.
fn manual_session() -> Station {
    let mut s = Station::new(Some(&KEY), Some(&KEY));
    assert!(s.hello().contains(&Seen::HelloReply { accepted: true }));
    s.send(&Message::Command(Command::SetMode(Mode::Manual)));
    let seen = s.run(20);
    assert_eq!(Station::replies(&seen), [&Seen::Ack(1)]);
    s
}

#[test]
fn unsigned_and_forged_commands_are_refused_and_no_motor_moves() {
    let mut s = manual_session();
    let moves = s.hal.motor_moves;
    s.send_unsigned(&teleop());
    s.send_forged(&teleop());
    let seen = s.run(100);
    assert!(Station::replies(&seen).is_empty(), "{seen:?}");
    assert_eq!(s.hal.motors, MotorCommand::STOP);
    assert_eq!(s.hal.motor_moves, moves, "a refused frame moved a motor");
    let a = s.robot.link().auth_stats();
    assert_eq!((a.unsigned, a.bad_signature), (1, 1));
    // The same command signed with the key is obeyed: the refusals above were the key's doing.
    let seq = s.seq;
    s.send(&teleop());
    let seen = s.run(100);
    assert_eq!(Station::replies(&seen), [&Seen::Ack(seq)]);
    assert_ne!(s.hal.motors, MotorCommand::STOP);
}

#[test]
fn a_command_signed_for_another_robot_or_session_is_refused_and_no_motor_moves() {
    // A fleet shares one key: robot 2's signed teleop, moved onto this robot's line (robot 1,
    // session 7), and one of an earlier session are both refused, as forgeries are.
    let mut s = manual_session();
    let moves = s.hal.motor_moves;
    let own = s.auth.binding();
    assert_eq!((own.session, own.robot_id), (7, 1));
    let key = LinkKey::new(&KEY);
    s.send_signed_as(&key, Binding::new(7, 2), &teleop());
    s.send_signed_as(&key, Binding::new(6, 1), &teleop());
    let seen = s.run(100);
    assert!(Station::replies(&seen).is_empty(), "{seen:?}");
    assert_eq!(
        s.hal.motor_moves, moves,
        "a frame for another robot moved a motor"
    );
    assert_eq!(s.robot.link().auth_stats().bad_signature, 2);
    // Bound to this robot and session, the same command is obeyed.
    let seq = s.seq;
    s.send_signed_as(&key, own, &teleop());
    let seen = s.run(100);
    assert_eq!(Station::replies(&seen), [&Seen::Ack(seq)]);
    assert_ne!(s.hal.motors, MotorCommand::STOP);
}

#[test]
fn a_replayed_command_is_refused() {
    let mut s = manual_session();
    let go = s.send(&teleop());
    s.run(50);
    assert_ne!(s.hal.motors, MotorCommand::STOP);
    s.send(&Message::Command(Command::Teleop {
        v_mm_s: 0,
        w_mrad_s: 0,
    }));
    s.run(100);
    let stopped = s.hal.motors;
    // The recorded "go" frame again: same seq, same timestamp.
    s.push(&go);
    let seen = s.run(100);
    assert!(
        Station::replies(&seen).is_empty(),
        "replay answered: {seen:?}"
    );
    assert_eq!(s.hal.motors, stopped);
    assert_eq!(s.robot.link().auth_stats().stale_timestamp, 1);
}

#[test]
fn unsigned_heartbeats_do_not_hold_off_the_failsafe() {
    let mut s = manual_session();
    s.send(&teleop());
    s.run(50);
    assert_ne!(s.hal.motors, MotorCommand::STOP);
    // Only forged and unsigned heartbeats from now on: the 300 ms failsafe must trip.
    for _ in 0..10 {
        s.send_unsigned(&Message::Heartbeat(Heartbeat { time_ms: 0 }));
        s.run(50);
        s.send_forged(&Message::Heartbeat(Heartbeat { time_ms: 0 }));
        s.run(50);
    }
    assert_eq!(s.hal.motors, MotorCommand::STOP);
}

#[test]
fn a_refused_hello_is_answered_with_its_reason() {
    let refusal = |value| {
        Seen::Event(Event {
            code: EventCode::HandshakeRefused,
            value,
        })
    };
    // Keyed robot, forged Hello: bad signature.
    let mut s = Station::new(Some(&KEY), Some(&KEY));
    s.send_forged(&Message::Hello(Hello {
        fingerprint: FINGERPRINT,
        protocol: PROTOCOL_VERSION,
        session: 1,
        station: "forger",
    }));
    assert_eq!(s.run(20), [refusal(-2)]);
    assert!(!s.robot.link().connected());
    // Unkeyed robot, signed Hello: it has no key; its answer is unsigned.
    let mut s = Station::new(None, Some(&KEY));
    let hello = Message::Hello(Hello {
        fingerprint: FINGERPRINT,
        protocol: PROTOCOL_VERSION,
        session: 1,
        station: "keyed",
    });
    s.send(&hello);
    s.auth = LinkAuth::new(None, STATION_LINK);
    assert_eq!(s.run(20), [refusal(-4)]);
    assert!(!s.robot.link().connected());
}

#[test]
fn a_keyed_robot_refuses_an_unsigned_hello_with_a_signed_event() {
    let mut s = Station::new(Some(&KEY), None);
    s.send(&Message::Hello(Hello {
        fingerprint: FINGERPRINT,
        protocol: PROTOCOL_VERSION,
        session: 1,
        station: "no key",
    }));
    // Read the answer with the key: it is signed by the robot's link.
    s.auth = LinkAuth::new(Some(LinkKey::new(&KEY)), STATION_LINK);
    let seen = s.run(20);
    assert_eq!(
        seen,
        [Seen::Event(Event {
            code: EventCode::HandshakeRefused,
            value: -1,
        })]
    );
    assert!(!s.robot.link().connected());
    assert_eq!(s.robot.link().auth_stats().unsigned, 1);
}

#[test]
fn the_robot_signs_on_from_the_stations_timestamps_and_stays_small() {
    let mut s = Station::new(Some(&KEY), Some(&KEY));
    s.hello();
    // The station's window for the robot's link holds the robot's last timestamp, which
    // counts on from the station's clock (the robot has none).
    let last = s
        .auth
        .replay()
        .last(ROBOT_LINK)
        .expect("robot frames verified");
    assert!(
        last > T0,
        "robot timestamp {last} not above the station's {T0}"
    );
    eprintln!(
        "size_of: Robot {} Link {} LinkAuth {} LinkKey {}",
        std::mem::size_of::<robot_firmware::Robot<robot_firmware::robot::DomDinis>>(),
        std::mem::size_of::<robot_firmware::link::Link>(),
        std::mem::size_of::<LinkAuth>(),
        std::mem::size_of::<LinkKey>()
    );
    assert!(
        std::mem::size_of::<robot_firmware::Robot<robot_firmware::robot::DomDinis>>() <= 32 * 1024
    );
}

mod hostile {
    use super::*;
    use proptest::prelude::*;

    fn command() -> impl Strategy<Value = Command> {
        prop_oneof![
            (any::<i16>(), any::<i16>()).prop_map(|(v, w)| Command::Teleop {
                v_mm_s: v,
                w_mrad_s: w
            }),
            Just(Command::SetMode(Mode::Wander)),
            Just(Command::SetMode(Mode::Explore)),
            (any::<i32>(), any::<i32>())
                .prop_map(|(x, y)| Command::GoTo(PointMm { x_mm: x, y_mm: y })),
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// Whatever arrives without the key (garbage, unsigned commands, commands signed
        /// with another key, a reflected robot frame) moves no motor and gets no reply.
        #[test]
        fn nothing_without_the_key_moves_a_motor(
            noise in prop::collection::vec(any::<u8>(), 0..300),
            commands in prop::collection::vec((command(), 0..3u8), 1..8),
        ) {
            let mut s = manual_session();
            let moves = s.hal.motor_moves;
            s.push(&noise);
            s.push(&[0]);
            for (c, how) in commands {
                let msg = Message::Command(c);
                match how {
                    0 => s.send_unsigned(&msg),
                    1 => s.send_forged(&msg),
                    _ => {
                        let mut robot = LinkAuth::new(Some(LinkKey::new(&KEY)), ROBOT_LINK);
                        let mut buf = [0u8; MAX_FRAME];
                        let n = robot.encode(0, &msg, T0 * 2, &mut buf).unwrap();
                        s.push(&buf[..n]);
                    }
                }
                let seen = s.run(30);
                prop_assert!(Station::replies(&seen).is_empty(), "{:?}", seen);
            }
            prop_assert_eq!(s.hal.motor_moves, moves);
            prop_assert_eq!(s.hal.motors, MotorCommand::STOP);
            prop_assert!(s.robot.link().auth_stats().refused() > 0);
        }
    }
}
