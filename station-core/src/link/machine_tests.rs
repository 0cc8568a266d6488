//! Unit tests of the link state machine against hand-made robot frames: no port, no clock.

use super::*;
use protocol::{encode, Ack, AckInfo, EmuTruth, MapCapacity, Mode, Nack, ProfileId, Telemetry};

const SESSION_SEED: u64 = 7;

fn machine() -> LinkMachine {
    LinkMachine::new(MachineConfig {
        station: "test".into(),
        nonce_seed: SESSION_SEED,
    })
}

/// What the station sent: (seq, kind, message summary).
fn sent(m: &mut LinkMachine) -> Vec<(u16, Kind, Option<Command>, Option<u32>)> {
    let bytes = m.take_output();
    let mut dec = FrameDecoder::new();
    let mut input = bytes.as_slice();
    let mut v = Vec::new();
    loop {
        match dec.feed(input) {
            Feed::NeedMore => break,
            Feed::Error { error, .. } => panic!("station sent a bad frame: {error}"),
            Feed::Frame { frame, rest } => {
                let (cmd, session) = match frame.message {
                    Message::Command(c) => (Some(c), None),
                    Message::Hello(h) => {
                        assert_eq!(h.fingerprint, FINGERPRINT);
                        assert_eq!(h.station, "test");
                        (None, Some(h.session))
                    }
                    _ => (None, None),
                };
                v.push((frame.header.seq, frame.header.kind, cmd, session));
                input = rest;
            }
        }
    }
    v
}

fn frame(seq: u16, msg: &Message<'_>) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME];
    let n = encode(seq, msg, &mut buf).expect("encode");
    buf[..n].to_vec()
}

fn reply(session: u32, fingerprint: [u8; 8], accepted: bool) -> Vec<u8> {
    frame(
        0,
        &Message::HelloReply(HelloReply {
            fingerprint,
            protocol: PROTOCOL_VERSION,
            session,
            accepted,
            firmware: "robot-firmware",
            firmware_version: "9.9.9",
            profile: ProfileId::Khepera,
            capabilities: 0,
            map_capacity: MapCapacity {
                width: 64,
                height: 64,
            },
            telemetry_hz: 10,
            failsafe_ms: 300,
            robot_id: 1,
        }),
    )
}

fn connections(events: &[LinkEvent]) -> Vec<&Connection> {
    events
        .iter()
        .filter_map(|e| match e {
            LinkEvent::Connection(c) => Some(c),
            _ => None,
        })
        .collect()
}

fn outcomes(events: &[LinkEvent]) -> Vec<(CommandId, CommandOutcome)> {
    events
        .iter()
        .filter_map(|e| match e {
            LinkEvent::CommandDone { id, outcome, .. } => Some((*id, *outcome)),
            _ => None,
        })
        .collect()
}

/// Opens the port at t=0 and completes the handshake; returns the session.
fn connect(m: &mut LinkMachine) -> u32 {
    m.port_opened(0, "test-port");
    let hello = sent(m);
    let session = hello[0].3.expect("hello first");
    m.receive(5, &reply(session, FINGERPRINT, true));
    assert!(m.connected());
    m.take_events();
    session
}

#[test]
fn opening_the_port_sends_a_delimiter_then_hello_repeated_every_200_ms_until_answered() {
    let mut m = machine();
    m.port_opened(0, "p");
    let out = m.take_output();
    assert_eq!(out[0], 0, "a lone 0x00 flushes the robot's decoder first");
    let mut m2 = machine();
    m2.port_opened(0, "p");
    let first = sent(&mut m2);
    assert_eq!(first.len(), 1);
    assert_eq!(first[0].1, Kind::Hello);
    let session = first[0].3;
    m2.poll(199);
    assert!(sent(&mut m2).is_empty(), "no hello before 200 ms");
    m2.poll(200);
    let again = sent(&mut m2);
    assert_eq!(again.len(), 1);
    assert_eq!(again[0].3, session, "the retry carries the same nonce");
    assert_ne!(again[0].0, first[0].0, "but a new frame number");
}

