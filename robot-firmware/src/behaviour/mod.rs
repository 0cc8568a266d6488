//! Reflexive behaviours and their arbitration (seed 000 §4).
//!
//! Layer: between the sensors and the motors, above odometry. Each behaviour is a small state
//! machine that turns one cycle's readings into a motor contribution: [`avoid`] (Braitenberg
//! IIIb, the base propulsion), [`edge`] (edge following), [`drift`] (go to a point),
//! [`turn`] (180° escapes and turns on the spot), [`light`] (drive to light, Braitenberg IIIa).
//! [`arbiter::Arbiter`] owns them and combines their outputs as §4 says: edge following (or
//! drift) is added to avoidance, avoidance has implicit priority and gives the propulsion, and
//! turning suppresses the others; a behaviour whose inputs were not refreshed this cycle has
//! its previous output reused.
//!
//! Invariants: no I/O, no clock, no heap; time is counted in control cycles (the paper's unit,
//! about 80 ms on a Khepera). Randomness comes from a caller-seeded [`XorShift32`], so a run is
//! reproducible. Motor commands are in Khepera speed units (1 unit = 8 mm/s) and are clamped
//! to the arbiter's `max_units`. Nothing here can fail or panic: all sensor values are
//! accepted (10-bit readings are not assumed, larger ones saturate the arithmetic sensibly).

pub mod arbiter;
pub mod avoid;
pub mod drift;
pub mod edge;
pub mod light;
pub mod turn;

pub use arbiter::{Arbiter, ArbiterParams, BehaviourSet, BehaviourState, Mode};

use crate::odometry::Pose;

/// Millimetres per second of one Khepera speed unit (0.08 mm per 10 ms: one encoder pulse per
/// 10 ms speed-controller tick).
pub const MM_PER_S_PER_UNIT: f32 = 8.0;

/// Index of IR/light sensor S0, left side (+90°). S1 +45°, S2 +10°, S3 -10°, S4 -45°.
pub const S_LEFT: usize = 0;
/// Index of IR/light sensor S5, right side (-90°). S6 and S7 face backwards and are unused.
pub const S_RIGHT: usize = 5;

/// Wheel speed command in Khepera speed units (1 unit = 8 mm/s), positive forwards.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct MotorCommand {
    /// Left wheel, units of 8 mm/s.
    pub left: i16,
    /// Right wheel, units of 8 mm/s.
    pub right: i16,
}

impl MotorCommand {
    /// Both wheels stopped.
    pub const STOP: Self = Self { left: 0, right: 0 };

    /// Makes a command from left and right speeds.
    pub const fn new(left: i16, right: i16) -> Self {
        Self { left, right }
    }

    /// Wheel-wise saturating sum (superposition of behaviour outputs, seed 000 §4).
    pub const fn plus(self, other: Self) -> Self {
        Self {
            left: self.left.saturating_add(other.left),
            right: self.right.saturating_add(other.right),
        }
    }

    /// Limits both wheels to `[-max, max]`.
    pub fn clamped(self, max: i16) -> Self {
        let m = max.max(0);
        Self {
            left: self.left.clamp(-m, m),
            right: self.right.clamp(-m, m),
        }
    }

    /// Speed of the left and right wheel in metres per second.
    pub fn to_mps(self) -> (f32, f32) {
        let k = MM_PER_S_PER_UNIT * 1e-3;
        (f32::from(self.left) * k, f32::from(self.right) * k)
    }
}

/// Rounds to the nearest i16, saturating at its range (NaN gives 0): speeds to motor
/// command units, and firmware values to the wire's integer fields.
pub(crate) fn units(v: f32) -> i16 {
    // `as` saturates and maps NaN to 0, so no value can panic here.
    libm::roundf(v) as i16
}

/// Which side a wall is followed on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Side {
    /// Wall on the left, sensed by S0; corrections slow the left motor.
    #[default]
    Left,
    /// Wall on the right, sensed by S5; corrections slow the right motor.
    Right,
}

