//! Turning on the spot (seed 000 §4.5, Figs. 15-16).
//!
//! The drift network without its thresholds and strong/weak switch: wheel speeds opposite and
//! proportional to the remaining angle. Two triggers start a 180° turn: the robot has not left
//! a circle of `circle_radius_m` within `circle_cycles` cycles, or the front sensors show a
//! dead-end pattern. While a turn runs the arbiter suppresses every other behaviour.
//!
//! Invariants: a turn tracks the angle still to turn from the measured heading changes, so a
//! 180° turn is exact and goes the way it started; it ends within `tolerance_rad` or after
//! `timeout_cycles` (a stuck robot must not spin forever). The 180° direction is drawn from
//! the PRNG (no preferred side, in the spirit of §4.2). Cannot fail.

use super::{units, MotorCommand, XorShift32};
use crate::odometry::{wrap_angle, Point, Pose};
use core::f32::consts::PI;

/// Parameters of turning (seed 000 §4.5; the paper gives no values, all are choices).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TurnParams {
    /// Wheel speed per radian still to turn, units/rad. 6: full speed beyond 1 rad.
    pub gain_units_per_rad: f32,
    /// Slowest wheel speed while turning, units (below 1 the rounding would stop the robot).
    pub min_units: i16,
    /// Fastest wheel speed while turning, units (6 = the base propulsion).
    pub max_units: i16,
    /// A turn is done when less than this remains, radians. 5°: a 1-unit turn moves about
    /// 1.8° per 80 ms cycle, so 5° cannot be overshot.
    pub tolerance_rad: f32,
    /// Longest turn, cycles: 150 (12 s) covers 180° at the slowest speed with margin.
    pub timeout_cycles: u16,
    /// Radius of the circle the robot must leave, metres. 0.10 m, about two Khepera diameters.
    pub circle_radius_m: f32,
    /// Cycles allowed inside the circle (N of §4.5). 200 cycles = 16 s: at 48 mm/s a free
    /// robot crosses 10 cm in 25 cycles, so only a trapped one stays 200.
    pub circle_cycles: u16,
    /// Dead end: both front sensors S2, S3 at least this. 500, at the avoidance threshold.
    pub dead_end_front: u16,
    /// Dead end: the strongest of S0/S1 and of S4/S5 at least this. 300: walls on both sides.
    pub dead_end_side: u16,
}

impl Default for TurnParams {
    fn default() -> Self {
        Self {
            gain_units_per_rad: 6.0,
            min_units: 1,
            max_units: 6,
            tolerance_rad: 5.0 * PI / 180.0,
            timeout_cycles: 150,
            circle_radius_m: 0.10,
            circle_cycles: 200,
            dead_end_front: 500,
            dead_end_side: 300,
        }
    }
}

/// Why a turn runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TurnReason {
    /// Could not leave the circle within N cycles (Fig. 16 left).
    Circle,
    /// Dead-end pattern on the front sensors (Fig. 16 right).
    DeadEnd,
    /// Requested by a caller (e.g. to face a direction).
    Requested,
}

/// A turn in progress.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ActiveTurn {
    /// Signed angle still to turn, radians (positive = counter-clockwise).
    pub remaining_rad: f32,
    /// Why.
    pub reason: TurnReason,
    last_heading: f32,
    cycles: u16,
}

/// Wheel command turning on the spot towards a signed angle error (Fig. 15 without the
/// thresholds): proportional, limited to `[min_units, max_units]`.
pub fn turn_on_spot(error_rad: f32, p: &TurnParams) -> MotorCommand {
    let lo = f32::from(p.min_units.max(0));
    let hi = f32::from(p.max_units.max(p.min_units).max(0));
    let speed = units(
        (p.gain_units_per_rad * libm::fabsf(error_rad))
            .max(lo)
            .min(hi),
    );
    if error_rad >= 0.0 {
        MotorCommand::new(-speed, speed)
    } else {
        MotorCommand::new(speed, -speed)
    }
}

