//! The message set: every payload that crosses the link, for the whole product.
//!
//! Layer: wire types only, no I/O. Each message is one postcard payload; its kind travels in the
//! frame header (see `frame.rs`), and `Message` ties kinds to payload types. The order of the
//! `Message` variants IS the kind numbering, and the whole enum is hashed into the schema
//! fingerprint, so adding, removing, reordering or retyping anything here changes the
//! fingerprint and two builds that disagree refuse each other at handshake.
//!
//! Units are integers wherever the robot measures in integers: millimetres, milliradians,
//! decidegrees, millivolts, microseconds. That keeps telemetry small (postcard varints) and
//! makes the firmware's arithmetic exact.
//!
//! The types live by concern in `session` (handshake), `telemetry`, `commands`, `transfers`
//! and `reports` (events, logs, localization, progress, traces, situations), all re-exported
//! here; `Message`, its kinds and the mode stay in this file.

use postcard_schema::Schema;
use serde::{Deserialize, Serialize};

mod commands;
mod reports;
mod session;
mod telemetry;
mod transfers;

pub use commands::*;
pub use reports::*;
pub use session::*;
pub use telemetry::*;
pub use transfers::*;

/// Length of the schema fingerprint exchanged at handshake.
pub const FINGERPRINT_LEN: usize = 8;
/// Longest text in a `Log` message, in bytes of UTF-8.
pub const MAX_LOG_TEXT: usize = 200;
/// Longest name string in `Hello`/`HelloReply`, in bytes of UTF-8.
pub const MAX_NAME: usize = 32;
/// Largest data slice in one `TransferChunk`.
pub const MAX_CHUNK: usize = 224;

/// What the robot is doing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub enum Mode {
    /// Motors off, nothing runs.
    #[default]
    Idle,
    /// Teleop velocity from the station; the failsafe stops the motors on link silence.
    Manual,
    /// Drive to a point (seed 000 §4 drift + avoidance, or seed 004 guided motion).
    GoTo,
    /// Braitenberg obstacle avoidance only (seed 000 §4.1).
    Wander,
    /// Follow the wall on the left (seed 000 §4.2).
    EdgeFollowLeft,
    /// Follow the wall on the right.
    EdgeFollowRight,
    /// Drive to the brightest light (seed 000 §4, Braitenberg IIIa).
    SeekLight,
    /// Reactive goal search that maps as it goes (seed 004 §5, Fig. 4).
    Explore,
    /// Follow the installed plan's waypoints (seed 004 §7).
    ExecutePlan,
    /// Seed 000 §7 foraging: find lit sources, grip their objects, carry them home, drop.
    Forage,
    /// Seed 003 §2.6-2.7: a long random walk over the floor grid, the grid fitter steering so
    /// lines are crossed at an angle; starts floor-grid line correction.
    Survey,
    /// Seed 000 §5.3: turn on the spot next to a light and train the light -> angle map
    /// online; back to `Idle` with `EventCode::LightCalibrated` when done.
    CalibrateLight,
}

/// Every message, in kind order: variant index == the header's kind byte.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, Schema)]
pub enum Message<'a> {
    #[serde(borrow)]
    Hello(Hello<'a>),
    #[serde(borrow)]
    HelloReply(HelloReply<'a>),
    Heartbeat(Heartbeat),
    Telemetry(Telemetry),
    Command(Command),
    Ack(Ack),
    Nack(Nack),
    TransferBegin(TransferBegin),
    #[serde(borrow)]
    TransferChunk(TransferChunk<'a>),
    TransferAck(TransferAck),
    Event(Event),
    #[serde(borrow)]
    Log(Log<'a>),
    EmuTruth(EmuTruth),
    Localization(Localization),
    Progress(Progress),
    #[serde(borrow)]
    HalTrace(HalTrace<'a>),
    AliceSituation(AliceSituation),
    #[serde(borrow)]
    TransferData(TransferData<'a>),
}

/// The header's kind byte for each message.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Kind {
    Hello = 0,
    HelloReply = 1,
    Heartbeat = 2,
    Telemetry = 3,
    Command = 4,
    Ack = 5,
    Nack = 6,
    TransferBegin = 7,
    TransferChunk = 8,
    TransferAck = 9,
    Event = 10,
    Log = 11,
    EmuTruth = 12,
    Localization = 13,
    Progress = 14,
    HalTrace = 15,
    AliceSituation = 16,
    TransferData = 17,
}

impl Kind {
    /// Every kind, in numeric order.
    pub const ALL: [Kind; 18] = [
        Kind::Hello,
        Kind::HelloReply,
        Kind::Heartbeat,
        Kind::Telemetry,
        Kind::Command,
        Kind::Ack,
        Kind::Nack,
        Kind::TransferBegin,
        Kind::TransferChunk,
        Kind::TransferAck,
        Kind::Event,
        Kind::Log,
        Kind::EmuTruth,
        Kind::Localization,
        Kind::Progress,
        Kind::HalTrace,
        Kind::AliceSituation,
        Kind::TransferData,
    ];

    /// The kind for a header byte, or `None` for an unknown kind.
    pub fn from_u8(b: u8) -> Option<Kind> {
        Kind::ALL.get(usize::from(b)).copied()
    }
}

impl Message<'_> {
    /// Checks the string limits the layouts state (PROTOCOL.md §6: names at most `MAX_NAME`
    /// bytes); the encoder refuses and the decoder reports a message that breaks one, so a
    /// peer can size its buffers on them. Err: the field and its limit.
    pub fn check_limits(&self) -> Result<(), (&'static str, usize)> {
        let check = |field: &'static str, s: &str, limit: usize| {
            if s.len() > limit {
                Err((field, limit))
            } else {
                Ok(())
            }
        };
        match self {
            Message::Hello(h) => check("Hello.station", h.station, MAX_NAME),
            Message::HelloReply(r) => {
                check("HelloReply.firmware", r.firmware, MAX_NAME)?;
                check("HelloReply.firmware_version", r.firmware_version, MAX_NAME)
            }
            Message::TransferData(d) if d.data.len() > MAX_CHUNK => {
                Err(("TransferData.data", MAX_CHUNK))
            }
            _ => Ok(()),
        }
    }

    /// The header kind byte for this message.
    pub fn kind(&self) -> Kind {
        match self {
            Message::Hello(_) => Kind::Hello,
            Message::HelloReply(_) => Kind::HelloReply,
            Message::Heartbeat(_) => Kind::Heartbeat,
            Message::Telemetry(_) => Kind::Telemetry,
            Message::Command(_) => Kind::Command,
            Message::Ack(_) => Kind::Ack,
            Message::Nack(_) => Kind::Nack,
            Message::TransferBegin(_) => Kind::TransferBegin,
            Message::TransferChunk(_) => Kind::TransferChunk,
            Message::TransferAck(_) => Kind::TransferAck,
            Message::Event(_) => Kind::Event,
            Message::Log(_) => Kind::Log,
            Message::EmuTruth(_) => Kind::EmuTruth,
            Message::Localization(_) => Kind::Localization,
            Message::Progress(_) => Kind::Progress,
            Message::HalTrace(_) => Kind::HalTrace,
            Message::AliceSituation(_) => Kind::AliceSituation,
            Message::TransferData(_) => Kind::TransferData,
        }
    }
}