impl Side {
    /// The opposite side.
    pub const fn other(self) -> Self {
        match self {
            Side::Left => Side::Right,
            Side::Right => Side::Left,
        }
    }

    /// A command that changes only this side's motor by `delta`.
    pub const fn motor(self, delta: i16) -> MotorCommand {
        match self {
            Side::Left => MotorCommand::new(delta, 0),
            Side::Right => MotorCommand::new(0, delta),
        }
    }
}

/// One control cycle's inputs to the behaviours.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Inputs {
    /// IR proximity S0..S7, 10-bit, higher = closer (seed 000 §4.1).
    pub ir: [u16; 8],
    /// Ambient light S0..S7, 10-bit, inverted: lower = brighter, about 500 = dark (§5.2).
    pub light: [u16; 8],
    /// Pose estimate (odometry).
    pub pose: Pose,
    /// `ir` was read this cycle; if not, IR-driven behaviours reuse their last output.
    pub ir_fresh: bool,
    /// `light` was read this cycle.
    pub light_fresh: bool,
    /// `pose` was updated this cycle.
    pub pose_fresh: bool,
}

impl Inputs {
    /// Inputs with all readings marked fresh.
    pub fn fresh(ir: [u16; 8], light: [u16; 8], pose: Pose) -> Self {
        Self {
            ir,
            light,
            pose,
            ir_fresh: true,
            light_fresh: true,
            pose_fresh: true,
        }
    }
}

/// xorshift32 (Marsaglia 2003): four bytes of state, deterministic for a given seed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct XorShift32 {
    state: u32,
}

impl XorShift32 {
    /// Seeds the generator; seed 0 (a fixed point of xorshift) is replaced by a constant.
    pub const fn new(seed: u32) -> Self {
        Self {
            state: if seed == 0 { 0x9E37_79B9 } else { seed },
        }
    }

    /// Next 32 random bits.
    pub fn next_u32(&mut self) -> u32 {
        let mut x = self.state;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.state = x;
        x
    }

    /// Uniform integer in `[centre - spread, centre + spread]` (slightly biased by the modulo,
    /// which does not matter for a threshold jitter).
    pub fn jitter(&mut self, centre: u16, spread: u16) -> u16 {
        let width = u32::from(spread) * 2 + 1;
        let offset = self.next_u32() % width;
        (u32::from(centre) + offset)
            .saturating_sub(u32::from(spread))
            .min(u32::from(u16::MAX)) as u16
    }

    /// A fair coin.
    pub fn coin(&mut self) -> bool {
        self.next_u32() & 0x8000_0000 != 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn xorshift_is_deterministic_and_jitter_stays_in_range() {
        let (mut a, mut b) = (XorShift32::new(7), XorShift32::new(7));
        let mut seen = [false; 51];
        for _ in 0..5000 {
            let t = a.jitter(475, 25);
            assert_eq!(t, b.jitter(475, 25));
            assert!((450..=500).contains(&t));
            seen[usize::from(t - 450)] = true;
        }
        assert!(
            seen.iter().all(|&s| s),
            "every threshold 450..=500 is drawn"
        );
        assert_ne!(XorShift32::new(0).next_u32(), 0);
    }

    #[test]
    fn motor_commands_add_saturate_and_clamp() {
        let a = MotorCommand::new(6, 6).plus(Side::Left.motor(-1));
        assert_eq!(a, MotorCommand::new(5, 6));
        assert_eq!(
            MotorCommand::new(i16::MAX, 0)
                .plus(MotorCommand::new(1, 0))
                .left,
            i16::MAX
        );
        assert_eq!(
            MotorCommand::new(30, -30).clamped(20),
            MotorCommand::new(20, -20)
        );
        let (l, r) = MotorCommand::new(10, -5).to_mps();
        assert!((l - 0.08).abs() < 1e-6 && (r + 0.04).abs() < 1e-6);
    }
}
