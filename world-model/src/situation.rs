//! Pre-processing (§4.2.1): raw readings to a situation vector.
//!
//! A situation is `[light_0 .. light_{L-1}, touch_0 .. touch_{T-1}, x, y]`, stored unweighted;
//! the weights enter the distance only ([`Weights`]), so a cell's position part stays in metres
//! for the spatial index. Readings arrive in the robot's frame (sensor `i` looks at
//! `i * 360/n` degrees anticlockwise from the robot's forward axis) and are rotated into the
//! world frame by the continuous heading estimate, interpolating linearly between sensors
//! (§4.2.4: "the incoming sensor-readings are interpolated linearly and rotated").

use std::f64::consts::TAU;

use crate::params::Params;

/// A pose: metres and radians anticlockwise from +x.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Pose {
    /// x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
    /// Heading, radians.
    pub heading: f64,
}

/// Per-component weights of the situation distance.
#[derive(Clone, Debug)]
pub struct Weights(pub Vec<f64>);

impl Weights {
    /// The weights `params` give each component (squared, ready for the distance).
    pub fn new(p: &Params) -> Self {
        let mut w = Vec::with_capacity(p.lights + p.touches + 2);
        w.extend(std::iter::repeat_n(p.w_light * p.w_light, p.lights));
        w.extend(std::iter::repeat_n(p.w_touch * p.w_touch, p.touches));
        w.extend([p.w_pos * p.w_pos; 2]);
        Weights(w)
    }

    /// [`Weights::distance`] over the first `n` components.
    pub fn distance_prefix(&self, a: &[f64], b: &[f64], n: usize) -> f64 {
        self.0
            .iter()
            .zip(a.iter().zip(b))
            .take(n)
            .map(|(w, (x, y))| w * (x - y) * (x - y))
            .sum::<f64>()
            .sqrt()
    }

    /// Weighted Euclidean distance between two situations of the same layout.
    pub fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        self.0
            .iter()
            .zip(a.iter().zip(b))
            .map(|(w, (x, y))| w * (x - y) * (x - y))
            .sum::<f64>()
            .sqrt()
    }
}

/// `readings` (robot frame, evenly spaced) rotated into the world frame for `heading`: the
/// world-frame value at direction `j * 360/n` is the robot's reading at `j * 360/n - heading`,
/// interpolated between the two nearest sensors.
pub fn rotate_to_world(readings: &[f64], heading: f64, out: &mut Vec<f64>) {
    out.clear();
    let n = readings.len();
    if n == 0 {
        return;
    }
    let step = TAU / n as f64;
    for j in 0..n {
        let rel = (j as f64 * step - heading).rem_euclid(TAU) / step;
        let i0 = (rel.floor() as usize) % n;
        let i1 = (i0 + 1) % n;
        let t = rel - rel.floor();
        out.push(readings[i0] * (1.0 - t) + readings[i1] * t);
    }
}

/// Binary touches smoothed by a Gaussian of `sigma` sensor spacings around the ring, each
/// value clipped to 1 (so a single whisker and a wall of them both read at most 1).
pub fn smooth_touch(touch: &[bool], sigma: f64, out: &mut Vec<f64>) {
    out.clear();
    let n = touch.len();
    for j in 0..n {
        let mut s = 0.0;
        for (i, &t) in touch.iter().enumerate() {
            if t {
                let d = i.abs_diff(j).min(n - i.abs_diff(j)) as f64;
                s += if sigma > 0.0 {
                    (-(d * d) / (2.0 * sigma * sigma)).exp()
                } else if d == 0.0 {
                    1.0
                } else {
                    0.0
                };
            }
        }
        out.push(s.min(1.0));
    }
}

/// Build the situation for readings taken at the internal pose `at` into `out`.
pub fn situation(p: &Params, light: &[f64], touch: &[bool], at: Pose, out: &mut Vec<f64>) {
    let mut tmp = Vec::with_capacity(p.touches.max(p.lights));
    out.clear();
    rotate_to_world(light, at.heading, &mut tmp);
    out.extend_from_slice(&tmp);
    let mut smooth = Vec::with_capacity(p.touches);
    smooth_touch(touch, p.touch_sigma, &mut smooth);
    rotate_to_world(&smooth, at.heading, &mut tmp);
    out.extend_from_slice(&tmp);
    out.extend([at.x, at.y]);
}