#[test]
fn a_reply_with_another_nonce_is_ignored_and_the_right_one_connects() {
    let mut m = machine();
    m.port_opened(0, "p");
    let session = sent(&mut m)[0].3.expect("hello");
    m.receive(10, &reply(session.wrapping_add(1), FINGERPRINT, true));
    assert!(!m.connected());
    m.receive(20, &reply(session, FINGERPRINT, true));
    assert!(m.connected());
    let events = m.take_events();
    let conns = connections(&events);
    match conns.last() {
        Some(Connection::Connected(p)) => {
            assert_eq!(p.firmware_version, "9.9.9");
            assert_eq!(p.session, session);
        }
        other => panic!("expected Connected, got {other:?}"),
    }
}

#[test]
fn a_fingerprint_mismatch_is_refused_naming_both_builds_and_retried_slowly() {
    let mut m = machine();
    m.port_opened(0, "p");
    let session = sent(&mut m)[0].3.expect("hello");
    let theirs = [1, 2, 3, 4, 5, 6, 7, 8];
    m.receive(10, &reply(session, theirs, false));
    assert!(!m.connected());
    let events = m.take_events();
    let Some(Connection::Refused { message }) = connections(&events).last().copied() else {
        panic!("expected a refusal: {events:?}");
    };
    assert!(message.contains("0102030405060708"), "{message}");
    assert!(message.contains(&hex(&FINGERPRINT)), "{message}");
    assert!(message.contains("robot-firmware 9.9.9"), "{message}");
    m.poll(1000);
    assert!(
        sent(&mut m).is_empty(),
        "no 200 ms hammering after a refusal"
    );
    m.poll(2010);
    assert_eq!(sent(&mut m).len(), 1);
}

#[test]
fn a_frame_of_another_protocol_version_is_reported_as_a_refusal() {
    let mut m = machine();
    m.port_opened(0, "p");
    m.take_output();
    let mut buf = [0u8; MAX_FRAME];
    let n = protocol::encode_raw(2, 1, 0, &[1, 2, 3], &mut buf).expect("raw");
    m.receive(5, &buf[..n]);
    let events = m.take_events();
    let Some(Connection::Refused { message }) = connections(&events).last().copied() else {
        panic!("expected a refusal: {events:?}");
    };
    assert!(message.contains("protocol version 2"), "{message}");
}

#[test]
fn a_command_before_the_handshake_fails_at_once_as_not_connected() {
    let mut m = machine();
    m.port_opened(0, "p");
    m.take_output();
    m.submit(1, 9, Command::Stop);
    assert!(sent(&mut m).is_empty());
    let events = m.take_events();
    assert_eq!(
        outcomes(&events),
        vec![(9, CommandOutcome::Failed(CommandFailure::NotConnected))]
    );
}

#[test]
fn an_unanswered_command_is_resent_with_its_seq_and_fails_after_five_sends() {
    let mut m = machine();
    connect(&mut m);
    m.submit(10, 1, Command::Stop);
    let first = sent(&mut m);
    assert_eq!(first.len(), 1);
    let seq = first[0].0;
    let mut sends = 1;
    let mut failed_at = None;
    for now in (20..=2000).step_by(10) {
        // Keep the link alive so only the command times out.
        m.receive(
            now,
            &frame(now as u16, &Message::Heartbeat(Heartbeat { time_ms: 0 })),
        );
        m.poll(now);
        for (s, kind, c, _) in sent(&mut m) {
            if kind == Kind::Command {
                assert_eq!(s, seq);
                assert_eq!(c, Some(Command::Stop));
                sends += 1;
            }
        }
        let events = m.take_events();
        if let Some((1, o)) = outcomes(&events).first() {
            assert_eq!(
                *o,
                CommandOutcome::Failed(CommandFailure::Timeout { sends: 5 })
            );
            failed_at = Some(now);
            break;
        }
    }
    assert_eq!(sends, 5);
    assert_eq!(
        failed_at,
        Some(1010),
        "5 sends 200 ms apart, then 200 ms of waiting"
    );
}

