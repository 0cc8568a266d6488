//! Values, modes, parameters and objects in words: the one place the station's views, logs,
//! reports and exports take these names from.
//!
//! Layer: pure functions, no state.

use protocol::{Mode, ObjectKind};
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
