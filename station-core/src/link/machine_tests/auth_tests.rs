//! Link authentication (PROTOCOL.md §13) against a hand-made keyed robot.

use super::*;
use protocol::sign::{Binding, LinkAuth, LinkKey, ROBOT_LINK, STATION_LINK};
use protocol::{Event, EventCode};

/// The robot id `reply` states.
const ROBOT_ID: u8 = 1;

const T0: u64 = 0x1f92_d63c_e000;

fn keyed_machine(key: u8) -> LinkMachine {
    let mut m = machine();
    m.set_key_at(Some(LinkKey::new(&[key; 32])), T0);
    m
}

/// The robot's side: verifies what the station sent, returns the Hello's session (which
/// the robot accepts, so its frames are bound to it from then on).
fn robot_reads(robot: &mut LinkAuth, m: &mut LinkMachine) -> Option<u32> {
    let bytes = m.take_output();
    let mut dec = FrameDecoder::new();
    let mut input = bytes.as_slice();
    let mut session = None;
    loop {
        match dec.feed(input) {
            Feed::NeedMore => return session,
            Feed::Error { error, .. } => panic!("station sent a bad frame: {error}"),
            Feed::Frame { frame, rest } => {
                robot.verify(&frame).expect("the station's frames verify");
                if let Message::Hello(h) = frame.message {
                    session = Some(h.session);
                    robot.bind(Binding::new(h.session, ROBOT_ID));
                }
                input = rest;
            }
        }
    }
}

fn signed(robot: &mut LinkAuth, seq: u16, msg: &Message<'_>) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME];
    let n = robot.encode(seq, msg, 0, &mut buf).expect("encode");
    buf[..n].to_vec()
}

fn telemetry() -> Message<'static> {
    Message::Telemetry(Telemetry::default())
}

#[test]
fn forged_unsigned_and_replayed_frames_are_counted_and_never_end_the_session() {
    let mut m = keyed_machine(1);
    let mut robot = LinkAuth::new(Some(LinkKey::new(&[1; 32])), ROBOT_LINK);
    m.port_opened(0, "p");
    let session = robot_reads(&mut robot, &mut m).expect("hello");
    let reply_bytes = reply(session, FINGERPRINT, true);
    // The robot's real reply, signed: decode the unsigned helper's message and re-sign.
    let mut dec = FrameDecoder::new();
    let msg = match dec.feed(&reply_bytes) {
        Feed::Frame { frame, .. } => frame.message,
        other => panic!("{other:?}"),
    };
    let good_reply = signed(&mut robot, 0, &msg);
    m.receive(5, &good_reply);
    assert!(m.connected());
    let t1 = signed(&mut robot, 1, &telemetry());
    m.receive(10, &t1);
    let mut forger = LinkAuth::new(Some(LinkKey::new(&[2; 32])), ROBOT_LINK);
    m.receive(20, &signed(&mut forger, 2, &telemetry()));
    m.receive(30, &frame(3, &telemetry()));
    m.receive(40, &t1);
    m.receive(50, &good_reply);
    let s = m.stats(60);
    assert!(m.connected(), "a refused frame ended the session");
    assert!(s.auth.keyed);
    assert_eq!(s.auth.verified, 2);
    assert_eq!(
        (
            s.auth.bad_signature,
            s.auth.unsigned,
            s.auth.stale_timestamp
        ),
        (1, 1, 2)
    );
    assert_eq!(s.telemetry_frames, 1, "only the verified telemetry counts");
}