#[test]
fn acks_and_nacks_are_matched_by_cmd_seq_in_any_order() {
    let mut m = machine();
    connect(&mut m);
    m.submit(10, 1, Command::SetMode(Mode::Manual));
    m.submit(
        10,
        2,
        Command::GetParam {
            id: protocol::ParamId(0),
        },
    );
    let s = sent(&mut m);
    let (seq1, seq2) = (s[0].0, s[1].0);
    let nack = Message::Nack(Nack {
        cmd_seq: seq2,
        reason: NackReason::UnknownParam,
    });
    m.receive(30, &frame(1, &nack));
    let ack = Message::Ack(Ack {
        cmd_seq: seq1,
        info: AckInfo::Done,
    });
    m.receive(42, &frame(2, &ack));
    let events = m.take_events();
    assert_eq!(
        outcomes(&events),
        vec![
            (
                2,
                CommandOutcome::Nacked {
                    reason: NackReason::UnknownParam,
                    sends: 1
                }
            ),
            (
                1,
                CommandOutcome::Acked {
                    info: AckInfo::Done,
                    sends: 1,
                    rtt_ms: 32
                }
            ),
        ]
    );
    let stats = m.stats(50);
    assert_eq!(stats.rtt_ms.samples, 1);
    assert_eq!(stats.rtt_ms.p50, Some(32.0));
    // A duplicate answer names nothing in flight any more.
    m.receive(60, &frame(3, &ack));
    assert_eq!(m.stats(60).commands.unmatched_replies, 1);
}

#[test]
fn a_heartbeat_goes_out_after_250_ms_without_sending() {
    let mut m = machine();
    connect(&mut m);
    m.receive(
        100,
        &frame(1, &Message::Heartbeat(Heartbeat { time_ms: 0 })),
    );
    m.poll(249);
    assert!(sent(&mut m).is_empty());
    m.poll(250);
    let s = sent(&mut m);
    assert_eq!(s.len(), 1);
    assert_eq!(s[0].1, Kind::Heartbeat);
    let d = m.next_deadline();
    assert!(
        d > 250 && d <= 500,
        "next heartbeat or stats deadline, got {d}"
    );
}

#[test]
fn a_robot_whose_clock_runs_ten_times_faster_gets_heartbeats_ten_times_as_often() {
    // `robot-emulator --speed 10`: its 1.5 s link timeout is 150 ms of ours, so 250 ms
    // heartbeats would lose the session; 250 ms of its time is 25 ms of ours.
    let mut m = machine();
    connect(&mut m);
    for i in 0..=12u16 {
        let t = 100 * u64::from(i);
        let time_ms = (t * 10) as u32;
        m.receive(t, &frame(i + 1, &Message::Heartbeat(Heartbeat { time_ms })));
    }
    m.poll(1_200);
    assert_eq!(
        sent(&mut m).len(),
        1,
        "a heartbeat after 1.2 s of not sending"
    );
    assert!(m.next_deadline() <= 1_225);
    m.poll(1_224);
    assert!(sent(&mut m).is_empty());
    m.poll(1_225);
    let s = sent(&mut m);
    assert_eq!(s.len(), 1);
    assert_eq!(s[0].1, Kind::Heartbeat);
}

#[test]
fn a_backlog_of_old_frames_read_at_open_does_not_hurry_the_heartbeats() {
    // A robot that has run for a minute served a station that left 30 s ago; the port kept
    // 1.5 s of the frames it sent that station (until its link timeout), and we read them
    // all at once on opening, before the robot answers our Hello. Measured against our
    // clock they span 30 s of the robot's in a few ms of ours.
    let mut m = machine();
    m.port_opened(0, "p");
    let session = sent(&mut m)[0].3.expect("hello");
    let backlog: Vec<u8> = (0..15u16)
        .flat_map(|i| {
            let time_ms = 30_000 + 100 * u32::from(i);
            let t = Telemetry {
                time_ms,
                ..Telemetry::default()
            };
            frame(i, &Message::Telemetry(t))
        })
        .collect();
    m.receive(1, &backlog);
    m.receive(5, &reply(session, FINGERPRINT, true));
    assert!(m.connected());
    sent(&mut m);
    // The robot now, 60 s into its run, in real time: telemetry every 100 ms.
    let mut heartbeats = Vec::new();
    for now in 6..=3_000u64 {
        if now % 100 == 0 {
            let t = Telemetry {
                time_ms: 60_000 + now as u32,
                ..Telemetry::default()
            };
            m.receive(now, &frame(100, &Message::Telemetry(t)));
        }
        m.poll(now);
        for s in sent(&mut m) {
            assert_eq!(s.1, Kind::Heartbeat);
            heartbeats.push(now);
        }
    }
    let gaps: Vec<u64> = heartbeats.windows(2).map(|w| w[1] - w[0]).collect();
    assert!(
        gaps.iter().all(|&g| g == 250),
        "heartbeats 250 ms apart: {gaps:?}"
    );
    assert_eq!(heartbeats.len(), 12, "{heartbeats:?}");
}

