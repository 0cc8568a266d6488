//! The motion laws both searches drive with (seed 004 §5's reactive behaviours): heading for
//! a point with the side sensors pushing off walls passed, and following a wall on one side.
//!
//! Pure functions of the parameters and one cycle's input; no state, cannot fail.

use super::{ExploreInput, ExploreParams, WallSide};
use crate::behaviour::{units, MotorCommand};
use crate::odometry::{wrap_angle, Point};

/// A wall within `wall_ir` straight ahead (a sensor within 20 degrees of the heading).
pub fn front_blocked(p: &ExploreParams, inp: &ExploreInput<'_>) -> bool {
    inp.ir
        .iter()
        .any(|&(r, a)| libm::fabsf(a) < 0.35 && r >= p.wall_ir)
}

/// Heads for `target`: on the spot when it is far off the heading, else proportionally,
/// side sensors pushing the robot off walls it passes.
pub fn steer(p: &ExploreParams, inp: &ExploreInput<'_>, target: Point) -> MotorCommand {
    let dir = inp.pose.point().bearing_to(target);
    let err = wrap_angle(dir - inp.pose.heading);
    if libm::fabsf(err) > 1.0 {
        let s = if err > 0.0 {
            p.follow_speed
        } else {
            -p.follow_speed
        };
        return MotorCommand::new(units(-s), units(s));
    }
    let mut push = 0.0;
    for &(r, a) in inp.ir {
        if libm::fabsf(a) >= 0.35 && r >= p.wall_ir {
            push += if a > 0.0 { -1.0 } else { 1.0 };
        }
    }
    let turn = p.heading_gain * err + push * p.heading_gain * 0.5;
    MotorCommand::new(units(p.seek_speed - turn), units(p.seek_speed + turn))
}

/// Wall following with three IR sensors: keep `follow_distance_m` from the wall on `side`;
/// turn away on the spot when the front is blocked; curve in when the wall is lost.
pub fn follow(p: &ExploreParams, inp: &ExploreInput<'_>, side: WallSide) -> MotorCommand {
    // +1 turns left (counter-clockwise): away from a wall on the right.
    let away = match side {
        WallSide::Left => -1.0,
        WallSide::Right => 1.0,
    };
    if front_blocked(p, inp) {
        let s = p.follow_speed * away;
        return MotorCommand::new(units(-s), units(s));
    }
    let side_reading = inp
        .ir
        .iter()
        .filter(|&&(_, a)| match side {
            WallSide::Left => a >= 0.35,
            WallSide::Right => a <= -0.35,
        })
        .map(|&(r, _)| r)
        .max()
        .unwrap_or(0);
    // A side sensor at 60 degrees sees the wall at d / sin(60) along its ray.
    let turn = match p.ir.distance(side_reading) {
        Some(d) => {
            let wall = d * 0.866;
            // Too close: turn away; too far: turn towards.
            (p.follow_distance_m - wall) * p.follow_gain * away
        }
        None => -away * p.follow_speed * 0.6,
    };
    MotorCommand::new(units(p.follow_speed - turn), units(p.follow_speed + turn))
}
