//! The hardware-abstraction trait: everything the firmware touches of its robot.
//!
//! Layer: the boundary between the firmware's logic and a particular robot. A microcontroller
//! board implements it over its timers, ADCs and UART; the emulator implements it over a
//! simulated world. The firmware calls it only from `Robot::step`, once per control cycle:
//! read the clock and sensors, write the motors, move serial bytes. Sensors a robot lacks (see
//! `Profile`) return their documented "absent" value; the firmware never asks the profile's
//! missing hardware for anything it relies on.

/// A beacon reading (seed 004 §3: an IR receiver in a tube at the front).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BeaconReading {
    /// Bearing of the beacon from the robot's heading, radians, positive to the left.
    pub bearing_rad: f32,
    /// Signal strength 0..=255; 0 when the beacon is not in view.
    pub strength: u8,
}

/// What the gripper turret is told (seed 000 §1.1: the arm moves to 256 positions, the grip
/// is open or closed).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GripperCommand {
    /// Arm position to move to: [`ARM_UP`] (carrying) .. [`ARM_DOWN`] (fingers on the floor).
    pub arm: u8,
    /// Close the grip (true) or open it.
    pub closed: bool,
}

/// Arm position with the arm raised (the object, if any, clear of the floor).
pub const ARM_UP: u8 = 0;
/// Arm position with the fingers at floor level, where an object can be gripped.
pub const ARM_DOWN: u8 = 255;

/// Pixels in one K213 camera line.
pub const CAMERA_PIXELS: usize = 64;

/// What the gripper turret reports.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GripperState {
    /// Where the arm is now (it moves towards the commanded position over some cycles).
    pub arm: u8,
    /// The grip is closed (and has finished closing).
    pub closed: bool,
    /// The object-present sensor: something is between the fingers.
    pub object: bool,
}

/// Motor command in the profile's native units (`Profile::motor_unit_mm_s` mm/s each; on a
/// Khepera the speed unit of 8 mm/s, on the micro-rato the nominal speed of seed 004 §4).
pub use crate::behaviour::MotorCommand;

/// The robot's hardware, as the firmware sees it.
pub trait Hal {
    /// Monotonic time since power-up, microseconds. Never goes backwards.
    fn now_us(&mut self) -> u64;

    /// Sets both motors. Values outside the profile's range are clamped by the firmware first.
    fn set_motors(&mut self, cmd: MotorCommand);

    /// Cumulative encoder pulses, left then right; `None` on robots without encoders.
    fn encoders(&mut self) -> Option<[i32; 2]>;

    /// IR proximity S0..S7, 10-bit counts (higher = closer); unused slots 0.
    fn ir(&mut self) -> [u16; 8];

    /// Ambient light S0..S7, 10-bit counts, inverted (lower = brighter); all 0 when absent.
    fn ambient(&mut self) -> [u16; 8];

    /// Compass heading, radians counter-clockwise from the map's +x axis, in (-pi, pi];
    /// `None` without a compass or while no new reading is ready.
    fn compass(&mut self) -> Option<f32>;

    /// Ground sensor: true over the goal area (seed 004 §3); false when absent.
    fn ground(&mut self) -> bool;

    /// Floor line sensor: true while over a line (seed 003); false when absent.
    fn line(&mut self) -> bool;

    /// Beacon sensor; `None` when absent.
    fn beacon(&mut self) -> Option<BeaconReading>;

    /// Battery voltage, millivolts; 0 when unknown.
    fn battery_mv(&mut self) -> u16;

    /// The gripper turret's state; `None` on robots without one (the default).
    fn gripper(&mut self) -> Option<GripperState> {
        None
    }

    /// Commands the gripper turret; ignored on robots without one (the default).
    fn set_gripper(&mut self, _cmd: GripperCommand) {}

    /// Grabs one line of the K213 camera (seed 000 §1.1: 64 pixels, 8 bit, 36 deg, pixel 0 at
    /// the left edge) into `image`; false on robots without one (the default).
    fn camera(&mut self, _image: &mut [u8; CAMERA_PIXELS]) -> bool {
        false
    }

    /// ALICE's 24 binary whiskers (seed 001 §3.1): bit `i` set while whisker `i` (looking
    /// `i * 15` degrees anticlockwise from forward) touches; `None` on robots without them
    /// (the default).
    fn whiskers(&mut self) -> Option<u32> {
        None
    }

    /// ALICE's 24 photoresistors, each 0 (dark) ..= 255 (saturated), uncalibrated, sensor `i`
    /// looking like whisker `i`; `None` on robots without them (the default).
    fn photoresistors(&mut self) -> Option<[u8; crate::alice::SENSORS]> {
        None
    }

    /// Reads received serial bytes into `buf`; returns how many (0 when none are waiting).
    fn serial_read(&mut self, buf: &mut [u8]) -> usize;

    /// Offers bytes to the serial transmitter; returns how many it took (may be fewer).
    fn serial_write(&mut self, bytes: &[u8]) -> usize;
}
