//! The ranges a telemetry frame's fields travel in, which bound the frame to 80 bytes on the
//! wire whatever the values (PROTOCOL.md §2, §6 kind 3).
//!
//! Telemetry is postcard varints (7 bits a byte; signed fields zigzag-mapped first), so a small
//! number takes few bytes: typical frames are 59-76 bytes. By type alone a `u32` or `i32` takes
//! up to 5 bytes and a `u16` or `i16` up to 3, which put the true worst case at 97 bytes.
//! Here every field that needs fewer bytes than its type allows is given the range those bytes
//! hold, chosen from what the field measures, and the encoder brings a value outside it in:
//! - angles (heading, compass, beacon bearing) by whole turns, so the angle is unchanged;
//! - everything else by saturating at the range's end ("at least this much").
//!
//! Fields that wrap (the clock, encoder counts) and those whose real values already need their
//! type's width (the battery's millivolts) keep it. A value inside its range is written exactly
//! as before, byte for byte, so frames are no larger than before and recordings made before
//! this bound read unchanged; the decoder accepts every value of the field's type.
//!
//! Layer: pure, no_std. `Telemetry`'s `Serialize` (in `msg`) writes `bounded()`, so every path
//! that encodes telemetry (the firmware, the emulator, the station's recordings) is bounded.

use crate::msg::{Beacon, BehaviourOut, CycleTiming, Pose, PoseSigma, Telemetry, Wheels};

/// The largest telemetry frame on the wire, delimiter included, for any `Telemetry` value.
pub const MAX_TELEMETRY_FRAME: usize = 80;

/// Largest unsigned value that a varint of `bytes` bytes holds.
pub const fn unsigned_max(bytes: u32) -> u64 {
    (1u64 << (7 * bytes)) - 1
}

/// Smallest and largest signed value whose zigzag varint takes `bytes` bytes.
pub const fn signed_range(bytes: u32) -> (i64, i64) {
    let half = 1i64 << (7 * bytes - 1);
    (-half, half - 1)
}

/// Bytes of the varint of `v` (unsigned LEB128, as postcard writes it).
pub const fn varint_len(mut v: u64) -> usize {
    let mut n = 1;
    while v >= 0x80 {
        v >>= 7;
        n += 1;
    }
    n
}

/// Bytes of the zigzag varint of `v`, as postcard writes a signed integer.
pub const fn zigzag_len(v: i64) -> usize {
    varint_len(((v << 1) ^ (v >> 63)) as u64)
}

/// Position in the map frame, mm: 3 bytes, +-1,048 m. The robots' worlds are metres across
/// (a Khepera box, a Micro-Rato lab, a 64 x 64-cell maze, a lab's ROS map): an estimate a
/// kilometre out is lost, and reads as the range's end.
pub const POSITION_MM: (i32, i32) = (
    signed_range(3).0 as i32, // -1_048_576
    signed_range(3).1 as i32, // 1_048_575
);
/// Heading, mrad: 2 bytes. The robot sends -3142..=3142; a heading outside is brought in by
/// whole turns.
pub const HEADING_MRAD: (i16, i16) = (signed_range(2).0 as i16, signed_range(2).1 as i16);
/// One-sigma position and heading uncertainty, mm and mrad: 2 bytes, up to 16.383 m and 16.383
/// rad (2.6 turns). Beyond either the estimate carries no information the station can use.
pub const SIGMA_MAX: u16 = unsigned_max(2) as u16;
/// Wheel speed and motor command, mm/s: 2 bytes, +-8.19 m/s (these robots drive below 1 m/s).
pub const SPEED_MM_S: (i16, i16) = (signed_range(2).0 as i16, signed_range(2).1 as i16);
/// Compass heading, decidegrees: the robot sends 0..=3599 (2 bytes); a value above 16383 is
/// brought in by whole turns.
pub const COMPASS_MAX_DDEG: u16 = unsigned_max(2) as u16;
/// Beacon bearing, decidegrees: the robot sends -1800..=1800 (2 bytes); a value outside
/// +-8191 is brought in by whole turns.
pub const BEARING_DDEG: (i16, i16) = (signed_range(2).0 as i16, signed_range(2).1 as i16);
/// Control-cycle period and busy time, us: 3 bytes, up to 2.097 s (cycles are 10-50 ms; a
/// cycle that takes seconds has overrun, which `overruns` counts, and reads as the range's end).
pub const CYCLE_MAX_US: u32 = unsigned_max(3) as u32;

/// Whole turns in mrad, rounded: wrapping by it moves an angle by at most 0.2 mrad a turn.
const TURN_MRAD: i32 = 6283;
/// Whole turns in decidegrees.
const TURN_DDEG: i32 = 3600;

