//! Parameters settable over the link (`Command::SetParam` / `GetParam`).
//!
//! Layer: a table from parameter ids to the fields of the robot's parameter structs. Every
//! value the papers leave open is here, with the default the firmware starts with, its unit
//! and its range; the station links this crate and shows the same names. Ids are part of the
//! protocol contract: never renumber, only append. A `set` outside the range, not finite, or
//! not whole for an integer parameter is refused with `OutOfRange` and changes nothing.

use protocol::NackReason;

use crate::behaviour::ArbiterParams;
use crate::deadreckon::DeadReckonParams;
use crate::explore::{ExploreParams, SearchMode};
use crate::guided::GuidedParams;
use crate::motion_progress::ProgressParams;
use crate::odometry::OdometryParams;

/// Robot-level settings that belong to no algorithm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RobotConfig {
    /// Manual-mode failsafe: motors stop after this much silence (PROTOCOL.md §7).
    pub failsafe_ms: u16,
    /// Telemetry rate, Hz; 0 = off.
    pub telemetry_hz: u8,
    /// Largest teleop wheel speed, mm/s.
    pub teleop_max_mm_s: f32,
    /// Battery voltage read as empty (level 0) and full (level 1), for the speed table.
    pub battery_empty_mv: u16,
    pub battery_full_mv: u16,
    /// Which robot this is in a fleet, stated in every `HelloReply` (like MAVLink's system
    /// id; 0 is left out, as MAVLink keeps it for "every system").
    pub robot_id: u8,
    /// The hardware trace (`hal_trace`, message kind 15): 1 on, 0 off.
    pub hal_trace: u8,
}

impl Default for RobotConfig {
    fn default() -> Self {
        RobotConfig {
            failsafe_ms: protocol::timing::FAILSAFE_DEFAULT_MS,
            telemetry_hz: protocol::timing::TELEMETRY_DEFAULT_HZ,
            teleop_max_mm_s: 300.0,
            battery_empty_mv: 7000,
            battery_full_mv: 9000,
            robot_id: DEFAULT_ROBOT_ID,
            hal_trace: 0,
        }
    }
}

/// The robot id a robot starts with; the emulator gives robot k of a fleet the id k.
pub const DEFAULT_ROBOT_ID: u8 = 1;

/// One parameter's description: the one table the robot checks values against, the
/// station's editor and `station params` show, and PROTOCOL.md §16 is generated from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamInfo {
    pub id: u16,
    pub name: &'static str,
    pub unit: &'static str,
    pub min: f32,
    pub max: f32,
    /// Only whole numbers are accepted.
    pub integer: bool,
    /// Capability bits (`protocol::caps`) the robot needs for this parameter to mean
    /// anything; a robot without them answers `Unsupported` to a get or set (a robot without
    /// encoders has no pulse length to show, not a length of 0).
    pub requires: u32,
    /// One line for the operator: what the parameter does, where its default comes from.
    pub desc: &'static str,
}

const fn p(
    id: u16,
    name: &'static str,
    unit: &'static str,
    min: f32,
    max: f32,
    desc: &'static str,
) -> ParamInfo {
    ParamInfo {
        id,
        name,
        unit,
        min,
        max,
        integer: false,
        requires: 0,
        desc,
    }
}

const fn pi(
    id: u16,
    name: &'static str,
    unit: &'static str,
    min: f32,
    max: f32,
    desc: &'static str,
) -> ParamInfo {
    ParamInfo {
        integer: true,
        ..p(id, name, unit, min, max, desc)
    }
}

/// `info` that only a robot with `caps` has.
const fn needs(caps: u32, info: ParamInfo) -> ParamInfo {
    ParamInfo {
        requires: caps,
        ..info
    }
}

use protocol::caps::{BEACON, COMPASS, ENCODERS};

