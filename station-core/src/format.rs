//! Values, modes, parameters and objects in words: the one place the station's views, logs,
//! reports and exports take these names from.
//!
//! Layer: pure functions, no state.

use protocol::{Event, EventCode, LogLevel, Mode, ObjectKind, Progress};
use robot_firmware::params::ParamInfo;

/// A mode's name for display.
pub fn mode_name(m: Mode) -> &'static str {
    match m {
        Mode::Idle => "Idle",
        Mode::Manual => "Manual",
        Mode::GoTo => "GoTo",
        Mode::Wander => "Wander",
        Mode::EdgeFollowLeft => "EdgeFollowLeft",
        Mode::EdgeFollowRight => "EdgeFollowRight",
        Mode::SeekLight => "SeekLight",
        Mode::Explore => "Explore",
        Mode::ExecutePlan => "ExecutePlan",
        Mode::Forage => "Forage",
        Mode::Survey => "Survey",
        Mode::CalibrateLight => "CalibrateLight",
    }
}

/// The mode with wire index `i` (as in `Event ModeChanged`).
pub fn mode_from_index(i: i32) -> Option<Mode> {
    MODES.get(usize::try_from(i).ok()?).copied()
}

/// Every mode in wire order; the digit keys 0-9 select the first ten.
pub const MODES: [Mode; 12] = [
    Mode::Idle,
    Mode::Manual,
    Mode::GoTo,
    Mode::Wander,
    Mode::EdgeFollowLeft,
    Mode::EdgeFollowRight,
    Mode::SeekLight,
    Mode::Explore,
    Mode::ExecutePlan,
    Mode::Forage,
    Mode::Survey,
    Mode::CalibrateLight,
];

/// A mode's name by its wire index, or `#i` for one this build does not know.
pub fn mode_name_i32(i: i32) -> String {
    mode_from_index(i).map_or_else(|| format!("#{i}"), |m| mode_name(m).to_string())
}

/// A value of parameter `info` with the decimals its unit and range need
/// (`robot_firmware::params::display_decimals`): 0.080 mm per pulse, not 0.
pub fn format_param(info: &ParamInfo, v: f32) -> String {
    format!("{v:.*}", robot_firmware::params::display_decimals(info))
}

/// A value of parameter `id` as `format_param` shows it (plain for an unknown id).
pub fn format_param_id(id: u16, v: f32) -> String {
    robot_firmware::params::info(id).map_or_else(|| format_value(v), |p| format_param(p, v))
}

/// `info`'s range in its unit, each bound with the parameter's decimals.
pub fn range_text(info: &ParamInfo) -> String {
    format!(
        "{} .. {}",
        format_param(info, info.min),
        format_param(info, info.max)
    )
}

/// A value without needless decimals.
pub fn format_value(v: f32) -> String {
    if v.fract() == 0.0 && v.abs() < 1e7 {
        format!("{v:.0}")
    } else {
        format!("{v}")
    }
}

/// The object's name for text and JSON.
pub fn object_name(o: ObjectKind) -> &'static str {
    match o {
        ObjectKind::Map => "map",
        ObjectKind::Plan => "plan",
        ObjectKind::Regions => "regions",
        ObjectKind::LightCalibration => "light calibration",
    }
}

/// What a `Progress` report says, in words: "waypoint 2 of 5, 1.2 m left, 14 s, stuck 6 s
/// (gives up at 120)"; `None` when it says nothing (Idle). `short` drops the time. The TUI's
/// header and `station status` show it.
pub fn progress_text(p: &Progress, short: bool) -> Option<String> {
    if p.mode == Mode::Idle {
        return None;
    }
    let mut parts = Vec::new();
    if p.waypoints > 0 {
        if p.waypoint > p.waypoints {
            parts.push("final approach".to_string());
        } else {
            parts.push(format!("waypoint {} of {}", p.waypoint, p.waypoints));
        }
    }
    if let Some(mm) = p.distance_left_mm {
        parts.push(format!("{:.1} m left", f64::from(mm) / 1000.0));
    }
    if !short {
        parts.push(format!("{} s", p.elapsed_ms / 1000));
    }
    // Stuck from 5 s on: shorter pauses are turns and wall following, not news.
    if p.stuck_ms >= 5000 {
        let s = p.stuck_ms / 1000;
        parts.push(if p.give_up_ms > 0 {
            format!("stuck {s} s (gives up at {})", p.give_up_ms / 1000)
        } else {
            format!("no progress {s} s")
        });
    }
    (!parts.is_empty()).then(|| parts.join(", "))
}

