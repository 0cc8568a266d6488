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

use postcard_schema::Schema;
use serde::{Deserialize, Serialize};

use crate::packed::Packed10x8;

/// Length of the schema fingerprint exchanged at handshake.
pub const FINGERPRINT_LEN: usize = 8;
/// Longest text in a `Log` message, in bytes of UTF-8.
pub const MAX_LOG_TEXT: usize = 200;
/// Longest name string in `Hello`/`HelloReply`, in bytes of UTF-8.
pub const MAX_NAME: usize = 32;
/// Largest data slice in one `TransferChunk`.
pub const MAX_CHUNK: usize = 224;

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

/// Robot pose estimate in the map frame: x right, y up, heading counter-clockwise from +x.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct Pose {
    pub x_mm: i32,
    pub y_mm: i32,
    pub heading_mrad: i16,
}

/// One-sigma uncertainty of the pose estimate.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct PoseSigma {
    pub xy_mm: u16,
    pub heading_mrad: u16,
}

/// Wheel state. Encoder counts wrap at 2^16; the station unwraps them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct Wheels {
    /// Measured (encoders) or estimated (no encoders) speed, left then right.
    pub speed_mm_s: [i16; 2],
    /// Cumulative encoder pulses, left then right; zero on robots without encoders.
    pub encoders: [u16; 2],
}

/// Beacon sensor reading (seed 004 §3).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct Beacon {
    /// Bearing of the beacon relative to the robot's heading, decidegrees, positive to the left.
    pub bearing_ddeg: i16,
    /// Signal strength 0..=255; 0 means not seen.
    pub strength: u8,
}

/// Bits of `Telemetry::flags`.
pub mod flags {
    /// Ground sensor sees the goal area (seed 004 §3).
    pub const GROUND: u8 = 1 << 0;
    /// Floor line sensor is over a line (seed 003).
    pub const LINE: u8 = 1 << 1;
    /// The robot's bumper or a wall contact was detected this cycle.
    pub const CONTACT: u8 = 1 << 2;
    /// The failsafe has stopped the motors.
    pub const FAILSAFE: u8 = 1 << 3;
    /// The current mode's goal was reached.
    pub const ARRIVED: u8 = 1 << 4;
    /// The robot holds a map.
    pub const HAS_MAP: u8 = 1 << 5;
    /// The robot holds a plan.
    pub const HAS_PLAN: u8 = 1 << 6;
    /// The gripper holds an object (its object-present sensor, seed 000 §7).
    pub const CARRYING: u8 = 1 << 7;
}

/// Failure values of `EventCode::LightCalibrated` (success is the number of examples, > 0).
pub mod calibration {
    /// No reading brighter than T1 = 470 during the first turn: no light near the robot.
    pub const NO_LIGHT: i32 = -1;
    /// The first turn did not give the light's direction (readings without a bright side).
    pub const NO_DIRECTION: i32 = -2;
    /// A turn took more than 4 times its nominal time (wheels blocked, robot wedged): the
    /// calibration gave up.
    pub const STALLED: i32 = -3;
}

/// Bits of `BehaviourOut::active` (seed 000 §4).
pub mod behaviours {
    pub const AVOID: u8 = 1 << 0;
    pub const EDGE: u8 = 1 << 1;
    pub const DRIFT: u8 = 1 << 2;
    pub const TURN: u8 = 1 << 3;
    pub const LIGHT: u8 = 1 << 4;
    pub const WALL_FOLLOW: u8 = 1 << 5;
    pub const GUIDED: u8 = 1 << 6;
}

/// What the behaviour arbitration produced this cycle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct BehaviourOut {
    /// `behaviours::*` bits of the behaviours that contributed.
    pub active: u8,
    /// The motor command sent, left then right, mm/s.
    pub motor_mm_s: [i16; 2],
}

/// Control-cycle timing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct CycleTiming {
    /// Time between the last two cycle starts.
    pub period_us: u32,
    /// Time the last cycle spent computing.
    pub busy_us: u32,
    /// Cycles that overran their period, wrapping.
    pub overruns: u8,
}

