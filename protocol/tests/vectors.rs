//! PROTOCOL.md's hex test vectors, checked byte for byte against the encoder and decoder, and
//! the schema fingerprint pinned so that a change to the message set cannot slip by unnoticed.
//!
//! To regenerate the document's blocks after a deliberate change:
//! `PRINT_VECTORS=1 cargo test -p protocol --test vectors -- --nocapture`.

#![allow(clippy::unwrap_used, clippy::panic)]

use protocol::*;

fn hex(bytes: &[u8]) -> String {
    bytes
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// (name, seq, message): the vectors PROTOCOL.md documents.
fn vectors() -> Vec<(&'static str, u16, Message<'static>)> {
    let telemetry = Telemetry {
        time_ms: 123_456,
        mode: Mode::Manual,
        pose: Pose {
            x_mm: 1500,
            y_mm: -250,
            heading_mrad: 1571,
        },
        sigma: PoseSigma {
            xy_mm: 12,
            heading_mrad: 35,
        },
        wheels: Wheels {
            speed_mm_s: [100, -100],
            encoders: [1250, 64000],
        },
        ir: Packed10x8::new([0, 5, 512, 1023, 1, 2, 3, 4]),
        light: Packed10x8::new([500; 8]),
        compass_ddeg: 900,
        flags: flags::LINE | flags::HAS_MAP,
        line_events: 3,
        beacon: Beacon {
            bearing_ddeg: -450,
            strength: 200,
        },
        battery_mv: 7400,
        behaviour: BehaviourOut {
            active: behaviours::AVOID | behaviours::DRIFT,
            motor_mm_s: [80, 120],
        },
        cycle: CycleTiming {
            period_us: 80_000,
            busy_us: 350,
            overruns: 0,
        },
    };
    vec![
        (
            "hello",
            0,
            Message::Hello(Hello {
                fingerprint: FINGERPRINT,
                protocol: PROTOCOL_VERSION,
                session: 0xC0FFEE,
                station: "station",
            }),
        ),
        (
            "hello-reply",
            0,
            Message::HelloReply(HelloReply {
                fingerprint: FINGERPRINT,
                protocol: PROTOCOL_VERSION,
                session: 0xC0FFEE,
                accepted: true,
                firmware: "robot-firmware",
                firmware_version: "0.1.0",
                profile: ProfileId::MicroRato,
                capabilities: caps::COMPASS
                    | caps::IR_PROXIMITY
                    | caps::BEACON
                    | caps::GROUND_SENSOR,
                map_capacity: MapCapacity {
                    width: 64,
                    height: 64,
                },
                telemetry_hz: 10,
                failsafe_ms: 300,
                robot_id: 1,
            }),
        ),
        (
            "heartbeat",
            7,
            Message::Heartbeat(Heartbeat { time_ms: 1000 }),
        ),
        ("telemetry", 300, Message::Telemetry(telemetry)),
        (
            "teleop",
            41,
            Message::Command(Command::Teleop {
                v_mm_s: 150,
                w_mrad_s: -500,
            }),
        ),
        (
            "set-param",
            42,
            Message::Command(Command::SetParam {
                id: ParamId(3),
                value: 0.25,
            }),
        ),
        (
            "plan-on-robot",
            43,
            Message::Command(Command::Plan {
                from: None,
                to: Some(PointMm {
                    x_mm: 3000,
                    y_mm: 2571,
                }),
            }),
        ),
        (
            // Issue 16: object kind 3 is downloadable, and no `offset` follows it.
            "download",
            47,
            Message::Command(Command::Download {
                object: ObjectKind::LightCalibration,
            }),
        ),
        (
            "ack-param",
            9,
            Message::Ack(Ack {
                cmd_seq: 42,
                info: AckInfo::Param {
                    id: ParamId(3),
                    value: 0.25,
                },
            }),
        ),
        (
            "nack",
            10,
            Message::Nack(Nack {
                cmd_seq: 41,
                reason: NackReason::NoHandshake,
            }),
        ),
        (
            "transfer-begin",
            44,
            Message::TransferBegin(TransferBegin {
                object: ObjectKind::Map,
                id: 0x1234_5678,
                len: 293,
                crc: 0x1234_5678,
                tag: 5,
            }),
        ),
        (
            "transfer-chunk",
            45,
            Message::TransferData(TransferData {
                tag: 5,
                offset: 224,
                data: &[0, 1, 2, 0, 255],
            }),
        ),
        (
            "transfer-ack",
            46,
            Message::TransferAck(TransferAck {
                tag: 5,
                next: 64,
                status: TransferStatus::Receiving,
                sack: 0b1011,
            }),
        ),
        (
            "progress",
            12,
            Message::Progress(Progress {
                mode: Mode::ExecutePlan,
                waypoint: 3,
                waypoints: 9,
                distance_left_mm: Some(2140),
                elapsed_ms: 41_000,
                stuck_ms: 12_000,
                give_up_ms: 40_000,
            }),
        ),
        (
            "event-no-progress",
            13,
            Message::Event(Event {
                code: EventCode::NoProgress,
                value: 40_050,
            }),
        ),
        (
            "hal-trace",
            14,
            // STEP 50 ms after the last pass, MOTORS (8, 8): PROTOCOL.md §17.
            Message::HalTrace(HalTrace {
                offset: 384,
                dropped_steps: 0,
                data: &[0x03, 0xd0, 0x86, 0x03, 0x16, 0x10, 0x10],
            }),
        ),
        (
            "log",
            11,
            Message::Log(Log {
                level: LogLevel::Warn,
                text: "wall lost",
            }),
        ),
    ]
}

/// The wire bytes PROTOCOL.md gives for vector `name`.
fn documented_wire(doc: &str, name: &str) -> Option<Vec<u8>> {
    let marker = format!("vector `{name}`");
    let start = doc.find(&marker)?;
    let block = &doc[start..];
    let line = block
        .lines()
        .find(|l| l.trim_start().starts_with("wire:"))?;
    line.trim_start()
        .trim_start_matches("wire:")
        .split_whitespace()
        .map(|h| u8::from_str_radix(h, 16).ok())
        .collect()
}

#[test]
fn protocol_md_vectors_match_the_encoder_and_decoder_byte_for_byte() {
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/PROTOCOL.md"))
        .expect("PROTOCOL.md beside the crate");
    let print = std::env::var_os("PRINT_VECTORS").is_some();
    let mut checked = 0;
    for (name, seq, msg) in vectors() {
        let mut buf = [0u8; MAX_FRAME];
        let n = encode(seq, &msg, &mut buf).expect("fits");
        let wire = &buf[..n];
        let mut payload = [0u8; MAX_FRAME];
        let raw = cobs::decode(&wire[..n - 1], &mut payload)
            .expect("cobs")
            .frame_size();
        let block = format!(
            "vector `{name}`: seq {seq}, `{msg:?}`\n\n    payload: {}\n    raw:     {}\n    \
             wire:    {}\n",
            hex(&payload[4..raw - 4]),
            hex(&payload[..raw]),
            hex(wire)
        );
        if print {
            println!("{block}");
            continue;
        }
        // The whole block, not only the wire line: the message text, the payload and the raw
        // frame are what a client written from the document reads (issue 16: the text once
        // gave other fingerprint bytes than the vector).
        assert!(
            doc.contains(&block),
            "PROTOCOL.md's vector `{name}` differs from the encoder; it should read:\n{block}"
        );
        let documented = documented_wire(&doc, name)
            .unwrap_or_else(|| panic!("PROTOCOL.md lacks vector `{name}` or its wire: line"));
        assert_eq!(
            hex(&documented),
            hex(wire),
            "vector `{name}` differs from PROTOCOL.md"
        );
        let mut dec = FrameDecoder::new();
        match dec.feed(&documented) {
            Feed::Frame { frame, rest } => {
                assert!(rest.is_empty());
                assert_eq!(frame.header.seq, seq);
                assert_eq!(
                    frame.message, msg,
                    "vector `{name}` decodes to another message"
                );
            }
            other => panic!("vector `{name}` does not decode: {other:?}"),
        }
        checked += 1;
    }
    assert!(print || checked >= 6);
}

#[test]
fn the_fingerprint_is_the_one_protocol_md_states() {
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/PROTOCOL.md"))
        .expect("PROTOCOL.md beside the crate");
    let fp = hex(&FINGERPRINT);
    println!("fingerprint: {fp}");
    assert!(
        doc.contains(&format!("fingerprint: {fp}")),
        "the message set changed: fingerprint is now {fp}; update PROTOCOL.md (and the vectors)"
    );
}

#[test]
fn the_crc_is_crc32c_with_the_standard_check_value() {
    assert_eq!(crc32c(b"123456789"), 0xE306_9283);
}

#[test]
fn kind_numbers_follow_the_message_enum_order() {
    // The fingerprint hashes the enum's variant order; the header kind byte must agree with it.
    for (i, kind) in Kind::ALL.iter().enumerate() {
        assert_eq!(*kind as usize, i);
        assert_eq!(Kind::from_u8(i as u8), Some(*kind));
    }
    assert_eq!(Kind::from_u8(Kind::ALL.len() as u8), None);
    for (_, _, msg) in vectors() {
        let expected = format!("{msg:?}");
        assert!(expected.starts_with(&format!("{:?}", msg.kind())));
    }
}

/// PROTOCOL.md §2: a decoded frame of the full 254 bytes with no zero byte is one block of
/// code 255: 255 bytes, then the delimiter, 256 on the wire. COBS libraries that append a
/// final code byte after it (0x01) make 256 bytes before the delimiter, which a receiver of
/// this protocol drops as oversize: the document says so, and this pins both.
#[test]
fn a_254_byte_frame_without_zeros_is_255_cobs_bytes_and_no_more() {
    // Any 246-byte payload whose frame has no zero byte (the seq is chosen to keep the CRC
    // free of zeros).
    let payload = [0x55u8; MAX_PAYLOAD];
    let mut buf = [0u8; MAX_FRAME];
    let (seq, n) = (1u16..)
        .find_map(|seq| {
            let n = encode_raw(PROTOCOL_VERSION, Kind::Log as u8, seq, &payload, &mut buf).ok()?;
            (buf[..n - 1].iter().all(|&b| b != 0) && buf[0] == 0xFF && seq & 0xFF != 0)
                .then_some((seq, n))
        })
        .unwrap();
    assert_eq!(
        n, MAX_FRAME,
        "256 bytes on the wire, the delimiter included"
    );
    assert_eq!(buf[0], 0xFF, "one block of code 255");
    assert_eq!(buf[n - 1], 0);
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/PROTOCOL.md"))
        .expect("PROTOCOL.md beside the crate");
    assert!(
        doc.contains("a decoded frame of 254 bytes without a zero is 255 COBS bytes"),
        "PROTOCOL.md §2 states the 254-byte case"
    );
    // The frame arrives whole (its payload is no Log: the framing is what is checked).
    let mut dec = FrameDecoder::new();
    match dec.feed(&buf[..n]) {
        Feed::Error {
            error: FrameError::Undecodable { .. },
            ..
        } => {}
        other => panic!("the 256-byte frame did not pass the framing: {other:?} (seq {seq})"),
    }
    // With the extra final code byte some libraries add: oversize, dropped.
    let mut long = buf[..n - 1].to_vec();
    long.extend([0x01, 0x00]);
    let mut dec = FrameDecoder::new();
    match dec.feed(&long) {
        Feed::Error {
            error: FrameError::Oversize { .. },
            ..
        } => {}
        other => panic!("a 256-byte COBS body was not refused as oversize: {other:?}"),
    }
}
