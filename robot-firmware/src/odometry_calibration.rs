//! Systematic odometry calibration from two wall-following laps (UMBmark's idea, Borenstein &
//! Feng 1996, with walls instead of an external position reference).
//!
//! Why: the Khepera's odometry error is systematic, not random: each wheel's ground speed is
//! off by a constant fraction (seed 003 §2.3.3: up to ±1 %), and the wheels may be truly
//! further apart than the nominal 52 mm (seed 000 Tables 1-2: about 53.3 mm). A difference
//! between the two wheels bends every "straight" path the encoders report, 4° a metre for a
//! 0.37 % difference; that curvature is what the go-to benchmark's misses come from. Real
//! robots calibrate it; this is that calibration, made with the robot's own sensors only.
//!
//! The manoeuvre (`odometry_manoeuvre`, driven by the emulator's `bench
//! --calibrate-odometry` and by `station calibrate odometry`): hold the wall, first with the
//! wall on the RIGHT, and close laps. (The manoeuvre takes its wheel ratio from straight walls,
//! `odometry_stretch`, when they cover a metre; these laps are its fallback.) A lap is closed when the robot is again moving
//! straight along a wall (its side sensor sees the wall and its believed heading has held
//! still over [`CalibrationParams::window_mm`]) and its believed heading is within
//! [`CalibrationParams::heading_tolerance_rad`] of the heading at the lap's start plus a
//! non-zero whole number of turns. Moving straight along a wall means moving along the
//! wall's direction, so the TRUE heading change between those two moments is exactly 2 pi k:
//! the walls are the reference, whatever the robot's position error. Laps chain (each closing
//! anchor starts the next). After [`CalibrationParams::direction_mm`] of laps one way the
//! calibrator asks for the other side (the caller turns the robot round), as UMBmark runs
//! both directions; it ends with enough both ways or [`MAX_LAPS`] laps, or when the caller's
//! time is up ([`LapCalibrator::finish`]).
//!
//! The model: a wheel's ground travel is its encoder travel times its own factor, so over a
//! lap the true turn is `a R - c L = 2 pi k`, R and L the encoder travel (pulses x nominal
//! pulse length), `a` and `c` the right and left factors divided by the true wheel distance.
//! Laps of both directions (their turns have opposite signs, their straight parts the same:
//! UMBmark's reason for running both) solve for `a` and `c`: wheel ratio `a / c`, effective
//! wheel distance `2 / (a + c)`. Laps of one direction only give the ratio with the mean
//! wheel factor taken as nominal. With three laps or more the ratio is the median of the laps'
//! own ratios, so one bad closure is an outlier, not a shift. Measured limit (docs/reproductions.md,
//! "Odometry calibration"): in the emulator's boxes the seed 000 edge follower rarely closes
//! a lap the second way round, so the mean factor stays nominal, and each lap's own ratio
//! then carries the wheels' common speed error (up to 1 %) into its turning term.
//!
//! An uncalibrated lap can drift by more than the closing tolerance (a 2 % wheel difference
//! turns the belief 0.38 rad a metre). So the recogniser also measures, on every straight
//! stretch along a wall (where the true heading is constant), the belief's heading rate per
//! metre, and judges a closure by the heading with that rate taken out: the wall as a
//! straight edge gives a first estimate, the closed laps the exact one.
//!
//! The anchors are window means: the believed heading is linear in the encoder counts, so the
//! window's mean heading belongs to its mean counts, and the wall-following wobble averages
//! out of the true heading too.
//!
//! Layer: pure arithmetic, no I/O, no clock, no heap (`#![no_std]`); fed one sample per
//! control cycle or telemetry frame. What can fail: a lap never closing (the caller's
//! timeout), or a solution outside [`CalibrationParams::max_ratio_error`] /
//! [`CalibrationParams::max_distance_error`] ([`CalibrationError`]).

use core::f32::consts::PI;