/// Every parameter, by id.
pub const PARAMS: [ParamInfo; 37] = [
    pi(
        0,
        "failsafe_ms",
        "ms",
        50.0,
        10_000.0,
        "manual mode: motors stop after this much silence from the station",
    ),
    pi(
        1,
        "telemetry_hz",
        "Hz",
        0.0,
        50.0,
        "telemetry frames a second, 0 = off (SetTelemetryRate sets it too)",
    ),
    p(
        2,
        "teleop_max_mm_s",
        "mm/s",
        0.0,
        2000.0,
        "fastest wheel speed in manual driving",
    ),
    pi(
        3,
        "battery_empty_mv",
        "mV",
        0.0,
        20_000.0,
        "battery voltage read as empty, for the speed table",
    ),
    pi(
        4,
        "battery_full_mv",
        "mV",
        0.0,
        20_000.0,
        "battery voltage read as full, for the speed table",
    ),
    needs(
        ENCODERS,
        p(
            5,
            "odo_wheel_distance_mm",
            "mm",
            10.0,
            500.0,
            "odometry: distance between the wheels (Löffler et al. §3.1: 52 mm)",
        ),
    ),
    needs(
        ENCODERS,
        p(
            6,
            "odo_mm_per_pulse",
            "mm",
            0.001,
            10.0,
            "odometry: wheel travel per encoder pulse",
        ),
    ),
    pi(
        7,
        "avoid_threshold",
        "counts",
        0.0,
        1023.0,
        "obstacle avoidance: IR activation threshold (Löffler et al. §4.2: 475)",
    ),
    pi(
        8,
        "avoid_threshold_spread",
        "counts",
        0.0,
        200.0,
        "obstacle avoidance: random spread of the threshold (Löffler et al. §4.2: 25)",
    ),
    pi(
        9,
        "avoid_base_units",
        "units",
        0.0,
        127.0,
        "obstacle avoidance: base propulsion of both wheels",
    ),
    pi(
        10,
        "edge_noise_threshold",
        "counts",
        1.0,
        500.0,
        "edge following: error below this is noise (Löffler et al. §4.3: 7)",
    ),
    pi(
        11,
        "edge_lost_threshold",
        "counts",
        1.0,
        1023.0,
        "edge following: error below minus this means the wall is lost (Löffler et al. §4.3: 100)",
    ),
    pi(
        12,
        "edge_lost_max_cycles",
        "cycles",
        1.0,
        10_000.0,
        "edge following: longest strong curve while the wall is lost (Löffler et al. §4.3: 120)",
    ),
    p(
        13,
        "drift_approach_radius_m",
        "m",
        0.01,
        2.0,
        "drift to target: turn to it and halve propulsion inside this (Löffler et al. §4.4: 0.15)",
    ),
    p(
        14,
        "drift_arrival_radius_m",
        "m",
        0.005,
        1.0,
        "drift to target: arrived inside this (Löffler et al. §4.4: 0.05)",
    ),
    pi(
        15,
        "behaviour_max_units",
        "units",
        1.0,
        127.0,
        "behaviours: largest wheel command the arbiter sends",
    ),
    pi(
        16,
        "light_t1",
        "counts",
        0.0,
        1023.0,
        "light: source detected below this front reading (Löffler et al. §6.1: T1 = 470)",
    ),
    pi(
        17,
        "light_t2",
        "counts",
        0.0,
        1023.0,
        "light: optimal distance below this average front reading (Löffler et al. §6.1: T2 = 200)",
    ),
    pi(
        18,
        "light_t3",
        "counts",
        0.0,
        1023.0,
        "light: source left when every front reading is above this (Löffler et al. §6.1: T3 = 490)",
    ),
    p(
        19,
        "xi_calibration_gain",
        "",
        0.0,
        1.0,
        "dead reckoning: confidence a beacon calibration adds (Dom Dinis paper §4)",
    ),
    p(
        20,
        "xi_collision_loss",
        "",
        0.0,
        1.0,
        "dead reckoning: confidence a collision removes (Dom Dinis paper §4)",
    ),
    p(
        21,
        "beacon_x_m",
        "m",
        -100.0,
        100.0,
        "beacon position x, map frame (exploration goal); the emulator sets it from its arena",
    ),
    p(
        22,
        "beacon_y_m",
        "m",
        -100.0,
        100.0,
        "beacon position y, map frame (exploration goal); the emulator sets it from its arena",
    ),
    p(
        23,
        "guided_top_speed",
        "nominal",
        0.0,
        100.0,
        "guided motion: nominal speed in free motion (Dom Dinis paper §4: 75)",
    ),
    p(
        24,
        "guided_heading_gain",
        "nominal/rad",
        0.0,
        500.0,
        "guided motion: wheel difference per radian of heading error",
    ),
    pi(
        25,
        "guided_obstacle_ir",
        "counts",
        0.0,
        1023.0,
        "guided motion: IR reading at which an obstacle counts as seen",
    ),
    p(
        26,
        "guided_arrival_m",
        "m",
        0.01,
        2.0,
        "guided motion: distance at which a point counts as reached",
    ),
    // seed 004 §4: a position outside the labyrinth is replaced by the closest inside point.
    p(
        27,
        "arena_min_x_m",
        "m",
        -100.0,
        100.0,
        "arena bounds: smallest x (Dom Dinis paper §4)",
    ),
    p(
        28,
        "arena_min_y_m",
        "m",
        -100.0,
        100.0,
        "arena bounds: smallest y (Dom Dinis paper §4)",
    ),
    p(
        29,
        "arena_max_x_m",
        "m",
        -100.0,
        100.0,
        "arena bounds: largest x (Dom Dinis paper §4)",
    ),
    p(
        30,
        "arena_max_y_m",
        "m",
        -100.0,
        100.0,
        "arena bounds: largest y (Dom Dinis paper §4)",
    ),
    // GoTo and ExecutePlan give up after this long without getting nearer (robot::progress).
    p(
        31,
        "stuck_limit_s",
        "s",
        5.0,
        3600.0,
        "go-to and plan execution: give up after this long without getting nearer",
    ),
    p(
        32,
        "stuck_progress_m",
        "m",
        0.01,
        2.0,
        "go-to and plan execution: getting this much nearer counts as progress",
    ),
    // Stated in the HelloReply; the station names the robot by it and warns of duplicates.
    pi(
        33,
        "robot_id",
        "",
        1.0,
        255.0,
        "which robot this is in a fleet (like MAVLink's system id); the handshake states it",
    ),
    pi(
        34,
        "hal_trace",
        "",
        0.0,
        1.0,
        "1: stream every hardware read as HalTrace frames, for `station retrace` (PROTOCOL.md §17)",
    ),
    // Issue 32: the paper's reactive search stays selectable for its reproductions.
    needs(
        COMPASS | BEACON,
        pi(
            35,
            "search_mode",
            "",
            0.0,
            1.0,
            "exploration: 1 plans on its own 0.15 m map as it goes (default), 0 is the Dom Dinis paper's reactive search (§5) on a 0.3 m map; read when a run starts",
        ),
    ),
    needs(
        ENCODERS,
        p(
            50,
            "odo_wheel_ratio_ppm",
            "ppm",
            -50_000.0,
            50_000.0,
            "odometry: right over left wheel travel per pulse, minus 1 (0: equal; `station calibrate odometry` measures it)",
        ),
    ),
];