#[test]
fn a_ten_times_faster_robot_is_measured_from_its_session_despite_a_backlog() {
    let mut m = machine();
    m.port_opened(0, "p");
    let session = sent(&mut m)[0].3.expect("hello");
    let old = |time_ms| frame(0, &Message::Heartbeat(Heartbeat { time_ms }));
    m.receive(1, &[old(5_000), old(6_000)].concat());
    m.receive(5, &reply(session, FINGERPRINT, true));
    for i in 1..=12u16 {
        let t = 5 + 100 * u64::from(i);
        let time_ms = 900_000 + (t * 10) as u32;
        m.receive(t, &frame(i, &Message::Heartbeat(Heartbeat { time_ms })));
    }
    assert_eq!(m.robot_clock.heartbeat_period_ms(), 25);
}

#[test]
fn silence_for_1500_ms_ends_the_session_fails_commands_and_handshakes_again() {
    let mut m = machine();
    let old = connect(&mut m);
    m.submit(1000, 5, Command::Stop);
    m.poll(1504);
    assert!(m.connected());
    m.poll(1505);
    assert!(!m.connected());
    let events = m.take_events();
    assert!(outcomes(&events).contains(&(5, CommandOutcome::Failed(CommandFailure::LinkLost))));
    assert!(matches!(
        connections(&events).last(),
        Some(Connection::Handshaking { .. })
    ));
    let hellos: Vec<_> = sent(&mut m)
        .into_iter()
        .filter(|s| s.1 == Kind::Hello)
        .collect();
    assert_eq!(hellos.len(), 1);
    assert_ne!(hellos[0].3, Some(old), "a new session gets a new nonce");
    assert_eq!(m.stats(1505).link_timeouts, 1);
}

#[test]
fn a_no_handshake_nack_reports_the_reason_and_starts_a_new_handshake() {
    let mut m = machine();
    connect(&mut m);
    m.submit(10, 3, Command::Stop);
    let seq = sent(&mut m)[0].0;
    let nack = Message::Nack(Nack {
        cmd_seq: seq,
        reason: NackReason::NoHandshake,
    });
    m.receive(20, &frame(1, &nack));
    assert!(!m.connected());
    let events = m.take_events();
    assert_eq!(
        outcomes(&events),
        vec![(
            3,
            CommandOutcome::Nacked {
                reason: NackReason::NoHandshake,
                sends: 1
            }
        )]
    );
    assert_eq!(sent(&mut m)[0].1, Kind::Hello);
}

#[test]
fn emu_truth_frames_are_counted_on_their_own_sequence_numbers() {
    let mut m = machine();
    connect(&mut m);
    let t = Message::Telemetry(Telemetry::default());
    let truth = Message::EmuTruth(EmuTruth::default());
    // Robot frames 1..=4 and truth frames 0..=2 interleaved: no loss on either counter.
    let mut bytes = Vec::new();
    for (i, seq) in (1..=4u16).enumerate() {
        bytes.extend(frame(seq, &t));
        if i < 3 {
            bytes.extend(frame(i as u16, &truth));
        }
    }
    // Then a robot frame 7 (5 and 6 lost) and truth frame 4 (3 lost).
    bytes.extend(frame(7, &t));
    bytes.extend(frame(4, &truth));
    m.receive(100, &bytes);
    let s = m.stats(100);
    assert_eq!(s.robot_seq.lost, 2);
    assert_eq!(s.truth_seq.lost, 1);
    assert_eq!(s.truth_seq.received, 4);
    assert_eq!(s.telemetry_frames, 5);
}