/// Orientation (modulo pi) of the principal axis of a ring of readings read as polar points
/// (eq. 10: reading `l_i` at angle `i * 360/s`), with the ratio of the larger to the smaller
/// second moment; `None` when the readings are all zero. A total-least-squares axis rather than
/// an ordinary regression, so the estimate turns exactly with the pattern.
pub fn principal_axis(readings: &[f64]) -> Option<(f64, f64)> {
    let n = readings.len();
    if n == 0 {
        return None;
    }
    let step = TAU / n as f64;
    let pts = readings
        .iter()
        .enumerate()
        .map(|(i, &l)| (l * (i as f64 * step).cos(), l * (i as f64 * step).sin()));
    let (mut sx, mut sy) = (0.0, 0.0);
    for (x, y) in pts.clone() {
        sx += x;
        sy += y;
    }
    let (mx, my) = (sx / n as f64, sy / n as f64);
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for (x, y) in pts {
        sxx += (x - mx) * (x - mx);
        syy += (y - my) * (y - my);
        sxy += (x - mx) * (y - my);
    }
    if sxx + syy <= 1e-12 {
        return None;
    }
    let angle = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let mean = 0.5 * (sxx + syy);
    let dev = (0.25 * (sxx - syy) * (sxx - syy) + sxy * sxy).sqrt();
    let ratio = if mean - dev <= 1e-12 {
        f64::INFINITY
    } else {
        (mean + dev) / (mean - dev)
    };
    Some((angle, ratio))
}

/// Why [`ring_shift`] found no turn, in the order it looks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShiftMiss {
    /// Nothing to align: the current ring is empty or flat (variance below 1e-6), or the two
    /// rings differ in length.
    Flat,
    /// The best turn lies at the edge of the +-`max` search: no minimum within it (a heading
    /// error beyond the search).
    NoTurn,
    /// The best turn's squared residual exceeds `max_residual` times the ring's variance: the
    /// stored ring is another place's pattern, not a turned copy of this one.
    Residual,
}

/// The rotation (radians, within +-`max`) by which ring `cur` is turned against ring `stored`:
/// the shift minimising the squared difference, searched in quarter-sensor steps and refined
/// by a parabola through the best step and its neighbours. The error says which check found
/// none ([`ShiftMiss`]); the best turn does not depend on `max_residual`, so a
/// [`ShiftMiss::Residual`] at one `max_residual` is a turn at a larger one.
pub fn ring_shift(
    cur: &[f64],
    stored: &[f64],
    max: f64,
    max_residual: f64,
) -> Result<f64, ShiftMiss> {
    let n = cur.len();
    if n == 0 || stored.len() != n {
        return Err(ShiftMiss::Flat);
    }
    let mean = cur.iter().sum::<f64>() / n as f64;
    let var = cur.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n as f64;
    if var < 1e-6 {
        return Err(ShiftMiss::Flat);
    }
    let step = TAU / n as f64 / 4.0;
    let k = (max / step).floor() as i64;
    let mut turned = Vec::with_capacity(n);
    let mut cost = |s: f64| {
        // Turning `cur` back by s: its value at direction j is cur at j + s.
        rotate_to_world(cur, -s, &mut turned);
        turned
            .iter()
            .zip(stored)
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
    };
    let costs: Vec<(f64, f64)> = (-k..=k)
        .map(|i| (i as f64 * step, cost(i as f64 * step)))
        .collect();
    let (bi, _) = costs
        .iter()
        .enumerate()
        .min_by(|a, b| a.1 .1.total_cmp(&b.1 .1))
        .ok_or(ShiftMiss::NoTurn)?;
    // A minimum at the edge of the search is no minimum; a poor best fit is another place's
    // pattern (a lamp in shadow, a different spot), not a turned copy of this one.
    if bi == 0 || bi + 1 == costs.len() {
        return Err(ShiftMiss::NoTurn);
    }
    if costs[bi].1 > max_residual * var * n as f64 {
        return Err(ShiftMiss::Residual);
    }
    let mut best = costs[bi].0;
    {
        let (l, c, r) = (costs[bi - 1].1, costs[bi].1, costs[bi + 1].1);
        let den = l - 2.0 * c + r;
        if den > 1e-12 {
            best += 0.5 * (l - r) / den * step;
        }
    }
    Ok(best)
}

