//! The wandering that feeds the scenarios: a few of the thesis's exploration instincts
//! (§6.2), fused by priority like its subsumption scheme: straight movement until a whisker
//! touches, turning away from the touch, and stochastic turns. (The network-based instincts
//! need the model's state and are not used: the scenarios judge the model, not the explorer.)
//! Wall following ([`Follower`]) is the §5.3 corridor scene's: the wanderer alone never
//! entered its corridor; the §4.5 scenarios keep the wanderer, as their figures were measured.

use crate::rng::SimRng;

use crate::sensors::alice::COUNT;

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

/// Whisker `i`'s direction from forward, radians (not wrapped).
fn bearing(i: usize) -> f64 {
    i as f64 * std::f64::consts::TAU / COUNT as f64
}

/// Decide from this sample's whiskers.
pub fn decide(touch: &[bool; COUNT], rng: &mut SimRng) -> Move {
    // Whiskers within 75 degrees of forward (indices 0..=5 and 19..=23).
    let front = |i: usize| !(6..=18).contains(&i);
    let (mut sx, mut sy, mut any) = (0.0, 0.0, false);
    for (i, &t) in touch.iter().enumerate() {
        if t && front(i) {
            let a = bearing(i);
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

/// Chance that a front contact starts wall following rather than a turn away (ours).
pub const FOLLOW_P: f64 = 0.5;
/// Samples a wall is followed before the wanderer takes over again (ours: about 20 s).
pub const FOLLOW_SAMPLES: u32 = 60;
/// Samples without a side contact before turning back towards the followed wall (ours).
pub const FOLLOW_LOST: u32 = 2;

/// §6.2's wall following on top of [`decide`]: a front contact either turns away (the
/// wanderer) or puts the wall alongside and follows it for a while, turning back towards
/// it whenever the side whiskers lose it. Narrow passages along a wall (a corridor) are then
/// explored, which the straight-and-turn-away wanderer alone almost never enters.
#[derive(Clone, Debug, Default)]
pub struct Follower {
    /// Samples left to follow; 0: wandering.
    left: u32,
    /// The wall's side: +1 on the left, -1 on the right.
    side: f64,
    /// Samples since a side whisker last touched.
    lost: u32,
}

impl Follower {
    /// Decide from this sample's whiskers.
    pub fn decide(&mut self, touch: &[bool; COUNT], rng: &mut SimRng) -> Move {
        // Whisker directions in (-pi, pi]: left positive, right negative.
        let dir = |i: usize| super::wrap(bearing(i));
        let front = touch
            .iter()
            .enumerate()
            .filter(|&(i, &t)| t && dir(i).abs() < 45f64.to_radians())
            .map(|(i, _)| dir(i))
            .next();
        if self.left == 0 {
            if let Some(c) = front {
                if rng.chance(FOLLOW_P) {
                    self.left = FOLLOW_SAMPLES;
                    self.side = if rng.chance(0.5) { 1.0 } else { -1.0 };
                    self.lost = 0;
                    // Turn so the contact ends up at 90 degrees on the chosen side.
                    return Move::Turn(super::wrap(c - self.side * std::f64::consts::FRAC_PI_2));
                }
            }
            return decide(touch, rng);
        }
        self.left -= 1;
        if let Some(c) = front {
            // A wall ahead (a corner): put it alongside too.
            self.lost = 0;
            return Move::Turn(super::wrap(c - self.side * std::f64::consts::FRAC_PI_2));
        }
        let side_touch = touch.iter().enumerate().any(|(i, &t)| {
            let b = dir(i) * self.side;
            t && (45f64.to_radians()..=135f64.to_radians()).contains(&b)
        });
        if side_touch {
            self.lost = 0;
            return Move::Straight;
        }
        self.lost += 1;
        if self.lost >= FOLLOW_LOST {
            self.lost = 0;
            return Move::Turn(self.side * 20f64.to_radians());
        }
        Move::Straight
    }
}
