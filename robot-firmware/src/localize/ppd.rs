//! The position probability distribution (PPD) as a fixed set of wheel-bias hypotheses.
//!
//! Layer: the model under [`super::Spps`]. seed 003 §2.3 models odometry error as a speed
//! error per wheel that is Gaussian but CONSTANT over a trajectory segment,
//! `V = *V + dV`, `p(V) = N(*V, sigma = dV/2)` (Eq 2-7), so the set of poses the robot may
//! be at is the image of the (V_L, V_R) distribution under the motion: a thin "banana".
//! The thesis could not compute that density on the Khepera and "approached [it] by several
//! sample points" updated at 10 Hz (§2.7 footnote); here each [`Sample`] is one hypothesis
//! (relative bias of each wheel) carrying the pose it implies, driven by the same encoder
//! counts as odometry. Sampling the bias prior (or sweeping it on a lattice, as the thesis's
//! Mathematica listing, App 5.3, does) reproduces the banana.
//!
//! Invariants: a sample's wheel travel per cycle is `n * mm_per_pulse * (1 + bias)`; a sample
//! with zero bias follows [`crate::odometry::integrate`] (to f32 rounding). Headings are
//! wrapped to `[-pi, pi]`. Nothing here fails or panics; non-finite parameters give
//! non-finite poses, which the caller's parameters must prevent.

use core::f32::consts::PI;

use crate::behaviour::XorShift32;
use crate::odometry::{wrap_angle, OdometryParams, Point, Pose};

/// One PPD hypothesis: the pose the robot would have if its wheels moved `1 + bias` times
/// what the encoders say.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Sample {
    /// Pose implied by the hypothesis, metres and radians.
    pub pose: Pose,
    /// Relative travel error of the left wheel (0.01 = 1 % further than counted).
    pub bias_left: f32,
    /// Relative travel error of the right wheel.
    pub bias_right: f32,
}

/// Bytes of one sample (five f32).
pub const SAMPLE_BYTES: usize = core::mem::size_of::<Sample>();

impl Sample {
    /// A hypothesis at `pose` with the given wheel biases.
    pub const fn new(pose: Pose, bias_left: f32, bias_right: f32) -> Self {
        Self {
            pose,
            bias_left,
            bias_right,
        }
    }

    /// Moves the sample by one cycle's encoder counts under its own wheel biases.
    pub fn step(&mut self, n_l: i32, n_r: i32, p: &OdometryParams) {
        let sl = n_l as f32 * p.mm_per_pulse * (1.0 + self.bias_left);
        let sr = n_r as f32 * p.mm_per_pulse * (1.0 + self.bias_right);
        self.pose = arc(self.pose, sl, sr, p.wheel_distance_mm);
    }

    /// Where a sensor `offset_m` ahead of the axle centre is, metres.
    pub fn sensor(&self, offset_m: f32) -> Point {
        sensor_point(self.pose, offset_m)
    }
}

/// Position of a floor sensor `offset_m` ahead of the axle centre of `pose`.
pub fn sensor_point(pose: Pose, offset_m: f32) -> Point {
    if offset_m == 0.0 {
        return pose.point();
    }
    Point::new(
        pose.x + offset_m * libm::cosf(pose.heading),
        pose.y + offset_m * libm::sinf(pose.heading),
    )
}

/// Exact constant-curvature move by wheel travels `sl`, `sr` (mm) with wheel distance `d`
/// (mm): the chord `ds * sinc(dθ/2)` along the mid-arc heading (seed 003 App 5.1 arc update,
/// written without the straight-line special case).
pub fn arc(pose: Pose, sl_mm: f32, sr_mm: f32, d_mm: f32) -> Pose {
    let ds = (sl_mm + sr_mm) / 2.0;
    let dth = (sr_mm - sl_mm) / d_mm;
    let half = dth / 2.0;
    // sin(u)/u; the series avoids 0/0 and f32 cancellation for small turns.
    let sinc = if libm::fabsf(half) < 1e-3 {
        1.0 - half * half / 6.0
    } else {
        libm::sinf(half) / half
    };
    let chord_m = ds * sinc * 1e-3;
    let mid = pose.heading + half;
    Pose {
        x: pose.x + chord_m * libm::cosf(mid),
        y: pose.y + chord_m * libm::sinf(mid),
        heading: wrap_angle(pose.heading + dth),
    }
}

/// One standard normal draw (Box-Muller; one of the pair is discarded to keep no state).
pub fn gauss(rng: &mut XorShift32) -> f32 {
    // 24-bit uniforms in (0, 1]: never 0, so ln is finite.
    let u1 = ((rng.next_u32() >> 8) + 1) as f32 / 16_777_216.0;
    let u2 = (rng.next_u32() >> 8) as f32 / 16_777_216.0;
    libm::sqrtf(-2.0 * libm::logf(u1)) * libm::cosf(2.0 * PI * u2)
}

/// How the wheel-bias hypotheses are drawn when the PPD is (re)seeded.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Prior {
    /// `N(0, sigma)` per wheel: seed 003 Eq 2-7's density.
    Gaussian,
    /// Uniform in `±2 sigma = ±dV` per wheel: the range the thesis sweeps to draw the PPD
    /// (App 5.3). It puts more samples at the corners (one wheel fast, the other slow), where
    /// the heading drifts fastest, so a finite set still covers the worst robots.
    #[default]
    Uniform,
}

