//! The wheel ratio from straight walls, no closed lap needed.
//!
//! Why: along a straight wall the robot's TRUE heading relative to the wall is the slope of
//! its distance from the wall, `phi = dy/ds`, and the side IR sensor measures that distance.
//! So over a stretch the believed heading is `theta(s) = theta_w + kappa s + (1 + eta) phi(s)`:
//! the wall's direction, the belief's drift (the wheels' speed difference, `kappa` radians a
//! metre), and the true wobble (scaled by `eta`, the wheels' common factor and distance
//! error). Integrated over the travel, `Psi(s) = int theta ds = c0 + theta_w s + kappa s^2/2 +
//! (1 + eta) y(s)`, and `y` is a smooth function of the reading `r`, so a least-squares fit
//! of `Psi` on `[1, s, s^2, rho, rho^2, rho^3]` (`rho` the reading, scaled; a cubic, as a
//! quadratic in the reading leaves a bias of up to 0.02 rad/m where the reading spans the
//! band) gives `kappa` with the
//! sensor's curve and gain learnt from the stretch itself: no IR model, no wall direction.
//! The true heading change over the stretch being zero, `kappa` is the wheel ratio alone:
//! `R kr = L kl` exactly, so `kr / kl = (1 - kappa B / 2) / (1 + kappa B / 2)` with `B` the
//! nominal wheel distance used by the belief, whatever the true distance and the wheels'
//! common factor (which a lap's turning term cannot separate from the ratio with laps one
//! way only).
//!
//! Error bound: the fit's `s^2` coefficient over a stretch of length `L` moves by about
//! `8 dy / L^2` for a distance error `dy` left at the ends. A Khepera's sensor gives about 60
//! counts a millimetre mid-band with a noise of about 3 counts, so `dy` is under 0.1 mm once
//! the model's curve is fitted; over `L` = 0.5 m that is `kappa` within 3.2e-3 rad/m, a ratio
//! error within 170 ppm (`kappa B`, B = 52 mm); stretches combine by their length-weighted
//! median.
//!
//! Rejected: stretches shorter than `min_mm`, or where the belief turned by more than
//! `max_turn_rad` from the start (a corner, a block), or where the fit's residual is above
//! `max_residual_mm` (a bent wall, a reading that is not the distance: another wall in view).
//! A stretch ends when the side reading leaves its band (saturated, lost) or the caller says
//! the robot is not holding a wall.
//!
//! Layer: pure arithmetic, no I/O, no heap (`#![no_std]`); fed one sample per observation.

/// How stretches are accepted. Not from the papers; each says why.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StretchParams {
    /// Lowest side reading that is a distance, counts (above the floor and noise).
    pub band_lo: u16,
    /// Highest, counts (below saturation at 1023).
    pub band_hi: u16,
    /// A stretch starts only with the reading within this many counts of the holder's set
    /// level, 450: after a corner the robot approaches the wall at an angle, and the reading
    /// then also depends on the angle (the ray's slant), not on the distance alone.
    pub start_window: u16,
    /// Shortest stretch, mm (the `s^2` term needs length: the bound goes as 1 / L^2).
    pub min_mm: f32,
    /// Largest believed turn from the stretch's start, radians (more than the belief's drift
    /// over a metre at 2 % wheel difference, 0.38 rad, less than a corner).
    pub max_turn_rad: f32,
    /// Largest RMS residual of the fit, mm.
    pub max_residual_mm: f32,
}

impl Default for StretchParams {
    fn default() -> Self {
        Self {
            band_lo: 250,
            band_hi: 700,
            start_window: 150,
            min_mm: 200.0,
            max_turn_rad: 0.45,
            max_residual_mm: 0.3,
        }
    }
}

/// The reading the wall holder keeps (`wall_holder::HolderParams::set_level`), counts.
const SET_LEVEL: u16 = 450;

/// Regressors: 1, u, u^2, rho, rho^2, rho^3.
const K: usize = 6;