#[test]
fn an_ack_signed_by_another_robot_of_the_fleet_is_refused_and_the_command_stays_unanswered() {
    // One key, two robots: robot 2's Ack relayed onto robot 1's line must not answer the
    // Stop sent to robot 1 (PROTOCOL.md §13, binding).
    let mut m = keyed_machine(1);
    let mut robot = LinkAuth::new(Some(LinkKey::new(&[1; 32])), ROBOT_LINK);
    m.port_opened(0, "p");
    let session = robot_reads(&mut robot, &mut m).expect("hello");
    let mut dec = FrameDecoder::new();
    let msg = match dec.feed(&reply(session, FINGERPRINT, true)) {
        Feed::Frame { frame, .. } => frame.message,
        other => panic!("{other:?}"),
    };
    m.receive(5, &signed(&mut robot, 0, &msg));
    assert!(m.connected());
    m.take_events();
    m.submit(10, 7, Command::Stop);
    let stop_seq = sent(&mut m)
        .iter()
        .find(|f| f.2 == Some(Command::Stop))
        .expect("stop sent")
        .0;
    let ack = Message::Ack(protocol::Ack {
        cmd_seq: stop_seq,
        info: protocol::AckInfo::Done,
    });
    let mut robot_2 = LinkAuth::new(Some(LinkKey::new(&[1; 32])), ROBOT_LINK);
    robot_2.bind(Binding::new(session, ROBOT_ID + 1));
    m.receive(20, &signed(&mut robot_2, 1, &ack));
    assert!(
        outcomes(&m.take_events()).is_empty(),
        "robot 2's ack answered"
    );
    assert_eq!(m.stats(30).auth.bad_signature, 1);
    // Robot 1's own Ack does.
    m.receive(40, &signed(&mut robot, 2, &ack));
    assert!(matches!(
        outcomes(&m.take_events()).as_slice(),
        [(7, CommandOutcome::Acked { .. })]
    ));
}

#[test]
fn the_robots_frames_to_the_last_station_do_not_look_like_another_key() {
    // The robot talks on to a station that left until its link timeout; those frames,
    // bound to that station's session, reach the next station as it handshakes. They
    // fail our MAC, and are counted, but only a refusal of our Hello says "another key".
    let mut m = keyed_machine(1);
    let mut robot = LinkAuth::new(Some(LinkKey::new(&[1; 32])), ROBOT_LINK);
    robot.bind(Binding::new(0x5e55_1014, ROBOT_ID));
    m.port_opened(0, "p");
    let session = robot_reads(&mut robot, &mut m).expect("hello");
    robot.bind(Binding::new(0x5e55_1014, ROBOT_ID));
    m.receive(3, &signed(&mut robot, 9, &telemetry()));
    assert!(
        !matches!(m.connection(), Connection::Refused { .. }),
        "{:?}",
        m.connection()
    );
    assert_eq!(m.stats(4).auth.bad_signature, 1);
    robot.bind(Binding::new(session, ROBOT_ID));
    let mut dec = FrameDecoder::new();
    let msg = match dec.feed(&reply(session, FINGERPRINT, true)) {
        Feed::Frame { frame, .. } => frame.message,
        other => panic!("{other:?}"),
    };
    m.receive(5, &signed(&mut robot, 10, &msg));
    assert!(m.connected());
}

#[test]
fn a_robot_on_another_key_ends_the_handshake_with_a_message_naming_the_key_file() {
    let mut m = keyed_machine(1);
    m.port_opened(0, "p");
    m.take_output();
    m.take_events();
    let mut robot = LinkAuth::new(Some(LinkKey::new(&[2; 32])), ROBOT_LINK);
    let refusal = Message::Event(Event {
        code: EventCode::HandshakeRefused,
        value: -2,
    });
    m.receive(10, &signed(&mut robot, 0, &refusal));
    let events = m.take_events();
    match connections(&events).as_slice() {
        [Connection::Refused { message }] => {
            assert!(
                message.starts_with("link authentication failed"),
                "{message}"
            );
            assert!(message.contains("another key"), "{message}");
            assert!(message.ends_with("check --key-file"), "{message}");
        }
        other => panic!("{other:?}"),
    }
    assert!(!m.connected());
}