/// Robot -> station at the rate the station sets. Fields a profile lacks are zero; the
/// `HelloReply` capabilities say which are meaningful. It is serialised within the ranges of
/// `telemetry_range` (80 bytes on the wire at most), by the `Serialize` impl below.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Schema)]
pub struct Telemetry {
    pub time_ms: u32,
    pub mode: Mode,
    pub pose: Pose,
    pub sigma: PoseSigma,
    pub wheels: Wheels,
    /// IR proximity S0..S7, 10-bit (seed 000 §1.1); micro-rato uses S0..S2.
    pub ir: Packed10x8,
    /// Ambient light S0..S7, 10-bit, inverted: lower is brighter (seed 000 §4).
    pub light: Packed10x8,
    /// Compass heading, decidegrees 0..3599, counter-clockwise from the map's +x axis.
    pub compass_ddeg: u16,
    /// `flags::*` bits.
    pub flags: u8,
    /// Floor lines crossed so far, wrapping.
    pub line_events: u8,
    pub beacon: Beacon,
    pub battery_mv: u16,
    pub behaviour: BehaviourOut,
    pub cycle: CycleTiming,
}

/// `Telemetry`'s fields in the same order, serialised as derived: what `Telemetry` writes after
/// bringing each field into its range, so that no encoding path can send a wider frame.
#[derive(Serialize)]
#[serde(rename = "Telemetry")]
struct TelemetryFields {
    time_ms: u32,
    mode: Mode,
    pose: Pose,
    sigma: PoseSigma,
    wheels: Wheels,
    ir: Packed10x8,
    light: Packed10x8,
    compass_ddeg: u16,
    flags: u8,
    line_events: u8,
    beacon: Beacon,
    battery_mv: u16,
    behaviour: BehaviourOut,
    cycle: CycleTiming,
}

impl Serialize for Telemetry {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        // Destructured so that a field added to `Telemetry` but not here fails to compile.
        let Telemetry {
            time_ms,
            mode,
            pose,
            sigma,
            wheels,
            ir,
            light,
            compass_ddeg,
            flags,
            line_events,
            beacon,
            battery_mv,
            behaviour,
            cycle,
        } = self.bounded();
        TelemetryFields {
            time_ms,
            mode,
            pose,
            sigma,
            wheels,
            ir,
            light,
            compass_ddeg,
            flags,
            line_events,
            beacon,
            battery_mv,
            behaviour,
            cycle,
        }
        .serialize(s)
    }
}

/// Parameters settable over the link. Values travel as f32 in the parameter's unit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct ParamId(pub u16);

/// Map-frame point in millimetres.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct PointMm {
    pub x_mm: i32,
    pub y_mm: i32,
}

/// Station -> robot. Every command is answered by `Ack` or `Nack` carrying its frame's
/// sequence number; a retry reuses that number and is executed once.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, Schema)]
pub enum Command {
    SetMode(Mode),
    /// Manual mode velocity: forward speed and turn rate (counter-clockwise positive).
    Teleop {
        v_mm_s: i16,
        w_mrad_s: i16,
    },
    /// Stop the motors and switch to `Mode::Idle`.
    Stop,
    /// Drive to a point (switches to `Mode::GoTo`).
    GoTo(PointMm),
    SetParam {
        id: ParamId,
        value: f32,
    },
    GetParam {
        id: ParamId,
    },
    /// Reactive goal search with mapping (switches to `Mode::Explore`).
    StartExploration,
    /// Execute the installed plan with this object id (switches to `Mode::ExecutePlan`).
    ExecutePlan {
        plan_id: u32,
    },
    /// Segment the robot's map; the regions become object `ObjectKind::Regions`.
    Segment,
    /// Plan on the robot from `from` (default: current pose) to `to` (default: the goal);
    /// the result becomes object `ObjectKind::Plan`.
    Plan {
        from: Option<PointMm>,
        to: Option<PointMm>,
    },
    /// Telemetry rate in Hz; 0 stops telemetry.
    SetTelemetryRate {
        hz: u8,
    },
    /// Ask the robot to send an object. Where its chunks start is the station's answer to
    /// the robot's `TransferBegin` (a resume keeps the bytes held); the `offset` this command
    /// once carried was checked but never used, and is gone (issue 16).
    Download {
        object: ObjectKind,
    },
    /// Overwrite the pose estimate.
    SetPose {
        pose: Pose,
    },
}