/// Whether the front sensors show a dead end: blocked ahead and on both sides.
pub fn is_dead_end(ir: &[u16; 8], p: &TurnParams) -> bool {
    ir[2] >= p.dead_end_front
        && ir[3] >= p.dead_end_front
        && ir[0].max(ir[1]) >= p.dead_end_side
        && ir[4].max(ir[5]) >= p.dead_end_side
}

/// Turning state: the circle monitor and the turn in progress.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Turning {
    anchor: Option<Point>,
    in_circle: u16,
    active: Option<ActiveTurn>,
}

/// What turning did this cycle.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct TurnOutput {
    /// Some while turning: the command that suppresses all other behaviours.
    pub cmd: Option<MotorCommand>,
    /// A turn was triggered by the dead-end pattern this cycle (a degrading event for
    /// dead reckoning, seed 004 §4).
    pub dead_end: bool,
}

impl Turning {
    /// Idle, no circle yet.
    pub const fn new() -> Self {
        Self {
            anchor: None,
            in_circle: 0,
            active: None,
        }
    }

    /// The turn in progress, if any.
    pub fn active(&self) -> Option<ActiveTurn> {
        self.active
    }

    /// Cycles spent inside the current circle.
    pub fn cycles_in_circle(&self) -> u16 {
        self.in_circle
    }

    /// Starts turning by `angle_rad` (signed) from `pose`.
    pub fn start(&mut self, angle_rad: f32, reason: TurnReason, pose: Pose) {
        self.active = Some(ActiveTurn {
            remaining_rad: angle_rad,
            reason,
            last_heading: pose.heading,
            cycles: 0,
        });
    }

    /// Cancels a turn and forgets the circle.
    pub fn reset(&mut self) {
        *self = Self::new();
    }

    /// One cycle. `monitor` enables the two 180° triggers (off while the robot is meant to
    /// stand still or another turn-on-the-spot runs).
    pub fn step(
        &mut self,
        ir: &[u16; 8],
        pose: Pose,
        monitor: bool,
        p: &TurnParams,
        rng: &mut XorShift32,
    ) -> TurnOutput {
        let mut out = TurnOutput::default();
        if self.active.is_none() && monitor {
            if is_dead_end(ir, p) {
                out.dead_end = true;
                self.start_half_turn(TurnReason::DeadEnd, pose, rng);
            } else if self.circle_expired(pose.point(), p) {
                self.start_half_turn(TurnReason::Circle, pose, rng);
            }
        } else if !monitor {
            self.in_circle = 0;
            self.anchor = None;
        }
        out.cmd = self.advance(pose, p);
        out
    }

    fn start_half_turn(&mut self, reason: TurnReason, pose: Pose, rng: &mut XorShift32) {
        let angle = if rng.coin() { PI } else { -PI };
        self.start(angle, reason, pose);
    }

    /// Counts cycles within the circle around the anchor; re-anchors when it is left.
    fn circle_expired(&mut self, at: Point, p: &TurnParams) -> bool {
        match self.anchor {
            Some(a) if a.distance_to(at) <= p.circle_radius_m => {
                self.in_circle = self.in_circle.saturating_add(1);
                self.in_circle >= p.circle_cycles
            }
            _ => {
                self.anchor = Some(at);
                self.in_circle = 0;
                false
            }
        }
    }

