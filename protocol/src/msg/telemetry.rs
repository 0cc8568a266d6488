//! Telemetry (PROTOCOL.md §6 kind 3): the robot's pose, wheels, sensors and behaviour
//! output at the rate the station sets, serialised within its ranges.

use postcard_schema::Schema;
use serde::{Deserialize, Serialize};

use super::Mode;
use crate::packed::Packed10x8;

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
