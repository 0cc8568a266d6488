//! One situation as the wire carries it (PROTOCOL.md §6 kind 16), and when the next is due.
//!
//! Seed 001 §3.1: "3 situations are sampled per second". The schedule keeps exact thirds of
//! a second (333, 667, 1000 ms ...) so the rate does not drift by the rounding of 333 ms.

use protocol::{AliceSituation, Pose as WirePose};

use super::SENSORS;
use crate::odometry::{wrap_angle, Pose};

/// Situations per second (seed 001 §3.1).
pub const PER_SECOND: u32 = 3;

/// The wire's form of one sample: whisker bits (bits 24..32 cleared), light bytes as read, the
/// odometry pose rounded to millimetres and milliradians (heading wrapped to (-pi, pi]).
pub fn situation(
    seq: u16,
    time_ms: u32,
    whiskers: u32,
    light: [u8; SENSORS],
    odometry: Pose,
) -> AliceSituation {
    let mm = |m: f32| {
        let v = libm::roundf(m * 1000.0);
        // A pose beyond +-2147 km cannot be carried; clamp rather than wrap.
        v.clamp(i32::MIN as f32, i32::MAX as f32) as i32
    };
    AliceSituation {
        time_ms,
        seq,
        whiskers: whiskers & ((1 << SENSORS) - 1),
        light,
        odometry: WirePose {
            x_mm: mm(odometry.x),
            y_mm: mm(odometry.y),
            heading_mrad: libm::roundf(wrap_angle(odometry.heading) * 1000.0) as i16,
        },
    }
}

/// The 3 Hz sampling schedule and the sequence number.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Schedule {
    /// When sampling began, ms.
    start_ms: Option<u32>,
    /// Samples taken since `start_ms`.
    taken: u32,
    /// The next sample's sequence number (wrapping; a jump on the station means losses).
    pub seq: u16,
}

impl Schedule {
    /// Whether a sample is due at `now_ms`; if so it is counted as taken and its sequence
    /// number is returned.
    pub fn due(&mut self, now_ms: u32) -> Option<u16> {
        let start = *self.start_ms.get_or_insert(now_ms);
        let next = start.wrapping_add(sample_ms(self.taken));
        if now_ms.wrapping_sub(next) >= 0x8000_0000 {
            return None;
        }
        // Behind by more than a sample (a stall): restart the grid from now.
        if now_ms.wrapping_sub(next) >= sample_ms(1) {
            self.start_ms = Some(now_ms);
            self.taken = 0;
        }
        self.taken += 1;
        // Restart the grid every 3 s, so `taken` cannot overflow in a long run.
        if self.taken == 3 * PER_SECOND {
            self.start_ms = Some(self.start_ms.unwrap_or(now_ms).wrapping_add(3000));
            self.taken = 0;
        }
        let seq = self.seq;
        self.seq = self.seq.wrapping_add(1);
        Some(seq)
    }
}

/// Time of sample `n` after the start of the grid, ms.
fn sample_ms(n: u32) -> u32 {
    n * 1000 / PER_SECOND
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn three_samples_a_second_on_exact_thirds() {
        let mut s = Schedule::default();
        let mut at: heapless::Vec<u32, 64> = heapless::Vec::new();
        for t in (0..=10_000u32).step_by(10) {
            if s.due(t).is_some() {
                at.push(t).unwrap();
            }
        }
        // 0, 340 (333 on a 10 ms cycle), 670, 1000, ...: 31 samples in 0..=10 s.
        assert_eq!(at.len(), 31, "{:?}", at.as_slice());
        assert_eq!(&at.as_slice()[..4], &[0, 340, 670, 1000]);
        assert_eq!(s.seq, 31);
    }

    #[test]
    fn a_stall_restarts_the_grid_instead_of_bursting() {
        let mut s = Schedule::default();
        assert!(s.due(0).is_some());
        // Nothing for 5 s: one sample now, not 15.
        assert!(s.due(5000).is_some());
        assert!(s.due(5010).is_none());
        assert!(s.due(5333).is_some());
    }

    #[test]
    fn the_wire_form_rounds_wraps_and_masks() {
        let p = Pose::new(1.2345, -0.0004, 3.5);
        let w = situation(7, 99, 0xFF00_0001, [9; SENSORS], p);
        assert_eq!((w.seq, w.time_ms), (7, 99));
        assert_eq!(w.whiskers, 0x0000_0001, "bits 24..32 are zero on the wire");
        assert_eq!((w.odometry.x_mm, w.odometry.y_mm), (1235, 0));
        let wrapped = 3.5 - core::f32::consts::TAU;
        assert_eq!(
            w.odometry.heading_mrad,
            libm::roundf(wrapped * 1000.0) as i16
        );
        let far = situation(0, 0, 0, [0; SENSORS], Pose::new(1e12, -1e12, 0.0));
        assert_eq!((far.odometry.x_mm, far.odometry.y_mm), (i32::MAX, i32::MIN));
    }
}
