//! Edge following (seed 000 §4.3, Figs. 11-12).
//!
//! Keeps the side sensor (S0 for a wall on the left, S5 mirrored for the right) near a
//! memorised value. At reset `S_mem = -S(t)`; each cycle `e = S(t) + S_mem`:
//! `e < -7` (drifted away) adds -1 to the wall-side motor, curving towards the wall;
//! `e > +7` (approaching) re-memorises `S_mem = -S(t)`; moving away from the wall is left to
//! obstacle avoidance. `e < -100` means the wall is lost: a strong curve towards it until
//! it is found again or 120 cycles have passed, after which the follower resets.
//!
//! Invariants: the output only ever slows the wall-side motor (it is added to avoidance, which
//! supplies the propulsion); the lost phase lasts at most `lost_max_cycles` cycles. Cannot
//! fail.

use super::{MotorCommand, Side, S_LEFT, S_RIGHT};

/// Parameters of edge following (seed 000 §4.3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeParams {
    /// Noise threshold on e, counts. seed 000 §4.3: 7 (about twice the sensor's sigma).
    pub noise_threshold: i32,
    /// Drift added to the wall-side motor when e < -noise, units. seed 000 §4.3: -1.
    pub drift_units: i16,
    /// e below minus this means the wall is lost, counts. seed 000 §4.3: 100.
    pub lost_threshold: i32,
    /// Longest strong curve while the wall is lost, cycles. seed 000 §4.3: 120.
    pub lost_max_cycles: u16,
    /// Slow-down of the wall-side motor in the strong curve, units. Not in the paper: 4 (with
    /// a base of 6 the wheels run 2 and 6, a radius of about 5 cm, the Khepera's size, which
    /// brings it round the end of a wall).
    pub lost_curve_units: i16,
    /// Side reading at which a lost wall counts as found again, counts. Not in the paper: 100,
    /// the same as the lost threshold (a wall cannot be lost below that reading).
    pub found_level: u16,
}

impl Default for EdgeParams {
    fn default() -> Self {
        Self {
            // seed 000 §4.3: noise-discriminating threshold ±7
            noise_threshold: 7,
            // seed 000 §4.3: drift value of -1 on the left motor
            drift_units: -1,
            // seed 000 §4.3: S0(t) + S_mem < -100 -> wall lost
            lost_threshold: 100,
            // seed 000 §4.3: strong curve for at most 120 program cycles
            lost_max_cycles: 120,
            lost_curve_units: 4,
            found_level: 100,
        }
    }
}

/// Where edge following is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum EdgePhase {
    /// Keeping the memorised distance (Fig. 11 a-c).
    #[default]
    Following,
    /// Wall lost: strong curve towards it, `cycles` so far.
    Lost {
        /// Cycles spent curving.
        cycles: u16,
    },
}

/// What edge following produced this cycle.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct EdgeOutput {
    /// Correction to add to avoidance's command.
    pub delta: MotorCommand,
    /// e = S(t) + S_mem.
    pub error: i32,
    /// Phase after this cycle.
    pub phase: EdgePhase,
}

/// Edge-following state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EdgeFollow {
    side: Side,
    s_mem: Option<i32>,
    phase: EdgePhase,
    /// At a reset with no wall in view, look for one (the lost-wall curve) instead of
    /// memorising the floor reading, which would make the follower drive straight on.
    seek: bool,
}

impl EdgeFollow {
    /// A follower for a wall on `side`, reset (memorises at its first step).
    pub const fn new(side: Side) -> Self {
        Self {
            side,
            s_mem: None,
            phase: EdgePhase::Following,
            seek: false,
        }
    }

    /// A follower that, after each reset, first curves towards `side` until a wall is in view
    /// (at most `lost_max_cycles`, as for a lost wall). Drift's pauses use it: they are meant
    /// to follow the obstacle that blocked the way (seed 000 §4.4), which after a turn is
    /// usually a few centimetres off, beyond the side sensor's 3.3 cm.
    pub const fn seeking(side: Side) -> Self {
        Self {
            seek: true,
            ..Self::new(side)
        }
    }

    /// Side being followed.
    pub fn side(&self) -> Side {
        self.side
    }

    /// Memorised value S_mem (negative of the memorised reading), if any.
    pub fn memory(&self) -> Option<i32> {
        self.s_mem
    }

    /// Current phase.
    pub fn phase(&self) -> EdgePhase {
        self.phase
    }

    /// "The edge following process starts with a reset" (§4.3): memorise at the next step.
    pub fn reset(&mut self) {
        self.s_mem = None;
        self.phase = EdgePhase::Following;
    }

