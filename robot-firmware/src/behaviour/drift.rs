//! Drift: navigation to a point of known coordinates (seed 000 §4.4, Figs. 13-15).
//!
//! Turn on the spot towards the target, then drive (propulsion from avoidance) while a drift
//! proportional to the heading error is superimposed, strong beyond a switch angle and weak
//! below it. To break cycles the nearest point reached is memorised: coming back to it (within
//! 5 cm) the first time halves the drift; coming back again pauses navigation for a number of
//! cycles that grows with each failure (the arbiter follows the obstacle's edge meanwhile,
//! alternating sides between failures), after which navigation restarts from the new place;
//! a pause also ends as soon as the edge has brought the robot nearer the target than its
//! nearest point (the cycle is broken; following on would only lead away again).
//! Within 15 cm the robot turns to the target again and halves its propulsion; within 5 cm the
//! target is reached.
//!
//! A 180° turn of the turning schema (the robot could not leave its circle, or faced a dead
//! end, §4.5) counts as cyclic behaviour exactly like a return to the nearest point
//! ([`Drift::cyclic`]): a robot pressed against a wall across its way never leaves the 5 cm
//! around its nearest point, so without this it would sit there for the whole run. The
//! nearest point and the failure count survive a pause, so driving back into the same trap
//! pauses again at once, for longer.
//!
//! Invariants: the drift only slows the motor on the side of the target (like edge following,
//! it is added to avoidance); `Reached` is final until a new target is set; pauses grow
//! linearly and saturate instead of overflowing. Cannot fail.

use super::turn::{turn_on_spot, TurnParams};
use super::{units, MotorCommand, Side};
use crate::odometry::{wrap_angle, Point, Pose};

/// Parameters of drift (seed 000 §4.4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DriftParams {
    /// Weak drift per radian of heading error, units/rad. Not in the paper: 4 (1 unit at 14°).
    pub weak_gain_units_per_rad: f32,
    /// Strong drift per radian, units/rad. Not in the paper: 8 (twice the weak one).
    pub strong_gain_units_per_rad: f32,
    /// Heading error beyond which the strong drift applies, radians. Not in the paper: 30°.
    pub strong_above_rad: f32,
    /// Largest drift, units. Not in the paper: 6, which stops the inner wheel at base speed.
    pub max_drift_units: i16,
    /// Tolerance of the nearest-point memory, metres. seed 000 §4.4: 5 cm.
    pub nearest_tolerance_m: f32,
    /// Drift factor applied on the first return to the nearest point. seed 000 §4.4: halved.
    pub revisit_factor: f32,
    /// Pause after a further return, cycles per failure so far. Not in the paper ("fixed but
    /// increasing with the number of failures"): 100 cycles = 8 s of edge following.
    pub pause_cycles_per_failure: u16,
    /// Approach radius: turn to the target and halve propulsion, metres. seed 000 §4.4: 15 cm.
    pub approach_radius_m: f32,
    /// Propulsion factor inside the approach radius. seed 000 §4.4: halved.
    pub approach_propulsion: f32,
    /// Arrival radius, metres. seed 000 §4.4: 5 cm.
    pub arrival_radius_m: f32,
    /// Cycles of commanded standstill (avoidance and drift cancel: both wheels at most 1
    /// unit) after which the robot counts as going round in circles. Not in the paper: 50
    /// cycles (4 s), a quarter of the circle criterion's 200. Pressed against a wall across
    /// its way the robot stood still until those 200 cycles (16 s) were over: 15-39 % of
    /// every failed run on the box benchmark. Measured on the 200 boxes (no noise / default
    /// noise): 12 cycles 196 / 82, 25 cycles 197 / 76, 50 cycles 195 / 75, none 182 / 59;
    /// Fig. 17 over 30 seeds within 5 cm: 7, 5, 10 and 9.
    pub standstill_cycles: u16,
}