impl Telemetry {
    /// The frame as it travels: each field within its range (module docs). A value already
    /// inside is unchanged.
    pub fn bounded(&self) -> Telemetry {
        let speed = |v: i16| v.clamp(SPEED_MM_S.0, SPEED_MM_S.1);
        let cycle = |v: u32| v.min(CYCLE_MAX_US);
        Telemetry {
            pose: Pose {
                x_mm: self.pose.x_mm.clamp(POSITION_MM.0, POSITION_MM.1),
                y_mm: self.pose.y_mm.clamp(POSITION_MM.0, POSITION_MM.1),
                heading_mrad: turn_into(self.pose.heading_mrad, HEADING_MRAD, TURN_MRAD),
            },
            sigma: PoseSigma {
                xy_mm: self.sigma.xy_mm.min(SIGMA_MAX),
                heading_mrad: self.sigma.heading_mrad.min(SIGMA_MAX),
            },
            wheels: Wheels {
                speed_mm_s: self.wheels.speed_mm_s.map(speed),
                encoders: self.wheels.encoders,
            },
            compass_ddeg: if self.compass_ddeg > COMPASS_MAX_DDEG {
                // u16 % 3600 < 3600: the narrowing is exact.
                (i32::from(self.compass_ddeg) % TURN_DDEG) as u16
            } else {
                self.compass_ddeg
            },
            beacon: Beacon {
                bearing_ddeg: turn_into(self.beacon.bearing_ddeg, BEARING_DDEG, TURN_DDEG),
                strength: self.beacon.strength,
            },
            behaviour: BehaviourOut {
                active: self.behaviour.active,
                motor_mm_s: self.behaviour.motor_mm_s.map(speed),
            },
            cycle: CycleTiming {
                period_us: cycle(self.cycle.period_us),
                busy_us: cycle(self.cycle.busy_us),
                overruns: self.cycle.overruns,
            },
            ..*self
        }
    }
}

/// An angle `v` inside `range` as it is; outside, moved by whole turns into -turn/2..turn/2.
fn turn_into(v: i16, range: (i16, i16), turn: i32) -> i16 {
    if (range.0..=range.1).contains(&v) {
        return v;
    }
    let half = turn / 2;
    // In -half..half, well inside i16 for both turns used here.
    ((i32::from(v) + half).rem_euclid(turn) - half) as i16
}

/// The widest telemetry payload the ranges allow, bytes: each field at the end of its range
/// that takes the most varint bytes (postcard writes structs as their fields in order, with
/// no lengths or tags; `u8` and the `Mode` index below 128 take one byte each, the packed
/// readings 10 each).
pub const WIDEST_PAYLOAD: usize = varint_len(u32::MAX as u64) // time_ms: wraps, full width
    + 1 // mode
    + 2 * zigzag_len(POSITION_MM.0 as i64)
    + zigzag_len(HEADING_MRAD.0 as i64)
    + 2 * varint_len(SIGMA_MAX as u64)
    + 2 * zigzag_len(SPEED_MM_S.0 as i64)
    + 2 * varint_len(u16::MAX as u64) // encoders: wrap, full width
    + 2 * crate::packed::PACKED_LEN
    + varint_len(COMPASS_MAX_DDEG as u64)
    + 2 // flags, line_events
    + zigzag_len(BEARING_DDEG.0 as i64)
    + 1 // beacon strength
    + varint_len(u16::MAX as u64) // battery_mv: full width
    + 1 // behaviour.active
    + 2 * zigzag_len(SPEED_MM_S.0 as i64)
    + 2 * varint_len(CYCLE_MAX_US as u64)
    + 1; // overruns

/// The same as a frame on the wire: header 4, CRC 4, COBS 1 (one overhead byte per 254) and
/// the 0x00 delimiter.
pub const WIDEST_FRAME: usize =
    crate::frame::HEADER_LEN + WIDEST_PAYLOAD + crate::frame::CRC_LEN + 2;

const _: () = assert!(WIDEST_FRAME <= MAX_TELEMETRY_FRAME);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn range_ends_take_the_bytes_they_are_chosen_for() {
        assert_eq!(POSITION_MM, (-1_048_576, 1_048_575));
        assert_eq!(HEADING_MRAD, (-8192, 8191));
        assert_eq!(
            (SIGMA_MAX, COMPASS_MAX_DDEG, CYCLE_MAX_US),
            (16383, 16383, 2_097_151)
        );
        for (lo, hi, bytes) in [
            (i64::from(POSITION_MM.0), i64::from(POSITION_MM.1), 3),
            (i64::from(HEADING_MRAD.0), i64::from(HEADING_MRAD.1), 2),
        ] {
            assert_eq!((zigzag_len(lo), zigzag_len(hi)), (bytes, bytes));
            assert_eq!(
                (zigzag_len(lo - 1), zigzag_len(hi + 1)),
                (bytes + 1, bytes + 1)
            );
        }
        assert_eq!(varint_len(u64::from(CYCLE_MAX_US)), 3);
        assert_eq!(varint_len(u64::from(CYCLE_MAX_US) + 1), 4);
        assert_eq!((WIDEST_PAYLOAD, WIDEST_FRAME), (70, 80));
    }

    #[test]
    fn angles_outside_their_range_keep_their_direction() {
        assert_eq!(turn_into(3142, HEADING_MRAD, TURN_MRAD), 3142);
        assert_eq!(turn_into(8191, HEADING_MRAD, TURN_MRAD), 8191);
        assert_eq!(turn_into(8192, HEADING_MRAD, TURN_MRAD), 8192 - 6283);
        assert_eq!(
            turn_into(i16::MIN, HEADING_MRAD, TURN_MRAD),
            -32768 + 5 * 6283
        );
        assert_eq!(
            turn_into(i16::MAX, BEARING_DDEG, TURN_DDEG),
            32767 - 9 * 3600
        );
        let t = Telemetry {
            compass_ddeg: u16::MAX,
            ..Telemetry::default()
        };
        assert_eq!(t.bounded().compass_ddeg, 65535 % 3600);
    }
}