/// Robot -> station: the command in frame `cmd_seq` was accepted.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, Schema)]
pub struct Ack {
    pub cmd_seq: u16,
    pub info: AckInfo,
}

/// Data an `Ack` carries back.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, Schema)]
pub enum AckInfo {
    Done,
    /// Reply to `GetParam` and `SetParam`: the value now in force.
    Param {
        id: ParamId,
        value: f32,
    },
    /// Reply to `Download`: the object that will follow in `TransferBegin` + chunks.
    Object {
        object: ObjectKind,
        id: u32,
        len: u32,
        crc: u32,
    },
}

/// Robot -> station: the command in frame `cmd_seq` was refused and changed nothing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct Nack {
    pub cmd_seq: u16,
    pub reason: NackReason,
}

/// Why a command was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub enum NackReason {
    /// No valid handshake yet: the robot executes nothing before `Hello` is accepted.
    NoHandshake,
    /// The robot lacks the hardware or feature (see `caps`).
    Unsupported,
    UnknownParam,
    /// A value outside the parameter's range, or a non-finite number.
    OutOfRange,
    /// Not allowed in the current mode or state.
    BadState,
    NoMap,
    NoPlan,
    /// `ExecutePlan` named a plan id the robot does not hold.
    PlanIdMismatch,
    /// The start or goal lies outside the map or in an obstacle.
    BadPoint,
    Unreachable,
    /// The robot's fixed capacity (map cells, regions, plan length) is too small.
    CapacityExceeded,
    /// Another transfer is in progress.
    Busy,
}

/// The objects that move by chunked transfer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub enum ObjectKind {
    Map,
    Plan,
    Regions,
    /// Seed 000 §5.3's light -> angle network (60 neurons x 6 inputs, in hundredths): trained
    /// on the robot (`Mode::CalibrateLight`) or by `station calibrate`, and moved either way.
    LightCalibration,
}

/// Sender -> receiver: an object of `len` bytes with CRC-32C `crc` follows in chunks.
/// `id` names the content (the station uses its CRC-32C of the content) so a receiver that
/// already holds it answers `AlreadyHave` and nothing is sent again. `tag` (1..=255, chosen
/// by the sender, different from its previous transfer's) names this transfer in its
/// `TransferData` chunks and in the receiver's answers: one byte instead of the 5-byte id in
/// every chunk. Last, so a build from before tags reads this frame as one with a trailing
/// byte and refuses it ("undecodable payload"), never as another Begin.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct TransferBegin {
    pub object: ObjectKind,
    pub id: u32,
    pub len: u32,
    pub crc: u32,
    pub tag: u8,
}

/// Kind 8, retired: protocol 1's chunk, which named the object by its 32-bit id and carried
/// a length. Still decoded (recordings made before tags hold it) and never sent; the robot
/// refuses it (`TransferAck` with tag 0, `Rejected`) and changes nothing, the station ignores
/// it. Chunks are [`TransferData`] (kind 17).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct TransferChunk<'a> {
    pub id: u32,
    pub offset: u32,
    pub data: &'a [u8],
}

/// Receiver -> sender: every byte before `next` of the transfer `tag` is held (cumulative
/// ack), and bit i of `sack` says the 32-byte unit `[next + 32 i, next + 32 i + 32)` past it
/// is held too (selective ack, PROTOCOL.md §8; 0 in every answer but `Receiving`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct TransferAck {
    pub tag: u8,
    pub next: u32,
    pub status: TransferStatus,
    pub sack: u32,
}