impl Default for DriftParams {
    fn default() -> Self {
        Self {
            weak_gain_units_per_rad: 4.0,
            strong_gain_units_per_rad: 8.0,
            strong_above_rad: 30.0 * core::f32::consts::PI / 180.0,
            max_drift_units: 6,
            // seed 000 §4.4: nearest point re-encountered within 5 cm -> drift halved
            nearest_tolerance_m: 0.05,
            revisit_factor: 0.5,
            pause_cycles_per_failure: 100,
            // seed 000 §4.4: within 15 cm turn on the spot and halve the basic propulsion
            approach_radius_m: 0.15,
            approach_propulsion: 0.5,
            // seed 000 §4.4: target reached within 5 cm
            arrival_radius_m: 0.05,
            standstill_cycles: 50,
        }
    }
}

/// Where navigation is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum DriftPhase {
    /// Turning on the spot to face the target (Fig. 14 (1) and (4)).
    #[default]
    Aligning,
    /// Driving with drift (Fig. 14 (2)-(3)).
    Driving,
    /// Navigation interrupted to find a new starting point, `remaining` cycles.
    Paused {
        /// Cycles left.
        remaining: u16,
    },
    /// Within the arrival radius: done.
    Reached,
}

/// What drift produced this cycle.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct DriftOutput {
    /// Drift to add to avoidance, or the on-the-spot turn when `turning`.
    pub cmd: MotorCommand,
    /// `cmd` is a turn on the spot that suppresses the other behaviours (§4.5).
    pub turning: bool,
    /// Factor for avoidance's base propulsion (1, 1/2 near the target, 0 when reached).
    pub propulsion: f32,
    /// Phase after this cycle.
    pub phase: DriftPhase,
    /// Distance to the target, metres.
    pub distance_m: f32,
    /// Signed heading error towards the target, radians (positive = target to the left).
    pub heading_error_rad: f32,
}

/// Drift state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drift {
    target: Point,
    phase: DriftPhase,
    nearest: Option<(Point, f32)>,
    left_nearest: bool,
    revisits: u8,
    factor: f32,
    failures: u16,
    approach: bool,
}

impl Drift {
    /// Starts navigating to `target`.
    pub const fn new(target: Point) -> Self {
        Self {
            target,
            phase: DriftPhase::Aligning,
            nearest: None,
            left_nearest: false,
            revisits: 0,
            factor: 1.0,
            failures: 0,
            approach: false,
        }
    }

    /// The target.
    pub fn target(&self) -> Point {
        self.target
    }

    /// Current phase.
    pub fn phase(&self) -> DriftPhase {
        self.phase
    }

    /// Current drift factor (1, or halved after a return to the nearest point).
    pub fn factor(&self) -> f32 {
        self.factor
    }

    /// Failed attempts so far (each paused navigation).
    pub fn failures(&self) -> u16 {
        self.failures
    }

    /// The memorised nearest point and its distance to the target.
    pub fn nearest(&self) -> Option<(Point, f32)> {
        self.nearest
    }

    /// One cycle.
    pub fn step(&mut self, pose: Pose, p: &DriftParams, tp: &TurnParams) -> DriftOutput {
        let here = pose.point();
        let dist = here.distance_to(self.target);
        let err = wrap_angle(here.bearing_to(self.target) - pose.heading);
        let mut out = DriftOutput {
            propulsion: 1.0,
            distance_m: dist,
            heading_error_rad: err,
            ..DriftOutput::default()
        };
        if self.phase == DriftPhase::Reached || dist < p.arrival_radius_m {
            self.phase = DriftPhase::Reached;
            out.propulsion = 0.0;
        } else if let DriftPhase::Paused { remaining } = self.phase {
            self.phase = match remaining.checked_sub(1) {
                Some(0) | None => self.restart(),
                // Following the edge has brought the robot nearer the target than it ever was:
                // the cycle the pause was meant to break is broken, so navigation restarts
                // from here instead of following the edge on, away again (seed 000 §4.4: the
                // pause is there to find a new starting point).
                _ if self.progressed(dist, p) => self.restart(),
                Some(r) => DriftPhase::Paused { remaining: r },
            };
        } else {
            self.navigate(here, dist, err, p, tp, &mut out);
        }
        if self.approach {
            out.propulsion *= p.approach_propulsion;
        }
        out.phase = self.phase;
        out
    }