/// How the laps are recognised. Not from the papers: chosen for a Khepera (5.5 cm) in boxes
/// of 0.6 m and more; each says why.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CalibrationParams {
    /// Travel over which the heading must hold still to count as moving along a wall, mm:
    /// 80 mm is about three control cycles' worth of wall-following wobble, short enough to
    /// fit between the corners of a 0.6 m box's walls.
    pub window_mm: f32,
    /// Largest heading spread (max - min) inside the window, radians (3°: the edge
    /// follower's wobble on a straight wall is about ±1°, a corner turns much more).
    pub straight_spread_rad: f32,
    /// Largest difference between a closing window's heading and the start's (plus whole
    /// turns), radians: 0.5 rad is more than an uncalibrated lap drifts (±1 % wheels: 0.2
    /// rad a metre worst case, laps of 1-2.5 m) and less than the 0.79 rad between walls at
    /// 45°.
    pub heading_tolerance_rad: f32,
    /// Shortest lap, mm of travel: a shorter "closure" is still the start's own wall.
    pub min_lap_mm: f32,
    /// Largest accepted |ratio - 1| (the thesis's ±1 % a wheel is 2 %; 5 % leaves room for a
    /// worn tyre and refuses nonsense).
    pub max_ratio_error: f32,
    /// Largest accepted |distance / nominal - 1| (seed 000's 53.3 vs 52 mm is 2.5 %).
    pub max_distance_error: f32,
    /// Lap travel wanted in each direction before the calibration ends, mm (laps in one
    /// direction are summed: more travel, smaller share of the anchors' error).
    pub direction_mm: f32,
    /// Shortest straight stretch whose heading rate counts towards the straight-edge
    /// estimate, mm (two windows).
    pub min_stretch_mm: f32,
}

impl Default for CalibrationParams {
    fn default() -> Self {
        Self {
            window_mm: 80.0,
            straight_spread_rad: 0.05,
            heading_tolerance_rad: 0.5,
            min_lap_mm: 500.0,
            max_ratio_error: 0.05,
            max_distance_error: 0.10,
            min_stretch_mm: 160.0,
            direction_mm: 2000.0,
        }
    }
}

/// Which side the wall is on during a lap (the edge-following mode to command).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WallSide {
    /// Wall on the right: counter-clockwise round a box (`Mode::EdgeFollowRight`).
    Right,
    /// Wall on the left: clockwise (`Mode::EdgeFollowLeft`).
    Left,
}

/// One observation: cumulative encoder pulses (unwrapped), the believed heading, and whether
/// the side sensor on the lap's wall side sees a wall.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Left and right encoder pulses since any fixed origin.
    pub pulses: [i64; 2],
    /// Believed heading, radians (any wrap: differences are unwrapped here).
    pub heading_rad: f32,
    /// The side sensor on the current [`WallSide`] sees a wall.
    pub wall_beside: bool,
}

/// One closed lap: encoder travel from anchor to anchor and the whole turns made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lap {
    /// Right wheel encoder travel, mm (pulses x nominal pulse length).
    pub right_mm: f32,
    /// Left wheel encoder travel, mm.
    pub left_mm: f32,
    /// Whole turns, counter-clockwise positive.
    pub turns: i32,
    /// Believed heading change minus `2 pi turns`, radians: the lap's drift before
    /// calibration.
    pub drift_rad: f32,
}

/// The calibration's result: what to set the odometry parameters to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Calibration {
    /// Right wheel's travel per pulse over the left's (`odo_wheel_ratio`).
    pub wheel_ratio: f32,
    /// Effective wheel distance, mm (`odo_wheel_distance_mm`).
    pub wheel_distance_mm: f32,
    /// Both directions were measured (else the mean wheel factor was taken as nominal and
    /// the wheel distance kept).
    pub both_directions: bool,
    /// The laps used: the sums of the counter-clockwise and of the clockwise ones.
    pub laps: [Lap; 2],
    /// The wheel ratio is the median of this many laps' own (0: from the sums).
    pub median_of: u8,
}