/// Sender -> receiver (kind 17): `data` belongs at `offset` of the transfer whose
/// `TransferBegin` carried `tag`. `data` runs to the end of the payload, with no length of
/// its own (the frame's delimiter bounds it): the payload is `tag`, `offset` as a varint,
/// then the bytes. Serialized and decoded by hand for that reason (`frame::decode_payload`);
/// serde's `Deserialize` cannot know where the data ends and refuses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TransferData<'a> {
    pub tag: u8,
    pub offset: u32,
    pub data: &'a [u8],
}

impl Serialize for TransferData<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeTuple;
        // A tuple has no length on the wire (postcard): tag, offset, then the bytes as they are.
        let mut t = s.serialize_tuple(2 + self.data.len())?;
        t.serialize_element(&self.tag)?;
        t.serialize_element(&self.offset)?;
        for b in self.data {
            t.serialize_element(b)?;
        }
        t.end()
    }
}

impl<'de> Deserialize<'de> for TransferData<'_> {
    fn deserialize<D: serde::Deserializer<'de>>(_: D) -> Result<Self, D::Error> {
        Err(serde::de::Error::custom(
            "TransferData's data runs to the end of the frame: decode it with frame::decode_payload",
        ))
    }
}

impl Schema for TransferData<'_> {
    const SCHEMA: &'static postcard_schema::schema::NamedType =
        &postcard_schema::schema::NamedType {
            name: "TransferData",
            ty: &postcard_schema::schema::DataModelType::Struct(&[
                &postcard_schema::schema::NamedValue {
                    name: "tag",
                    ty: u8::SCHEMA,
                },
                &postcard_schema::schema::NamedValue {
                    name: "offset",
                    ty: u32::SCHEMA,
                },
                &postcard_schema::schema::NamedValue {
                    name: "data",
                    ty: &postcard_schema::schema::NamedType {
                        name: "rest of the payload",
                        ty: &postcard_schema::schema::DataModelType::Seq(u8::SCHEMA),
                    },
                },
            ]),
        };
}

/// State of a transfer at the receiver.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub enum TransferStatus {
    /// Send from `next` on.
    Receiving,
    /// All bytes arrived, the CRC matched and the object is installed.
    Complete,
    /// The receiver already holds this id; nothing to send.
    AlreadyHave,
    /// All bytes arrived but the CRC did not match; the old object is kept. Start again.
    CrcMismatch,
    /// The object is larger than the receiver can hold, or malformed.
    Rejected,
    /// A chunk or ack named an id that is not the transfer in progress.
    UnknownId,
    /// The receiver cannot take this object now (the robot is calibrating the network the
    /// object would replace); nothing was changed. Try again later.
    Busy,
}

/// Robot -> station: something happened.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct Event {
    pub code: EventCode,
    pub value: i32,
}

/// What happened.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub enum EventCode {
    ModeChanged,
    GoalReached,
    /// Manual-mode failsafe stopped the motors; value = ms of silence.
    FailsafeStop,
    Collision,
    /// A floor line was crossed (seed 003); value = line events so far.
    LineCrossed,
    /// The pose was corrected; value = correction in mm.
    PoseCorrected,
    /// A beacon calibration ran (seed 004 §4); value = confidence xi in thousandths.
    BeaconCalibration,
    MapUpdated,
    PlanInstalled,
    PlanFinished,
    /// A plan step failed; value = waypoint index.
    PlanAborted,
    /// The station's fingerprint or version did not match; value = protocol version seen.
    /// Negative: the `Hello` failed link authentication, value = reason (PROTOCOL.md §13).
    HandshakeRefused,
    /// A parameter changed; value = parameter id.
    ParamChanged,
    /// Foraging (seed 000 §7): the gripper closed on an object at a light source; value =
    /// objects grasped so far.
    ObjectGrasped,
    /// Foraging: an object was put down at the home base; value = objects delivered so far.
    ObjectDelivered,
    /// Foraging: a light source held no object (already emptied); value = empty sources known.
    SourceEmpty,
    /// Light calibration (seed 000 §5.3) finished; value = training examples used, or a
    /// negative `calibration::*` failure code.
    LightCalibrated,
    /// The calibrated light -> angle map sees a light; value = its bearing from the heading,
    /// decidegrees, counter-clockwise (-900 right .. 900 left). At most 2 per second.
    LightBearing,
    /// A light calibration arrived by upload and replaced the robot's; value = its id.
    CalibrationInstalled,
    /// A motion mode with a target (GoTo, ExecutePlan) gave up: the distance left did not
    /// shrink by `stuck_progress_m` for `stuck_limit_s`; the motors stopped and the mode is
    /// Idle. Value = milliseconds without progress.
    NoProgress,
}

