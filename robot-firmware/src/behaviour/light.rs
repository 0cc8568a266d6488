//! Drive to a light source after Braitenberg's vehicle IIIa (seed 000 §6.1, Fig. 29).
//!
//! The same crossed two-neuron network as obstacle avoidance (§4.2) but excitatory: brightness
//! seen on the left speeds up the right wheel, so the robot turns towards the light. Ambient
//! readings are inverted (lower = brighter, about 500 = dark, §5.2), so brightness is
//! `dark - reading`. Phases follow §6.1: a reading below T1 = 470 detects a source; approach
//! until the average front reading drops below T2 = 200 (optimal distance, then stop); after
//! the caller releases the source, ignore light until every front reading is above T3 = 490
//! (the source's area is left), so the same source is not re-detected at once.
//!
//! Invariants: only the six front sensors (S0..S5) are used; output is a correction added to
//! avoidance, except in `Arrived`, where the propulsion factor is 0. Cannot fail.

use super::{units, MotorCommand};

/// Parameters of drive-to-light (seed 000 §6.1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightParams {
    /// Source detected when a front reading is below this. seed 000 §6.1: T1 = 470.
    pub detect: u16,
    /// Optimal distance reached when the average front reading is below this. §6.1: T2 = 200.
    pub optimal: u16,
    /// Source area left when every front reading is above this. seed 000 §6.1: T3 = 490.
    pub leave: u16,
    /// Reading of darkness, the zero of brightness. seed 000 §5.2: about 500.
    pub dark: u16,
    /// Weights of S0..S5 (left neuron S0..S2, right neuron S3..S5). Not in the paper: 1/3
    /// each, so a neuron is the mean brightness of its side.
    pub weights: [f32; 6],
    /// Excitation per unit of brightness, units/count. Not in the paper: 1/50 (a side 100
    /// counts brighter than the other steers by 2 units).
    pub gain_units_per_count: f32,
    /// Largest excitation per wheel, units. Not in the paper: 6 (the base propulsion).
    pub max_units: i16,
}

impl Default for LightParams {
    fn default() -> Self {
        Self {
            // seed 000 §6.1: Θ1 = 470, Θ2 = 200, Θ3 = 490
            detect: 470,
            optimal: 200,
            leave: 490,
            // seed 000 §5.2: about 500 is dark
            dark: 500,
            weights: [1.0 / 3.0; 6],
            gain_units_per_count: 0.02,
            max_units: 6,
        }
    }
}

/// Where drive-to-light is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LightPhase {
    /// No source seen.
    #[default]
    Searching,
    /// Source detected (reading < T1): steering towards it.
    Approaching,
    /// Optimal distance (average < T2): stopped until released.
    Arrived,
    /// Released: ignoring light until every reading is above T3.
    Leaving,
}

/// What drive-to-light produced this cycle.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct LightOutput {
    /// Excitation to add to avoidance.
    pub delta: MotorCommand,
    /// Factor for avoidance's base propulsion (0 once arrived).
    pub propulsion: f32,
    /// Phase after this cycle.
    pub phase: LightPhase,
}

/// Drive-to-light state.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct DriveToLight {
    phase: LightPhase,
}

impl DriveToLight {
    /// Searching.
    pub const fn new() -> Self {
        Self {
            phase: LightPhase::Searching,
        }
    }

    /// Current phase.
    pub fn phase(&self) -> LightPhase {
        self.phase
    }

    /// The caller is done at the source (e.g. mapped it, §6.1): leave its area.
    pub fn release(&mut self) {
        if matches!(self.phase, LightPhase::Approaching | LightPhase::Arrived) {
            self.phase = LightPhase::Leaving;
        }
    }

    /// One cycle over the ambient readings.
    pub fn step(&mut self, light: &[u16; 8], p: &LightParams) -> LightOutput {
        let front = &light[..6];
        let min = front.iter().copied().min().unwrap_or(u16::MAX);
        let mean = front.iter().map(|&v| u32::from(v)).sum::<u32>() / 6;
        self.phase = match self.phase {
            LightPhase::Searching if min < p.detect => LightPhase::Approaching,
            LightPhase::Approaching if mean < u32::from(p.optimal) => LightPhase::Arrived,
            LightPhase::Leaving if min > p.leave => LightPhase::Searching,
            phase => phase,
        };
        let mut out = LightOutput {
            propulsion: 1.0,
            phase: self.phase,
            ..LightOutput::default()
        };
        match self.phase {
            LightPhase::Approaching => out.delta = excitation(front, p),
            LightPhase::Arrived => out.propulsion = 0.0,
            LightPhase::Searching | LightPhase::Leaving => {}
        }
        out
    }
}

/// Crossed excitation: the left neuron drives the right wheel and vice versa.
fn excitation(front: &[u16], p: &LightParams) -> MotorCommand {
    let bright = |i: usize| {
        let v = front.get(i).copied().unwrap_or(p.dark);
        f32::from(p.dark.saturating_sub(v))
    };
    let w = &p.weights;
    let left = w[0] * bright(0) + w[1] * bright(1) + w[2] * bright(2);
    let right = w[3] * bright(3) + w[4] * bright(4) + w[5] * bright(5);
    let max = p.max_units.max(0);
    let drive = |n: f32| units(n * p.gain_units_per_count).clamp(0, max);
    MotorCommand::new(drive(right), drive(left))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn front(l: [u16; 6]) -> [u16; 8] {
        [l[0], l[1], l[2], l[3], l[4], l[5], 500, 500]
    }

    #[test]
    fn a_reading_below_t1_starts_the_approach() {
        let p = LightParams::default();
        let mut l = DriveToLight::new();
        assert_eq!(l.step(&front([470; 6]), &p).phase, LightPhase::Searching);
        let out = l.step(&front([500, 469, 500, 500, 500, 500]), &p);
        assert_eq!(out.phase, LightPhase::Approaching);
    }

    #[test]
    fn light_on_the_left_speeds_up_the_right_wheel() {
        let p = LightParams::default();
        let mut l = DriveToLight::new();
        let out = l.step(&front([200, 200, 350, 480, 500, 500]), &p);
        // left neuron (300+300+150)/3 = 250 -> 5 units on the right wheel; right one 20/3 -> 0.
        assert_eq!(out.delta, MotorCommand::new(0, 5));
        assert_eq!(out.propulsion, 1.0);
    }

    #[test]
    fn average_below_t2_stops_at_the_optimal_distance() {
        let p = LightParams::default();
        let mut l = DriveToLight::new();
        l.step(&front([300; 6]), &p);
        assert_eq!(l.step(&front([200; 6]), &p).phase, LightPhase::Approaching);
        let out = l.step(&front([100, 150, 150, 150, 200, 440]), &p);
        assert_eq!((out.phase, out.propulsion), (LightPhase::Arrived, 0.0));
    }

    #[test]
    fn after_release_light_is_ignored_until_every_reading_is_above_t3() {
        let p = LightParams::default();
        let mut l = DriveToLight::new();
        l.step(&front([300; 6]), &p);
        l.step(&front([100; 6]), &p);
        l.release();
        let out = l.step(&front([300; 6]), &p);
        assert_eq!(
            (out.phase, out.delta),
            (LightPhase::Leaving, MotorCommand::STOP)
        );
        assert_eq!(
            l.step(&front([491, 491, 491, 490, 491, 491]), &p).phase,
            LightPhase::Leaving
        );
        assert_eq!(l.step(&front([491; 6]), &p).phase, LightPhase::Searching);
        assert_eq!(l.step(&front([460; 6]), &p).phase, LightPhase::Approaching);
    }
}
