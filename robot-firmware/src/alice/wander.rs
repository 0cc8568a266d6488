//! ALICE's wandering while its world model learns (seed 001 §6.2): of the thesis's
//! exploration instincts, those that need only the whiskers, fused by priority like its
//! subsumption scheme: turning away from a touch (the reflex) over stochastic turns over
//! straight movement. (The network-based instincts, curiosity and stabilising, need the
//! model's state, which lives on the station.)
//!
//! The drive is differential (the firmware's only drive; ALICE steered six wheels): it drives
//! straight along its heading at 25 cm/s (§3.1) and turns on the spot, by the odometry's
//! heading, at `TURN_RAD_S`. The reflex is checked every control cycle, so a touch turns the
//! robot within a cycle; the stochastic turn is drawn once per situation (3 a second), as the
//! emulator's scenarios draw it.

use super::{sensor_angle_rad, SENSORS};
use crate::behaviour::XorShift32;
use crate::odometry::wrap_angle;

/// Driving speed, mm/s (seed 001 §3.1: 25 cm/s, nearly constant).
pub const SPEED_MM_S: f32 = 250.0;
/// Turning rate on the spot, rad/s (ours: the thesis gives none).
pub const TURN_RAD_S: f32 = 1.5;
/// Chance per situation of a stochastic turn (ours).
pub const RANDOM_TURN_P: f32 = 0.03;
/// A turn ends when the odometry's heading is this close to its target, radians (ours).
const TURN_DONE_RAD: f32 = 0.03;
/// Spread around "away from the touch", radians (ours: 70 degrees).
const AWAY_JITTER_RAD: f32 = 70.0 * core::f32::consts::PI / 180.0;

/// Whether whisker `i` looks ahead: within 75 degrees of forward (indices 0..=5, 19..=23).
pub fn is_front(i: usize) -> bool {
    !(6..=18).contains(&i)
}

/// What the wandering wants next.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Move {
    /// Drive straight.
    Straight,
    /// Turn on the spot by this many radians (anticlockwise positive), then drive on.
    Turn(f32),
}

/// Uniform in [0, 1) from the generator's top 24 bits.
fn uniform(rng: &mut XorShift32) -> f32 {
    (rng.next_u32() >> 8) as f32 / (1u32 << 24) as f32
}

/// The reflex: away from the mean direction of the front whiskers touching, give or take
/// 70 degrees; `None` without a front touch.
pub fn reflex(whiskers: u32, rng: &mut XorShift32) -> Option<Move> {
    let (mut sx, mut sy, mut any) = (0.0f32, 0.0f32, false);
    for i in (0..SENSORS).filter(|&i| is_front(i) && whiskers & (1 << i) != 0) {
        let a = sensor_angle_rad(i);
        sx += libm::cosf(a);
        sy += libm::sinf(a);
        any = true;
    }
    if !any {
        return None;
    }
    let away = libm::atan2f(sy, sx) + core::f32::consts::PI;
    let jitter = (2.0 * uniform(rng) - 1.0) * AWAY_JITTER_RAD;
    Some(Move::Turn(wrap_angle(away + jitter)))
}

/// The stochastic instinct, once per situation: a turn of 30..150 degrees either way with
/// chance `RANDOM_TURN_P`.
pub fn random_turn(rng: &mut XorShift32) -> Option<Move> {
    if uniform(rng) >= RANDOM_TURN_P {
        return None;
    }
    let a = (30.0 + 120.0 * uniform(rng)).to_radians();
    Some(Move::Turn(if rng.coin() { a } else { -a }))
}

/// The wandering's state: the turn in progress, if any.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wander {
    rng: XorShift32,
    /// Target heading of the turn in progress (odometry frame), radians.
    turning_to: Option<f32>,
}

impl Wander {
    pub fn new(seed: u32) -> Self {
        Wander {
            rng: XorShift32::new(seed),
            turning_to: None,
        }
    }

