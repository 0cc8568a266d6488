//! A small, seeded, portable pseudo-random generator for the simulation's noise.
//!
//! Layer: the bottom of the emulator's world model; every noisy thing (wheel bias, slip, each
//! sensor's noise) owns one [`SimRng`] made from the run's seed and its own stream number, so
//! the draws of one sensor never shift when another sensor is read more or less often.
//!
//! Algorithm: xoshiro256++ (Blackman & Vigna 2019, public domain reference code), seeded by
//! SplitMix64 from `seed` and `stream` as the authors recommend. Normal deviates use the
//! Marsaglia polar method. Invariants: the same (seed, stream) gives the same sequence on every
//! platform for the integer draws; float draws go through `ln`/`sqrt` only (polar method, no
//! trigonometry), so a run is bit-for-bit repeatable on one machine. Nothing here can fail.

/// Stream numbers of the simulation's random sources (one per noisy component).
pub mod stream {
    /// Per-run draws: wheel bias, IR gain spread.
    pub const RUN: u64 = 1;
    /// Wheel slip, redrawn during the run.
    pub const SLIP: u64 = 2;
    /// IR proximity noise.
    pub const IR: u64 = 3;
    /// Ambient light noise.
    pub const LIGHT: u64 = 4;
    /// Floor line sensor misses and double detections.
    pub const LINE: u64 = 5;
    /// Compass noise.
    pub const COMPASS: u64 = 6;
    /// Beacon noise.
    pub const BEACON: u64 = 7;
    /// Battery reading noise.
    pub const BATTERY: u64 = 8;
    /// The firmware's own seed (behaviour threshold jitter).
    pub const FIRMWARE: u64 = 9;
    /// ALICE's whiskers and photoresistors (seed 001: `sensors::alice`).
    pub const ALICE: u64 = 10;
}

/// xoshiro256++ with a cached second normal deviate.
#[derive(Clone, Debug, PartialEq)]
pub struct SimRng {
    s: [u64; 4],
    spare_normal: Option<f64>,
}

/// SplitMix64 step: the recommended seeder for xoshiro generators.
fn splitmix64(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

impl SimRng {
    /// The generator for `stream` of the run seeded with `seed`.
    pub fn new(seed: u64, stream: u64) -> Self {
        // Mixing the stream through its own SplitMix64 output keeps nearby (seed, stream)
        // pairs far apart in the state space.
        let mut st = seed ^ splitmix64(&mut stream.wrapping_mul(0xD1B5_4A32_D192_ED03));
        let s = [
            splitmix64(&mut st),
            splitmix64(&mut st),
            splitmix64(&mut st),
            splitmix64(&mut st),
        ];
        // An all-zero state is xoshiro's one fixed point; SplitMix64 cannot produce four zero
        // outputs in a row, but keep the guard explicit.
        let s = if s == [0; 4] { [1, 2, 3, 4] } else { s };
        SimRng {
            s,
            spare_normal: None,
        }
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        let s = &mut self.s;
        let result = s[0].wrapping_add(s[3]).rotate_left(23).wrapping_add(s[0]);
        let t = s[1] << 17;
        s[2] ^= s[0];
        s[3] ^= s[1];
        s[1] ^= s[2];
        s[0] ^= s[3];
        s[2] ^= t;
        s[3] = s[3].rotate_left(45);
        result
    }

    /// Uniform in [0, 1), 53 bits of resolution.
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// True with probability `p` (p <= 0 never, p >= 1 always).
    pub fn chance(&mut self, p: f64) -> bool {
        if p <= 0.0 || p.is_nan() {
            return false;
        }
        self.uniform() < p
    }

    /// A standard normal deviate (Marsaglia polar method).
    pub fn normal(&mut self) -> f64 {
        if let Some(z) = self.spare_normal.take() {
            return z;
        }
        loop {
            let u = 2.0 * self.uniform() - 1.0;
            let v = 2.0 * self.uniform() - 1.0;
            let s = u * u + v * v;
            if s > 0.0 && s < 1.0 {
                let k = (-2.0 * s.ln() / s).sqrt();
                self.spare_normal = Some(v * k);
                return u * k;
            }
        }
    }

    /// A normal deviate with standard deviation `sigma` (0 when `sigma` is 0 or not finite,
    /// without consuming a draw, so a noiseless configuration leaves the stream untouched).
    pub fn gaussian(&mut self, sigma: f64) -> f64 {
        if sigma > 0.0 && sigma.is_finite() {
            self.normal() * sigma
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_seed_and_stream_repeat_and_streams_differ() {
        let (mut a, mut b) = (SimRng::new(42, 3), SimRng::new(42, 3));
        let mut c = SimRng::new(42, 4);
        let xs: Vec<u64> = (0..100).map(|_| a.next_u64()).collect();
        let ys: Vec<u64> = (0..100).map(|_| b.next_u64()).collect();
        let zs: Vec<u64> = (0..100).map(|_| c.next_u64()).collect();
        assert_eq!(xs, ys);
        assert_ne!(xs, zs);
    }

    #[test]
    fn normal_deviates_have_unit_variance() {
        let mut r = SimRng::new(7, 1);
        let n = 200_000;
        let (mut sum, mut sq) = (0.0, 0.0);
        for _ in 0..n {
            let z = r.normal();
            sum += z;
            sq += z * z;
        }
        let mean = sum / n as f64;
        let var = sq / n as f64 - mean * mean;
        assert!(mean.abs() < 0.01, "{mean}");
        assert!((var - 1.0).abs() < 0.02, "{var}");
    }

    #[test]
    fn zero_sigma_consumes_nothing() {
        let mut a = SimRng::new(1, 1);
        let mut b = SimRng::new(1, 1);
        assert_eq!(a.gaussian(0.0), 0.0);
        assert_eq!(a.gaussian(f64::NAN), 0.0);
        assert_eq!(a.next_u64(), b.next_u64());
        assert!(!a.chance(0.0) && a.chance(1.0));
    }
}
