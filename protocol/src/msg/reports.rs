//! What the robot reports besides telemetry: events, log lines, the emulator's ground truth,
//! floor-line localization, motion progress, the hardware trace and ALICE's situations.

use postcard_schema::Schema;
use serde::{Deserialize, Serialize};

use super::{Mode, Pose};

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