/// Why no calibration came out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CalibrationError {
    /// The solution's ratio is beyond `max_ratio_error` (value: the ratio).
    RatioOutOfRange(f32),
    /// The solution's wheel distance is beyond `max_distance_error` (value: mm).
    DistanceOutOfRange(f32),
    /// The equations have no usable solution (a degenerate lap).
    Degenerate,
    /// No lap closed.
    NoLap,
}

/// What the caller should do next.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Next {
    /// Keep following the wall on this side.
    Follow(WallSide),
    /// Done: stop the robot; the result.
    Done(Result<Calibration, CalibrationError>),
}

/// Window length in samples held for the straightness test (a 25 Hz telemetry at a Khepera's
/// 40-60 mm/s gives about 2 mm a sample; 64 samples always cover 80 mm at 10-25 Hz and the
/// 12.5 Hz control cycle).
const WINDOW: usize = 64;

#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Point {
    travel_mm: f32,
    heading: f32,
    left_mm: f32,
    right_mm: f32,
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct Anchor {
    heading: f32,
    left_mm: f32,
    right_mm: f32,
    travel_mm: f32,
}

/// The lap recogniser and solver (see the module text).
#[derive(Clone, Debug)]
pub struct LapCalibrator {
    params: CalibrationParams,
    mm_per_pulse: f32,
    nominal_distance_mm: f32,
    side: WallSide,
    origin: Option<[i64; 2]>,
    last_heading: f32,
    unwrapped: f32,
    ring: [Point; WINDOW],
    len: usize,
    head: usize,
    start: Option<Anchor>,
    laps: [Option<Lap>; 2],
    // Every closed lap, for the median (a lap whose anchors caught the follower's wobble at
    // its worst, or a closure on the wrong wall, is an outlier, not a shift of the result).
    each: [Lap; MAX_LAPS],
    count: usize,
    // The straight stretch under way (first and last anchor), and the sums of the finished
    // stretches' belief heading change and travel.
    stretch: Option<(Anchor, Anchor)>,
    stretch_heading: f32,
    stretch_travel: f32,
}

/// Most laps kept; the calibration ends when it has this many.
pub const MAX_LAPS: usize = 12;

/// An empty lap (no travel, no turn).
pub const NO_LAP: Lap = Lap {
    right_mm: 0.0,
    left_mm: 0.0,
    turns: 0,
    drift_rad: 0.0,
};

/// What the newest samples say.
enum Window {
    /// Less than `window_mm` of travel along the wall yet.
    Short,
    /// The heading moved more than `straight_spread_rad`.
    Bent,
    /// Straight along the wall: the window's mean anchor.
    Straight(Anchor),
}

impl LapCalibrator {
    /// A calibrator for a robot whose nominal pulse length and wheel distance are these, mm.
    pub fn new(params: CalibrationParams, mm_per_pulse: f32, nominal_distance_mm: f32) -> Self {
        Self {
            params,
            mm_per_pulse,
            nominal_distance_mm,
            side: WallSide::Right,
            origin: None,
            last_heading: 0.0,
            unwrapped: 0.0,
            ring: [Point::default(); WINDOW],
            len: 0,
            head: 0,
            start: None,
            laps: [None, None],
            each: [NO_LAP; MAX_LAPS],
            count: 0,
            stretch: None,
            stretch_heading: 0.0,
            stretch_travel: 0.0,
        }
    }

    /// The belief's heading rate along straight walls so far, radians a millimetre (0 until
    /// `2 min_stretch_mm` of straight stretches): minus the path's true curvature error.
    pub fn straight_rate(&self) -> f32 {
        if self.stretch_travel < 2.0 * self.params.min_stretch_mm {
            0.0
        } else {
            self.stretch_heading / self.stretch_travel
        }
    }

    fn end_stretch(&mut self) {
        if let Some((a, b)) = self.stretch.take() {
            let ds = b.travel_mm - a.travel_mm;
            if ds >= self.params.min_stretch_mm {
                self.stretch_heading += b.heading - a.heading;
                self.stretch_travel += ds;
            }
        }
    }

