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

// This file is loaded by `#[path]`, so its own modules' paths start from `link/`.
#[path = "machine_tests/auth_tests.rs"]
mod auth_tests;
#[path = "machine_tests/pacing_tests.rs"]
mod pacing_tests;
#[path = "machine_tests/renewal_tests.rs"]
mod renewal_tests;
