//! Obstacle avoidance after Braitenberg's vehicle IIIb (seed 000 §4.2).
//!
//! Two neurons: the left one sums the left front sensors, the right one the right front
//! sensors, with weights `w0 = w5 = 0, w1..w4 = 1/2` (so S0 and S5, the side sensors that edge
//! following uses, never trigger avoidance). Each neuron inhibits the OPPOSITE motor through a
//! step-plus-proportional activation whose threshold is drawn at random in 475 ± 25, so there
//! is no preferred escape direction. The behaviour also supplies the base propulsion.
//!
//! Invariants: the thresholds stay within `threshold ± threshold_spread`; they are redrawn
//! when an encounter ends (both neurons fall silent) so each obstacle meets fresh thresholds
//! while one encounter keeps the same ones (no flicker at the boundary). Cannot fail.

use super::{units, MotorCommand, XorShift32};

/// Parameters of the IIIb avoidance (seed 000 §4.2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AvoidParams {
    /// Sensor weights w0..w5. seed 000 §4.2: w0 = w5 = 0, w1..w4 = 1/2.
    pub weights: [f32; 6],
    /// Activation threshold centre. seed 000 §4.2: 475.
    pub threshold: u16,
    /// Random spread of the threshold. seed 000 §4.2: ± 25.
    pub threshold_spread: u16,
    /// Height of the activation step at the threshold, speed units. Not in the paper: 4 takes
    /// the opposite wheel from 6 to 2 at first contact, a clear but smooth turn away.
    pub step_units: f32,
    /// Proportional part above the threshold, units per count. Not in the paper: 1/50, so an
    /// obstacle 250 counts past the threshold reverses the opposite wheel (6 - 4 - 5 = -3).
    pub gain_units_per_count: f32,
    /// Base propulsion of both wheels, units. Not in the paper: 6 units = 48 mm/s, close to
    /// the 2-lap run of §3.3 (about 4.7 m in 92 s, 51 mm/s).
    pub base_units: i16,
}

impl Default for AvoidParams {
    fn default() -> Self {
        Self {
            // seed 000 §4.2: w0 = w5 = 0, w1..w4 = 1/2
            weights: [0.0, 0.5, 0.5, 0.5, 0.5, 0.0],
            // seed 000 §4.2: threshold 475 ± 25, drawn at random
            threshold: 475,
            threshold_spread: 25,
            step_units: 4.0,
            gain_units_per_count: 0.02,
            base_units: 6,
        }
    }
}

/// What avoidance produced this cycle.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct AvoidOutput {
    /// Propulsion minus inhibition, per wheel.
    pub cmd: MotorCommand,
    /// Net input of the left and right neuron.
    pub neurons: [f32; 2],
    /// Whether each neuron is above its threshold.
    pub firing: [bool; 2],
}

impl AvoidOutput {
    /// Whether avoidance is reacting to an obstacle (either neuron firing).
    pub fn active(&self) -> bool {
        self.firing[0] || self.firing[1]
    }
}

/// Avoidance state: the two current thresholds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Avoid {
    thresholds: [u16; 2],
    was_active: bool,
}

impl Avoid {
    /// Draws the first thresholds.
    pub fn new(p: &AvoidParams, rng: &mut XorShift32) -> Self {
        Self {
            thresholds: draw(p, rng),
            was_active: false,
        }
    }

    /// Thresholds of the left and right neuron in force.
    pub fn thresholds(&self) -> [u16; 2] {
        self.thresholds
    }

    /// One cycle: `propulsion` scales the base speed (1 normally, 1/2 near a drift target).
    pub fn step(
        &mut self,
        ir: &[u16; 8],
        propulsion: f32,
        p: &AvoidParams,
        rng: &mut XorShift32,
    ) -> AvoidOutput {
        let w = &p.weights;
        let s = |i: usize| f32::from(ir[i]);
        let left = w[0] * s(0) + w[1] * s(1) + w[2] * s(2);
        let right = w[3] * s(3) + w[4] * s(4) + w[5] * s(5);
        let (act_l, fire_l) = activation(left, self.thresholds[0], p);
        let (act_r, fire_r) = activation(right, self.thresholds[1], p);
        let base = f32::from(p.base_units) * propulsion;
        // Crossed inhibition: an obstacle on the left slows the right wheel (turn right).
        let out = AvoidOutput {
            cmd: MotorCommand::new(units(base - act_r), units(base - act_l)),
            neurons: [left, right],
            firing: [fire_l, fire_r],
        };
        if self.was_active && !out.active() {
            self.thresholds = draw(p, rng);
        }
        self.was_active = out.active();
        out
    }
}