/// Decimals that show every value of `info` in its unit: none for an integer parameter, else
/// enough for the smallest non-zero bound (0.001 mm needs 3) and at least 2, so a value in
/// range never shows as 0.
pub fn display_decimals(info: &ParamInfo) -> usize {
    if info.integer {
        return 0;
    }
    let mut d = 2;
    for bound in [info.min, info.max] {
        let mut b = libm::fabsf(bound);
        if b == 0.0 {
            continue;
        }
        let mut needed = 0;
        while b < 1.0 && needed < 6 {
            b *= 10.0;
            needed += 1;
        }
        d = d.max(needed);
    }
    d
}

/// Ids of the parameters other crates set by name in code (the emulator's scenario runner
/// briefs the robot as an operator would). A test checks each against `PARAMS`.
pub mod id {
    pub const TELEMETRY_HZ: u16 = 1;
    pub const DRIFT_ARRIVAL_RADIUS_M: u16 = 14;
    pub const BEACON_X_M: u16 = 21;
    pub const BEACON_Y_M: u16 = 22;
    pub const GUIDED_ARRIVAL_M: u16 = 26;
    pub const ARENA_MIN_X_M: u16 = 27;
    pub const ARENA_MIN_Y_M: u16 = 28;
    pub const ARENA_MAX_X_M: u16 = 29;
    pub const ARENA_MAX_Y_M: u16 = 30;
    pub const ROBOT_ID: u16 = 33;
    pub const ODO_WHEEL_DISTANCE_MM: u16 = 5;
    pub const ODO_WHEEL_RATIO_PPM: u16 = 50;
    pub const HAL_TRACE: u16 = 34;
    pub const SEARCH_MODE: u16 = 35;
}

/// The description of parameter `id`.
pub fn info(id: u16) -> Option<&'static ParamInfo> {
    PARAMS.iter().find(|p| p.id == id)
}

/// The description of the parameter called `name`.
pub fn by_name(name: &str) -> Option<&'static ParamInfo> {
    PARAMS.iter().find(|p| p.name == name)
}