#[test]
fn corrupted_bytes_are_counted_as_crc_errors_and_dropped_bytes() {
    let mut m = machine();
    connect(&mut m);
    let mut f = frame(1, &Message::Heartbeat(Heartbeat { time_ms: 5 }));
    f[3] ^= 0x40;
    m.receive(10, &f);
    let s = m.stats(10);
    assert_eq!(s.decoder.crc_errors, 1);
    assert_eq!(s.decoder.bytes_dropped, f.len() as u64);
}

#[test]
fn closing_the_port_fails_what_is_in_flight_and_reports_why() {
    let mut m = machine();
    connect(&mut m);
    m.submit(10, 4, Command::Stop);
    m.port_closed("gone".into());
    let events = m.take_events();
    assert!(outcomes(&events).contains(&(4, CommandOutcome::Failed(CommandFailure::LinkLost))));
    assert_eq!(
        connections(&events).last(),
        Some(&&Connection::Closed {
            reason: "gone".into()
        })
    );
}

mod auth {
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
}

/// A robot as the station's tests need it for the sequence-number rule (PROTOCOL.md §7): it
/// answers every Hello and command at once and remembers every command of its session, a
/// superset of what a real robot remembers (the last 8, for 2 s).
#[derive(Default)]
struct RememberingRobot {
    remembered: Vec<u16>,
    seq: u16,
    /// Commands whose number the robot still remembered a reply for.
    reused: Vec<(u16, Command)>,
    hellos: u32,
}

impl RememberingRobot {
    fn frame(&mut self, msg: &Message<'_>) -> Vec<u8> {
        self.seq = self.seq.wrapping_add(1);
        frame(self.seq, msg)
    }

    /// Answers what the station sent, and what it sent in answer, until it is quiet; returns
    /// the number of frames it sent.
    fn serve(&mut self, m: &mut LinkMachine, now_ms: u64) -> usize {
        let mut frames = 0;
        loop {
            let out = sent(m);
            if out.is_empty() {
                return frames;
            }
            frames += out.len();
            self.answer(m, now_ms, &out);
        }
    }

    fn answer(
        &mut self,
        m: &mut LinkMachine,
        now_ms: u64,
        out: &[(u16, Kind, Option<Command>, Option<u32>)],
    ) {
        for (seq, kind, cmd, session) in out {
            match (kind, cmd, session) {
                (Kind::Hello, _, Some(session)) => {
                    self.hellos += 1;
                    self.remembered.clear();
                    m.receive(now_ms, &reply(*session, FINGERPRINT, true));
                }
                (Kind::Command, Some(c), _) => {
                    if self.remembered.contains(seq) {
                        self.reused.push((*seq, *c));
                    }
                    self.remembered.push(*seq);
                    let ack = Message::Ack(Ack {
                        cmd_seq: *seq,
                        info: AckInfo::Done,
                    });
                    let bytes = self.frame(&ack);
                    m.receive(now_ms, &bytes);
                }
                _ => {}
            }
        }
    }
}

