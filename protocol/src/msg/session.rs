//! The handshake (PROTOCOL.md §4) and the link's keep-alive: `Hello`, `HelloReply` with the
//! robot's profile and capabilities, `Heartbeat`.

use postcard_schema::Schema;
use serde::{Deserialize, Serialize};

use super::FINGERPRINT_LEN;

/// Station -> robot, first frame of a session. Layout frozen across protocol versions:
/// `fingerprint` and `protocol` come first so that even a peer built from a different message
/// set can read them and refuse with a clear message.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct Hello<'a> {
    pub fingerprint: [u8; FINGERPRINT_LEN],
    pub protocol: u8,
    /// A nonce chosen by the station per session, echoed in `HelloReply`, so a reply from an
    /// earlier session cannot be mistaken for this one.
    pub session: u32,
    pub station: &'a str,
}

/// Robot -> station, the answer to `Hello`. Layout frozen like `Hello`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct HelloReply<'a> {
    pub fingerprint: [u8; FINGERPRINT_LEN],
    pub protocol: u8,
    pub session: u32,
    /// False when the robot refused the station's fingerprint or protocol version.
    pub accepted: bool,
    pub firmware: &'a str,
    pub firmware_version: &'a str,
    pub profile: ProfileId,
    /// `caps::*` bits: which sensors and features this robot has.
    pub capabilities: u32,
    pub map_capacity: MapCapacity,
    /// Current telemetry rate; 0 means off.
    pub telemetry_hz: u8,
    /// The robot's failsafe time in manual mode.
    pub failsafe_ms: u16,
    /// Which robot this is in a fleet (parameter `robot_id`, like MAVLink's system id): the
    /// station names the robot by it and reports two robots that give the same one. Last, so
    /// the frozen prefix (fingerprint, protocol) stays where a peer of another build reads it.
    pub robot_id: u8,
}

/// Which robot this is; selects the station's sensor layout.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub enum ProfileId {
    Khepera,
    MicroRato,
    /// ALICE (seed 001 §3.1): 24 whiskers, 24 photoresistors, odometry; sends
    /// `AliceSituation` (kind 16).
    Alice,
}

/// Capability bits carried in `HelloReply::capabilities`.
pub mod caps {
    pub const ENCODERS: u32 = 1 << 0;
    pub const IR_PROXIMITY: u32 = 1 << 1;
    pub const AMBIENT_LIGHT: u32 = 1 << 2;
    pub const COMPASS: u32 = 1 << 3;
    pub const GROUND_SENSOR: u32 = 1 << 4;
    pub const LINE_SENSOR: u32 = 1 << 5;
    pub const BEACON: u32 = 1 << 6;
    pub const BATTERY: u32 = 1 << 7;
    pub const GRIPPER: u32 = 1 << 8;
    /// The robot can segment its map and plan on it (seed 004 §6).
    pub const ONBOARD_PLANNING: u32 = 1 << 9;
    /// The robot accepts map and plan transfers.
    pub const TRANSFERS: u32 = 1 << 10;
    /// The robot corrects its odometry with a floor grid and sends `Localization` (seed 003).
    pub const LINE_CORRECTION: u32 = 1 << 11;
    /// The K213 line camera turret (seed 000 §1.1, §6.2: landmark bearings).
    pub const CAMERA: u32 = 1 << 13;
    /// The peer is the emulator and sends `EmuTruth`.
    pub const EMULATED: u32 = 1 << 31;
}

/// Largest map the robot can hold, in cells.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct MapCapacity {
    pub width: u16,
    pub height: u16,
}

/// Either side, periodically; keeps the link and the robot's failsafe alive.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct Heartbeat {
    /// The sender's monotonic clock, milliseconds, wrapping.
    pub time_ms: u32,
}