#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Fit {
    s0: f32,
    th0: f32,
    last_s: f32,
    last_th: f32,
    last_wheels: [f32; 2],
    psi: f64,
    // Normal equations: sum x x^T (full, K x K), sum x psi, sum psi^2, samples.
    xx: [[f64; K]; K],
    xy: [f64; K],
    yy: f64,
    n: u32,
}

/// Most stretches kept (their drift rate and length).
pub const MAX_STRETCHES: usize = 48;

/// One accepted stretch.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stretch {
    /// Belief drift rate, radians a metre of travel.
    pub kappa: f32,
    /// Travel, mm.
    pub length_mm: f32,
    /// RMS residual of the fit, mm.
    pub residual_mm: f32,
    /// The wall's direction in the belief at the stretch's last sample (the fit's heading
    /// without the wobble), unwrapped radians.
    pub wall_end: f32,
    /// The believed heading at that sample minus `wall_end`: the robot's angle to the wall.
    pub phi_end: f32,
    /// Left and right wheel encoder travel at that sample, mm.
    pub wheels_mm: [f32; 2],
}

/// The straight-wall estimator (see the module text).
#[derive(Clone, Debug)]
pub struct StraightWalls {
    params: StretchParams,
    fit: Option<Fit>,
    kept: [Stretch; MAX_STRETCHES],
    count: usize,
    /// Stretches rejected (for a report).
    pub rejected: u16,
}

impl StraightWalls {
    /// An estimator with these acceptance rules.
    pub fn new(params: StretchParams) -> Self {
        Self {
            params,
            fit: None,
            kept: [Stretch::default(); MAX_STRETCHES],
            count: 0,
            rejected: 0,
        }
    }

    /// The stretches accepted so far.
    pub fn stretches(&self) -> &[Stretch] {
        &self.kept[..self.count]
    }

    /// Total length of the accepted stretches, mm.
    pub fn total_mm(&self) -> f32 {
        self.stretches().iter().map(|s| s.length_mm).sum()
    }

    /// One sample: the wheels' encoder travel (left, right, mm), believed heading
    /// (unwrapped, radians), the side reading, and whether the robot is holding a wall.
    pub fn observe(&mut self, wheels_mm: [f32; 2], heading: f32, side: u16, holding: bool) {
        let p = self.params;
        let travel_mm = (wheels_mm[0] + wheels_mm[1]) / 2.0;
        if !holding || side < p.band_lo || side > p.band_hi {
            self.end();
            return;
        }
        if self.fit.is_none() && side.abs_diff(SET_LEVEL) > p.start_window {
            return;
        }
        let f = self.fit.get_or_insert(Fit {
            s0: travel_mm,
            th0: heading,
            last_s: travel_mm,
            last_th: heading,
            ..Fit::default()
        });
        if libm::fabsf(heading - f.th0) > p.max_turn_rad {
            self.end();
            return;
        }
        let ds = f64::from(travel_mm - f.last_s) / 1000.0;
        f.psi += ds * f64::from((heading + f.last_th) / 2.0 - f.th0);
        f.last_s = travel_mm;
        f.last_th = heading;
        f.last_wheels = wheels_mm;
        let u = f64::from(travel_mm - f.s0) / 1000.0;
        let rho = (f64::from(side) - f64::from(SET_LEVEL)) / f64::from(SET_LEVEL);
        let x = [1.0, u, u * u, rho, rho * rho, rho * rho * rho];
        for i in 0..K {
            for j in 0..K {
                f.xx[i][j] += x[i] * x[j];
            }
            f.xy[i] += x[i] * f.psi;
        }
        f.yy += f.psi * f.psi;
        f.n += 1;
    }

