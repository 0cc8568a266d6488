//! Robot profiles: which hardware a robot has and its physical constants.
//!
//! Three robots come from the papers. `khepera` (seeds 000 and 003) has encoders, eight IR
//! proximity sensors and ambient light; `micro-rato` (seed 004, Dom Dinis) has a compass and no
//! encoders, three IR sensors, a beacon sensor and a ground sensor; `alice` (seed 001) has
//! odometry, 24 whiskers and 24 photoresistors. Constants the papers give
//! are cited; constants they leave open are marked "default" and can be changed over the link
//! as parameters where they affect behaviour. Each profile's robot carries the state of the
//! capabilities it uses (`robot::kit`: micro-rato runs `DomDinis`, khepera `Khepera`).

use protocol::{caps, MapCapacity, ProfileId};

/// Which IR slots a profile uses, with each sensor's direction from the heading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IrLayout {
    /// Number of sensors in use, slots 0..count.
    pub count: usize,
    /// Direction of each slot, radians, positive to the left.
    pub angle_rad: [f32; 8],
}

/// A robot's hardware description.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Profile {
    pub id: ProfileId,
    pub name: &'static str,
    /// `protocol::caps` bits.
    pub capabilities: u32,
    /// Body diameter, metres.
    pub body_diameter_m: f32,
    /// Distance between the wheels, metres.
    pub wheel_distance_m: f32,
    /// Wheel travel per encoder pulse, metres; 0 without encoders.
    pub pulse_m: f32,
    /// Speed of one motor command unit, mm/s.
    pub motor_unit_mm_s: f32,
    /// Largest motor command magnitude.
    pub motor_max: i16,
    /// Control cycle period, microseconds.
    pub cycle_us: u32,
    pub ir: IrLayout,
    /// Distance at which IR readings fall to noise, metres.
    pub ir_range_m: f32,
}

const DEG: f32 = core::f32::consts::PI / 180.0;

/// Khepera (seed 000 §1.1, §3; seed 003).
pub const KHEPERA: Profile = Profile {
    id: ProfileId::Khepera,
    name: "khepera",
    capabilities: caps::ENCODERS
        | caps::IR_PROXIMITY
        | caps::AMBIENT_LIGHT
        | caps::LINE_SENSOR
        | caps::BATTERY
        // seed 000 §1.1, §7: the gripper and K213 camera turrets.
        | caps::GRIPPER
        | caps::CAMERA
        | caps::ONBOARD_PLANNING
        | caps::TRANSFERS
        // seed 003: encoders + floor line sensor: grid-line correction, Mode::Survey.
        | caps::LINE_CORRECTION,
    // seed 000 §1.1: 55 mm diameter.
    body_diameter_m: 0.055,
    // seed 000 §3: d = 52 mm, dl = 0.08 mm per pulse.
    wheel_distance_m: 0.052,
    pulse_m: 0.000_08,
    // Khepera speed unit: one pulse (0.08 mm) per 10 ms = 8 mm/s.
    motor_unit_mm_s: 8.0,
    // Khepera motors saturate near 1 m/s (127 units); behaviours use far less.
    motor_max: 127,
    // seed 000 §4: a control cycle of about 80 ms (1126 cycles in 92 s).
    cycle_us: 80_000,
    // seed 000 §1.1: S0 left side .. S5 right side, S6/S7 rear.
    ir: IrLayout {
        count: 8,
        angle_rad: [
            90.0 * DEG,
            45.0 * DEG,
            10.0 * DEG,
            -10.0 * DEG,
            -45.0 * DEG,
            -90.0 * DEG,
            180.0 * DEG,
            180.0 * DEG,
        ],
    },
    // seed 000 §1.1: useful 1.7..3.3 cm, only noise beyond (measured from the body's edge).
    ir_range_m: 0.033,
};

