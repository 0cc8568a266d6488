//! How sure the robot is of its position, and how much a landmark match should move it.
//!
//! The thesis resets the odometry to the stored position on every match (§3.15.1). A stored
//! position is only as good as the robot's estimate when the landmark was made: landmarks made
//! late, after some drift or after an earlier imprecise reset, carry that error, and resetting
//! to them walks the error like a random walk (measured in the seed 003 ch. 3 scenario: with
//! perfect wheels 100-200 resets still took the error to 0.6-3.5 diameters). So every estimate
//! carries a variance, from what the robot knows of its own sensors (the compass's noise, the
//! wheels' speed error; both are sensor specifications, not measurements of this run):
//! - between matches the variance grows with the distance driven: the compass's white noise
//!   moves the position sideways by ds x sigma_compass each step (independent steps), and the
//!   wheels' common speed bias stretches the displacement since the last fix by the mean bias;
//! - a landmark is stored with the variance of the estimate that made it;
//! - on a match the position moves by the gain k = P / (P + P_landmark + R) of the way to the
//!   stored position, R being the variance of a kernel's place about the landmark's (a kernel
//!   fires a little earlier or later along the track). k = 1 is the thesis's reset; an old
//!   landmark made with a fresh estimate pulls hard, a late one made with a drifted estimate
//!   pulls little.
//!
//! Variances are per axis, metres squared. `no_std`, heap-free, no state beyond a few floats.

/// The robot's sensor specifications the variance model needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FusionParams {
    /// Compass noise, radians (one sigma, white, per reading).
    pub compass_sigma_rad: f32,
    /// Sigma of the mean of the two wheels' constant relative speed errors (seed 003 §2.3.3:
    /// sigma 0.5 % a wheel, so 0.5 % / sqrt 2 for their mean).
    pub mean_bias_sigma: f32,
    /// Sigma of a kernel's place about its landmark's, metres.
    pub match_sigma_m: f32,
}

/// The position variance of the robot's estimate since its last fix.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Uncertainty {
    /// Variance right after the last fix (the start: 0, the start pose is known).
    at_fix: f32,
    /// Accumulated white (compass) variance since then.
    white: f32,
    /// Odometric position at the last fix.
    fix: (f32, f32),
}

impl Uncertainty {
    /// Certain at `(x, y)` (the start pose is known).
    pub fn at(x: f32, y: f32) -> Self {
        Self {
            at_fix: 0.0,
            white: 0.0,
            fix: (x, y),
        }
    }

    /// The position variance at odometric position `(x, y)`.
    pub fn variance(&self, (x, y): (f32, f32), p: &FusionParams) -> f32 {
        // The common bias scales the displacement since the fix (not the path: loops cancel).
        let along = libm::hypotf(x - self.fix.0, y - self.fix.1) * p.mean_bias_sigma;
        self.at_fix + self.white + along * along
    }

    /// One step of `ds` metres with the heading from the compass.
    pub fn advance(&mut self, ds: f32, p: &FusionParams) {
        let side = ds * p.compass_sigma_rad;
        self.white += side * side;
    }

    /// A match with a landmark stored with variance `landmark_var`, seen while the robot was at
    /// odometric position `at` (the kernel's time). Returns the gain: the caller moves its
    /// position by gain x (stored - kernel-time position). The variance becomes the fused one
    /// and the fix moves to the corrected position `fixed`.
    pub fn fuse(
        &mut self,
        at: (f32, f32),
        fixed: impl FnOnce(f32) -> (f32, f32),
        landmark_var: f32,
        p: &FusionParams,
    ) -> f32 {
        let own = self.variance(at, p);
        let k = gain(own, landmark_var, p);
        self.at_fix = (1.0 - k) * own;
        self.white = 0.0;
        self.fix = fixed(k);
        k
    }
}

/// How far (0..=1) an estimate of variance `own` moves towards a landmark stored with
/// variance `other`.
pub fn gain(own: f32, other: f32, p: &FusionParams) -> f32 {
    let r = p.match_sigma_m * p.match_sigma_m;
    let total = own + other + r;
    if total > 0.0 && total.is_finite() {
        (own / total).clamp(0.0, 1.0)
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p() -> FusionParams {
        FusionParams {
            compass_sigma_rad: 0.035,
            mean_bias_sigma: 0.0035,
            match_sigma_m: 0.008,
        }
    }

    #[test]
    fn variance_grows_with_distance_and_a_match_shrinks_it() {
        let mut u = Uncertainty::at(0.0, 0.0);
        assert_eq!(u.variance((0.0, 0.0), &p()), 0.0);
        for _ in 0..1000 {
            u.advance(0.0024, &p());
        }
        let v = u.variance((1.0, 0.0), &p());
        // 1000 x (2.4 mm x 0.035)^2 + (1 m x 0.35 %)^2.
        let want = 1000.0 * (0.0024f32 * 0.035).powi(2) + 0.0035f32.powi(2);
        assert!((v - want).abs() < 1e-9, "{v} {want}");
        // A landmark made with a fresh estimate (variance 0) pulls almost all the way.
        let k = u.fuse((1.0, 0.0), |k| (1.0 - k, 0.0), 0.0, &p());
        let r = 0.008f32 * 0.008;
        assert!((k - v / (v + r)).abs() < 1e-6, "{k}");
        let after = u.variance((1.0 - k, 0.0), &p());
        assert!((after - (1.0 - k) * v).abs() < 1e-9 && after < v, "{after}");
    }

    #[test]
    fn a_landmark_made_uncertain_pulls_little() {
        let own = 1e-4;
        let fresh = gain(own, 0.0, &p());
        let late = gain(own, 1e-3, &p());
        assert!(fresh > 0.5 && late < 0.1, "{fresh} {late}");
        // Nothing known (zero variances, zero R): the thesis's reset.
        let exact = FusionParams {
            match_sigma_m: 0.0,
            ..p()
        };
        assert_eq!(gain(0.0, 0.0, &exact), 1.0);
    }
}
