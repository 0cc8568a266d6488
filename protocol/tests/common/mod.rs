//! Proptest strategies for every message, and a few fixed samples.
#![allow(dead_code)]
#![allow(clippy::unwrap_used, clippy::panic)]

use proptest::prelude::*;
use protocol::*;

/// A message that owns its borrowed parts, so a strategy can produce it.
#[derive(Clone, Debug)]
pub enum OwnedMsg {
    Hello {
        fingerprint: [u8; 8],
        protocol: u8,
        session: u32,
        station: String,
    },
    HelloReply {
        base: HelloFixed,
        firmware: String,
        version: String,
    },
    /// The retired kind-8 chunk (still decoded).
    Chunk {
        id: u32,
        offset: u32,
        data: Vec<u8>,
    },
    /// A `TransferData` chunk (kind 17).
    Data {
        tag: u8,
        offset: u32,
        data: Vec<u8>,
    },
    Log {
        level: LogLevel,
        text: String,
    },
    Plain(Message<'static>),
}

/// The non-borrowed fields of `HelloReply`.
#[derive(Clone, Copy, Debug)]
pub struct HelloFixed {
    pub fingerprint: [u8; 8],
    pub protocol: u8,
    pub session: u32,
    pub accepted: bool,
    pub profile: ProfileId,
    pub capabilities: u32,
    pub map_capacity: MapCapacity,
    pub telemetry_hz: u8,
    pub failsafe_ms: u16,
    pub robot_id: u8,
}

impl OwnedMsg {
    pub fn as_message(&self) -> Message<'_> {
        match self {
            OwnedMsg::Hello {
                fingerprint,
                protocol,
                session,
                station,
            } => Message::Hello(Hello {
                fingerprint: *fingerprint,
                protocol: *protocol,
                session: *session,
                station,
            }),
            OwnedMsg::HelloReply {
                base,
                firmware,
                version,
            } => Message::HelloReply(HelloReply {
                fingerprint: base.fingerprint,
                protocol: base.protocol,
                session: base.session,
                accepted: base.accepted,
                firmware,
                firmware_version: version,
                profile: base.profile,
                capabilities: base.capabilities,
                map_capacity: base.map_capacity,
                telemetry_hz: base.telemetry_hz,
                failsafe_ms: base.failsafe_ms,
                robot_id: base.robot_id,
            }),
            OwnedMsg::Chunk { id, offset, data } => Message::TransferChunk(TransferChunk {
                id: *id,
                offset: *offset,
                data,
            }),
            OwnedMsg::Data { tag, offset, data } => Message::TransferData(TransferData {
                tag: *tag,
                offset: *offset,
                data,
            }),
            OwnedMsg::Log { level, text } => Message::Log(Log {
                level: *level,
                text,
            }),
            OwnedMsg::Plain(m) => *m,
        }
    }
}

fn name() -> impl Strategy<Value = String> {
    proptest::string::string_regex("[ -~]{0,32}").expect("valid regex")
}

fn mode() -> impl Strategy<Value = Mode> {
    prop_oneof![
        Just(Mode::Idle),
        Just(Mode::Manual),
        Just(Mode::GoTo),
        Just(Mode::Wander),
        Just(Mode::EdgeFollowLeft),
        Just(Mode::EdgeFollowRight),
        Just(Mode::SeekLight),
        Just(Mode::Explore),
        Just(Mode::ExecutePlan),
    ]
}

fn pose() -> impl Strategy<Value = Pose> {
    (any::<i32>(), any::<i32>(), any::<i16>()).prop_map(|(x_mm, y_mm, heading_mrad)| Pose {
        x_mm,
        y_mm,
        heading_mrad,
    })
}

fn point() -> impl Strategy<Value = PointMm> {
    (any::<i32>(), any::<i32>()).prop_map(|(x_mm, y_mm)| PointMm { x_mm, y_mm })
}

fn object() -> impl Strategy<Value = ObjectKind> {
    prop_oneof![
        Just(ObjectKind::Map),
        Just(ObjectKind::Plan),
        Just(ObjectKind::Regions)
    ]
}

fn finite_f32() -> impl Strategy<Value = f32> {
    // NaN != NaN would make round-trip equality meaningless; the wire carries any bits.
    any::<f32>().prop_filter("finite", |v| v.is_finite())
}

pub fn packed() -> impl Strategy<Value = Packed10x8> {
    any::<[u16; 8]>().prop_map(|v| Packed10x8::new(v.map(|x| x % 1024)))
}