/// Log severity.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize, Schema)]
pub enum LogLevel {
    Debug,
    Info,
    Warn,
    Error,
}

/// Robot -> station: a line of log text.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct Log<'a> {
    pub level: LogLevel,
    pub text: &'a str,
}

/// EMULATOR ONLY. The simulated world's ground truth, for the station's true-versus-believed
/// views. A real robot never sends it, and the emulator never feeds it to the firmware.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct EmuTruth {
    pub time_ms: u32,
    pub pose: Pose,
    pub collisions: u32,
    /// The robot this truth is about (its `robot_id`), so truth from a fleet's robots, once
    /// recorded or merged, is never credited to the wrong one.
    pub robot_id: u8,
}

/// Which family of floor lines (seed 003 §2.6): `X` lines lie at x = k * pitch and fix x (the
/// thesis's "V" lines), `Y` lines fix y ("H").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub enum LineAxis {
    #[default]
    X,
    Y,
}

/// What the robot made of a floor-line pulse (seed 003 §2.5).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub enum LineVerdict {
    /// The PPD was cut with a line and the pose corrected.
    #[default]
    Corrected,
    /// No line lay near enough to the PPD, or none held enough of it (a crossing): ignored.
    Rejected,
    /// Too soon after the last correction: taken as a double detection and ignored.
    Echo,
}

/// The last floor-line pulse and what it did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct LineEventInfo {
    /// Robot clock at the pulse.
    pub time_ms: u32,
    pub verdict: LineVerdict,
    /// The line the PPD was cut with (`Corrected` only; else X).
    pub axis: LineAxis,
    /// Its index k from the grid's origin (`Corrected` only; else 0).
    pub index: i16,
    /// `Corrected`: how far the corrected position moved; `Rejected`: distance of the PPD from
    /// the best line; `Echo`: 0. Millimetres, saturating.
    pub moved_mm: u16,
    /// Heading correction applied (`Corrected` only), milliradians.
    pub turned_mrad: i16,
    /// Share of the PPD's weight on the winning line, percent (`Corrected` only).
    pub support_pct: u8,
}

/// One PPD sample: where the hypothesis puts the robot and its wheel-bias pair.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct PpdSample {
    /// Offset from `Localization::corrected`, millimetres (saturating).
    pub dx_mm: i16,
    pub dy_mm: i16,
    /// Relative wheel speed error, left then right, in units of 0.01 % (saturating at ±1.27 %).
    pub bias: [i8; 2],
}

/// PPD samples carried by one `Localization` (of the robot's 64).
pub const PPD_SAMPLES_SENT: usize = 16;

/// Robot -> station at 5 Hz while floor-grid line correction runs (seed 003 §2.5): the
/// corrected, plain-odometry and nearest-line poses, the last line event and a summary of the
/// position probability distribution (PPD).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct Localization {
    pub time_ms: u32,
    /// Pose corrected by the PPD (the pose telemetry reports).
    pub corrected: Pose,
    /// Plain odometry from the same encoder counts.
    pub uncorrected: Pose,
    /// The nearest-line baseline the thesis rejects (seed 003 §2.2.4).
    pub baseline: Pose,
    /// Root-mean-square distance of the PPD's samples from their mean, millimetres.
    pub ppd_size_mm: u16,
    /// Mean wheel bias of the PPD, left then right, in units of 0.001 %.
    pub bias_mean: [i16; 2],
    /// Line pulses, accepted corrections and ignored pulses since line correction started,
    /// wrapping.
    pub lines: u16,
    pub corrections: u16,
    pub rejected: u16,
    /// The last line pulse, if any.
    pub last_event: Option<LineEventInfo>,
    /// Every fourth PPD sample.
    pub samples: [PpdSample; PPD_SAMPLES_SENT],
}

