//! Link fault injection: dropped bytes, flipped bits, stalls and disconnects, per direction.
//!
//! Layer: a seeded wrapper around the byte stream between the pty and the robot's UART
//! (smoltcp's `FaultInjector` idea): the world and the firmware know nothing of it. Each
//! direction has its own generator, derived from the run's seed, so a run with the same seed
//! and the same traffic corrupts the same bytes. Rates are probabilities per byte
//! (drop) and per bit (flip); a stall holds bytes back for a while and then releases them,
//! as a USB-serial adapter that hangs does.

use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

/// Faults for one direction of the link.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FaultConfig {
    /// Probability that a byte is lost, 0..=1.
    pub drop_rate: f64,
    /// Probability that a bit is flipped, 0..=1.
    pub flip_rate: f64,
    /// Stalls: every `period_s` seconds, bytes are held for `duration_s` seconds.
    pub stall: Option<Stall>,
}

/// A periodic stall.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stall {
    pub period_s: f64,
    pub duration_s: f64,
}

impl FaultConfig {
    /// Whether this direction is untouched.
    pub fn is_clean(&self) -> bool {
        self.drop_rate <= 0.0 && self.flip_rate <= 0.0 && self.stall.is_none()
    }

    /// Checks the rates are probabilities and stalls are sane; says which field is wrong.
    pub fn validate(&self, name: &str) -> Result<(), String> {
        for (field, v) in [("drop rate", self.drop_rate), ("flip rate", self.flip_rate)] {
            if !(0.0..=1.0).contains(&v) {
                return Err(format!("{name} {field} {v} is not a probability in 0..=1"));
            }
        }
        if let Some(s) = self.stall {
            if !(s.period_s > 0.0 && s.duration_s >= 0.0 && s.duration_s < s.period_s) {
                return Err(format!(
                    "{name} stall: need 0 <= duration ({}) < period ({})",
                    s.duration_s, s.period_s
                ));
            }
        }
        Ok(())
    }
}

/// Counters of what was done to the stream.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FaultStats {
    pub bytes_in: u64,
    pub bytes_dropped: u64,
    pub bits_flipped: u64,
}

/// A seeded fault injector for one direction.
pub struct FaultInjector {
    cfg: FaultConfig,
    rng: Pcg64Mcg,
    held: Vec<u8>,
    stats: FaultStats,
}

impl FaultInjector {
    /// `stream` distinguishes the two directions of one run.
    pub fn new(cfg: FaultConfig, seed: u64, stream: u64) -> Self {
        FaultInjector {
            cfg,
            rng: Pcg64Mcg::seed_from_u64(seed ^ stream.wrapping_mul(0x9E37_79B9_7F4A_7C15)),
            held: Vec::new(),
            stats: FaultStats::default(),
        }
    }

    pub fn stats(&self) -> FaultStats {
        self.stats
    }

    /// Whether the link is stalled at simulated time `t_s`.
    pub fn stalled(&self, t_s: f64) -> bool {
        self.cfg
            .stall
            .is_some_and(|s| t_s.rem_euclid(s.period_s) < s.duration_s)
    }

    /// Passes `bytes` through the faults at time `t_s`, appending survivors to `out`.
    pub fn apply(&mut self, bytes: &[u8], t_s: f64, out: &mut Vec<u8>) {
        self.stats.bytes_in += bytes.len() as u64;
        if self.cfg.is_clean() {
            out.extend_from_slice(bytes);
            return;
        }
        for &b in bytes {
            if self.cfg.drop_rate > 0.0 && self.rng.random_bool(self.cfg.drop_rate) {
                self.stats.bytes_dropped += 1;
                continue;
            }
            let mut b = b;
            if self.cfg.flip_rate > 0.0 {
                for bit in 0..8 {
                    if self.rng.random_bool(self.cfg.flip_rate) {
                        b ^= 1 << bit;
                        self.stats.bits_flipped += 1;
                    }
                }
            }
            self.held.push(b);
        }
        if !self.stalled(t_s) {
            out.append(&mut self.held);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_clean_link_passes_everything() {
        let mut f = FaultInjector::new(FaultConfig::default(), 1, 0);
        let mut out = Vec::new();
        f.apply(&[1, 2, 3], 0.0, &mut out);
        assert_eq!(out, [1, 2, 3]);
    }

    #[test]
    fn drop_and_flip_rates_are_met_and_seeded() {
        let cfg = FaultConfig {
            drop_rate: 0.01,
            flip_rate: 1e-3,
            stall: None,
        };
        let data = vec![0u8; 1_000_000];
        let run = |seed| {
            let mut f = FaultInjector::new(cfg, seed, 0);
            let mut out = Vec::new();
            f.apply(&data, 0.0, &mut out);
            (out, f.stats())
        };
        let (a, sa) = run(7);
        let (b, _) = run(7);
        let (c, _) = run(8);
        assert_eq!(a, b, "same seed, same faults");
        assert_ne!(a, c, "another seed, other faults");
        let drop = sa.bytes_dropped as f64 / 1e6;
        let flip = sa.bits_flipped as f64 / (8.0 * (1e6 - sa.bytes_dropped as f64));
        assert!((drop - 0.01).abs() < 0.001, "drop rate {drop}");
        assert!((flip - 1e-3).abs() < 1e-4, "flip rate {flip}");
    }

    #[test]
    fn a_stall_holds_bytes_then_releases_them_in_order() {
        let cfg = FaultConfig {
            stall: Some(Stall {
                period_s: 10.0,
                duration_s: 2.0,
            }),
            ..FaultConfig::default()
        };
        let mut f = FaultInjector::new(cfg, 1, 0);
        let mut out = Vec::new();
        f.apply(&[1, 2], 1.0, &mut out);
        assert!(out.is_empty());
        f.apply(&[3], 3.0, &mut out);
        assert_eq!(out, [1, 2, 3]);
    }

    #[test]
    fn rates_outside_zero_to_one_are_refused() {
        let bad = FaultConfig {
            drop_rate: 1.5,
            ..FaultConfig::default()
        };
        assert!(bad.validate("to-robot").is_err());
    }
}