    /// Forgets a turn in progress (the mode was left).
    pub fn reset(&mut self) {
        self.turning_to = None;
    }

    /// Whether a turn is in progress.
    pub fn turning(&self) -> bool {
        self.turning_to.is_some()
    }

    /// One control cycle: the forward speed (mm/s) and turn rate (rad/s) to drive, from this
    /// cycle's whiskers, the odometry's heading and whether a situation was sampled now.
    pub fn step(&mut self, whiskers: u32, heading: f32, sampled: bool) -> (f32, f32) {
        if self.turning_to.is_none() {
            let next = reflex(whiskers, &mut self.rng).or_else(|| {
                if sampled {
                    random_turn(&mut self.rng)
                } else {
                    None
                }
            });
            if let Some(Move::Turn(a)) = next {
                self.turning_to = Some(wrap_angle(heading + a));
            }
        }
        match self.turning_to {
            Some(target) => {
                let left = wrap_angle(target - heading);
                if libm::fabsf(left) <= TURN_DONE_RAD {
                    self.turning_to = None;
                    (SPEED_MM_S, 0.0)
                } else {
                    (0.0, libm::copysignf(TURN_RAD_S, left))
                }
            }
            None => (SPEED_MM_S, 0.0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const FRONT: u32 = 1 << 0;

    #[test]
    fn a_front_touch_turns_away_and_a_rear_touch_does_not() {
        let mut rng = XorShift32::new(3);
        for _ in 0..200 {
            let Some(Move::Turn(a)) = reflex(FRONT, &mut rng) else {
                panic!("a front touch must turn")
            };
            // Away from 0 degrees: 180 +- 70 degrees.
            assert!(libm::fabsf(a) >= (110f32).to_radians() - 1e-4, "{a}");
        }
        // Whisker 12 looks straight back: no reflex.
        assert_eq!(reflex(1 << 12, &mut rng), None);
        // A touch on the left front (whisker 4, 60 degrees) turns right of "away" less often
        // than not: the mean turn points to the right-rear.
        let mut sum = 0.0;
        for _ in 0..500 {
            if let Some(Move::Turn(a)) = reflex(1 << 4, &mut rng) {
                sum += a;
            }
        }
        assert!(sum / 500.0 < -1.5, "mean turn {}", sum / 500.0);
    }

    #[test]
    fn random_turns_come_at_their_rate_and_size() {
        let mut rng = XorShift32::new(11);
        let n = 20_000;
        let mut turns = 0;
        for _ in 0..n {
            if let Some(Move::Turn(a)) = random_turn(&mut rng) {
                turns += 1;
                let d = libm::fabsf(a).to_degrees();
                assert!((30.0..=150.0).contains(&d), "{d}");
            }
        }
        let rate = turns as f32 / n as f32;
        assert!((0.025..0.035).contains(&rate), "{rate}");
    }

    #[test]
    fn it_drives_straight_turns_on_the_spot_by_the_heading_and_drives_on() {
        let mut w = Wander::new(5);
        assert_eq!(w.step(0, 0.0, false), (SPEED_MM_S, 0.0));
        let (v, turn) = w.step(FRONT, 0.0, false);
        assert_eq!(v, 0.0, "turning on the spot");
        assert_eq!(libm::fabsf(turn), TURN_RAD_S);
        // The turn goes on, whiskers or not, until the heading arrives.
        let mut heading = 0.0;
        let mut cycles = 0;
        while w.turning() {
            let (v, turn) = w.step(0, heading, false);
            if w.turning() {
                assert_eq!(v, 0.0);
            }
            heading = wrap_angle(heading + turn * 0.05);
            cycles += 1;
            assert!(cycles < 100, "the turn ends");
        }
        assert!(libm::fabsf(heading) > 1.8, "turned away: {heading}");
        assert_eq!(w.step(0, heading, false), (SPEED_MM_S, 0.0));
    }
}