    fn navigate(
        &mut self,
        here: Point,
        dist: f32,
        err: f32,
        p: &DriftParams,
        tp: &TurnParams,
        out: &mut DriftOutput,
    ) {
        // Entering the approach radius: turn to the target once, then half propulsion.
        if dist < p.approach_radius_m && !self.approach {
            self.approach = true;
            self.phase = DriftPhase::Aligning;
        } else if dist >= p.approach_radius_m {
            self.approach = false;
        }
        if self.phase == DriftPhase::Aligning {
            if libm::fabsf(err) >= tp.tolerance_rad {
                out.cmd = turn_on_spot(err, tp);
                out.turning = true;
                return;
            }
            self.phase = DriftPhase::Driving;
        }
        if self.remember(here, dist, p) {
            return;
        }
        let gain = if libm::fabsf(err) > p.strong_above_rad {
            p.strong_gain_units_per_rad
        } else {
            p.weak_gain_units_per_rad
        };
        let mag = units(gain * libm::fabsf(err) * self.factor).clamp(0, p.max_drift_units.max(0));
        // Slow the wheel on the target's side: target to the left -> slow the left wheel.
        out.cmd = if err > 0.0 {
            MotorCommand::new(-mag, 0)
        } else {
            MotorCommand::new(0, -mag)
        };
    }

    /// Nearest-point memory (§4.4). Returns true when navigation has just been paused.
    fn remember(&mut self, here: Point, dist: f32, p: &DriftParams) -> bool {
        let tol = p.nearest_tolerance_m;
        match self.nearest {
            // A new nearest point: progress by more than the tolerance.
            Some((_, best)) if dist >= best - tol => {}
            _ => {
                self.nearest = Some((here, dist));
                self.left_nearest = false;
                self.revisits = 0;
                return false;
            }
        }
        let Some((point, _)) = self.nearest else {
            return false;
        };
        if here.distance_to(point) > tol {
            self.left_nearest = true;
            return false;
        }
        if !self.left_nearest {
            return false;
        }
        // Re-encountered the nearest point.
        self.left_nearest = false;
        self.escalate(p)
    }

    /// The robot is going round in circles: it came back to its nearest point, or the
    /// turning schema had to turn it by 180° (it could not leave its circle, or it faced a
    /// dead end, seed 000 §4.5). The first time the drift is halved; every further time
    /// navigation pauses, longer with each failure (§4.4). Returns true when it pauses.
    ///
    /// A 180° turn counts because a robot pressed against a wall across its way never leaves
    /// the 5 cm around its nearest point, so it would never "re-encounter" it: avoidance and
    /// drift cancel and only the circle criterion notices.
    pub fn cyclic(&mut self, p: &DriftParams) -> bool {
        if !matches!(self.phase, DriftPhase::Aligning | DriftPhase::Driving) {
            return false;
        }
        self.escalate(p)
    }

    fn escalate(&mut self, p: &DriftParams) -> bool {
        self.revisits = self.revisits.saturating_add(1);
        if self.revisits == 1 {
            self.factor *= p.revisit_factor;
            return false;
        }
        self.failures = self.failures.saturating_add(1);
        let pause = p.pause_cycles_per_failure.saturating_mul(self.failures);
        self.phase = DriftPhase::Paused {
            remaining: pause.max(1),
        };
        true
    }

    /// The side whose edge the current pause follows: `first` on odd failures, the other
    /// side on even ones, so that successive, longer pauses search both ways round the
    /// obstacle (a trap that one side leaves only after a long way, the other may leave soon).
    pub fn pause_side(&self, first: Side) -> Side {
        if self.failures % 2 == 1 {
            first
        } else {
            first.other()
        }
    }

    /// Nearer the target than the memorised nearest point, by more than its tolerance.
    fn progressed(&self, dist: f32, p: &DriftParams) -> bool {
        self.nearest
            .is_some_and(|(_, best)| dist < best - p.nearest_tolerance_m)
    }