/// Fills `samples` at `pose` with biases drawn from `prior` with the given `sigma` per wheel
/// (seed 003 Eq 2-7: sigma = dV/2).
pub fn seed_prior(
    samples: &mut [Sample],
    pose: Pose,
    prior: Prior,
    sigma: f32,
    rng: &mut XorShift32,
) {
    for s in samples.iter_mut() {
        let (l, r) = match prior {
            Prior::Gaussian => (gauss(rng), gauss(rng)),
            Prior::Uniform => (2.0 * symmetric(rng), 2.0 * symmetric(rng)),
        };
        *s = Sample::new(pose, sigma * l, sigma * r);
    }
}

/// Uniform in `[-1, 1)`.
fn symmetric(rng: &mut XorShift32) -> f32 {
    2.0 * ((rng.next_u32() >> 8) as f32 / 16_777_216.0) - 1.0
}

/// Fills `samples` at `pose` with the thesis's sweep (App 5.3: each wheel from `-dv` to
/// `+dv` in `side - 1` steps, all pairs): a `side x side` lattice, `side = floor(sqrt(len))`,
/// row-major, left bias varying slowest; samples beyond `side^2` get zero bias.
pub fn seed_lattice(samples: &mut [Sample], pose: Pose, dv: f32) {
    let side = isqrt(samples.len());
    let step = if side > 1 {
        2.0 * dv / (side - 1) as f32
    } else {
        0.0
    };
    let at = |i: usize| if side > 1 { -dv + i as f32 * step } else { 0.0 };
    for (k, s) in samples.iter_mut().enumerate() {
        *s = if k < side * side {
            Sample::new(pose, at(k / side), at(k % side))
        } else {
            Sample::new(pose, 0.0, 0.0)
        };
    }
}

fn isqrt(n: usize) -> usize {
    let mut r = 0usize;
    while (r + 1).saturating_mul(r + 1) <= n {
        r += 1;
    }
    r
}

/// Mean pose of `samples` (heading as the mean offset from the first sample's, so the wrap
/// at ±pi does not matter for a PPD narrower than a half turn); `None` if empty.
pub fn mean_pose(samples: &[Sample]) -> Option<Pose> {
    let first = samples.first()?.pose;
    let (mut x, mut y, mut dh) = (0.0f32, 0.0f32, 0.0f32);
    for s in samples {
        x += s.pose.x;
        y += s.pose.y;
        dh += wrap_angle(s.pose.heading - first.heading);
    }
    let n = samples.len() as f32;
    Some(Pose::new(x / n, y / n, first.heading + dh / n))
}

/// Root-mean-square distance of the samples from their mean position, metres: the PPD's
/// size (seed 003 §2.6.4: "the average size of the PPD stays constant").
pub fn rms_size(samples: &[Sample]) -> f32 {
    let Some(m) = mean_pose(samples) else {
        return 0.0;
    };
    let mut acc = 0.0f32;
    for s in samples {
        let (dx, dy) = (s.pose.x - m.x, s.pose.y - m.y);
        acc += dx * dx + dy * dy;
    }
    libm::sqrtf(acc / samples.len() as f32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::odometry::integrate;

    #[test]
    fn a_zero_bias_sample_follows_odometry() {
        let p = OdometryParams::default();
        let mut s = Sample::new(Pose::new(0.1, -0.2, 0.3), 0.0, 0.0);
        let mut o = s.pose;
        for k in 0..500 {
            let (l, r) = ((k * 7) % 90 - 20, (k * 13) % 110 - 30);
            s.step(l, r, &p);
            o = integrate(o, l, r, &p);
        }
        assert!(s.pose.point().distance_to(o.point()) < 2e-5, "{s:?} {o:?}");
        assert!(wrap_angle(s.pose.heading - o.heading).abs() < 1e-4);
    }

    #[test]
    fn a_faster_right_wheel_turns_left() {
        let p = OdometryParams::default();
        let mut s = Sample::new(Pose::default(), 0.0, 0.01);
        for _ in 0..100 {
            s.step(125, 125, &p);
        }
        // 1 m, 1 % more on the right: 10 mm / 52 mm of turn, to the left (+y).
        assert!((s.pose.heading - 10.0 / 52.0).abs() < 1e-4, "{s:?}");
        assert!(s.pose.y > 0.09 && s.pose.y < 0.1, "{s:?}");
    }

    #[test]
    fn the_lattice_sweeps_each_wheel_between_the_limits() {
        let mut s = [Sample::default(); 123];
        seed_lattice(&mut s, Pose::default(), 0.01);
        assert_eq!((s[0].bias_left, s[0].bias_right), (-0.01, -0.01));
        assert!((s[120].bias_left - 0.01).abs() < 1e-7 && (s[120].bias_right - 0.01).abs() < 1e-7);
        assert!((s[60].bias_left).abs() < 1e-7 && s[60].bias_right.abs() < 1e-7);
        assert_eq!((s[122].bias_left, s[122].bias_right), (0.0, 0.0));
    }

    #[test]
    fn gauss_has_unit_variance() {
        let mut rng = XorShift32::new(11);
        let n = 20_000;
        let (mut m, mut v) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let z = f64::from(gauss(&mut rng));
            m += z;
            v += z * z;
        }
        let (m, v) = (m / n as f64, v / n as f64);
        assert!(m.abs() < 0.03 && (v - 1.0).abs() < 0.04, "{m} {v}");
    }
}
