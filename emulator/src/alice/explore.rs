//! The wandering that feeds the scenarios: a few of the thesis's exploration instincts
//! (§6.2), fused by priority like its subsumption scheme: straight movement until a whisker
//! touches, turning away from the touch, and stochastic turns. (The network-based instincts
//! need the model's state and are not used: the scenarios judge the model, not the explorer.)

use crate::rng::SimRng;

use super::sensors::COUNT;

/// Chance per sample of a stochastic turn (ours).
pub const RANDOM_TURN_P: f64 = 0.03;

/// What the explorer wants next.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Move {
    /// Drive straight.
    Straight,
    /// Turn on the spot by this many radians, then drive on.
    Turn(f64),
}

/// Decide from this sample's whiskers.
pub fn decide(touch: &[bool; COUNT], rng: &mut SimRng) -> Move {
    // Whiskers within 75 degrees of forward (indices 0..=5 and 19..=23).
    let front = |i: usize| !(6..=18).contains(&i);
    let (mut sx, mut sy, mut any) = (0.0, 0.0, false);
    for (i, &t) in touch.iter().enumerate() {
        if t && front(i) {
            let a = i as f64 * std::f64::consts::TAU / COUNT as f64;
            sx += a.cos();
            sy += a.sin();
            any = true;
        }
    }
    if any {
        // Away from the contacts' mean direction, give or take 70 degrees.
        let away = super::wrap(sy.atan2(sx) + std::f64::consts::PI);
        let jitter = (2.0 * rng.uniform() - 1.0) * 70f64.to_radians();
        return Move::Turn(super::wrap(away + jitter));
    }
    if rng.chance(RANDOM_TURN_P) {
        let a = (30.0 + 120.0 * rng.uniform()).to_radians();
        return Move::Turn(if rng.chance(0.5) { a } else { -a });
    }
    Move::Straight
}