    /// Every lap closed so far, in order (for a caller's progress report).
    pub fn closed_laps(&self) -> &[Lap] {
        &self.each[..self.count]
    }

    /// The side to follow now.
    pub fn side(&self) -> WallSide {
        self.side
    }

    /// Takes one sample; says what to do next.
    pub fn observe(&mut self, s: Sample) -> Next {
        if self.origin.is_none() {
            self.origin = Some(s.pulses);
            self.last_heading = s.heading_rad;
        }
        let origin = self.origin.unwrap_or(s.pulses);
        let d = s.heading_rad - self.last_heading;
        self.unwrapped += libm::remainderf(d, 2.0 * PI);
        self.last_heading = s.heading_rad;
        // i64 differences then f32: exact for any run shorter than 2^24 pulses (1.3 km).
        let left_mm = (s.pulses[0] - origin[0]) as f32 * self.mm_per_pulse;
        let right_mm = (s.pulses[1] - origin[1]) as f32 * self.mm_per_pulse;
        let travel_mm = (libm::fabsf(left_mm) + libm::fabsf(right_mm)) / 2.0;
        if !s.wall_beside {
            // Not along a wall: the window and the stretch restart.
            self.len = 0;
            self.end_stretch();
            return Next::Follow(self.side);
        }
        let p = Point {
            travel_mm,
            heading: self.unwrapped,
            left_mm,
            right_mm,
        };
        self.push(p);
        let anchor = match self.window() {
            Window::Short => return Next::Follow(self.side),
            Window::Bent => {
                self.end_stretch();
                return Next::Follow(self.side);
            }
            Window::Straight(a) => a,
        };
        self.stretch = Some(match self.stretch {
            Some((first, _)) => (first, anchor),
            None => (anchor, anchor),
        });
        match self.start {
            None => {
                self.start = Some(anchor);
                self.len = 0;
            }
            Some(start) => {
                if anchor.travel_mm - start.travel_mm < self.params.min_lap_mm {
                    return Next::Follow(self.side);
                }
                let travel = anchor.travel_mm - start.travel_mm;
                // The straight-edge estimate of the lap's drift taken out (module text).
                let turned = anchor.heading - start.heading - self.straight_rate() * travel;
                let turns = libm::roundf(turned / (2.0 * PI));
                let drift = turned - turns * 2.0 * PI;
                if turns == 0.0 || libm::fabsf(drift) > self.params.heading_tolerance_rad {
                    return Next::Follow(self.side);
                }
                let lap = Lap {
                    right_mm: anchor.right_mm - start.right_mm,
                    left_mm: anchor.left_mm - start.left_mm,
                    turns: turns as i32,
                    drift_rad: anchor.heading - start.heading - turns * 2.0 * PI,
                };
                // Laps chain: this closing anchor starts the next one.
                self.start = Some(anchor);
                self.len = 0;
                if let Some(e) = self.each.get_mut(self.count) {
                    *e = lap;
                    self.count += 1;
                }
                let slot = usize::from(lap.turns < 0);
                self.laps[slot] = Some(match self.laps[slot] {
                    Some(sum) => Lap {
                        right_mm: sum.right_mm + lap.right_mm,
                        left_mm: sum.left_mm + lap.left_mm,
                        turns: sum.turns + lap.turns,
                        drift_rad: sum.drift_rad + lap.drift_rad,
                    },
                    None => lap,
                });
                let enough = |l: Option<Lap>| {
                    l.is_some_and(|l| {
                        (libm::fabsf(l.right_mm) + libm::fabsf(l.left_mm)) / 2.0
                            >= self.params.direction_mm
                    })
                };
                if (enough(self.laps[0]) && enough(self.laps[1])) || self.count == MAX_LAPS {
                    return Next::Done(self.finish());
                }
                // Counter-clockwise first, then ask for the other way round.
                let side = if enough(self.laps[0]) {
                    WallSide::Left
                } else {
                    WallSide::Right
                };
                if side != self.side {
                    // The caller turns the robot round: the next lap starts afresh.
                    self.side = side;
                    self.start = None;
                    self.len = 0;
                    self.end_stretch();
                }
            }
        }
        Next::Follow(self.side)
    }