    /// One cycle.
    pub fn step(&mut self, ir: &[u16; 8], p: &EdgeParams) -> EdgeOutput {
        let idx = match self.side {
            Side::Left => S_LEFT,
            Side::Right => S_RIGHT,
        };
        let s = i32::from(ir[idx]);
        if self.s_mem.is_none() && self.seek && s < i32::from(p.found_level) {
            // Nothing to memorise yet: search for the wall as if it had just been lost.
            self.s_mem = Some(-s);
            self.phase = EdgePhase::Lost { cycles: 0 };
        }
        let mem = *self.s_mem.get_or_insert(-s);
        let e = s + mem;
        let mut delta = MotorCommand::STOP;
        match self.phase {
            EdgePhase::Following => {
                if e < -p.lost_threshold {
                    self.phase = EdgePhase::Lost { cycles: 1 };
                    delta = self.side.motor(-p.lost_curve_units);
                } else if e < -p.noise_threshold {
                    delta = self.side.motor(p.drift_units);
                } else if e > p.noise_threshold {
                    self.s_mem = Some(-s);
                }
            }
            EdgePhase::Lost { cycles } => {
                if s >= i32::from(p.found_level) {
                    // Wall relocated: S_mem = -S(t).
                    self.s_mem = Some(-s);
                    self.phase = EdgePhase::Following;
                } else if cycles >= p.lost_max_cycles {
                    // Gave up after the limit: start over with a reset.
                    self.s_mem = Some(-s);
                    self.phase = EdgePhase::Following;
                } else {
                    self.phase = EdgePhase::Lost { cycles: cycles + 1 };
                    delta = self.side.motor(-p.lost_curve_units);
                }
            }
        }
        EdgeOutput {
            delta,
            error: e,
            phase: self.phase,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn left(s0: u16) -> [u16; 8] {
        [s0, 0, 0, 0, 0, 0, 0, 0]
    }

    #[test]
    fn reset_memorises_the_current_reading() {
        let p = EdgeParams::default();
        let mut f = EdgeFollow::new(Side::Left);
        let out = f.step(&left(300), &p);
        assert_eq!((out.error, out.delta), (0, MotorCommand::STOP));
        assert_eq!(f.memory(), Some(-300));
    }

    #[test]
    fn drifting_away_by_more_than_7_adds_minus_1_to_the_wall_side_motor() {
        let p = EdgeParams::default();
        let mut f = EdgeFollow::new(Side::Left);
        f.step(&left(300), &p);
        assert_eq!(
            f.step(&left(293), &p).delta,
            MotorCommand::STOP,
            "e = -7: noise"
        );
        let out = f.step(&left(292), &p);
        assert_eq!((out.error, out.delta), (-8, MotorCommand::new(-1, 0)));
        assert_eq!(f.memory(), Some(-300), "drifting away does not re-memorise");
    }

    #[test]
    fn approaching_by_more_than_7_re_memorises() {
        let p = EdgeParams::default();
        let mut f = EdgeFollow::new(Side::Left);
        f.step(&left(300), &p);
        f.step(&left(307), &p);
        assert_eq!(f.memory(), Some(-300), "e = 7: noise");
        let out = f.step(&left(308), &p);
        assert_eq!(out.delta, MotorCommand::STOP);
        assert_eq!(f.memory(), Some(-308));
        assert_eq!(f.step(&left(300), &p).delta, MotorCommand::new(-1, 0));
    }

    #[test]
    fn the_right_side_mirrors_with_s5() {
        let p = EdgeParams::default();
        let mut f = EdgeFollow::new(Side::Right);
        f.step(&[0, 0, 0, 0, 0, 300, 0, 0], &p);
        let out = f.step(&[900, 0, 0, 0, 0, 290, 0, 0], &p);
        assert_eq!(out.delta, MotorCommand::new(0, -1));
    }

    #[test]
    fn losing_the_wall_curves_strongly_for_at_most_120_cycles_then_resets() {
        let p = EdgeParams::default();
        let mut f = EdgeFollow::new(Side::Left);
        f.step(&left(300), &p);
        let first = f.step(&left(199), &p);
        assert_eq!(first.error, -101);
        assert_eq!(first.phase, EdgePhase::Lost { cycles: 1 });
        assert_eq!(first.delta, MotorCommand::new(-4, 0));
        let mut curving = 1;
        for _ in 0..200 {
            if f.step(&left(20), &p).delta == MotorCommand::new(-4, 0) {
                curving += 1;
            } else {
                break;
            }
        }
        assert_eq!(curving, 120);
        assert_eq!(f.phase(), EdgePhase::Following);
        assert_eq!(f.memory(), Some(-20), "reset to the current reading");
    }

    #[test]
    fn e_of_exactly_minus_100_is_not_yet_lost() {
        let p = EdgeParams::default();
        let mut f = EdgeFollow::new(Side::Left);
        f.step(&left(300), &p);
        let out = f.step(&left(200), &p);
        assert_eq!(out.phase, EdgePhase::Following);
        assert_eq!(out.delta, MotorCommand::new(-1, 0));
    }

    #[test]
    fn a_lost_wall_found_again_is_memorised_and_followed() {
        let p = EdgeParams::default();
        let mut f = EdgeFollow::new(Side::Left);
        f.step(&left(300), &p);
        f.step(&left(10), &p);
        for _ in 0..30 {
            f.step(&left(15), &p);
        }
        let out = f.step(&left(150), &p);
        assert_eq!(out.phase, EdgePhase::Following);
        assert_eq!(out.delta, MotorCommand::STOP);
        assert_eq!(f.memory(), Some(-150));
    }

    #[test]
    fn a_seeking_follower_with_no_wall_in_view_curves_towards_its_side_until_it_sees_one() {
        let p = EdgeParams::default();
        let mut f = EdgeFollow::seeking(Side::Right);
        let out = f.step(&[0; 8], &p);
        assert_eq!(out.phase, EdgePhase::Lost { cycles: 1 });
        assert_eq!(out.delta, MotorCommand::new(0, -4));
        let out = f.step(&[0, 0, 0, 0, 0, 300, 0, 0], &p);
        assert_eq!(out.phase, EdgePhase::Following);
        assert_eq!(f.memory(), Some(-300));
        // With a wall in view at the reset it memorises at once, as the plain follower does.
        let mut g = EdgeFollow::seeking(Side::Left);
        assert_eq!(g.step(&left(300), &p).phase, EdgePhase::Following);
        assert_eq!(g.memory(), Some(-300));
        g.reset();
        assert_eq!(
            g.step(&left(5), &p).phase,
            EdgePhase::Lost { cycles: 1 },
            "after a reset too"
        );
    }
}