pub fn telemetry() -> impl Strategy<Value = Telemetry> {
    (
        (any::<u32>(), mode(), pose(), any::<(u16, u16)>()),
        (any::<[i16; 2]>(), any::<[u16; 2]>(), packed(), packed()),
        (any::<u16>(), any::<u8>(), any::<u8>(), any::<(i16, u8)>()),
        (any::<u16>(), any::<u8>(), any::<[i16; 2]>()),
        (any::<u32>(), any::<u32>(), any::<u8>()),
    )
        .prop_map(
            |(
                (time_ms, mode, pose, (sxy, sh)),
                (speed, enc, ir, light),
                (compass_ddeg, flags, line_events, (bearing, strength)),
                (battery_mv, active, motor),
                (period_us, busy_us, overruns),
            )| Telemetry {
                time_ms,
                mode,
                pose,
                sigma: PoseSigma {
                    xy_mm: sxy,
                    heading_mrad: sh,
                },
                wheels: Wheels {
                    speed_mm_s: speed,
                    encoders: enc,
                },
                ir,
                light,
                compass_ddeg,
                flags,
                line_events,
                beacon: Beacon {
                    bearing_ddeg: bearing,
                    strength,
                },
                battery_mv,
                behaviour: BehaviourOut {
                    active,
                    motor_mm_s: motor,
                },
                cycle: CycleTiming {
                    period_us,
                    busy_us,
                    overruns,
                },
            },
        )
}

pub fn command() -> impl Strategy<Value = Command> {
    prop_oneof![
        mode().prop_map(Command::SetMode),
        any::<(i16, i16)>().prop_map(|(v_mm_s, w_mrad_s)| Command::Teleop { v_mm_s, w_mrad_s }),
        Just(Command::Stop),
        point().prop_map(Command::GoTo),
        (any::<u16>(), finite_f32()).prop_map(|(id, value)| Command::SetParam {
            id: ParamId(id),
            value
        }),
        any::<u16>().prop_map(|id| Command::GetParam { id: ParamId(id) }),
        Just(Command::StartExploration),
        any::<u32>().prop_map(|plan_id| Command::ExecutePlan { plan_id }),
        Just(Command::Segment),
        (proptest::option::of(point()), proptest::option::of(point()))
            .prop_map(|(from, to)| Command::Plan { from, to }),
        any::<u8>().prop_map(|hz| Command::SetTelemetryRate { hz }),
        object().prop_map(|object| Command::Download { object }),
        pose().prop_map(|pose| Command::SetPose { pose }),
    ]
}

fn nack_reason() -> impl Strategy<Value = NackReason> {
    prop_oneof![
        Just(NackReason::NoHandshake),
        Just(NackReason::Unsupported),
        Just(NackReason::UnknownParam),
        Just(NackReason::OutOfRange),
        Just(NackReason::BadState),
        Just(NackReason::NoMap),
        Just(NackReason::NoPlan),
        Just(NackReason::PlanIdMismatch),
        Just(NackReason::BadPoint),
        Just(NackReason::Unreachable),
        Just(NackReason::CapacityExceeded),
        Just(NackReason::Busy),
    ]
}

fn transfer_status() -> impl Strategy<Value = TransferStatus> {
    prop_oneof![
        Just(TransferStatus::Receiving),
        Just(TransferStatus::Complete),
        Just(TransferStatus::AlreadyHave),
        Just(TransferStatus::CrcMismatch),
        Just(TransferStatus::Rejected),
        Just(TransferStatus::UnknownId),
    ]
}

fn event_code() -> impl Strategy<Value = EventCode> {
    prop_oneof![
        Just(EventCode::ModeChanged),
        Just(EventCode::GoalReached),
        Just(EventCode::FailsafeStop),
        Just(EventCode::Collision),
        Just(EventCode::LineCrossed),
        Just(EventCode::PoseCorrected),
        Just(EventCode::BeaconCalibration),
        Just(EventCode::MapUpdated),
        Just(EventCode::PlanInstalled),
        Just(EventCode::PlanFinished),
        Just(EventCode::PlanAborted),
        Just(EventCode::HandshakeRefused),
        Just(EventCode::ParamChanged),
    ]
}

fn level() -> impl Strategy<Value = LogLevel> {
    prop_oneof![
        Just(LogLevel::Debug),
        Just(LogLevel::Info),
        Just(LogLevel::Warn),
        Just(LogLevel::Error)
    ]
}

fn ack_info() -> impl Strategy<Value = AckInfo> {
    prop_oneof![
        Just(AckInfo::Done),
        (any::<u16>(), finite_f32()).prop_map(|(id, value)| AckInfo::Param {
            id: ParamId(id),
            value
        }),
        (object(), any::<u32>(), any::<u32>(), any::<u32>()).prop_map(|(object, id, len, crc)| {
            AckInfo::Object {
                object,
                id,
                len,
                crc,
            }
        }),
    ]
}

fn hello_fixed() -> impl Strategy<Value = HelloFixed> {
    (
        any::<[u8; 8]>(),
        any::<u8>(),
        any::<u32>(),
        any::<bool>(),
        prop_oneof![Just(ProfileId::Khepera), Just(ProfileId::MicroRato)],
        any::<u32>(),
        any::<(u16, u16)>(),
        any::<u8>(),
        any::<u16>(),
        any::<u8>(),
    )
        .prop_map(
            |(
                fingerprint,
                protocol,
                session,
                accepted,
                profile,
                capabilities,
                (w, h),
                telemetry_hz,
                failsafe_ms,
                robot_id,
            )| HelloFixed {
                fingerprint,
                protocol,
                session,
                accepted,
                profile,
                capabilities,
                map_capacity: MapCapacity {
                    width: w,
                    height: h,
                },
                telemetry_hz,
                failsafe_ms,
                robot_id,
            },
        )
}