/// Robot -> station about once a second while a mode other than Idle runs: what the mode is
/// doing, for a status line (PROTOCOL.md §6 kind 14). Telemetry stays small; this is the
/// slow, descriptive half.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct Progress {
    /// The mode this describes.
    pub mode: Mode,
    /// ExecutePlan: the waypoint being driven to, 1-based (`waypoints + 1` on the final
    /// approach to the goal light); 0 otherwise.
    pub waypoint: u16,
    /// ExecutePlan: the plan's waypoint count; 0 otherwise.
    pub waypoints: u16,
    /// Distance left to the target (GoTo: the point; ExecutePlan: along the remaining
    /// waypoints; Explore: to the goal light), millimetres; `None` for a mode without one.
    pub distance_left_mm: Option<u32>,
    /// Time since the mode was entered, milliseconds.
    pub elapsed_ms: u32,
    /// Time since the distance left last shrank by `stuck_progress_m`, milliseconds.
    pub stuck_ms: u32,
    /// The mode gives up at this `stuck_ms` (`stuck_limit_s`); 0: it does not give up.
    pub give_up_ms: u32,
}

/// Largest `HalTrace::data`: a chunk leaves room for the offsets' varints and a signed
/// frame's trailer inside `MAX_SIGNED_PAYLOAD`.
pub const MAX_HAL_TRACE_CHUNK: usize = 192;

/// Robot -> station while parameter 34 `hal_trace` is on (PROTOCOL.md §6 kind 15): the next
/// bytes of the robot's hardware trace, everything its hardware layer gave the firmware (clock,
/// sensor reads, encoder counts, serial bytes in) and the motor commands it gave back, one
/// entry a call, in the order of the calls (the entry format is PROTOCOL.md §17). A station
/// concatenates `data` by `offset`; `station retrace` feeds it to the firmware again.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct HalTrace<'a> {
    /// Position of `data[0]` in the trace stream: bytes since tracing was switched on,
    /// wrapping. A jump means frames were lost on the wire.
    pub offset: u32,
    /// Passes of the main loop whose entries the robot could not send since tracing was
    /// switched on (its buffer was full: the link could not keep up), wrapping; each loss is
    /// also marked in the stream where it happened (a `GAP` entry).
    pub dropped_steps: u32,
    /// At most `MAX_HAL_TRACE_CHUNK` bytes of the stream.
    pub data: &'a [u8],
}

/// Sensors of each kind on ALICE (seed 001 §3.1): whiskers and photoresistors, sensor `i`
/// looking `i * 15` degrees anticlockwise from the robot's forward axis.
pub const ALICE_SENSORS: usize = 24;

/// Robot -> station every control cycle on an ALICE (PROTOCOL.md §6 kind 16): the situation
/// the station's QT world model (seed 001 ch. 4-5) learns from. The model needs a heap and
/// far more memory than the robot has, so the robot streams its raw situation and the
/// station builds the network.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct AliceSituation {
    pub time_ms: u32,
    /// Situations sent since power-up, wrapping: a jump means frames were lost.
    pub seq: u16,
    /// Whisker contacts: bit `i` set when whisker `i` touches (bits 24..32 are zero).
    pub whiskers: u32,
    /// Photoresistor readings, 0 (dark) ..= 255 (saturated), uncalibrated.
    pub light: [u8; ALICE_SENSORS],
    /// The odometry's pose (uncorrected dead reckoning, as the model wants it).
    pub odometry: Pose,
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