    /// Ends the stretch under way (the caller's manoeuvre ends or turns).
    pub fn end(&mut self) {
        let Some(f) = self.fit.take() else { return };
        let length_mm = f.last_s - f.s0;
        if length_mm < self.params.min_mm || f.n < 20 {
            return;
        }
        let Some(c) = solve(f.xx, f.xy) else {
            self.rejected += 1;
            return;
        };
        // Residual sum of squares: sum psi^2 - c . (X^T psi) at the least-squares solution.
        let rss: f64 = f.yy - c.iter().zip(&f.xy).map(|(a, b)| a * b).sum::<f64>();
        let residual_mm = (libm::sqrt(rss.max(0.0) / f64::from(f.n)) * 1000.0) as f32;
        if residual_mm > self.params.max_residual_mm {
            self.rejected += 1;
            return;
        }
        if let Some(slot) = self.kept.get_mut(self.count) {
            *slot = Stretch {
                kappa: (2.0 * c[2]) as f32,
                length_mm,
                residual_mm,
                // d Psi / du without the wobble term: theta_w - th0 + kappa u.
                wall_end: f.th0 + (c[1] + 2.0 * c[2] * f64::from(length_mm) / 1000.0) as f32,
                phi_end: f.last_th
                    - f.th0
                    - (c[1] + 2.0 * c[2] * f64::from(length_mm) / 1000.0) as f32,
                wheels_mm: f.last_wheels,
            };
            self.count += 1;
        }
    }

    /// The belief's drift rate along straight walls, radians a metre: the length-weighted
    /// median of the stretches' own (a stretch whose reading was not the distance all along,
    /// another wall in the sensor's cone near a corner, is an outlier, not a shift); `None`
    /// below `min_total_mm` of accepted stretches.
    pub fn kappa(&self, min_total_mm: f32) -> Option<f32> {
        let total = self.total_mm();
        if total < min_total_mm || total <= 0.0 {
            return None;
        }
        let mut v = self.kept;
        let v = &mut v[..self.count];
        v.sort_unstable_by(|a, b| a.kappa.total_cmp(&b.kappa));
        let mut acc = 0.0;
        for s in v.iter() {
            acc += s.length_mm;
            if acc >= total / 2.0 {
                return Some(s.kappa);
            }
        }
        v.last().map(|s| s.kappa)
    }
}

impl StraightWalls {
    /// The effective wheel distance (`odo_wheel_distance_mm`) from pairs of stretches along
    /// walls of the same direction (the same wall a lap later, or a parallel one traversed
    /// the same way): the true turn between their last samples is `2 pi k` plus the robot's
    /// angle to the wall at each (`phi_end`), and the odometry with ratio `r` turns by `2 (r
    /// R - L) / ((1 + r) B)` for encoder travel R, L, so `B = 2 (r R - L) / ((1 + r) (2 pi k +
    /// phi_j - phi_i))`. The fitted wall directions, free of the wobble, make this sharper
    /// than a lap's window means. A pair is one when its wall directions, less the belief's
    /// drift (`kappa` radians a metre), differ by whole turns within `tolerance_rad`, and
    /// `min_lap_mm` of travel apart; each stretch pairs with the latest such one before it.
    /// The median of the pairs; `None` without a pair.
    pub fn lap_distance(
        &self,
        ratio: f32,
        kappa: f32,
        tolerance_rad: f32,
        min_lap_mm: f32,
    ) -> Option<f32> {
        let two_pi = 2.0 * core::f32::consts::PI;
        let mut d = [0.0f32; MAX_STRETCHES];
        let mut n = 0;
        let v = self.stretches();
        for (j, b) in v.iter().enumerate() {
            let travel = |s: &Stretch| (s.wheels_mm[0] + s.wheels_mm[1]) / 2.0;
            let pair = v[..j].iter().rev().find_map(|a| {
                let dist = travel(b) - travel(a);
                if dist < min_lap_mm {
                    return None;
                }
                let turned = b.wall_end - a.wall_end - kappa * dist / 1000.0;
                let k = libm::roundf(turned / two_pi);
                (k != 0.0 && libm::fabsf(turned - k * two_pi) < tolerance_rad).then_some((a, k))
            });
            let Some((a, k)) = pair else { continue };
            let (dl, dr) = (
                b.wheels_mm[0] - a.wheels_mm[0],
                b.wheels_mm[1] - a.wheels_mm[1],
            );
            let turn = k * two_pi + b.phi_end - a.phi_end;
            d[n] = 2.0 * (ratio * dr - dl) / ((1.0 + ratio) * turn);
            n += 1;
        }
        let v = &mut d[..n];
        v.sort_unstable_by(f32::total_cmp);
        match n {
            0 => None,
            n if n % 2 == 1 => Some(v[n / 2]),
            n => Some((v[n / 2 - 1] + v[n / 2]) / 2.0),
        }
    }
}