    fn push(&mut self, p: Point) {
        if self.len == 0 {
            self.head = 0;
        }
        // Keep samples at least 1 mm apart so a slow robot's window still spans window_mm.
        if self.len > 0 {
            let last = self.ring[(self.head + WINDOW - 1) % WINDOW];
            if p.travel_mm - last.travel_mm < 1.0 {
                return;
            }
        }
        self.ring[self.head] = p;
        self.head = (self.head + 1) % WINDOW;
        self.len = (self.len + 1).min(WINDOW);
    }

    /// The mean anchor of the newest samples spanning `window_mm`, if they are straight.
    fn window(&self) -> Window {
        if self.len < 2 {
            return Window::Short;
        }
        let newest = self.ring[(self.head + WINDOW - 1) % WINDOW];
        let (mut lo, mut hi) = (newest.heading, newest.heading);
        let mut sum = Point::default();
        let mut n = 0.0f32;
        for k in 1..=self.len {
            let q = self.ring[(self.head + WINDOW - k) % WINDOW];
            lo = lo.min(q.heading);
            hi = hi.max(q.heading);
            if hi - lo > self.params.straight_spread_rad {
                return Window::Bent;
            }
            sum.heading += q.heading;
            sum.left_mm += q.left_mm;
            sum.right_mm += q.right_mm;
            sum.travel_mm += q.travel_mm;
            n += 1.0;
            if newest.travel_mm - q.travel_mm >= self.params.window_mm {
                return Window::Straight(Anchor {
                    heading: sum.heading / n,
                    left_mm: sum.left_mm / n,
                    right_mm: sum.right_mm / n,
                    travel_mm: sum.travel_mm / n,
                });
            }
        }
        Window::Short
    }

    /// The calibration from the laps closed so far (the caller's time is up, or both
    /// directions have enough): both directions if there are, else one.
    pub fn finish(&self) -> Result<Calibration, CalibrationError> {
        let (l1, l2) = match self.laps {
            [Some(a), Some(b)] => (a, b),
            // One direction: split nothing, solve it with itself (the nominal-mean branch).
            [Some(a), None] | [None, Some(a)] => (a, NO_LAP),
            [None, None] => return Err(CalibrationError::NoLap),
        };
        let solved = solve_laps(
            [l1, l2],
            self.nominal_distance_mm,
            self.params.max_ratio_error,
            self.params.max_distance_error,
        );
        // Three laps or more: each lap's own ratio (mean wheel factor nominal), the median,
        // whatever one outlier did to the sums.
        let mut r = [0.0f32; MAX_LAPS];
        let mut n = 0;
        for lap in &self.each[..self.count] {
            if let Some(x) = lap_ratio(lap, self.nominal_distance_mm) {
                r[n] = x;
                n += 1;
            }
        }
        if n < 3 {
            return solved;
        }
        let v = &mut r[..n];
        v.sort_unstable_by(f32::total_cmp);
        let median = if n % 2 == 1 {
            v[n / 2]
        } else {
            (v[n / 2 - 1] + v[n / 2]) / 2.0
        };
        if libm::fabsf(median - 1.0) > self.params.max_ratio_error {
            return Err(CalibrationError::RatioOutOfRange(median));
        }
        let c = match solved {
            // The sums agree with the median: keep their wheel distance.
            Ok(c) if libm::fabsf(c.wheel_ratio - median) < 2e-3 => Calibration {
                wheel_ratio: median,
                median_of: n as u8,
                ..c
            },
            _ => Calibration {
                wheel_ratio: median,
                wheel_distance_mm: self.nominal_distance_mm,
                both_directions: false,
                laps: [l1, l2],
                median_of: n as u8,
            },
        };
        Ok(c)
    }
}