/// Modified step plus proportionality (seed 000 §4.2, Fig. 10 right).
fn activation(x: f32, threshold: u16, p: &AvoidParams) -> (f32, bool) {
    let t = f32::from(threshold);
    if x >= t {
        (p.step_units + p.gain_units_per_count * (x - t), true)
    } else {
        (0.0, false)
    }
}

fn draw(p: &AvoidParams, rng: &mut XorShift32) -> [u16; 2] {
    [
        rng.jitter(p.threshold, p.threshold_spread),
        rng.jitter(p.threshold, p.threshold_spread),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ir_front(left: u16, right: u16) -> [u16; 8] {
        [0, left, left, right, right, 0, 0, 0]
    }

    #[test]
    fn below_the_lowest_threshold_avoidance_is_inactive_and_drives_straight() {
        let p = AvoidParams::default();
        let mut rng = XorShift32::new(1);
        let mut a = Avoid::new(&p, &mut rng);
        let out = a.step(&ir_front(449, 449), 1.0, &p, &mut rng);
        assert!(!out.active());
        assert_eq!(out.cmd, MotorCommand::new(6, 6));
    }

    #[test]
    fn above_the_highest_threshold_the_opposite_motor_is_inhibited() {
        let p = AvoidParams::default();
        let mut rng = XorShift32::new(2);
        let mut a = Avoid::new(&p, &mut rng);
        let t = a.thresholds();
        let out = a.step(&ir_front(501, 0), 1.0, &p, &mut rng);
        assert!(out.firing[0] && !out.firing[1]);
        // Obstacle on the left: the right wheel slows by step + gain * (501 - t).
        let act = 4.0 + 0.02 * (501.0 - f32::from(t[0]));
        assert_eq!(out.cmd, MotorCommand::new(6, units(6.0 - act)));
        let out = a.step(&ir_front(0, 900), 1.0, &p, &mut rng);
        assert!(out.cmd.left < 0 && out.cmd.right == 6, "{out:?}");
    }

    #[test]
    fn side_sensors_do_not_trigger_avoidance() {
        let p = AvoidParams::default();
        let mut rng = XorShift32::new(3);
        let mut a = Avoid::new(&p, &mut rng);
        let out = a.step(&[1023, 0, 0, 0, 0, 1023, 1023, 1023], 1.0, &p, &mut rng);
        assert!(!out.active());
    }

    #[test]
    fn the_switch_happens_exactly_at_the_drawn_threshold() {
        let p = AvoidParams::default();
        let mut rng = XorShift32::new(4);
        let mut a = Avoid::new(&p, &mut rng);
        let t = a.thresholds()[1];
        assert!(!a.step(&ir_front(0, t - 1), 1.0, &p, &mut rng).active());
        let at = a.step(&ir_front(0, t), 1.0, &p, &mut rng);
        assert!(at.firing[1]);
        assert_eq!(at.cmd.left, 2, "step of 4 units at the threshold");
    }

    #[test]
    fn thresholds_are_redrawn_after_each_encounter_within_475_plus_minus_25() {
        let p = AvoidParams::default();
        let mut rng = XorShift32::new(5);
        let mut a = Avoid::new(&p, &mut rng);
        let mut lower_left = 0;
        for _ in 0..400 {
            let during = a.thresholds();
            a.step(&ir_front(800, 800), 1.0, &p, &mut rng);
            assert_eq!(a.thresholds(), during, "held during an encounter");
            a.step(&ir_front(0, 0), 1.0, &p, &mut rng);
            let [l, r] = a.thresholds();
            assert!((450..=500).contains(&l) && (450..=500).contains(&r));
            lower_left += i32::from(l < r);
        }
        // No preferred side: each neuron is the more sensitive one about half the time.
        assert!((150..250).contains(&lower_left), "{lower_left}");
    }

    #[test]
    fn propulsion_factor_scales_the_base_speed() {
        let p = AvoidParams::default();
        let mut rng = XorShift32::new(6);
        let mut a = Avoid::new(&p, &mut rng);
        assert_eq!(
            a.step(&[0; 8], 0.5, &p, &mut rng).cmd,
            MotorCommand::new(3, 3)
        );
    }
}