#[test]
fn the_sequence_counter_never_reaches_a_number_the_robot_remembers_a_reply_for() {
    let mut m = machine();
    let mut robot = RememberingRobot::default();
    m.port_opened(0, "p");
    robot.serve(&mut m, 0);
    assert!(m.connected());
    let (mut now, mut frames, mut submitted) = (0u64, 0usize, 0u64);
    // Two wraps of the counter: an idle session at 4 Hz with a command now and then.
    while frames < 2 * 65_536 + 1_000 {
        now += 250;
        let time_ms = now as u32;
        let hb = robot.frame(&Message::Heartbeat(Heartbeat { time_ms }));
        m.receive(now, &hb);
        // Every 8th frame a command: 8 divides 65,536, so each wrap meets the old numbers.
        if now % 2_000 == 0 {
            let command = if submitted % 2 == 0 {
                Command::StartExploration
            } else {
                Command::Stop
            };
            m.submit(now, submitted, command);
            submitted += 1;
        }
        m.poll(now);
        frames += robot.serve(&mut m, now);
    }
    assert!(
        robot.reused.is_empty(),
        "reused: {:?}",
        &robot.reused[..5.min(robot.reused.len())]
    );
    let events = m.take_events();
    let done = outcomes(&events);
    assert_eq!(done.len() as u64, submitted);
    assert!(
        done.iter()
            .all(|(_, o)| matches!(o, CommandOutcome::Acked { .. })),
        "a renewal fails no command"
    );
    let stats = m.stats(now);
    assert!(stats.renewals >= 2, "renewals {}", stats.renewals);
    assert_eq!(robot.hellos, 1 + stats.renewals);
    assert_eq!(stats.link_timeouts, 0);
}

#[test]
fn at_the_renewal_point_new_commands_wait_for_those_in_flight_and_the_new_session() {
    let mut m = machine();
    connect(&mut m);
    m.session_frames = RENEW_AFTER_FRAMES - 1;
    m.submit(10, 1, Command::StartExploration);
    let first = sent(&mut m);
    assert_eq!(first.len(), 1, "the last number before the renewal point");
    m.submit(20, 2, Command::Stop);
    assert!(
        sent(&mut m).is_empty(),
        "the Stop waits: a command is in flight"
    );
    let ack = |seq| {
        frame(
            seq,
            &Message::Ack(Ack {
                cmd_seq: seq,
                info: AckInfo::Done,
            }),
        )
    };
    m.receive(30, &ack(first[0].0));
    let hello = sent(&mut m);
    assert_eq!(hello.len(), 1);
    assert_eq!(
        hello[0].1,
        Kind::Hello,
        "nothing in flight: the station handshakes again"
    );
    m.submit(40, 3, Command::Stop);
    assert!(sent(&mut m).is_empty());
    m.receive(50, &reply(hello[0].3.expect("nonce"), FINGERPRINT, true));
    let after = sent(&mut m);
    let cmds: Vec<_> = after.iter().filter_map(|f| f.2).collect();
    assert_eq!(
        cmds,
        vec![Command::Stop, Command::Stop],
        "the waiting commands go out"
    );
    assert!(after.iter().all(|f| f.0 != first[0].0));
    let events = m.take_events();
    assert!(
        !outcomes(&events)
            .iter()
            .any(|(_, o)| matches!(o, CommandOutcome::Failed(_))),
        "{events:?}"
    );
}

/// A robot at 50 Hz on our clock: burst `k`'s telemetry (stamped `20 k` ms of the robot's
/// clock) read 5.4 ms after its stamp, its truth frame 7.2 ms after; the robot's clock reads
/// 1 s behind ours.
fn burst(m: &mut LinkMachine, k: u64) {
    burst_at(m, 1_000_000 + k * 20_000, (k * 20) as u32, 5_400, 7_200);
}

/// A burst stamped `time_ms` by the robot at our `stamp_us`: its telemetry read
/// `telemetry_after_us` later, its truth frame `truth_after_us` later.
fn burst_at(
    m: &mut LinkMachine,
    stamp_us: u64,
    time_ms: u32,
    telemetry_after_us: u64,
    truth_after_us: u64,
) {
    let t = Telemetry {
        time_ms,
        ..Telemetry::default()
    };
    m.receive_us(
        stamp_us + telemetry_after_us,
        &frame(100, &Message::Telemetry(t)),
    );
    let truth = EmuTruth {
        time_ms,
        ..EmuTruth::default()
    };
    m.receive_us(
        stamp_us + truth_after_us,
        &frame(101, &Message::EmuTruth(truth)),
    );
}

/// The commands the station sent (heartbeats and other frames left out).
fn commands_sent(m: &mut LinkMachine) -> Vec<(u16, Command)> {
    sent(m)
        .into_iter()
        .filter_map(|f| f.2.map(|c| (f.0, c)))
        .collect()
}

