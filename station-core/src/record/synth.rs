//! Recordings made from messages instead of a link: known content for tests, benchmarks and
//! examples.
//!
//! Layer: pure; builds the bytes of a recording file with the real frame encoder, each side
//! numbering its frames as PROTOCOL.md §3 says (the emulator's `EmuTruth` on its own counter).
//! `demo` is a whole session: handshake, telemetry and truth at a rate, a command and its ack,
//! a log line and an event. Cannot fail: every message built here fits a frame.

use protocol::{
    caps, encode, Ack, AckInfo, Command, EmuTruth, Event, EventCode, HelloReply, Log, LogLevel,
    MapCapacity, Message, Mode, Packed10x8, Pose, ProfileId, Telemetry, FINGERPRINT, MAX_FRAME,
    PROTOCOL_VERSION,
};

use super::live::link_record;
use super::{encode_header, encode_record, Meta, RecordKind, StationLine};
use crate::link::{Connection, PeerInfo};

/// A recording being built.
pub struct Synth {
    bytes: Vec<u8>,
    robot_seq: u16,
    truth_seq: u16,
    station_seq: u16,
}

impl Synth {
    pub fn new(meta: &Meta) -> Synth {
        Synth {
            bytes: encode_header(meta),
            robot_seq: 0,
            truth_seq: 0,
            station_seq: 0,
        }
    }

    fn frame(seq: u16, msg: &Message<'_>) -> Vec<u8> {
        let mut buf = [0u8; MAX_FRAME];
        let n = encode(seq, msg, &mut buf).unwrap_or(0);
        buf.get(..n).unwrap_or(&[]).to_vec()
    }

    /// Raw bytes in a record.
    pub fn raw(&mut self, t_us: u64, kind: RecordKind, data: &[u8]) {
        encode_record(&mut self.bytes, t_us, kind, 0, data);
    }

    /// A frame from the robot (truth frames on their own counter).
    pub fn from_robot(&mut self, t_us: u64, msg: &Message<'_>) {
        let seq = if matches!(msg, Message::EmuTruth(_)) {
            self.truth_seq = self.truth_seq.wrapping_add(1);
            self.truth_seq.wrapping_sub(1)
        } else {
            self.robot_seq = self.robot_seq.wrapping_add(1);
            self.robot_seq.wrapping_sub(1)
        };
        let f = Self::frame(seq, msg);
        self.raw(t_us, RecordKind::FromRobot, &f);
    }

    /// A frame from the station; returns its sequence number.
    pub fn to_robot(&mut self, t_us: u64, msg: &Message<'_>) -> u16 {
        let seq = self.station_seq;
        self.station_seq = seq.wrapping_add(1);
        let f = Self::frame(seq, msg);
        self.raw(t_us, RecordKind::ToRobot, &f);
        seq
    }

    /// A connection change.
    pub fn link(&mut self, t_us: u64, c: &Connection) {
        let (state, text) = link_record(c);
        let mut data = vec![state.code()];
        data.extend_from_slice(text.as_bytes());
        self.raw(t_us, RecordKind::Link, &data);
    }

    /// A line of the station's log.
    pub fn station_log(&mut self, t_us: u64, line: &StationLine) {
        self.raw(t_us, RecordKind::StationLog, &line.encode());
    }

    /// The opening of a session with `peer`: handshaking, the station's wake-up byte and
    /// `Hello`, the robot's accepting `HelloReply` at 5 ms, connected at 5.1 ms.
    pub fn handshake(&mut self, peer: PeerInfo) {
        self.handshake_at(0, peer);
    }

    /// The same starting at `t0_us` (a session after a gap): handshaking at `t0_us`, the reply
    /// 5 ms later, connected 5.1 ms later.
    pub fn handshake_at(&mut self, t0_us: u64, peer: PeerInfo) {
        self.link(
            t0_us,
            &Connection::Handshaking {
                port: "memory".into(),
            },
        );
        self.raw(t0_us + 100, RecordKind::ToRobot, &[0]);
        self.to_robot(
            t0_us + 100,
            &Message::Hello(protocol::Hello {
                fingerprint: FINGERPRINT,
                protocol: PROTOCOL_VERSION,
                session: peer.session,
                station: "synth",
            }),
        );
        self.from_robot(
            t0_us + 5_000,
            &Message::HelloReply(HelloReply {
                fingerprint: FINGERPRINT,
                protocol: PROTOCOL_VERSION,
                session: peer.session,
                accepted: true,
                firmware: "robot-firmware",
                firmware_version: "0.1.0",
                profile: peer.profile,
                capabilities: peer.capabilities,
                map_capacity: peer.map_capacity,
                telemetry_hz: 10,
                failsafe_ms: 300,
                robot_id: peer.robot_id,
            }),
        );
        self.link(t0_us + 5_100, &Connection::Connected(peer));
    }

    /// The file's bytes, finished with an end record.
    pub fn finish(mut self, t_us: u64, reason: &str) -> Vec<u8> {
        encode_record(&mut self.bytes, t_us, RecordKind::End, 0, reason.as_bytes());
        self.bytes
    }

    /// The file's bytes without an end record (as a crash leaves a `.partial`).
    pub fn unfinished(self) -> Vec<u8> {
        self.bytes
    }
}