/// `a - b` for axes (modulo pi), in (-pi/2, pi/2].
pub fn axis_difference(a: f64, b: f64) -> f64 {
    let half = std::f64::consts::FRAC_PI_2;
    let d = (a - b).rem_euclid(std::f64::consts::PI);
    if d > half {
        d - std::f64::consts::PI
    } else {
        d
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_moves_a_reading_to_its_world_direction() {
        let mut r = vec![0.0; 24];
        r[0] = 1.0; // straight ahead
        let mut out = Vec::new();
        // Facing 90 degrees: the forward reading belongs to world direction 6 (90 degrees).
        rotate_to_world(&r, TAU / 4.0, &mut out);
        assert!((out[6] - 1.0).abs() < 1e-9, "{out:?}");
        assert!(out[0].abs() < 1e-9);
        // Half a sensor spacing: split between two directions.
        rotate_to_world(&r, TAU / 48.0, &mut out);
        assert!(
            (out[0] - 0.5).abs() < 1e-9 && (out[1] - 0.5).abs() < 1e-9,
            "{out:?}"
        );
    }

    #[test]
    fn the_principal_axis_turns_with_the_pattern() {
        let base: Vec<f64> = (0..24)
            .map(|i| 1.0 + 0.8 * ((i as f64) * TAU / 24.0 - 0.3).cos().powi(2))
            .collect();
        let (a0, ratio) = principal_axis(&base).expect("pattern");
        assert!(ratio > 1.15);
        let mut rotated = Vec::new();
        rotate_to_world(&base, 0.5, &mut rotated);
        let (a1, _) = principal_axis(&rotated).expect("pattern");
        assert!((axis_difference(a1, a0) - 0.5).abs() < 0.02, "{a0} {a1}");
    }

    #[test]
    fn the_ring_shift_finds_the_turn() {
        let base: Vec<f64> = (0..24)
            .map(|i| {
                (-(((i as f64) - 7.0) / 1.5).powi(2)).exp()
                    + 0.5 * (-(((i as f64) - 16.0) / 2.0).powi(2)).exp()
            })
            .collect();
        let mut turned = Vec::new();
        rotate_to_world(&base, 0.2, &mut turned);
        let s = ring_shift(&turned, &base, 0.6, 0.25).expect("pattern");
        assert!((s - 0.2).abs() < 0.03, "{s}");
    }

    /// Each way of finding no turn says which it is.
    #[test]
    fn the_ring_shift_says_why_it_found_no_turn() {
        let base: Vec<f64> = (0..24)
            .map(|i| (-(((i as f64) - 7.0) / 1.5).powi(2)).exp())
            .collect();
        let flat = vec![0.4; 24];
        assert_eq!(ring_shift(&flat, &base, 0.6, 0.25), Err(ShiftMiss::Flat));
        assert_eq!(
            ring_shift(&base, &base[..20], 0.6, 0.25),
            Err(ShiftMiss::Flat)
        );
        assert_eq!(ring_shift(&[], &[], 0.6, 0.25), Err(ShiftMiss::Flat));
        // Turned by 1 radian, searched within 0.3: the best is the search's edge.
        let mut turned = Vec::new();
        rotate_to_world(&base, 1.0, &mut turned);
        assert_eq!(
            ring_shift(&turned, &base, 0.3, 0.25),
            Err(ShiftMiss::NoTurn)
        );
        // Another place's ring: the peak plus a second lamp; the best turn is (about: the
        // interpolation blurs the left-over lamp at a fractional turn) no turn, with the
        // second lamp left over.
        let other: Vec<f64> = base
            .iter()
            .enumerate()
            .map(|(i, v)| v + (-(((i as f64) - 18.0) / 1.5).powi(2)).exp())
            .collect();
        assert_eq!(
            ring_shift(&other, &base, 0.6, 0.25),
            Err(ShiftMiss::Residual)
        );
        let s = ring_shift(&other, &base, 0.6, f64::INFINITY).expect("any residual");
        assert!(s.abs() < 0.1, "{s}");
    }

    #[test]
    fn touches_are_smoothed_and_clipped() {
        let mut t = vec![false; 24];
        t[0] = true;
        t[1] = true;
        let mut out = Vec::new();
        smooth_touch(&t, 1.0, &mut out);
        assert_eq!(out[0], 1.0);
        assert!(out[23] > 0.5 && out[23] < 1.0);
        assert!(out[12] < 1e-6);
    }
}