/// Mutable views of every parameter struct.
pub struct Tunables<'a> {
    pub robot: &'a mut RobotConfig,
    pub odometry: &'a mut OdometryParams,
    pub arbiter: &'a mut ArbiterParams,
    pub dead_reckon: &'a mut DeadReckonParams,
    pub guided: &'a mut GuidedParams,
    pub progress: &'a mut ProgressParams,
    /// The search's parameters, on a robot that has one.
    pub explore: Option<&'a mut ExploreParams>,
}

enum Slot<'a> {
    F32(&'a mut f32),
    U16(&'a mut u16),
    I16(&'a mut i16),
    I32(&'a mut i32),
    U8(&'a mut u8),
    Search(&'a mut SearchMode),
}

impl Tunables<'_> {
    fn slot(&mut self, id: u16) -> Option<Slot<'_>> {
        Some(match id {
            0 => Slot::U16(&mut self.robot.failsafe_ms),
            1 => Slot::U8(&mut self.robot.telemetry_hz),
            2 => Slot::F32(&mut self.robot.teleop_max_mm_s),
            3 => Slot::U16(&mut self.robot.battery_empty_mv),
            4 => Slot::U16(&mut self.robot.battery_full_mv),
            5 => Slot::F32(&mut self.odometry.wheel_distance_mm),
            6 => Slot::F32(&mut self.odometry.mm_per_pulse),
            7 => Slot::U16(&mut self.arbiter.avoid.threshold),
            8 => Slot::U16(&mut self.arbiter.avoid.threshold_spread),
            9 => Slot::I16(&mut self.arbiter.avoid.base_units),
            10 => Slot::I32(&mut self.arbiter.edge.noise_threshold),
            11 => Slot::I32(&mut self.arbiter.edge.lost_threshold),
            12 => Slot::U16(&mut self.arbiter.edge.lost_max_cycles),
            13 => Slot::F32(&mut self.arbiter.drift.approach_radius_m),
            14 => Slot::F32(&mut self.arbiter.drift.arrival_radius_m),
            15 => Slot::I16(&mut self.arbiter.max_units),
            16 => Slot::U16(&mut self.arbiter.light.detect),
            17 => Slot::U16(&mut self.arbiter.light.optimal),
            18 => Slot::U16(&mut self.arbiter.light.leave),
            19 => Slot::F32(&mut self.dead_reckon.xi_calibration_gain),
            20 => Slot::F32(&mut self.dead_reckon.xi_collision_loss),
            21 => Slot::F32(&mut self.dead_reckon.beacon.x),
            22 => Slot::F32(&mut self.dead_reckon.beacon.y),
            23 => Slot::F32(&mut self.guided.top_speed),
            24 => Slot::F32(&mut self.guided.heading_gain),
            25 => Slot::U16(&mut self.guided.obstacle_ir),
            26 => Slot::F32(&mut self.guided.arrival_m),
            27 => Slot::F32(&mut self.dead_reckon.bounds.min.x),
            28 => Slot::F32(&mut self.dead_reckon.bounds.min.y),
            29 => Slot::F32(&mut self.dead_reckon.bounds.max.x),
            30 => Slot::F32(&mut self.dead_reckon.bounds.max.y),
            31 => Slot::F32(&mut self.progress.stuck_limit_s),
            32 => Slot::F32(&mut self.progress.stuck_progress_m),
            33 => Slot::U8(&mut self.robot.robot_id),
            50 => Slot::F32(&mut self.odometry.wheel_ratio_error_ppm),
            34 => Slot::U8(&mut self.robot.hal_trace),
            35 => Slot::Search(&mut self.explore.as_mut()?.mode),
            _ => return None,
        })
    }

    /// The value of parameter `id`.
    pub fn get(&mut self, id: u16) -> Result<f32, NackReason> {
        Ok(match self.slot(id).ok_or(NackReason::UnknownParam)? {
            Slot::F32(v) => *v,
            Slot::U16(v) => f32::from(*v),
            Slot::I16(v) => f32::from(*v),
            // Every i32 parameter's range fits f32 exactly (|v| < 2^24).
            Slot::I32(v) => *v as f32,
            Slot::U8(v) => f32::from(*v),
            Slot::Search(v) => f32::from(v.code()),
        })
    }

    /// Sets parameter `id` if `value` is valid for it; returns the value now in force.
    pub fn set(&mut self, id: u16, value: f32) -> Result<f32, NackReason> {
        let info = info(id).ok_or(NackReason::UnknownParam)?;
        let whole = libm::truncf(value) == value;
        if !value.is_finite() || value < info.min || value > info.max || (info.integer && !whole) {
            return Err(NackReason::OutOfRange);
        }
        // The range check above bounds every integer cast below to its type.
        match self.slot(id).ok_or(NackReason::UnknownParam)? {
            Slot::F32(v) => *v = value,
            Slot::U16(v) => *v = value as u16,
            Slot::I16(v) => *v = value as i16,
            Slot::I32(v) => *v = value as i32,
            Slot::U8(v) => *v = value as u8,
            Slot::Search(v) => *v = SearchMode::from_code(value as u8),
        }
        self.get(id)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with_tunables<R>(f: impl FnOnce(&mut Tunables<'_>) -> R) -> R {
        let mut robot = RobotConfig::default();
        let mut odometry = OdometryParams::default();
        let mut arbiter = ArbiterParams::default();
        let mut dead_reckon = DeadReckonParams::default();
        let mut guided = GuidedParams::default();
        let mut progress = ProgressParams::default();
        let mut explore = ExploreParams::default();
        f(&mut Tunables {
            progress: &mut progress,
            robot: &mut robot,
            odometry: &mut odometry,
            arbiter: &mut arbiter,
            dead_reckon: &mut dead_reckon,
            guided: &mut guided,
            explore: Some(&mut explore),
        })
    }

    #[test]
    fn every_listed_parameter_has_a_slot_and_ids_are_unique() {
        with_tunables(|t| {
            for (i, info) in PARAMS.iter().enumerate() {
                // Ascending and unique (ids are appended, never renumbered). Not dense: ids
                // are assigned to work in progress ahead of time (33 robot_id, 34 hal_trace),
                // so a branch may hold a later id before an earlier one has landed.
                if let Some(prev) = i.checked_sub(1).and_then(|j| PARAMS.get(j)) {
                    assert!(info.id > prev.id, "ids ascending and unique: {}", info.name);
                }
                let v = t.get(info.id).expect("slot exists");
                assert!(
                    v >= info.min && v <= info.max,
                    "{} default {v} outside its range",
                    info.name
                );
                // Setting the default back is always accepted and changes nothing.
                assert_eq!(t.set(info.id, v), Ok(v));
            }
            let past = PARAMS.last().map_or(0, |p| p.id + 1);
            assert_eq!(t.get(past), Err(NackReason::UnknownParam));
        });
    }

    #[test]
    fn named_ids_point_at_their_parameters() {
        for (i, name) in [
            (id::TELEMETRY_HZ, "telemetry_hz"),
            (id::DRIFT_ARRIVAL_RADIUS_M, "drift_arrival_radius_m"),
            (id::BEACON_X_M, "beacon_x_m"),
            (id::BEACON_Y_M, "beacon_y_m"),
            (id::GUIDED_ARRIVAL_M, "guided_arrival_m"),
            (id::ARENA_MIN_X_M, "arena_min_x_m"),
            (id::ARENA_MIN_Y_M, "arena_min_y_m"),
            (id::ARENA_MAX_X_M, "arena_max_x_m"),
            (id::ARENA_MAX_Y_M, "arena_max_y_m"),
            (id::ROBOT_ID, "robot_id"),
            (id::ODO_WHEEL_DISTANCE_MM, "odo_wheel_distance_mm"),
            (id::ODO_WHEEL_RATIO_PPM, "odo_wheel_ratio_ppm"),
            (id::SEARCH_MODE, "search_mode"),
        ] {
            assert_eq!(info(i).map(|p| p.name), Some(name));
        }
    }

    #[test]
    fn papers_defaults_are_in_force() {
        with_tunables(|t| {
            assert_eq!(t.get(0), Ok(300.0)); // failsafe 300 ms
            assert_eq!(t.get(5), Ok(52.0)); // seed 000 §3: d = 52 mm
            assert_eq!(t.get(7), Ok(475.0)); // seed 000 §4: threshold 475
            assert_eq!(t.get(10), Ok(7.0)); // edge noise 7
            assert_eq!(t.get(16), Ok(470.0)); // T1
        });
    }

    #[test]
    fn invalid_values_are_refused_and_change_nothing() {
        with_tunables(|t| {
            for bad in [f32::NAN, f32::INFINITY, -1.0, 1e9, 300.5] {
                assert_eq!(t.set(0, bad), Err(NackReason::OutOfRange), "{bad}");
                assert_eq!(t.get(0), Ok(300.0));
            }
            assert_eq!(t.set(999, 1.0), Err(NackReason::UnknownParam));
            assert_eq!(t.set(0, 500.0), Ok(500.0));
            assert_eq!(by_name("failsafe_ms").map(|p| p.id), Some(0));
        });
    }
}