/// A task mode's name in a sentence ("go-to gave up"), for the modes that end by arriving.
pub fn task_name(m: Mode) -> &'static str {
    match m {
        Mode::GoTo => "go-to",
        Mode::ExecutePlan => "plan execution",
        Mode::Explore => "exploration",
        _ => "the motion mode",
    }
}

/// The `NoProgress` event in words: which mode gave up (`mode`, from its last progress report
/// if one came), after how long, how far from its target, and the parameter that sets the limit.
pub fn no_progress_text(
    mode: Option<Mode>,
    distance_left_mm: Option<u32>,
    stuck_ms: i32,
) -> String {
    let mode = mode.map_or("the motion mode", task_name);
    let left = distance_left_mm.map_or(String::new(), |mm| {
        format!(", {:.1} m from its target", f64::from(mm) / 1000.0)
    });
    format!(
        "{mode} gave up: no progress for {:.0} s{left}; the robot stopped (limit: parameter \
         stuck_limit_s)",
        f64::from(stuck_ms) / 1000.0
    )
}

/// A log level's name for text and JSON.
pub fn log_level_name(l: LogLevel) -> &'static str {
    match l {
        LogLevel::Debug => "debug",
        LogLevel::Info => "info",
        LogLevel::Warn => "warn",
        LogLevel::Error => "error",
    }
}

/// The `GoalReached` event in words: what the task that arrived was (`mode`), and where (the
/// robot says only that its task reached its end; the goal is the goal only when exploring
/// found it, or when the plan was made `to_goal`, to the map's goal).
pub fn arrival_text(mode: Option<Mode>, at: Option<(f64, f64)>, to_goal: bool) -> String {
    let at = at.map_or(String::new(), |(x, y)| format!(" at ({x:.2}, {y:.2})"));
    match mode {
        Some(Mode::Explore) => format!("goal reached{at}: exploration found the goal area"),
        Some(Mode::GoTo) => format!("arrived{at}: the go-to point"),
        Some(Mode::ExecutePlan) if to_goal => format!("goal reached{at}: the plan's end"),
        Some(Mode::ExecutePlan) => format!("arrived{at}: the plan's end"),
        _ => format!("task ended{at}: the robot arrived"),
    }
}

/// An event's name: what the export's `/events` and the station's reports call it.
pub fn event_name(code: EventCode) -> &'static str {
    match code {
        EventCode::ModeChanged => "mode changed",
        EventCode::GoalReached => "goal reached",
        EventCode::FailsafeStop => "failsafe stop",
        EventCode::Collision => "collision",
        EventCode::LineCrossed => "floor line crossed",
        EventCode::PoseCorrected => "pose corrected",
        EventCode::BeaconCalibration => "beacon calibration",
        EventCode::MapUpdated => "map updated",
        EventCode::PlanInstalled => "plan installed",
        EventCode::PlanFinished => "plan finished",
        EventCode::PlanAborted => "plan aborted",
        EventCode::HandshakeRefused => "handshake refused",
        EventCode::ParamChanged => "parameter changed",
        EventCode::ObjectGrasped => "object gripped",
        EventCode::ObjectDelivered => "object delivered",
        EventCode::SourceEmpty => "light source empty",
        EventCode::LightCalibrated => "light calibrated",
        EventCode::LightBearing => "light bearing",
        EventCode::CalibrationInstalled => "light calibration installed",
        EventCode::NoProgress => "no progress",
    }
}

