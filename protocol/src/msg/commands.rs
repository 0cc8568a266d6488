//! Commands and their answers (PROTOCOL.md §7): `Command`, `Ack` with what it carries back,
//! `Nack` with why.

use postcard_schema::Schema;
use serde::{Deserialize, Serialize};

use super::{Mode, ObjectKind, Pose};

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