    /// After a pause: navigation starts again from wherever the robot now is. The nearest
    /// point is kept, and so is the failure count, so that driving back into the same trap
    /// counts at once as a further failure and the next pause is longer.
    fn restart(&mut self) -> DriftPhase {
        self.left_nearest = true;
        self.revisits = self.revisits.max(1);
        self.factor = 1.0;
        self.approach = false;
        DriftPhase::Aligning
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f32::consts::FRAC_PI_2;

    fn step_at(d: &mut Drift, x: f32, y: f32, heading: f32) -> DriftOutput {
        d.step(
            Pose::new(x, y, heading),
            &DriftParams::default(),
            &TurnParams::default(),
        )
    }

    #[test]
    fn first_turns_on_the_spot_towards_the_target_then_drives() {
        let mut d = Drift::new(Point::new(1.0, 1.0));
        let out = step_at(&mut d, 0.0, 1.0, FRAC_PI_2);
        assert!(
            out.turning && out.cmd.left > 0 && out.cmd.right < 0,
            "{out:?}"
        );
        let out = step_at(&mut d, 0.0, 1.0, 0.01);
        assert!(!out.turning);
        assert_eq!(out.phase, DriftPhase::Driving);
        assert_eq!(out.propulsion, 1.0);
    }

    #[test]
    fn drift_is_weak_below_the_switch_angle_and_strong_above() {
        let mut d = Drift::new(Point::new(2.0, 0.0));
        step_at(&mut d, 0.0, 0.0, 0.0);
        // Target 20° to the left: weak gain 4/rad -> 1.4 -> 1 unit off the left wheel.
        let out = step_at(&mut d, 0.0, 0.0, -20f32.to_radians());
        assert_eq!(out.cmd, MotorCommand::new(-1, 0));
        // 40° to the right: strong gain 8/rad -> 5.6 -> 6 units off the right wheel.
        let out = step_at(&mut d, 0.0, 0.0, 40f32.to_radians());
        assert_eq!(out.cmd, MotorCommand::new(0, -6));
    }

    #[test]
    fn within_15_cm_it_turns_to_the_target_and_halves_propulsion() {
        let mut d = Drift::new(Point::new(1.0, 0.0));
        step_at(&mut d, 0.0, 0.0, 0.0);
        assert_eq!(step_at(&mut d, 0.84, 0.0, 0.3).propulsion, 1.0);
        let out = step_at(&mut d, 0.86, 0.0, 0.3);
        assert!(out.turning, "re-orients on entering 15 cm");
        assert_eq!(out.propulsion, 0.5);
        let out = step_at(&mut d, 0.86, 0.0, 0.0);
        assert!(!out.turning);
        assert_eq!((out.phase, out.propulsion), (DriftPhase::Driving, 0.5));
    }

    #[test]
    fn within_5_cm_the_target_is_reached_and_stays_reached() {
        let mut d = Drift::new(Point::new(1.0, 0.0));
        step_at(&mut d, 0.0, 0.0, 0.0);
        assert_ne!(step_at(&mut d, 0.949, 0.0, 0.0).phase, DriftPhase::Reached);
        let out = step_at(&mut d, 0.96, 0.0, 0.0);
        assert_eq!((out.phase, out.propulsion), (DriftPhase::Reached, 0.0));
        assert_eq!(step_at(&mut d, 0.5, 0.0, 0.0).phase, DriftPhase::Reached);
    }

    #[test]
    fn returning_to_the_nearest_point_halves_drift_then_pauses_for_growing_times() {
        let mut d = Drift::new(Point::new(0.0, 1.0));
        step_at(&mut d, 0.0, 0.0, FRAC_PI_2);
        assert_eq!(d.nearest().map(|n| n.0), Some(Point::new(0.0, 0.0)));
        // A loop around an obstacle: away (beyond 5 cm) and back without progress.
        step_at(&mut d, 0.2, -0.1, FRAC_PI_2);
        assert_eq!(d.factor(), 1.0);
        step_at(&mut d, 0.02, 0.0, FRAC_PI_2);
        assert_eq!(d.factor(), 0.5, "first return halves the drift");
        // Halved drift: 40° error -> strong 8/rad * 0.70 * 0.5 = 2.8 -> 3 units.
        let out = step_at(&mut d, 0.0, 0.0, FRAC_PI_2 + 40f32.to_radians());
        assert_eq!(out.cmd, MotorCommand::new(0, -3));
        step_at(&mut d, -0.2, -0.1, FRAC_PI_2);
        let out = step_at(&mut d, 0.0, 0.01, FRAC_PI_2);
        assert_eq!(out.phase, DriftPhase::Paused { remaining: 100 });
        assert_eq!(out.cmd, MotorCommand::STOP);
        for _ in 0..99 {
            assert!(matches!(
                step_at(&mut d, 0.3, 0.0, 0.0).phase,
                DriftPhase::Paused { .. }
            ));
        }
        let out = step_at(&mut d, 0.3, 0.0, 0.0);
        assert_eq!(
            out.phase,
            DriftPhase::Aligning,
            "restarts from the new place"
        );
        assert_eq!(d.factor(), 1.0);
        // The nearest point is kept: driving back to it is at once the second failure
        // (1.86 rad faces the target from (0.3, 0)), and the pause is twice as long.
        step_at(&mut d, 0.3, 0.0, 1.86);
        let out = step_at(&mut d, 0.0, 0.01, FRAC_PI_2);
        assert_eq!(out.phase, DriftPhase::Paused { remaining: 200 });
        assert_eq!(d.failures(), 2);
    }

    #[test]
    fn a_half_turn_is_cyclic_behaviour_halving_first_then_pausing_on_alternate_sides() {
        let p = DriftParams::default();
        let mut d = Drift::new(Point::new(0.0, 1.0));
        step_at(&mut d, 0.0, 0.0, FRAC_PI_2);
        assert!(!d.cyclic(&p));
        assert_eq!(d.factor(), 0.5);
        assert!(d.cyclic(&p));
        assert_eq!(d.phase(), DriftPhase::Paused { remaining: 100 });
        assert_eq!(d.pause_side(Side::Left), Side::Left);
        assert!(!d.cyclic(&p), "a turn during a pause changes nothing");
        for _ in 0..100 {
            step_at(&mut d, 0.3, 0.0, 0.0);
        }
        assert_eq!(d.phase(), DriftPhase::Aligning);
        assert!(d.cyclic(&p), "after a pause the next sign pauses again");
        assert_eq!(d.phase(), DriftPhase::Paused { remaining: 200 });
        assert_eq!(d.pause_side(Side::Left), Side::Right);
    }

    #[test]
    fn a_pause_ends_as_soon_as_the_edge_brings_the_robot_nearer_than_ever() {
        let p = DriftParams::default();
        let mut d = Drift::new(Point::new(0.0, 1.0));
        step_at(&mut d, 0.0, 0.0, FRAC_PI_2);
        d.cyclic(&p);
        assert!(d.cyclic(&p));
        assert_eq!(d.phase(), DriftPhase::Paused { remaining: 100 });
        // Following the edge sideways, no nearer than the nearest point (1 m): still paused.
        for i in 0..10u8 {
            let out = step_at(&mut d, 0.02 * f32::from(i), 0.0, 0.0);
            assert!(matches!(out.phase, DriftPhase::Paused { .. }), "{out:?}");
        }
        // Round the obstacle's end, 0.1 m nearer than ever: navigation restarts at once,
        // long before the 100 cycles are over.
        let out = step_at(&mut d, 0.2, 0.2, FRAC_PI_2);
        assert_eq!(out.phase, DriftPhase::Aligning);
        assert_eq!(d.failures(), 1, "the failure count is kept");
    }

    #[test]
    fn progress_towards_the_target_moves_the_nearest_point() {
        let mut d = Drift::new(Point::new(0.0, 1.0));
        for i in 0..16u8 {
            step_at(&mut d, 0.0, f32::from(i) * 0.05, FRAC_PI_2);
        }
        assert_eq!(d.factor(), 1.0);
        let nearest = d.nearest().map(|n| n.0.y).unwrap_or(0.0);
        assert!(nearest > 0.7, "{nearest}");
    }
}