/// Any message of any kind.
pub fn any_message() -> impl Strategy<Value = OwnedMsg> {
    prop_oneof![
        (any::<[u8; 8]>(), any::<u8>(), any::<u32>(), name()).prop_map(
            |(fingerprint, protocol, session, station)| OwnedMsg::Hello {
                fingerprint,
                protocol,
                session,
                station
            }
        ),
        (hello_fixed(), name(), name()).prop_map(|(base, firmware, version)| {
            OwnedMsg::HelloReply {
                base,
                firmware,
                version,
            }
        }),
        any::<u32>().prop_map(|time_ms| OwnedMsg::Plain(Message::Heartbeat(Heartbeat { time_ms }))),
        // As it travels: a field outside its range is brought in by the encoder
        // (`protocol::telemetry_range`), so only in-range telemetry decodes to itself.
        telemetry().prop_map(|t| OwnedMsg::Plain(Message::Telemetry(t.bounded()))),
        command().prop_map(|c| OwnedMsg::Plain(Message::Command(c))),
        (any::<u16>(), ack_info())
            .prop_map(|(cmd_seq, info)| OwnedMsg::Plain(Message::Ack(Ack { cmd_seq, info }))),
        (any::<u16>(), nack_reason())
            .prop_map(|(cmd_seq, reason)| OwnedMsg::Plain(Message::Nack(Nack { cmd_seq, reason }))),
        (
            object(),
            any::<u32>(),
            any::<u32>(),
            any::<u32>(),
            any::<u8>()
        )
            .prop_map(|(object, id, len, crc, tag)| {
                OwnedMsg::Plain(Message::TransferBegin(TransferBegin {
                    object,
                    id,
                    len,
                    crc,
                    tag,
                }))
            }),
        (
            any::<u32>(),
            any::<u32>(),
            proptest::collection::vec(any::<u8>(), 0..=MAX_CHUNK)
        )
            .prop_map(|(id, offset, data)| OwnedMsg::Chunk { id, offset, data }),
        (
            any::<u8>(),
            any::<u32>(),
            proptest::collection::vec(any::<u8>(), 0..=MAX_CHUNK)
        )
            .prop_map(|(tag, offset, data)| OwnedMsg::Data { tag, offset, data }),
        (any::<u8>(), any::<u32>(), transfer_status(), any::<u32>()).prop_map(
            |(tag, next, status, sack)| {
                OwnedMsg::Plain(Message::TransferAck(TransferAck {
                    tag,
                    next,
                    status,
                    sack,
                }))
            }
        ),
        (event_code(), any::<i32>())
            .prop_map(|(code, value)| OwnedMsg::Plain(Message::Event(Event { code, value }))),
        (
            level(),
            proptest::string::string_regex("[\\PC]{0,60}").expect("valid regex")
        )
            .prop_filter("fits MAX_LOG_TEXT", |(_, t)| t.len() <= MAX_LOG_TEXT)
            .prop_map(|(level, text)| OwnedMsg::Log { level, text }),
        (any::<u32>(), pose(), any::<u32>(), any::<u8>()).prop_map(
            |(time_ms, pose, collisions, robot_id)| {
                OwnedMsg::Plain(Message::EmuTruth(EmuTruth {
                    time_ms,
                    pose,
                    collisions,
                    robot_id,
                }))
            }
        ),
    ]
}

/// A telemetry frame with every field at its widest plausible value.
pub fn full_telemetry() -> Telemetry {
    Telemetry {
        // Over 2^28 ms (3.1 days) the time takes its maximum 5 varint bytes.
        time_ms: u32::MAX,
        mode: Mode::ExecutePlan,
        // Any pose inside +-8 m takes 3 bytes per coordinate.
        pose: Pose {
            x_mm: -8191,
            y_mm: 8191,
            heading_mrad: -3142,
        },
        sigma: PoseSigma {
            xy_mm: 16383,
            heading_mrad: 3142,
        },
        wheels: Wheels {
            speed_mm_s: [-4095, 4095],
            encoders: [u16::MAX, u16::MAX],
        },
        ir: Packed10x8::new([1023; 8]),
        light: Packed10x8::new([1023; 8]),
        compass_ddeg: 3599,
        flags: 0xFF,
        line_events: 255,
        beacon: Beacon {
            bearing_ddeg: -1800,
            strength: 255,
        },
        battery_mv: 9000,
        behaviour: BehaviourOut {
            active: 0x7F,
            motor_mm_s: [-4095, 4095],
        },
        cycle: CycleTiming {
            period_us: 2_000_000,
            busy_us: 16383,
            overruns: 255,
        },
    }
}