#[test]
fn an_unkeyed_station_says_the_robot_has_a_key() {
    let mut m = machine();
    m.port_opened(0, "p");
    m.take_events();
    let mut robot = LinkAuth::new(Some(LinkKey::new(&[2; 32])), ROBOT_LINK);
    let refusal = Message::Event(Event {
        code: EventCode::HandshakeRefused,
        value: -1,
    });
    m.receive(10, &signed(&mut robot, 0, &refusal));
    let events = m.take_events();
    let msg = match connections(&events).as_slice() {
        [Connection::Refused { message }] => message.clone(),
        other => panic!("{other:?}"),
    };
    assert!(msg.contains("this station has no key"), "{msg}");
    assert_eq!(m.stats(20).auth.unexpected_signature, 1);
}

#[test]
fn a_refusal_of_another_stations_signed_hello_is_not_taken_for_ours() {
    // A keyed station tried a robot without a key and exited on its refusal; a refusal
    // of one more Hello was still in the port. We sign nothing, so it is not ours.
    let mut m = machine();
    m.port_opened(0, "p");
    let session = sent(&mut m)[0].3.expect("hello");
    m.take_events();
    let refusal = |value| {
        frame(
            0,
            &Message::Event(Event {
                code: EventCode::HandshakeRefused,
                value,
            }),
        )
    };
    m.receive(1, &refusal(-4));
    m.receive(1, &refusal(-2));
    let events = m.take_events();
    assert!(connections(&events).is_empty(), "{events:?}");
    m.receive(5, &reply(session, FINGERPRINT, true));
    assert!(m.connected());
    // A keyed station is told the same refusal: the robot has no key.
    let mut k = keyed_machine(1);
    k.port_opened(0, "p");
    k.take_events();
    k.receive(1, &refusal(-4));
    assert!(
        matches!(k.connection(), Connection::Refused { message }
            if message.contains("has no key")),
        "{:?}",
        k.connection()
    );
}

#[test]
fn a_robot_ahead_of_our_clock_refuses_once_then_our_timestamps_follow_its() {
    let mut m = keyed_machine(1);
    let mut robot = LinkAuth::new(Some(LinkKey::new(&[1; 32])), ROBOT_LINK);
    // The robot last heard a station whose clock was an hour ahead of ours.
    let ahead = Message::Heartbeat(Heartbeat { time_ms: 0 });
    let mut fast = LinkAuth::new(Some(LinkKey::new(&[1; 32])), STATION_LINK);
    let mut buf = [0u8; MAX_FRAME];
    let n = fast.encode(0, &ahead, T0 + 360_000_000, &mut buf).unwrap();
    let mut dec = FrameDecoder::new();
    match dec.feed(&buf[..n]) {
        Feed::Frame { frame, .. } => robot.verify(&frame).unwrap(),
        other => panic!("{other:?}"),
    }
    m.port_opened(0, "p");
    let out = m.take_output();
    let mut dec = FrameDecoder::new();
    let mut input = out.as_slice();
    let mut refused = None;
    while let Feed::Frame { frame, rest } = dec.feed(input) {
        input = rest;
        refused = robot.verify(&frame).err();
    }
    assert!(matches!(refused, Some(AuthError::StaleTimestamp { .. })));
    let refusal = Message::Event(Event {
        code: EventCode::HandshakeRefused,
        value: -3,
    });
    m.receive(10, &signed(&mut robot, 0, &refusal));
    assert!(
        !matches!(m.connection(), Connection::Refused { .. }),
        "a stale refusal heals by itself"
    );
    m.poll(HELLO_RETRY_MS);
    assert!(
        robot_reads(&mut robot, &mut m).is_some(),
        "the next Hello verifies"
    );
}

#[test]
fn a_replaying_station_trusts_signatures_it_cannot_check() {
    let mut m = machine();
    m.trust_signatures();
    m.port_opened(0, "p");
    let mut robot = LinkAuth::new(Some(LinkKey::new(&[2; 32])), ROBOT_LINK);
    m.receive(10, &signed(&mut robot, 0, &telemetry()));
    let s = m.stats(20);
    assert_eq!(s.telemetry_frames, 1);
    assert_eq!(s.auth.refused(), 0);
}