/// An event in the station's words, with its severity in the station's log: what the event
/// alone says. The TUI's log says more of a few where it knows more (where the robot arrived,
/// which mode gave up how far from its target, the floor line a correction completes).
pub fn event_text(e: &Event) -> (LogLevel, String) {
    let v = e.value;
    match e.code {
        EventCode::ModeChanged => (
            LogLevel::Info,
            format!("mode changed to {}", mode_name_i32(v)),
        ),
        EventCode::GoalReached => (LogLevel::Info, "goal reached: the robot arrived".into()),
        EventCode::FailsafeStop => (
            LogLevel::Warn,
            format!("failsafe stop after {v} ms of silence"),
        ),
        EventCode::Collision => (LogLevel::Warn, "collision".into()),
        EventCode::LineCrossed => (LogLevel::Debug, format!("floor line {v} crossed")),
        EventCode::PoseCorrected => (LogLevel::Info, format!("pose corrected by {v} mm")),
        // Once a second while the robot sees the beacon standing still: detail, not news.
        EventCode::BeaconCalibration => (
            LogLevel::Debug,
            format!(
                "beacon calibration, confidence {:.3}",
                f64::from(v) / 1000.0
            ),
        ),
        EventCode::MapUpdated => (LogLevel::Debug, "map updated".into()),
        EventCode::PlanInstalled => (LogLevel::Info, "plan installed".into()),
        EventCode::PlanFinished => (
            LogLevel::Info,
            format!("plan finished: all {v} waypoints done, the robot stopped"),
        ),
        EventCode::NoProgress => (
            LogLevel::Warn,
            format!(
                "gave up: no progress for {:.0} s; the robot stopped (limit: parameter \
                 stuck_limit_s)",
                f64::from(v) / 1000.0
            ),
        ),
        EventCode::PlanAborted => (LogLevel::Warn, format!("plan aborted at waypoint {v}")),
        // Negative: the robot could not authenticate our Hello (PROTOCOL.md §13).
        EventCode::HandshakeRefused if v < 0 => (
            LogLevel::Warn,
            format!("robot refused our handshake: link authentication, reason {v}"),
        ),
        EventCode::HandshakeRefused => (
            LogLevel::Error,
            format!("robot refused our handshake (it saw protocol {v})"),
        ),
        EventCode::ObjectGrasped => (LogLevel::Info, format!("object gripped ({v} so far)")),
        EventCode::ObjectDelivered => (
            LogLevel::Info,
            format!("object delivered home ({v} so far)"),
        ),
        EventCode::SourceEmpty => (LogLevel::Info, format!("light source empty ({v} known)")),
        EventCode::LightCalibrated if v > 0 => (
            LogLevel::Info,
            format!("light calibration done ({v} examples)"),
        ),
        EventCode::LightCalibrated => (
            LogLevel::Warn,
            match v {
                protocol::calibration::NO_LIGHT => {
                    "light calibration failed: no light near the robot".into()
                }
                protocol::calibration::NO_DIRECTION => {
                    "light calibration failed: the first turn gave no light direction".into()
                }
                protocol::calibration::STALLED => {
                    "light calibration aborted: the robot stalled mid-turn (wheels blocked?)".into()
                }
                _ => format!("light calibration failed (code {v})"),
            },
        ),
        EventCode::CalibrationInstalled => (
            LogLevel::Info,
            format!("light calibration {:08x} installed", v as u32),
        ),
        EventCode::LightBearing => (
            LogLevel::Debug,
            format!("light at {:+.1} deg", f64::from(v) / 10.0),
        ),
        EventCode::ParamChanged => {
            let id = u16::try_from(v).unwrap_or(u16::MAX);
            (
                LogLevel::Info,
                format!("parameter {} changed", crate::link::api::param_name(id)),
            )
        }
    }
}