/// Micro-Rato / Dom Dinis (seed 004 §3).
pub const MICRO_RATO: Profile = Profile {
    id: ProfileId::MicroRato,
    name: "micro-rato",
    capabilities: caps::IR_PROXIMITY
        | caps::COMPASS
        | caps::GROUND_SENSOR
        | caps::BEACON
        | caps::BATTERY
        | caps::ONBOARD_PLANNING
        | caps::TRANSFERS,
    // seed 004 §3: round, 24 cm diameter.
    body_diameter_m: 0.24,
    // default: the paper gives no wheel base; 0.20 m fits a 24 cm body.
    wheel_distance_m: 0.20,
    pulse_m: 0.0,
    // seed 004 §4: nominal speeds 25/50/75; 75 is 0.23 m/s at average battery, so one unit
    // is about 3.07 mm/s (the dead reckoning uses the battery-dependent table instead).
    motor_unit_mm_s: 230.0 / 75.0,
    motor_max: 100,
    // default: the paper gives no cycle; 50 ms is 4 cycles per compass reading (~5 Hz).
    cycle_us: 50_000,
    // Three IR proximity sensors: left, front, right (default directions).
    ir: IrLayout {
        count: 3,
        angle_rad: [60.0 * DEG, 0.0, -60.0 * DEG, 0.0, 0.0, 0.0, 0.0, 0.0],
    },
    // seed 004 §3: IR range 25 cm after calibration.
    ir_range_m: 0.25,
};

/// ALICE (seed 001 §3.1, Zimmer's thesis): round, 40 cm, 25 cm/s, odometry, 24 binary
/// whiskers and 24 photoresistors (read through `Hal::whiskers` and `Hal::photoresistors`, not
/// the IR slots: it has no IR proximity sensors). ALICE steered six wheels; here the drive is
/// differential like the other robots' (the firmware's and the emulator's only drive).
pub const ALICE: Profile = Profile {
    id: ProfileId::Alice,
    name: "alice",
    capabilities: caps::ENCODERS,
    // seed 001 §3.1: 40 cm.
    body_diameter_m: 0.40,
    // default: the thesis gives no wheel base (six steered wheels); 0.36 m fits a 40 cm body.
    wheel_distance_m: 0.36,
    // default: the thesis gives no encoder resolution; 0.1 mm per pulse.
    pulse_m: 0.000_1,
    // default: 5 mm/s a unit, so the thesis's 25 cm/s is 50 units and 100 is twice it.
    motor_unit_mm_s: 5.0,
    motor_max: 100,
    // default: 50 ms; situations are sampled on their own 3 Hz grid (`alice::situation`).
    cycle_us: 50_000,
    ir: IrLayout {
        count: 0,
        angle_rad: [0.0; 8],
    },
    ir_range_m: 0.0,
};

impl Profile {
    /// The profile for a command-line or link name.
    pub fn by_name(name: &str) -> Option<&'static Profile> {
        match name {
            "khepera" => Some(&KHEPERA),
            "micro-rato" | "microrato" | "dom-dinis" => Some(&MICRO_RATO),
            "alice" => Some(&ALICE),
            _ => None,
        }
    }

    /// The profile a hardware trace's `START` names (`ProfileId as u8`, as the robot writes
    /// it).
    pub fn by_trace_code(code: u8) -> Option<&'static Profile> {
        [&KHEPERA, &MICRO_RATO, &ALICE]
            .into_iter()
            .find(|p| p.id as u8 == code)
    }

    /// Whether the robot has every capability in `bits`.
    pub fn has(&self, bits: u32) -> bool {
        self.capabilities & bits == bits
    }

    /// Converts a speed in mm/s to motor units, rounded and clamped to the motor range.
    pub fn motor_units(&self, mm_s: f32) -> i16 {
        let u = libm::roundf(mm_s / self.motor_unit_mm_s);
        let max = f32::from(self.motor_max);
        // Clamped into i16 range first, so the cast cannot saturate unexpectedly.
        u.clamp(-max, max) as i16
    }

    /// Converts motor units to mm/s.
    pub fn motor_mm_s(&self, units: i16) -> f32 {
        f32::from(units) * self.motor_unit_mm_s
    }

    /// Map capacity this firmware build offers.
    pub fn map_capacity(&self) -> MapCapacity {
        MapCapacity {
            width: crate::MAP_CAPACITY as u16,
            height: crate::MAP_CAPACITY as u16,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn motor_units_round_and_clamp() {
        assert_eq!(KHEPERA.motor_units(80.0), 10);
        assert_eq!(KHEPERA.motor_units(-84.0), -11);
        assert_eq!(KHEPERA.motor_units(1e9), 127);
        assert_eq!(KHEPERA.motor_units(f32::NAN), 0);
        assert_eq!(MICRO_RATO.motor_units(230.0), 75);
    }

    #[test]
    fn profiles_are_found_by_name() {
        assert_eq!(
            Profile::by_name("khepera").map(|p| p.id),
            Some(ProfileId::Khepera)
        );
        assert_eq!(
            Profile::by_name("micro-rato").map(|p| p.id),
            Some(ProfileId::MicroRato)
        );
        assert!(Profile::by_name("roomba").is_none());
    }
}