/// Several one-link recordings as one file of as many links (format version 2), link `i`
/// holding `parts[i]`'s records, interleaved by time as a fleet's recorder writes them; the
/// header is the first part's with every part's port in `links`. Ends with one end record at
/// the last time. Parts that are not whole recordings are left out.
pub fn merge(parts: &[Vec<u8>], reason: &str) -> Vec<u8> {
    let recs: Vec<super::Recording> = parts
        .iter()
        .filter_map(|p| super::Recording::parse_strict(p).ok())
        .collect();
    let mut meta = recs.first().map(|r| r.meta.clone()).unwrap_or_default();
    meta.links = recs.iter().map(|r| r.meta.port.clone()).collect();
    meta.port = meta.links.join(", ");
    let mut all: Vec<(u64, u8, &super::Record)> = Vec::new();
    for (i, r) in recs.iter().enumerate() {
        let link = u8::try_from(i).unwrap_or(u8::MAX);
        all.extend(
            r.records
                .iter()
                .filter(|x| x.kind != RecordKind::End)
                .map(|x| (x.t_us, link, x)),
        );
    }
    // Stable: each link's own order is kept at equal times.
    all.sort_by_key(|&(t, ..)| t);
    let mut bytes = encode_header(&meta);
    let mut last = 0;
    for (t, link, r) in all {
        encode_record(&mut bytes, t, r.kind, link, &r.data);
        last = t;
    }
    encode_record(&mut bytes, last, RecordKind::End, 0, reason.as_bytes());
    bytes
}

/// The robot a demo recording talks to.
pub fn demo_peer() -> PeerInfo {
    PeerInfo {
        session: 0x5eed,
        firmware: "robot-firmware".into(),
        firmware_version: "0.1.0".into(),
        profile: ProfileId::Khepera,
        capabilities: caps::ENCODERS | caps::IR_PROXIMITY | caps::AMBIENT_LIGHT | caps::EMULATED,
        map_capacity: MapCapacity {
            width: 64,
            height: 64,
        },
        telemetry_hz: 10,
        failsafe_ms: 300,
        robot_id: 1,
    }
}

/// Telemetry number `i` of a robot driving a slow circle.
pub fn telemetry(i: u32, hz: u32) -> Telemetry {
    let t = f64::from(i) / f64::from(hz.max(1));
    let a = t * 0.2;
    Telemetry {
        time_ms: (t * 1000.0) as u32,
        mode: Mode::Wander,
        pose: Pose {
            x_mm: (1000.0 + 500.0 * a.cos()) as i32,
            y_mm: (1000.0 + 500.0 * a.sin()) as i32,
            heading_mrad: ((a + std::f64::consts::FRAC_PI_2)
                .sin()
                .atan2((a + std::f64::consts::FRAC_PI_2).cos())
                * 1000.0) as i16,
        },
        ir: Packed10x8::new([(i % 1024) as u16, 10, 20, 30, 40, 50, 60, 70]),
        light: Packed10x8::new([500; 8]),
        compass_ddeg: ((a.to_degrees().rem_euclid(360.0)) * 10.0) as u16,
        battery_mv: 7400,
        ..Telemetry::default()
    }
}

/// A whole session of `seconds` at `hz`: the handshake (both sides), telemetry and truth,
/// heartbeats, a `SetMode` answered by an Ack, a log line and an event.
pub fn demo(seconds: u32, hz: u32) -> Vec<u8> {
    demo_robot(seconds, hz, 1, "memory")
}

/// `demo` of the robot with id `robot_id` on `port` (the parts of a fleet recording, `merge`).
pub fn demo_robot(seconds: u32, hz: u32, robot_id: u8, port: &str) -> Vec<u8> {
    let meta = Meta {
        created_unix_ms: 1_700_000_000_000,
        writer: "synth".into(),
        port: port.into(),
        baud: 115_200,
        protocol: PROTOCOL_VERSION,
        ..Meta::default()
    };
    let mut s = Synth::new(&meta);
    s.handshake(PeerInfo {
        robot_id,
        ..demo_peer()
    });
    let period_us = 1_000_000 / u64::from(hz.max(1));
    let mut cmd_seq = None;
    for i in 0..seconds * hz {
        let t_us = 10_000 + u64::from(i) * period_us;
        let tm = telemetry(i, hz);
        s.from_robot(t_us, &Message::Telemetry(tm));
        s.from_robot(
            t_us + 200,
            &Message::EmuTruth(EmuTruth {
                time_ms: tm.time_ms,
                pose: Pose {
                    x_mm: tm.pose.x_mm + 7,
                    ..tm.pose
                },
                collisions: 0,
                robot_id,
            }),
        );
        if i % (hz / 4).max(1) == 0 {
            s.to_robot(
                t_us + 300,
                &Message::Heartbeat(protocol::Heartbeat {
                    time_ms: (t_us / 1000) as u32,
                }),
            );
        }
        if i == hz {
            cmd_seq = Some(s.to_robot(
                t_us + 400,
                &Message::Command(Command::SetMode(Mode::Wander)),
            ));
        }
        if let (Some(seq), true) = (cmd_seq, i == hz + 1) {
            s.from_robot(
                t_us + 400,
                &Message::Ack(Ack {
                    cmd_seq: seq,
                    info: AckInfo::Done,
                }),
            );
            s.from_robot(
                t_us + 500,
                &Message::Event(Event {
                    code: EventCode::ModeChanged,
                    value: 3,
                }),
            );
            s.from_robot(
                t_us + 600,
                &Message::Log(Log {
                    level: LogLevel::Info,
                    text: "wandering",
                }),
            );
        }
    }
    let end = 10_000 + u64::from(seconds * hz) * period_us;
    s.finish(end, "synthetic")
}