/// One lap's ratio with the mean wheel factor nominal (`a + c = 2` in units of the nominal
/// distance), `None` for a degenerate lap.
fn lap_ratio(lap: &Lap, nominal_distance_mm: f32) -> Option<f32> {
    let (r, q) = (
        lap.right_mm / nominal_distance_mm,
        lap.left_mm / nominal_distance_mm,
    );
    let t = 2.0 * PI * lap.turns as f32;
    if libm::fabsf(r + q) < 1e-6 {
        return None;
    }
    let a = (t + 2.0 * q) / (r + q);
    let c = 2.0 - a;
    (a > 0.0 && c > 0.0).then(|| a / c)
}

/// Solves two laps' equations `a R - c L = 2 pi k` (see the module text), in f64-free f32
/// with the equations scaled to unit size.
pub fn solve_laps(
    laps: [Lap; 2],
    nominal_distance_mm: f32,
    max_ratio_error: f32,
    max_distance_error: f32,
) -> Result<Calibration, CalibrationError> {
    let [l1, l2] = laps;
    let t = |l: &Lap| 2.0 * PI * l.turns as f32;
    // Unknowns scaled by the nominal distance: a' = a B, c' = c B (both near 1).
    let b = nominal_distance_mm;
    let (r1, q1, r2, q2) = (
        l1.right_mm / b,
        l1.left_mm / b,
        l2.right_mm / b,
        l2.left_mm / b,
    );
    let det = -r1 * q2 + q1 * r2;
    let both = l1.turns * l2.turns < 0;
    let (a, c) = if both && libm::fabsf(det) > 1e-3 * (r1 * q2).abs().max(1.0) {
        // Cramer on [r1 -q1; r2 -q2] [a; c] = [t1; t2].
        let a = (t(&l1) * -q2 + q1 * t(&l2)) / det;
        let c = (r1 * t(&l2) - r2 * t(&l1)) / det;
        (a, c)
    } else {
        // Mean factor nominal: a + c = 2, with both laps' equations summed (more travel).
        let (r, q, tt) = (r1 + r2, q1 + q2, t(&l1) + t(&l2));
        if libm::fabsf(r + q) < 1e-6 {
            return Err(CalibrationError::Degenerate);
        }
        // a r - (2 - a) q = tt
        let a = (tt + 2.0 * q) / (r + q);
        (a, 2.0 - a)
    };
    if !(a.is_finite() && c.is_finite() && a > 0.0 && c > 0.0) {
        return Err(CalibrationError::Degenerate);
    }
    let ratio = a / c;
    if libm::fabsf(ratio - 1.0) > max_ratio_error {
        return Err(CalibrationError::RatioOutOfRange(ratio));
    }
    let distance = if both { 2.0 / (a + c) * b } else { b };
    if libm::fabsf(distance / b - 1.0) > max_distance_error {
        return Err(CalibrationError::DistanceOutOfRange(distance));
    }
    Ok(Calibration {
        wheel_ratio: ratio,
        wheel_distance_mm: distance,
        both_directions: both,
        laps,
        median_of: 0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Laps of a robot whose right wheel truly travels `kr` and left `kl` times its encoder
    /// travel, wheels `b` mm apart: a rectangle of `w` x `h` mm driven straight along its
    /// sides, turning on the spot at the corners.
    fn lap(kr: f32, kl: f32, b: f32, w: f32, h: f32, ccw: bool) -> Lap {
        // The true travel: straights w, h, w, h; the corners turn pi/2 each on the spot.
        // A true straight needs encoder travel s/kr and s/kl; a true on-the-spot turn of
        // +-pi/2 needs (pi/4) b / k on each wheel, in opposite directions.
        let straight = 2.0 * (w + h);
        let turn = PI / 4.0 * b * 4.0;
        let sgn = if ccw { 1.0 } else { -1.0 };
        Lap {
            right_mm: straight / kr + sgn * turn / kr,
            left_mm: straight / kl - sgn * turn / kl,
            turns: if ccw { 1 } else { -1 },
            drift_rad: 0.0,
        }
    }

    #[test]
    fn two_directions_recover_both_wheel_factors() {
        let (kr, kl, b) = (1.0037, 0.9990, 53.3);
        let laps = [
            lap(kr, kl, b, 700.0, 550.0, true),
            lap(kr, kl, b, 700.0, 550.0, false),
        ];
        let c = solve_laps(laps, 52.0, 0.05, 0.1).expect("solves");
        assert!(c.both_directions);
        assert!((c.wheel_ratio - kr / kl).abs() < 1e-4, "{c:?}");
        // Effective distance: true distance over the mean factor.
        let want = b / ((kr + kl) / 2.0);
        assert!(
            (c.wheel_distance_mm - want).abs() < 0.02,
            "{c:?} want {want}"
        );
    }

    #[test]
    fn one_direction_still_gives_the_ratio_with_the_mean_factor_nominal() {
        let (kr, kl) = (1.004, 0.996);
        let laps = [
            lap(kr, kl, 52.0, 700.0, 550.0, true),
            lap(kr, kl, 52.0, 900.0, 550.0, true),
        ];
        let c = solve_laps(laps, 52.0, 0.05, 0.1).expect("solves");
        assert!(!c.both_directions);
        assert!((c.wheel_ratio - kr / kl).abs() < 2e-4, "{c:?}");
        assert_eq!(c.wheel_distance_mm, 52.0);
    }

    #[test]
    fn nonsense_is_refused() {
        let laps = [
            lap(1.2, 0.8, 52.0, 700.0, 550.0, true),
            lap(1.2, 0.8, 52.0, 700.0, 550.0, false),
        ];
        assert!(matches!(
            solve_laps(laps, 52.0, 0.05, 0.1),
            Err(CalibrationError::RatioOutOfRange(_))
        ));
    }

    /// The recogniser on a synthetic robot: a 700 x 550 mm rectangle, both directions, the
    /// believed heading integrated from the encoders with the nominal model.
    #[test]
    fn the_recogniser_closes_one_lap_each_way_and_the_result_fits() {
        let (kr, kl, b) = (1.0037_f32, 0.9990_f32, 52.0_f32);
        let mut cal = LapCalibrator::new(CalibrationParams::default(), 0.08, b);
        let mut pulses = [0.0f64; 2];
        let mut believed = 0.3f32;
        let mut result = None;
        // Drive: along a side in 2 mm true steps, then a corner on the spot in 1° true steps.
        'outer: for _ in 0..6 {
            for side in 0..4 {
                let len = if side % 2 == 0 { 700.0 } else { 550.0 };
                let mut s = 0.0;
                while s < len {
                    pulses[0] += f64::from(2.0 / kl / 0.08);
                    pulses[1] += f64::from(2.0 / kr / 0.08);
                    // Believed turn of this step: nominal model on the encoder travel.
                    believed += (2.0 / kr - 2.0 / kl) / b;
                    s += 2.0;
                    let sample = Sample {
                        pulses: [pulses[0] as i64, pulses[1] as i64],
                        heading_rad: believed,
                        wall_beside: true,
                    };
                    if let Next::Done(r) = cal.observe(sample) {
                        result = Some(r);
                        break 'outer;
                    }
                }
                let sgn = if cal.side() == WallSide::Right {
                    1.0
                } else {
                    -1.0
                };
                for _ in 0..90 {
                    let arc = (PI / 180.0) * b / 2.0;
                    pulses[0] -= f64::from(sgn * arc / kl / 0.08);
                    pulses[1] += f64::from(sgn * arc / kr / 0.08);
                    believed += sgn * (arc / kr + arc / kl) / b;
                    let _ = cal.observe(Sample {
                        pulses: [pulses[0] as i64, pulses[1] as i64],
                        heading_rad: libm::remainderf(believed, 2.0 * PI),
                        wall_beside: false,
                    });
                }
            }
        }
        let c = result.expect("two laps closed").expect("solves");
        assert!(c.both_directions, "{c:?}");
        assert!((c.wheel_ratio - kr / kl).abs() < 3e-4, "{c:?}");
        assert_eq!(c.laps[0].turns, 1);
        assert_eq!(c.laps[1].turns, -1);
    }
}
