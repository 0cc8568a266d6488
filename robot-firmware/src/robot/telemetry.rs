//! Builds the telemetry frame from the robot's state (PROTOCOL.md §6, kind 3).
//!
//! Layer: a pure conversion from firmware units (metres, radians, f32) to wire units
//! (millimetres, milliradians, decidegrees, integers). Values outside a wire field's range
//! saturate at its limits; NaN becomes 0. Cannot fail.

use protocol::{
    flags, Beacon, BehaviourOut, CycleTiming, Packed10x8, Pose as WirePose, PoseSigma, Telemetry,
    Wheels,
};

use super::{Core, Kit};
use crate::behaviour::units;

/// The telemetry frame for the robot's current state.
pub fn build<K: Kit>(core: &Core<K>, now_ms: u32) -> Telemetry {
    let pose = core.pose();
    let s = &core.sensors;
    let (sigma_xy_m, sigma_heading) = sigma(core);
    let (active, motor) = core.behaviour_report();
    let mut f = 0u8;
    for (on, bit) in [
        (s.ground, flags::GROUND),
        (s.line, flags::LINE),
        (core.failsafe, flags::FAILSAFE),
        (core.arrived, flags::ARRIVED),
        (core.objects.has_map(), flags::HAS_MAP),
        (core.objects.has_plan(), flags::HAS_PLAN),
        (
            core.sensors.gripper.is_some_and(|g| g.object),
            flags::CARRYING,
        ),
    ] {
        if on {
            f |= bit;
        }
    }
    let encoders = s.encoders.unwrap_or([0, 0]);
    Telemetry {
        time_ms: now_ms,
        mode: core.mode,
        pose: WirePose {
            x_mm: sat_i32(pose.x * 1000.0),
            y_mm: sat_i32(pose.y * 1000.0),
            heading_mrad: units(pose.heading * 1000.0),
        },
        sigma: PoseSigma {
            xy_mm: sat_u16(sigma_xy_m * 1000.0),
            heading_mrad: sat_u16(sigma_heading * 1000.0),
        },
        wheels: Wheels {
            speed_mm_s: core.wheel_speed_mm_s,
            // The wire carries the low 16 bits; the station unwraps them.
            encoders: [encoders[0] as u16, encoders[1] as u16],
        },
        ir: Packed10x8::new(s.ir),
        light: Packed10x8::new(s.ambient),
        // The compass updates at ~5 Hz (seed 004 §3) and reads None in between: report the
        // last heading it gave.
        compass_ddeg: if core.profile.has(protocol::caps::COMPASS) {
            ddeg(core.compass_heading)
        } else {
            0
        },
        flags: f,
        line_events: core.line_events,
        beacon: s
            .beacon
            .map(|b| Beacon {
                bearing_ddeg: units(b.bearing_rad.to_degrees() * 10.0),
                strength: b.strength,
            })
            .unwrap_or_default(),
        battery_mv: s.battery_mv,
        behaviour: BehaviourOut {
            active,
            motor_mm_s: [
                units(core.profile.motor_mm_s(motor.left)),
                units(core.profile.motor_mm_s(motor.right)),
            ],
        },
        cycle: CycleTiming {
            period_us: core.timing.period_us,
            busy_us: core.timing.busy_us,
            overruns: core.timing.overruns,
        },
    }
}

/// One-sigma position (m) and heading (rad) uncertainty.
fn sigma<K: Kit>(core: &Core<K>) -> (f32, f32) {
    if core.profile.has(protocol::caps::ENCODERS) {
        let c = core.odometry.covariance();
        (c.sigma_position_m(), c.sigma_heading_rad())
    } else {
        // seed 004 §4: dead reckoning is good to about 0.3 m in free motion; the confidence
        // xi (1 = just calibrated or at the known start) scales that, with the compass's
        // 2 degrees RMS (seed 004 §3) for the heading.
        let xy = 0.3 * (1.0 - core.dead.confidence()) + 0.05;
        (xy, 2.0f32.to_radians())
    }
}

/// Heading in radians (counter-clockwise from +x) to decidegrees 0..=3599.
fn ddeg(rad: f32) -> u16 {
    let d = libm::roundf(rad.to_degrees() * 10.0) as i32;
    // rem_euclid keeps the value in 0..3600 for any input, negative ones included.
    d.rem_euclid(3600) as u16
}

fn sat_i32(v: f32) -> i32 {
    libm::roundf(v) as i32
}

fn sat_u16(v: f32) -> u16 {
    libm::roundf(v) as u16
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compass_decidegrees_wrap_into_range() {
        assert_eq!(ddeg(0.0), 0);
        assert_eq!(ddeg(core::f32::consts::FRAC_PI_2), 900);
        assert_eq!(ddeg(-core::f32::consts::FRAC_PI_2), 2700);
        assert_eq!(ddeg(f32::NAN), 0);
    }

    #[test]
    fn out_of_range_values_saturate() {
        assert_eq!(units(1e9), i16::MAX);
        assert_eq!(sat_u16(-5.0), 0);
        assert_eq!(sat_i32(f32::NAN), 0);
    }
}