    fn advance(&mut self, pose: Pose, p: &TurnParams) -> Option<MotorCommand> {
        let mut t = self.active?;
        t.remaining_rad -= wrap_angle(pose.heading - t.last_heading);
        t.last_heading = pose.heading;
        if libm::fabsf(t.remaining_rad) < p.tolerance_rad || t.cycles >= p.timeout_cycles {
            self.active = None;
            // A fresh circle starts where the turn ended.
            self.anchor = Some(pose.point());
            self.in_circle = 0;
            return None;
        }
        t.cycles += 1;
        self.active = Some(t);
        Some(turn_on_spot(t.remaining_rad, p))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Spins a pose by what `cmd` does in one 80 ms Khepera cycle (d = 52 mm).
    fn spin(pose: Pose, cmd: MotorCommand) -> Pose {
        let (l, r) = cmd.to_mps();
        Pose::new(pose.x, pose.y, pose.heading + (r - l) / 0.052 * 0.08)
    }

    #[test]
    fn turn_command_is_proportional_and_limited() {
        let p = TurnParams::default();
        assert_eq!(turn_on_spot(0.5, &p), MotorCommand::new(-3, 3));
        assert_eq!(turn_on_spot(-3.0, &p), MotorCommand::new(6, -6));
        assert_eq!(turn_on_spot(0.01, &p), MotorCommand::new(-1, 1));
    }

    #[test]
    fn staying_inside_the_circle_for_n_cycles_triggers_a_half_turn() {
        let p = TurnParams::default();
        let mut rng = XorShift32::new(9);
        let mut t = Turning::new();
        let pose = Pose::new(1.0, 1.0, 0.0);
        for i in 0..p.circle_cycles {
            let out = t.step(&[0; 8], pose, true, &p, &mut rng);
            assert_eq!(out.cmd, None, "cycle {i}");
        }
        let out = t.step(&[0; 8], pose, true, &p, &mut rng);
        assert!(out.cmd.is_some());
        assert_eq!(t.active().map(|a| a.reason), Some(TurnReason::Circle));
    }

    #[test]
    fn leaving_the_circle_restarts_the_count() {
        let p = TurnParams::default();
        let mut rng = XorShift32::new(9);
        let mut t = Turning::new();
        for i in 0..1000u16 {
            // 5 mm per cycle: leaves a 10 cm circle every 21 cycles.
            let pose = Pose::new(f32::from(i) * 0.005, 0.0, 0.0);
            assert_eq!(t.step(&[0; 8], pose, true, &p, &mut rng).cmd, None);
        }
        assert!(t.cycles_in_circle() <= 21);
    }

    #[test]
    fn a_dead_end_pattern_turns_180_degrees_and_then_stops_turning() {
        let p = TurnParams::default();
        let mut rng = XorShift32::new(10);
        let mut t = Turning::new();
        let dead_end = [350, 200, 600, 650, 100, 400, 0, 0];
        let mut pose = Pose::new(0.5, 0.5, 0.3);
        let first = t.step(&dead_end, pose, true, &p, &mut rng);
        assert!(first.dead_end);
        let mut cmd = first.cmd;
        let mut turned = 0.0;
        let mut cycles = 0;
        while let Some(c) = cmd {
            assert_eq!(c.left, -c.right, "on the spot");
            let next = spin(pose, c);
            turned += wrap_angle(next.heading - pose.heading);
            pose = next;
            cycles += 1;
            cmd = t.step(&dead_end, pose, true, &p, &mut rng).cmd;
            assert!(cycles < 200);
        }
        assert!(
            (libm::fabsf(turned) - PI).abs() < p.tolerance_rad,
            "{turned}"
        );
        assert!(!is_dead_end(&[350, 200, 600, 100, 100, 400, 0, 0], &p));
    }

    #[test]
    fn a_turn_that_makes_no_progress_times_out() {
        let p = TurnParams::default();
        let mut rng = XorShift32::new(11);
        let mut t = Turning::new();
        t.start(PI, TurnReason::Requested, Pose::default());
        let mut cycles = 0;
        while t
            .step(&[0; 8], Pose::default(), true, &p, &mut rng)
            .cmd
            .is_some()
        {
            cycles += 1;
        }
        assert_eq!(cycles, p.timeout_cycles);
    }

    #[test]
    fn half_turns_go_both_ways() {
        let p = TurnParams::default();
        let mut rng = XorShift32::new(12);
        let mut ccw = 0;
        for _ in 0..100 {
            let mut t = Turning::new();
            let out = t.step(
                &[400, 0, 600, 600, 0, 400, 0, 0],
                Pose::default(),
                true,
                &p,
                &mut rng,
            );
            ccw += i32::from(out.cmd.is_some_and(|c| c.right > 0));
        }
        assert!((30..70).contains(&ccw), "{ccw}");
    }
}