/// The wheel ratio (right over left wheel travel per pulse) from a drift rate along straight
/// walls, radians a metre, for a belief using wheel distance `b_mm` (module text).
pub fn ratio_from_kappa(kappa: f32, b_mm: f32) -> f32 {
    let k = kappa * b_mm / 1000.0;
    (1.0 - k / 2.0) / (1.0 + k / 2.0)
}

/// Gaussian elimination with partial pivoting; `None` for a singular system.
fn solve(mut a: [[f64; K]; K], mut b: [f64; K]) -> Option<[f64; K]> {
    for col in 0..K {
        let piv =
            (col..K).max_by(|&i, &j| libm::fabs(a[i][col]).total_cmp(&libm::fabs(a[j][col])))?;
        if libm::fabs(a[piv][col]) < 1e-12 {
            return None;
        }
        a.swap(col, piv);
        b.swap(col, piv);
        let pivot_row = a[col];
        for row in col + 1..K {
            let f = a[row][col] / pivot_row[col];
            for (x, p) in a[row].iter_mut().zip(&pivot_row).skip(col) {
                *x -= f * p;
            }
            b[row] -= f * b[col];
        }
    }
    let mut x = [0.0; K];
    for row in (0..K).rev() {
        let s: f64 = (row + 1..K).map(|k| a[row][k] * x[k]).sum();
        x[row] = (b[row] - s) / a[row][row];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A robot wobbling along a straight wall: true heading phi(s) = 0.02 sin(s / 60 mm), the
    /// distance its integral, the reading a convex curve of the distance with an unknown
    /// gain; the belief drifts at kappa and sees the wobble 3 % too large.
    #[test]
    fn the_drift_rate_comes_out_of_a_wobbling_stretch() {
        let kappa = -0.25f32;
        let mut w = StraightWalls::new(StretchParams::default());
        let mut y = 24.0f64; // mm from the wall
        for i in 0..400 {
            let s = i as f32 * 2.0;
            let phi = 0.02 * libm::sinf(s / 60.0);
            y += f64::from(phi) * 2.0;
            let r = 1.1 * 1023.0 * libm::pow((33.0 - y) / 16.0, 1.5) + 5.0;
            let heading = 1.0 + kappa * s / 1000.0 + 1.03 * phi;
            w.observe([s, s], heading, r as u16, true);
        }
        w.end();
        let k = w.kappa(100.0).expect("a stretch");
        assert!((k - kappa).abs() < 3e-3, "{k} {:?}", w.stretches());
        let ratio = ratio_from_kappa(k, 52.0);
        assert!((ratio - ratio_from_kappa(kappa, 52.0)).abs() < 2e-4);
    }

    #[test]
    fn a_corner_ends_the_stretch_and_short_ones_count_for_nothing() {
        let mut w = StraightWalls::new(StretchParams::default());
        for i in 0..50 {
            w.observe([i as f32 * 2.0; 2], 0.0, 450, true);
        }
        // Turned by a corner: the 98 mm before it are too short.
        w.observe([100.0; 2], 1.5, 450, true);
        w.end();
        assert_eq!(w.stretches().len(), 0);
        assert_eq!(w.kappa(1.0), None);
    }
}
