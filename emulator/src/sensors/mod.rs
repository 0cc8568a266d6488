//! Sensor models: what each of the robot's sensors reads in the simulated world.
//!
//! Layer: std, between the world + physics (true state) and the simulated hardware
//! (`sim::SimHal`), which calls a model only when the firmware reads that sensor (once per
//! control cycle), so ray casts are paid per cycle, not per millisecond.
//!
//! - [`ir`]: active IR proximity, per profile (Khepera: seed 000 §1.1's 1.7-3.3 cm
//!   characteristic; micro-rato: seed 004 §3's 25 cm sensors).
//! - [`light`]: Khepera passive ambient light, inverted (seed 000 §5.2, §6.1).
//! - [`line`]: a downward floor-line sensor over the floor grid (seed 003 §2.2.3).
//! - [`rato`]: the micro-rato's compass, beacon sensor, ground sensor and the battery.
//! - [`alice`]: ALICE's whiskers and photoresistors (seed 001 §3.1).
//!
//! Noise levels are fields of [`Noise`], named after CiberRato's simulator parameters where it
//! has one (CompassNoise, BeaconNoise, ObstacleNoise, MotorsNoise). Every model draws from its
//! own seeded [`SimRng`] stream, so a run is repeatable bit for bit and one sensor's draws do
//! not depend on how often another is read. Nothing here can fail; readings are clamped to
//! their hardware ranges.

pub mod alice;
pub mod ir;
pub mod light;
pub mod line;
pub mod rato;

use crate::rng::SimRng;

/// Noise levels of one run. [`Default`] gives the papers' values; [`Noise::none`] switches
/// every random effect off (exact readings, no wheel bias).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Noise {
    /// IR proximity noise, counts (1 sigma). seed 000 §1.1: about 3.
    pub obstacle_counts: f64,
    /// Sensor-to-sensor IR gain spread, relative (1 sigma), drawn per run. seed 000 §1.1 gives
    /// a spread of about 100 counts; 0.05 gives +-2 sigma = +-10 %, about 100 counts across
    /// the band's middle (~500 counts).
    pub obstacle_gain_spread: f64,
    /// Ambient light noise, counts (1 sigma). seed 000 §5.2 says noise matters much less than
    /// for the proximity sensors: 1.5.
    pub light_counts: f64,
    /// Compass noise, degrees RMS. seed 004 §3: 2.
    pub compass_deg: f64,
    /// Beacon bearing noise, degrees (1 sigma). Not in seed 004; CiberRato's default is 2.
    pub beacon_deg: f64,
    /// Beacon strength noise, relative (1 sigma): 0.05 keeps the firmware's distance within
    /// seed 004 §4's +-0.3 m over most of the arena.
    pub beacon_strength: f64,
    /// Per-wheel constant speed error, relative (1 sigma), drawn per run (MotorsNoise).
    /// seed 003 §2.3.3: at most +-1 %, sigma = dV/2 = 0.005.
    pub motors: f64,
    /// Probability that a floor-line crossing is missed. seed 003 gives none: 0.02.
    pub line_miss: f64,
    /// Probability that a floor-line crossing gives two pulses. seed 003 gives none: 0.02.
    pub line_double: f64,
    /// Battery voltage reading noise, millivolts (1 sigma).
    pub battery_mv: f64,
}

impl Default for Noise {
    fn default() -> Self {
        Noise {
            obstacle_counts: 3.0,
            obstacle_gain_spread: 0.05,
            light_counts: 1.5,
            compass_deg: 2.0,
            beacon_deg: 2.0,
            beacon_strength: 0.05,
            motors: 0.005,
            line_miss: 0.02,
            line_double: 0.02,
            battery_mv: 5.0,
        }
    }
}

impl Noise {
    /// No noise at all: exact sensors, nominal wheels.
    pub fn none() -> Self {
        Noise {
            obstacle_counts: 0.0,
            obstacle_gain_spread: 0.0,
            light_counts: 0.0,
            compass_deg: 0.0,
            beacon_deg: 0.0,
            beacon_strength: 0.0,
            motors: 0.0,
            line_miss: 0.0,
            line_double: 0.0,
            battery_mv: 0.0,
        }
    }

    /// Every level made non-negative and finite (a bad value becomes 0), probabilities
    /// clamped to [0, 1].
    pub fn sanitised(self) -> Noise {
        let s = |v: f64| if v.is_finite() && v > 0.0 { v } else { 0.0 };
        let p = |v: f64| s(v).min(1.0);
        Noise {
            obstacle_counts: s(self.obstacle_counts),
            obstacle_gain_spread: s(self.obstacle_gain_spread).min(0.2),
            light_counts: s(self.light_counts),
            compass_deg: s(self.compass_deg),
            beacon_deg: s(self.beacon_deg),
            beacon_strength: s(self.beacon_strength),
            motors: s(self.motors).min(0.1),
            line_miss: p(self.line_miss),
            line_double: p(self.line_double),
            battery_mv: s(self.battery_mv),
        }
    }
}

/// Adds Gaussian noise and clamps to a 10-bit reading.
pub(crate) fn counts10(value: f64, sigma: f64, rng: &mut SimRng) -> u16 {
    let v = (value + rng.gaussian(sigma)).round();
    // NaN fails both comparisons and ends as 0 through the saturating cast.
    v.clamp(0.0, 1023.0) as u16
}
