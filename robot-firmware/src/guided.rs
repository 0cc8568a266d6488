//! Guided motion to a point: seed 004 §7's `guided_motion()` for the micro-rato profile.
//!
//! Layer: a control law under the plan executor and the go-to mode. In obstacle-free motion
//! the robot drives at top speed with a heading correction proportional to the difference
//! between its heading and the direction of the end point. When an IR sensor sees an obstacle
//! it slows down, stops the heading correction and reacts: it turns away from the nearer side
//! until the sensors clear, then resumes. A large heading error is first removed by turning on
//! the spot. Pure: pose and IR in, motor command out; no clock, no I/O, cannot fail.

use crate::behaviour::{units, MotorCommand};
use crate::odometry::{wrap_angle, Point, Pose};

/// Guided-motion parameters. The paper gives the method, not the numbers: every value here is
/// a documented default, settable over the link.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GuidedParams {
    /// Nominal speed in free motion (seed 004 §4: 75 is "near the maximum speed").
    pub top_speed: f32,
    /// Nominal speed near obstacles.
    pub slow_speed: f32,
    /// Wheel-speed difference per radian of heading error (nominal units per rad).
    pub heading_gain: f32,
    /// Heading error above which the robot turns on the spot first, radians.
    pub turn_in_place_rad: f32,
    /// Nominal wheel speed when turning on the spot.
    pub turn_speed: f32,
    /// IR reading (10-bit, higher = closer) at which an obstacle counts as seen.
    pub obstacle_ir: u16,
    /// Distance at which the end point counts as reached, metres.
    pub arrival_m: f32,
    /// Distance under which speed is halved so the robot does not overshoot, metres.
    pub approach_m: f32,
}

impl Default for GuidedParams {
    fn default() -> Self {
        GuidedParams {
            top_speed: 75.0,
            slow_speed: 25.0,
            heading_gain: 40.0,
            turn_in_place_rad: 1.0,
            turn_speed: 25.0,
            obstacle_ir: 350,
            arrival_m: 0.15,
            approach_m: 0.4,
        }
    }
}

/// Sensors within this of straight ahead see what blocks the way, radians (20 degrees).
const FRONT_RAD: f32 = 0.35;

/// What guided motion did this cycle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GuidedPhase {
    /// Turning on the spot towards the end point.
    Aligning,
    /// Driving with heading correction.
    Driving,
    /// An obstacle is in view: slow, reactive avoidance, no heading correction.
    Avoiding,
    /// Within `arrival_m` of the end point.
    Arrived,
}

/// One guided-motion step. `ir` holds the profile's sensors as (reading, direction in radians,
/// positive to the left) pairs; returns the motor command in nominal units and the phase.
pub fn guided_step(
    pose: Pose,
    target: Point,
    ir: &[(u16, f32)],
    p: &GuidedParams,
) -> (MotorCommand, GuidedPhase) {
    let here = pose.point();
    let distance = here.distance_to(target);
    if distance <= p.arrival_m {
        return (MotorCommand::STOP, GuidedPhase::Arrived);
    }
    // Obstacle pressure: left sensors push right, right sensors push left.
    let mut left_pressure = 0.0f32;
    let mut right_pressure = 0.0f32;
    let mut front = false;
    let mut seen = false;
    for &(reading, angle) in ir {
        if reading >= p.obstacle_ir {
            seen = true;
            front |= libm::fabsf(angle) < FRONT_RAD;
            let w = f32::from(reading);
            if angle >= 0.0 {
                left_pressure += w;
            } else {
                right_pressure += w;
            }
        }
    }
    if seen {
        // Away from the side that reads more; a dead-ahead obstacle (equal pressure) is
        // passed on the right-hand side, consistently, so the robot does not dither.
        let away_right = left_pressure >= right_pressure;
        let turn = p.slow_speed;
        let cmd = match (front, away_right) {
            // Blocked ahead: turn on the spot.
            (true, true) => MotorCommand::new(units(turn), units(-turn * 0.5)),
            (true, false) => MotorCommand::new(units(-turn * 0.5), units(turn)),
            // A wall beside: keep going at reduced speed, veering off it (seed 004 §7:
            // "reduces speed and stops applying the speed correction").
            (false, true) => MotorCommand::new(units(turn), units(turn * 0.3)),
            (false, false) => MotorCommand::new(units(turn * 0.3), units(turn)),
        };
        return (cmd, GuidedPhase::Avoiding);
    }
    let error = wrap_angle(here.bearing_to(target) - pose.heading);
    if libm::fabsf(error) > p.turn_in_place_rad {
        let s = if error > 0.0 {
            p.turn_speed
        } else {
            -p.turn_speed
        };
        return (
            MotorCommand::new(units(-s), units(s)),
            GuidedPhase::Aligning,
        );
    }
    let speed = if distance < p.approach_m {
        p.top_speed * 0.5
    } else {
        p.top_speed
    };
    let correction = p.heading_gain * error;
    (
        MotorCommand::new(units(speed - correction), units(speed + correction)),
        GuidedPhase::Driving,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    const IR_NONE: [(u16, f32); 3] = [(0, 1.0), (0, 0.0), (0, -1.0)];

    #[test]
    fn free_motion_is_top_speed_with_proportional_correction() {
        let p = GuidedParams::default();
        let pose = Pose::new(0.0, 0.0, 0.0);
        let (cmd, phase) = guided_step(pose, Point::new(2.0, 0.0), &IR_NONE, &p);
        assert_eq!(phase, GuidedPhase::Driving);
        assert_eq!((cmd.left, cmd.right), (75, 75));
        // Target slightly to the left: the right wheel speeds up.
        let (cmd, _) = guided_step(pose, Point::new(2.0, 0.4), &IR_NONE, &p);
        assert!(cmd.right > cmd.left);
        let err = libm::atan2f(0.4, 2.0);
        assert_eq!(cmd.right - cmd.left, units(2.0 * p.heading_gain * err));
    }

    #[test]
    fn a_large_heading_error_turns_on_the_spot_first() {
        let p = GuidedParams::default();
        let (cmd, phase) = guided_step(
            Pose::new(0.0, 0.0, 0.0),
            Point::new(-2.0, 0.1),
            &IR_NONE,
            &p,
        );
        assert_eq!(phase, GuidedPhase::Aligning);
        assert_eq!(cmd.left, -cmd.right);
    }

    #[test]
    fn an_obstacle_slows_down_and_stops_heading_correction() {
        let p = GuidedParams::default();
        let ir = [(0, 1.0), (0, 0.0), (600, -1.0)];
        let (cmd, phase) = guided_step(Pose::new(0.0, 0.0, 0.0), Point::new(2.0, 1.0), &ir, &p);
        assert_eq!(phase, GuidedPhase::Avoiding);
        // Obstacle on the right: turn left, slower than top speed.
        assert!(cmd.right > cmd.left);
        assert!(cmd.right <= units(p.slow_speed));
    }

    #[test]
    fn arrival_stops_the_motors_and_approach_halves_speed() {
        let p = GuidedParams::default();
        let pose = Pose::new(1.0, 1.0, 0.0);
        let (cmd, phase) = guided_step(pose, Point::new(1.1, 1.0), &IR_NONE, &p);
        assert_eq!((cmd, phase), (MotorCommand::STOP, GuidedPhase::Arrived));
        let (cmd, _) = guided_step(pose, Point::new(1.3, 1.0), &IR_NONE, &p);
        assert_eq!(cmd.left, units(p.top_speed * 0.5));
    }
}