#[test]
fn a_teleop_repeat_waits_for_the_end_of_the_robots_burst_and_a_key_press_goes_at_once() {
    use crate::link::line_phase::MARGIN_US;
    let mut m = machine();
    connect(&mut m);
    for k in 0..20 {
        burst(&mut m, k);
    }
    sent(&mut m);
    let teleop = Command::Teleop {
        v_mm_s: 100,
        w_mrad_s: 0,
    };
    // A repeat asked for 2 ms into burst 20: held to its end.
    let start = 1_000_000 + 20 * 20_000;
    m.submit_when(start + 2_000, 1, teleop, SendWhen::QuietLine);
    assert!(commands_sent(&mut m).is_empty(), "held");
    let release = start + 7_200 + MARGIN_US;
    assert_eq!(m.next_release_us(), Some(release));
    assert!(!m.awaiting_reply(), "a held command is not in flight");
    m.poll_us(release - 1);
    assert!(commands_sent(&mut m).is_empty());
    m.poll_us(release);
    let s = commands_sent(&mut m);
    assert_eq!(s.len(), 1);
    assert_eq!(s[0].1, teleop);
    assert_eq!(m.next_release_us(), None);
    // Its round trip is timed from the send, to the microsecond.
    let ack = Message::Ack(Ack {
        cmd_seq: s[0].0,
        info: AckInfo::Done,
    });
    m.receive_us(release + 2_345, &frame(102, &ack));
    assert_eq!(m.stats(1_500).rtt_ms.p50, Some(2.345));

    // A key press 3 ms into the next burst goes at once.
    let start = 1_000_000 + 21 * 20_000;
    m.submit_when(start + 3_000, 2, teleop, SendWhen::Now);
    assert_eq!(commands_sent(&mut m).len(), 1);
    burst(&mut m, 21);
    // A repeat asked for 2 ms into the burst after is held (superseding the press still
    // unanswered, as any newer teleop does); a key press 5 ms into it goes at once and
    // supersedes the held repeat.
    m.submit_when(start + 22_000, 3, teleop, SendWhen::QuietLine);
    assert!(commands_sent(&mut m).is_empty());
    m.take_events();
    m.submit_when(start + 25_000, 4, teleop, SendWhen::Now);
    assert_eq!(commands_sent(&mut m).len(), 1);
    let superseded: Vec<_> = outcomes(&m.take_events())
        .into_iter()
        .filter(|(_, o)| *o == CommandOutcome::Failed(CommandFailure::Superseded))
        .map(|(id, _)| id)
        .collect();
    assert_eq!(superseded, vec![3]);
    assert_eq!(m.next_release_us(), None);
}

#[test]
fn a_repeat_goes_at_once_when_no_burst_is_known() {
    let mut m = machine();
    connect(&mut m);
    sent(&mut m);
    let teleop = Command::Teleop {
        v_mm_s: 100,
        w_mrad_s: 0,
    };
    m.submit_when(50_000, 1, teleop, SendWhen::QuietLine);
    assert_eq!(
        commands_sent(&mut m).len(),
        1,
        "no telemetry: nothing to wait for"
    );
}

#[test]
fn a_repeat_goes_at_once_when_the_robots_clock_runs_faster_than_ours() {
    // An emulator at ten times real time: a burst stamped every 20 ms of its clock comes every
    // 2 ms of ours. Read through the stamps, the next burst would seem 20 ms away and a
    // repeat asked for 3 ms after the last one would be held for 17 ms.
    let mut m = machine();
    connect(&mut m);
    let base = 1_000_000;
    let mut last_truth_us = 0;
    for k in 0..40u64 {
        let stamp_us = base + k * 2_000;
        burst_at(&mut m, stamp_us, (k * 20) as u32, 540, 720);
        last_truth_us = stamp_us + 720;
    }
    sent(&mut m);
    let teleop = Command::Teleop {
        v_mm_s: 100,
        w_mrad_s: 0,
    };
    m.submit_when(last_truth_us + 3_000, 1, teleop, SendWhen::QuietLine);
    assert_eq!(commands_sent(&mut m).len(), 1, "not held");
    assert_eq!(m.next_release_us(), None);
}
