//! Received messages copied out of the decoder's buffer, so the machine can act on them while
//! mutating itself.

use super::*;

/// A received message copied out of the decoder's buffer, so the machine can act on it while
/// mutating itself.
pub(super) enum Owned {
    HelloReply(OwnedHelloReply),
    Telemetry(protocol::Telemetry),
    Truth(protocol::EmuTruth),
    Localization(Box<protocol::Localization>),
    Progress(protocol::Progress),
    Situation(protocol::AliceSituation),
    Ack(protocol::Ack),
    Nack(protocol::Nack),
    Event(protocol::Event),
    Log {
        level: protocol::LogLevel,
        text: String,
    },
    Transfer(TransferIn),
    /// A heartbeat's time: the robot's clock.
    Heartbeat(u32),
    Other,
}

pub(super) struct OwnedHelloReply {
    pub(super) fingerprint: [u8; protocol::FINGERPRINT_LEN],
    pub(super) protocol: u8,
    pub(super) session: u32,
    pub(super) accepted: bool,
    pub(super) firmware: String,
    pub(super) firmware_version: String,
    pub(super) profile: protocol::ProfileId,
    pub(super) capabilities: u32,
    pub(super) map_capacity: protocol::MapCapacity,
    pub(super) telemetry_hz: u8,
    pub(super) failsafe_ms: u16,
    pub(super) robot_id: u8,
}

impl From<Message<'_>> for Owned {
    fn from(m: Message<'_>) -> Self {
        match m {
            Message::HelloReply(r) => Owned::HelloReply(owned_reply(&r)),
            Message::Telemetry(t) => Owned::Telemetry(t),
            Message::EmuTruth(t) => Owned::Truth(t),
            Message::Localization(l) => Owned::Localization(Box::new(l)),
            Message::Progress(p) => Owned::Progress(p),
            Message::AliceSituation(s) => Owned::Situation(s),
            Message::Ack(a) => Owned::Ack(a),
            Message::Nack(n) => Owned::Nack(n),
            Message::Event(e) => Owned::Event(e),
            Message::Log(l) => Owned::Log {
                level: l.level,
                text: printable(l.text).into_owned(),
            },
            Message::TransferBegin(b) => Owned::Transfer(TransferIn::Begin(b)),
            Message::TransferData(c) => Owned::Transfer(TransferIn::Chunk {
                tag: c.tag,
                offset: c.offset,
                data: c.data.to_vec(),
            }),
            Message::TransferAck(a) => Owned::Transfer(TransferIn::Ack(a)),
            Message::Heartbeat(h) => Owned::Heartbeat(h.time_ms),
            // The hardware trace is kept with the link's bytes by a recording and read by
            // `station retrace`; the live views have no use for it.
            // Protocol 1's chunk (kind 8, retired): no robot of this build sends it.
            Message::Hello(_)
            | Message::Command(_)
            | Message::HalTrace(_)
            | Message::TransferChunk(_) => Owned::Other,
        }
    }
}

pub(super) fn owned_reply(r: &HelloReply<'_>) -> OwnedHelloReply {
    OwnedHelloReply {
        fingerprint: r.fingerprint,
        protocol: r.protocol,
        session: r.session,
        accepted: r.accepted,
        // Robot-supplied text is made printable once, here: every screen, message and
        // report (the schema-mismatch refusal, `station stats`) then shows it safely.
        firmware: printable(r.firmware).into_owned(),
        firmware_version: printable(r.firmware_version).into_owned(),
        profile: r.profile,
        capabilities: r.capabilities,
        map_capacity: r.map_capacity,
        telemetry_hz: r.telemetry_hz,
        failsafe_ms: r.failsafe_ms,
        robot_id: r.robot_id,
    }
}

/// Hex digits of a fingerprint, as PROTOCOL.md prints it.
pub(super) fn is_handshake_refusal(msg: &Message<'_>) -> bool {
    matches!(msg, Message::Event(e) if e.code == EventCode::HandshakeRefused)
}
