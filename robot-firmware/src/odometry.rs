//! Khepera odometry from wheel encoder deltas (seed 000 §3).
//!
//! Layer: pure pose arithmetic under the control loop. Each control cycle hands in the integer
//! encoder deltas `(nL, nR)` since the previous cycle; [`integrate`] moves the pose with the
//! paper's two cases (Eqs 1-3 for `|nL| == |nR|`, the constant-curvature arc of Eqs 4-10
//! otherwise, with the digest's fix to Eqs 4-5), and [`Odometry`] keeps the pose, the total
//! signed rotation and a pose covariance. No I/O, no clock, no heap.
//!
//! Invariants: poses are in metres and radians, heading counter-clockwise from +x and wrapped to
//! `[-pi, pi]`; the covariance stays symmetric positive semi-definite. Nothing here can fail or
//! panic: every `(nL, nR)` pair (zero, equal, opposite, negative, one wheel stopped) has a
//! defined result. Parameters that are not finite or not positive produce non-finite poses,
//! which is the caller's (profile's) responsibility to prevent.
//!
//! f32 is deliberate: the firmware target is a small MCU with (at best) a single-precision FPU.
//! Per-cycle displacements are millimetres and headings are wrapped, so the worst rounding is
//! about 1e-7 m per cycle, far below the 1-pulse error (0.08 mm) of §3.2.

use core::f32::consts::PI;

/// A point in the arena, metres.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Point {
    /// Metres along the arena's x axis.
    pub x: f32,
    /// Metres along the arena's y axis.
    pub y: f32,
}

impl Point {
    /// Makes a point from metres.
    pub const fn new(x: f32, y: f32) -> Self {
        Self { x, y }
    }

    /// Euclidean distance to `other`, metres.
    pub fn distance_to(self, other: Point) -> f32 {
        libm::hypotf(other.x - self.x, other.y - self.y)
    }

    /// Direction from `self` towards `other`, radians counter-clockwise from +x.
    pub fn bearing_to(self, other: Point) -> f32 {
        libm::atan2f(other.y - self.y, other.x - self.x)
    }
}

/// A robot pose: position in metres, heading in radians counter-clockwise from +x.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Pose {
    /// Metres.
    pub x: f32,
    /// Metres.
    pub y: f32,
    /// Radians, counter-clockwise from +x, in `[-pi, pi]`.
    pub heading: f32,
}

impl Pose {
    /// Makes a pose; the heading is wrapped to `[-pi, pi]`.
    pub fn new(x: f32, y: f32, heading: f32) -> Self {
        Self {
            x,
            y,
            heading: wrap_angle(heading),
        }
    }

    /// The position part of the pose.
    pub const fn point(self) -> Point {
        Point {
            x: self.x,
            y: self.y,
        }
    }
}

/// Wraps an angle to `[-pi, pi]`.
pub fn wrap_angle(a: f32) -> f32 {
    // remainder rounds the quotient to nearest, so the result lies in [-pi, pi].
    libm::remainderf(a, 2.0 * PI)
}

/// Encoder delta between two raw counter readings, robust to counter wrap-around.
pub const fn encoder_delta(previous: i32, now: i32) -> i32 {
    now.wrapping_sub(previous)
}

/// Odometry parameters of one robot (Khepera defaults, seed 000 §3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OdometryParams {
    /// Wheel distance d, millimetres. seed 000 §3.1: d = 52 mm.
    pub wheel_distance_mm: f32,
    /// Advancement per encoder pulse Δl, millimetres. seed 000 §3.1: Δl = 0.08 mm.
    pub mm_per_pulse: f32,
    /// Standard deviation of each encoder's per-cycle count error, pulses, used by the
    /// covariance model. seed 000 §3.2 assumes an error of 1 pulse per encoder and cycle
    /// (`F_nL = F_nR = 1`); it uses it as a worst-case bound, we use it as 1 sigma.
    pub encoder_sigma_pulses: f32,
    /// The right wheel's travel per pulse over the left's, minus 1, in parts per million
    /// (UMBmark's E_d - 1, Borenstein & Feng 1996; ppm so the link's f32 and a parameter
    /// file's decimals keep it exact): 0 = equal wheels. Not in seed 000, which takes the
    /// wheels as equal; measured by [`crate::odometry_calibration`]. With r = 1 + ppm / 1e6
    /// the mean of the two stays `mm_per_pulse`: the left wheel's is `2 / (1 + r)` times it,
    /// the right's `2 r / (1 + r)`.
    pub wheel_ratio_error_ppm: f32,
}

impl Default for OdometryParams {
    fn default() -> Self {
        Self {
            // seed 000 §3.1: d = 52 mm
            wheel_distance_mm: 52.0,
            // seed 000 §3.1: Δl = 0.08 mm per pulse
            mm_per_pulse: 0.08,
            // seed 000 §3.2: F_nL = F_nR = 1 pulse per update cycle
            encoder_sigma_pulses: 1.0,
            // Equal wheels until calibrated.
            wheel_ratio_error_ppm: 0.0,
        }
    }
}

/// Advances `pose` by one cycle's encoder deltas (seed 000 §3.1, Eqs 1-10).
pub fn integrate(pose: Pose, n_l: i32, n_r: i32, p: &OdometryParams) -> Pose {
    integrate_with_turn(pose, n_l, n_r, p).0
}

/// [`integrate`], also returning the cycle's signed, unwrapped heading change (Eq 1 or 10).
pub fn integrate_with_turn(pose: Pose, n_l: i32, n_r: i32, p: &OdometryParams) -> (Pose, f32) {
    let dl = p.mm_per_pulse;
    let d = p.wheel_distance_mm;
    // Widen before summing so extreme counts cannot overflow.
    let (nl, nr) = (i64::from(n_l), i64::from(n_r));
    if nl.abs() == nr.abs() {
        // Case 1, Eqs 1-3: straight line (nL = nR) or turn on the spot (nL = -nR). The paper
        // uses the new heading α_R in cos/sin; either choice is exact here because one of the
        // rotation and the translation is zero.
        let turn = (nr - nl) as f32 * dl / d;
        let heading = pose.heading + turn;
        let s_m = (nr + nl) as f32 / 2.0 * dl * 1e-3;
        let moved = Pose {
            x: pose.x + s_m * libm::cosf(heading),
            y: pose.y + s_m * libm::sinf(heading),
            heading: wrap_angle(heading),
        };
        return (moved, turn);
    }
    // Case 2, Eqs 4-10 with the digest's fix: Δα = |nR - nL| Δl/d and
    // r = |(nR + nL)/(nR - nL)| d/2. (Printed Eq 4 gives Δα = 0 whenever nR = 0.)
    // nR - nL != 0 and nR + nL != 0 here, because |nL| != |nR|.
    let da = (nr - nl).abs() as f32 * dl / d;
    let r = libm::fabsf((nr + nl) as f32 / (nr - nl) as f32) * d / 2.0;
    // Eq 6, Δx = r - r cos Δα, written as 2 r sin²(Δα/2) to avoid f32 cancellation.
    let half = libm::sinf(da / 2.0);
    let lateral_mm = 2.0 * r * half * half;
    // Eq 7, Δy = r sin Δα (the displacement along the old heading).
    let forward_mm = r * libm::sinf(da);
    let s_fwd = signum(nr + nl);
    // sign(|nR| - |nL|) picks the side of the lateral shift: +pi/2 (left) when the right wheel
    // travels further. cos(a0 ± pi/2) = ∓ sin a0, sin(a0 ± pi/2) = ± cos a0.
    let s_lat = signum(nr.abs() - nl.abs());
    let (sin0, cos0) = (libm::sinf(pose.heading), libm::cosf(pose.heading));
    let fwd = s_fwd * forward_mm * 1e-3;
    let lat = s_lat * lateral_mm * 1e-3;
    // Eq 10
    let turn = da * signum(nr - nl);
    let moved = Pose {
        // Eqs 8-9
        x: pose.x + fwd * cos0 - lat * sin0,
        y: pose.y + fwd * sin0 + lat * cos0,
        heading: wrap_angle(pose.heading + turn),
    };
    (moved, turn)
}

fn signum(v: i64) -> f32 {
    match v {
        0 => 0.0,
        v if v > 0 => 1.0,
        _ => -1.0,
    }
}

/// Per-cycle error bound of seed 000 §3.2 (Eqs 11-14) for a 1-pulse-per-encoder error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorBound {
    /// F_alpha, radians (0.18 deg for the Khepera, independent of the counts).
    pub f_alpha_rad: f32,
    /// F_x, millimetres.
    pub f_x_mm: f32,
    /// F_y, millimetres.
    pub f_y_mm: f32,
    /// F = sqrt(F_x² + F_y²), millimetres (<= 0.081 mm for counts < 100, seed 000 §3.2).
    pub f_mm: f32,
}

/// Eqs 11-14 of seed 000 §3.2: the linear error bound of one cycle from the derivatives of
/// Eqs 1-3 with respect to `nL` and `nR`, evaluated at the cycle's new heading `heading`, with
/// `F_nL = F_nR = encoder_sigma_pulses`.
pub fn error_bound(n_l: i32, n_r: i32, heading: f32, p: &OdometryParams) -> ErrorBound {
    let j = noise_jacobian(n_l, n_r, heading, p.mm_per_pulse, p.wheel_distance_mm);
    let f = p.encoder_sigma_pulses;
    let f_x = (libm::fabsf(j[0][0]) + libm::fabsf(j[0][1])) * f;
    let f_y = (libm::fabsf(j[1][0]) + libm::fabsf(j[1][1])) * f;
    let f_alpha = (libm::fabsf(j[2][0]) + libm::fabsf(j[2][1])) * f;
    ErrorBound {
        f_alpha_rad: f_alpha,
        f_x_mm: f_x,
        f_y_mm: f_y,
        f_mm: libm::sqrtf(f_x * f_x + f_y * f_y),
    }
}

/// d(x, y, α)/d(nL, nR) of Eqs 1-3 at the new heading; x and y in the unit of `dl`.
fn noise_jacobian(n_l: i32, n_r: i32, heading: f32, dl: f32, d: f32) -> [[f32; 2]; 3] {
    let s = (n_l as f32 + n_r as f32) / 2.0 * dl;
    let (sin, cos) = (libm::sinf(heading), libm::cosf(heading));
    let k = dl / d; // dα/dnR = -dα/dnL
    [
        [dl / 2.0 * cos + s * sin * k, dl / 2.0 * cos - s * sin * k],
        [dl / 2.0 * sin - s * cos * k, dl / 2.0 * sin + s * cos * k],
        [-k, k],
    ]
}

/// Symmetric 3x3 covariance of (x, y, heading) in metres and radians.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct PoseCovariance {
    /// Row-major 3x3 matrix; symmetric.
    pub m: [[f32; 3]; 3],
}

impl PoseCovariance {
    /// Root of the summed x and y variances: a one-number position uncertainty, metres.
    pub fn sigma_position_m(&self) -> f32 {
        libm::sqrtf((self.m[0][0] + self.m[1][1]).max(0.0))
    }

    /// Heading standard deviation, radians.
    pub fn sigma_heading_rad(&self) -> f32 {
        libm::sqrtf(self.m[2][2].max(0.0))
    }
}

/// Odometry state: pose, total rotation, covariance and the §3.2 worst-case accumulation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Odometry {
    /// Parameters in use (settable over the link).
    pub params: OdometryParams,
    pose: Pose,
    // f64 so 1000s of small increments sum without f32 drift; one soft-float add per cycle.
    turned_rad: f64,
    covariance: PoseCovariance,
    worst_case_m: f32,
    worst_case_rad: f32,
    cycles: u32,
    // Fractions of a pulse the wheel-ratio scaling has not yet passed on (left, right).
    carry: [f32; 2],
}

impl Odometry {
    /// Starts at `pose` with zero uncertainty (the start pose is taken as known).
    pub fn new(params: OdometryParams, pose: Pose) -> Self {
        Self {
            params,
            pose: Pose::new(pose.x, pose.y, pose.heading),
            turned_rad: 0.0,
            covariance: PoseCovariance::default(),
            worst_case_m: 0.0,
            worst_case_rad: 0.0,
            cycles: 0,
            carry: [0.0; 2],
        }
    }

    /// One cycle's counts in equal-wheel pulses: scaled by the calibrated wheel ratio, the
    /// fraction carried to the next cycle so that nothing is lost however long the run. With
    /// the ratio 1 (uncalibrated) the counts pass unchanged, so the paper's Eqs 1-10 see
    /// exactly the encoders, as before.
    fn scaled_counts(&mut self, n_l: i32, n_r: i32) -> (i32, i32) {
        let ppm = self.params.wheel_ratio_error_ppm;
        let r = 1.0 + ppm * 1e-6;
        if ppm == 0.0 || !(r.is_finite() && r > 0.0) {
            return (n_l, n_r);
        }
        let factor = [2.0 / (1.0 + r), 2.0 * r / (1.0 + r)];
        let mut out = [n_l, n_r];
        for ((n, c), f) in out.iter_mut().zip(self.carry.iter_mut()).zip(factor) {
            let want = *n as f32 * f + *c;
            let whole = libm::roundf(want);
            *c = want - whole;
            // |want| <= 2 |n| + 1 for ratios in the parameter's range: fits i32 whenever n
            // does (per-cycle counts are hundreds).
            *n = whole as i32;
        }
        (out[0], out[1])
    }

    /// Integrates one control cycle's encoder deltas and returns the new pose.
    pub fn step(&mut self, n_l: i32, n_r: i32) -> Pose {
        let (n_l, n_r) = self.scaled_counts(n_l, n_r);
        let p = self.params;
        let old = self.pose;
        let (new, turn) = integrate_with_turn(old, n_l, n_r, &p);
        self.turned_rad += f64::from(turn);
        self.propagate_covariance(n_l, n_r, new.heading);
        let b = error_bound(n_l, n_r, new.heading, &p);
        self.worst_case_m += b.f_mm * 1e-3;
        self.worst_case_rad += b.f_alpha_rad;
        self.cycles = self.cycles.wrapping_add(1);
        self.pose = new;
        new
    }

    /// Linearised propagation P' = F P Fᵀ + σ² G Gᵀ of the Eqs 1-3 model: F moves heading
    /// uncertainty into position (the dominant term, seed 000 §3.2: "the angular error is
    /// much more critical"), G maps independent per-encoder count errors of σ pulses. This is
    /// a random-walk model; systematic parameter error (Tables 1-2) is not in it.
    fn propagate_covariance(&mut self, n_l: i32, n_r: i32, heading: f32) {
        let p = self.params;
        let dl_m = p.mm_per_pulse * 1e-3;
        let d_m = p.wheel_distance_mm * 1e-3;
        let s = (n_l as f32 + n_r as f32) / 2.0 * dl_m;
        let f = [
            [1.0, 0.0, -s * libm::sinf(heading)],
            [0.0, 1.0, s * libm::cosf(heading)],
            [0.0, 0.0, 1.0],
        ];
        let g = noise_jacobian(n_l, n_r, heading, dl_m, d_m);
        let var = p.encoder_sigma_pulses * p.encoder_sigma_pulses;
        let old = self.covariance.m;
        let mut out = [[0.0f32; 3]; 3];
        for (i, row) in out.iter_mut().enumerate() {
            for (j, cell) in row.iter_mut().enumerate() {
                let mut acc = 0.0;
                for (k, fik) in f[i].iter().enumerate() {
                    for (l, fjl) in f[j].iter().enumerate() {
                        acc += fik * old[k][l] * fjl;
                    }
                }
                acc += var * (g[i][0] * g[j][0] + g[i][1] * g[j][1]);
                *cell = acc;
            }
        }
        self.covariance.m = out;
    }

    /// Current pose estimate.
    pub fn pose(&self) -> Pose {
        self.pose
    }

    /// Replaces the pose (e.g. after a landmark correction, seed 000 §6) keeping the
    /// covariance; use [`Odometry::set_covariance`] to say how good the correction was.
    pub fn set_pose(&mut self, pose: Pose) {
        self.pose = Pose::new(pose.x, pose.y, pose.heading);
    }

    /// Replaces the covariance (e.g. after an external fix).
    pub fn set_covariance(&mut self, covariance: PoseCovariance) {
        self.covariance = covariance;
    }

    /// Total signed rotation since construction, radians, not wrapped (sum of Eqs 1 and 10).
    pub fn turned_rad(&self) -> f32 {
        self.turned_rad as f32
    }

    /// Pose covariance under the random-walk model.
    pub fn covariance(&self) -> PoseCovariance {
        self.covariance
    }

    /// Worst-case bound accumulated as in seed 000 §3.2 (sum of F and F_alpha over cycles):
    /// (position metres, heading radians). 1000 Khepera cycles give about 8 cm and 176 deg.
    pub fn worst_case(&self) -> (f32, f32) {
        (self.worst_case_m, self.worst_case_rad)
    }

    /// Number of cycles integrated.
    pub fn cycles(&self) -> u32 {
        self.cycles
    }
}

/// Seed 000 §3.3, Tables 1 and 2: the final angular error (degrees) of two wall-following
/// laps of the 75 x 60 cm box re-integrated with other odometry constants. The one copy of the
/// paper's figures: the firmware's arithmetic test and the emulator's `odometry-laps` scenario
/// both check against it.
pub mod paper_000 {
    /// Pulse length dl (mm, with d = 52) -> final angular error (deg).
    pub const TABLE_1: [(f64, f64); 9] = [
        (0.076, 18.6),
        (0.077, 9.4),
        (0.078, 0.1),
        (0.079, -9.1),
        (0.080, -18.3),
        (0.081, -27.6),
        (0.082, -36.8),
        (0.083, -46.0),
        (0.084, -55.2),
    ];
    /// Wheel distance d (mm, with dl = 0.080) -> final angular error (deg).
    pub const TABLE_2: [(f64, f64); 9] = [
        (48.0, -79.8),
        (49.0, -63.5),
        (50.0, -47.9),
        (51.0, -32.81),
        (52.0, -18.3),
        (53.0, -4.4),
        (54.0, 9.0),
        (55.0, 21.9),
        (56.0, 34.4),
    ];
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::vec::Vec;

    /// Exact constant-curvature motion of a differential drive, f64, mm in and m out.
    fn exact_arc(pose: (f64, f64, f64), nl: i32, nr: i32, dl: f64, d: f64) -> (f64, f64, f64) {
        let (x, y, a) = pose;
        let s = f64::from(nl + nr) / 2.0 * dl * 1e-3;
        let th = f64::from(nr - nl) * dl / d;
        if th == 0.0 {
            return (x + s * a.cos(), y + s * a.sin(), a);
        }
        let r = s / th;
        let (x1, y1) = (
            x + r * ((a + th).sin() - a.sin()),
            y - r * ((a + th).cos() - a.cos()),
        );
        (x1, y1, a + th)
    }

    fn angle_diff(a: f64, b: f64) -> f64 {
        let d = (a - b).rem_euclid(2.0 * core::f64::consts::PI);
        d.min(2.0 * core::f64::consts::PI - d)
    }

    #[test]
    fn integrate_matches_exact_arc_for_many_count_pairs() {
        let p = OdometryParams::default();
        let mut counts: Vec<i32> = (-120..=120).step_by(7).collect();
        counts.extend_from_slice(&[0, 1, -1, 50, -50, 99, -99]);
        let mut checked = 0;
        for &nl in &counts {
            for &nr in &counts {
                for a0 in [0.0f32, 0.7, -2.0, 3.1] {
                    let got = integrate(Pose::new(0.3, -0.2, a0), nl, nr, &p);
                    let want = exact_arc((0.3, -0.2, f64::from(a0)), nl, nr, 0.08, 52.0);
                    let err = (f64::from(got.x) - want.0).hypot(f64::from(got.y) - want.1);
                    assert!(err < 1e-6, "nl={nl} nr={nr} a0={a0}: {got:?} vs {want:?}");
                    assert!(angle_diff(f64::from(got.heading), want.2) < 1e-5);
                    checked += 1;
                }
            }
        }
        assert!(checked > 5000);
    }

    #[test]
    fn straight_line_moves_along_the_heading_without_turning() {
        let p = OdometryParams::default();
        let got = integrate(Pose::new(0.0, 0.0, PI / 2.0), 100, 100, &p);
        assert!(got.x.abs() < 1e-7 && (got.y - 0.008).abs() < 1e-7);
        assert_eq!(got.heading, PI / 2.0);
        let back = integrate(got, -100, -100, &p);
        assert!(back.y.abs() < 1e-7);
    }

    #[test]
    fn turn_on_the_spot_only_rotates() {
        let p = OdometryParams::default();
        let got = integrate(Pose::default(), -65, 65, &p);
        assert_eq!((got.x, got.y), (0.0, 0.0));
        // (nR - nL) Δl/d = 130 * 0.08 / 52 = 0.2 rad (Eq 1)
        assert!((got.heading - 0.2).abs() < 1e-6);
    }

    #[test]
    fn one_wheel_stopped_still_turns_unlike_printed_eq_4() {
        let p = OdometryParams::default();
        // nR = 0: printed Eq 4 gives Δα = 0; the fixed form gives -|nL| Δl/d.
        let right_stopped = integrate(Pose::default(), 50, 0, &p);
        assert!((right_stopped.heading + 50.0 * 0.08 / 52.0).abs() < 1e-6);
        assert!(
            right_stopped.y < 0.0,
            "pivoting about the right wheel moves right"
        );
        let left_stopped = integrate(Pose::default(), 0, -50, &p);
        assert!((left_stopped.heading + 50.0 * 0.08 / 52.0).abs() < 1e-6);
        assert!(left_stopped.x < 0.0 && left_stopped.y > 0.0);
    }

    #[test]
    fn heading_stays_wrapped_after_many_turns() {
        let mut odo = Odometry::new(OdometryParams::default(), Pose::default());
        for _ in 0..1000 {
            odo.step(-40, 40);
        }
        let h = odo.pose().heading;
        assert!((-PI..=PI).contains(&h));
        let turned = 1000.0 * 80.0 * 0.08 / 52.0;
        assert!((odo.turned_rad() - turned).abs() < 1e-4);
        assert!(angle_diff(f64::from(h), f64::from(turned)) < 1e-3);
    }

    #[test]
    fn encoder_delta_survives_counter_wrap() {
        assert_eq!(encoder_delta(i32::MAX - 2, i32::MIN + 3), 6);
        assert_eq!(encoder_delta(10, -5), -15);
    }

    #[test]
    fn error_bound_reproduces_section_3_2_figures() {
        let p = OdometryParams::default();
        let b = error_bound(50, 50, 0.0, &p);
        // F_alpha = 2 Δl/d = 0.176 deg, "0.18 deg" in the paper.
        assert!((b.f_alpha_rad.to_degrees() - 0.1763).abs() < 1e-3);
        // F = 0.081 mm for deltas below 100 (nL + nR = 100).
        assert!((b.f_mm - 0.081).abs() < 5e-4, "{b:?}");
        // Nearly independent of the heading, as the paper says.
        for h in [0.3f32, 0.785, 1.57, -2.0] {
            let f = error_bound(50, 50, h, &p).f_mm;
            assert!((0.0795..=0.0815).contains(&f), "{h}: {f}");
        }
        // 1000 cycles: 8.1 cm and about 180 deg worst case.
        let mut odo = Odometry::new(p, Pose::default());
        for _ in 0..1000 {
            odo.step(50, 50);
        }
        let (pos, head) = odo.worst_case();
        assert!((pos - 0.081).abs() < 1e-3, "{pos}");
        assert!((head.to_degrees() - 176.3).abs() < 0.5, "{head}");
    }

    #[test]
    fn covariance_grows_as_a_random_walk_and_stays_symmetric() {
        let p = OdometryParams::default();
        let mut odo = Odometry::new(p, Pose::default());
        let mut last = 0.0;
        for i in 1..=500 {
            odo.step(50, 52);
            let c = odo.covariance();
            // Heading variance: 2 σ² (Δl/d)² per cycle.
            let want = i as f32 * 2.0 * (0.08f32 / 52.0).powi(2);
            assert!((c.m[2][2] - want).abs() < want * 1e-3);
            for (r, row) in c.m.iter().enumerate() {
                for (k, v) in row.iter().enumerate() {
                    assert!((v - c.m[k][r]).abs() < 1e-9);
                }
            }
            assert!(c.sigma_position_m() >= last);
            last = c.sigma_position_m();
        }
        // Heading error dominates: lateral sigma ≈ L σ_α / sqrt(3) for a random-walk heading,
        // L = 500 * 4.08 mm, σ_α = sqrt(1000) Δl/d = 0.049 rad, i.e. about 5.7 cm.
        assert!((0.045..0.065).contains(&last), "{last}");
    }

    // ---- Tables 1-2 of seed 000 §3.3 ----------------------------------------------------------

    /// One piece of the true path: a straight (mm) or a clockwise corner (radius mm, angle rad).
    #[derive(Clone, Copy)]
    enum Piece {
        Straight(f64),
        Corner(f64, f64),
    }

    struct Run {
        nl: Vec<i32>,
        nr: Vec<i32>,
        true_rotation_rad: f64,
    }

    const BOX_MM: (f64, f64) = (750.0, 600.0); // seed 000 §3.3: 75 x 60 cm
    const CLEARANCE_MM: f64 = 50.0; // centre to wall: 27.5 mm radius + 2.25 cm IR range (§4.1)
    const ROUND_CORNER_MM: f64 = 60.0;
    const WEAVE_RAD: f64 = 0.035; // ±2 deg heading weave from the ±1 edge-following drift
    const WAVES_PER_WALL: f64 = 3.0;

    /// Simulates two clockwise laps of left-wall following (S0, §4.3) in the box: straights with
    /// a small heading weave, corners alternately pivoting on the stopped right wheel (what the
    /// avoidance does at a front wall, so nR = 0 cycles occur) and rounded (60 mm). The outer
    /// wheel keeps one speed throughout, chosen so the run lasts `cycles`. The last corner
    /// stops `short_rad` early. Encoders count whole pulses of `dl_true` of the wheels' true
    /// travel; heading comes from the true wheel distance `d_true`.
    fn two_lap_wall_following_run(d_true: f64, dl_true: f64, cycles: usize, short_rad: f64) -> Run {
        let quarter = core::f64::consts::FRAC_PI_2;
        let radius = |i: usize| {
            if i % 2 == 0 {
                d_true / 2.0
            } else {
                ROUND_CORNER_MM
            }
        };
        let mut pieces = Vec::new();
        for i in 0..8 {
            let wall = if i % 2 == 0 { BOX_MM.0 } else { BOX_MM.1 };
            let prev = radius((i + 7) % 8);
            pieces.push(Piece::Straight(
                wall - 2.0 * CLEARANCE_MM - prev - radius(i),
            ));
            let angle = if i == 7 { quarter - short_rad } else { quarter };
            pieces.push(Piece::Corner(radius(i), angle));
        }
        // Centre speed relative to the outer wheel's.
        let rel_speed = |p: &Piece| match *p {
            Piece::Straight(_) => 1.0,
            Piece::Corner(r, _) => r / (r + d_true / 2.0),
        };
        let length = |p: &Piece| match *p {
            Piece::Straight(l) => l,
            Piece::Corner(r, a) => r * a,
        };
        let total_time: f64 = pieces.iter().map(|p| length(p) / rel_speed(p)).sum();
        // (arc length, heading) at time t; heading decreases (clockwise).
        let state = |t: f64| -> (f64, f64) {
            let (mut t0, mut s0, mut phi0) = (0.0, 0.0, 0.0);
            for (k, p) in pieces.iter().enumerate() {
                let dur = length(p) / rel_speed(p);
                if t <= t0 + dur || k + 1 == pieces.len() {
                    let u = (t - t0).clamp(0.0, dur) * rel_speed(p);
                    let phi = match *p {
                        Piece::Straight(l) => {
                            phi0 - WEAVE_RAD
                                * (2.0 * core::f64::consts::PI * WAVES_PER_WALL * u / l).sin()
                        }
                        Piece::Corner(r, _) => phi0 - u / r,
                    };
                    return (s0 + u, phi);
                }
                t0 += dur;
                s0 += length(p);
                if let Piece::Corner(_, a) = *p {
                    phi0 -= a;
                }
            }
            (s0, phi0)
        };
        // Wheel travel: S_L = s - (d/2) φ, S_R = s + (d/2) φ; counters count whole pulses.
        let counts = |t: f64| {
            let (s, phi) = state(t);
            let l = ((s - d_true / 2.0 * phi) / dl_true).round() as i64;
            let r = ((s + d_true / 2.0 * phi) / dl_true).round() as i64;
            (l, r)
        };
        let (mut nl, mut nr) = (Vec::new(), Vec::new());
        let mut prev = counts(0.0);
        for k in 1..=cycles {
            let now = counts(total_time * k as f64 / cycles as f64);
            nl.push((now.0 - prev.0) as i32);
            nr.push((now.1 - prev.1) as i32);
            prev = now;
        }
        Run {
            nl,
            nr,
            true_rotation_rad: state(total_time).1,
        }
    }

    /// A calibrated wheel ratio straightens the path of a robot whose right wheel truly
    /// travels 0.4 % more per pulse: driven truly straight (its encoders then count fewer
    /// right pulses), the uncalibrated odometry turns right, the calibrated one does not.
    #[test]
    fn the_wheel_ratio_straightens_a_truly_straight_path() {
        let ratio = 1.004_f32;
        let run = |r: f32| {
            let p = OdometryParams {
                wheel_ratio_error_ppm: (r - 1.0) * 1e6,
                ..OdometryParams::default()
            };
            let mut odo = Odometry::new(p, Pose::default());
            // True: both wheels travel the same ground distance d per cycle; the left pulse
            // length is 2/(1+ratio) dl, the right's 2 ratio/(1+ratio) dl.
            let (mut cl, mut cr) = (0.0f64, 0.0f64);
            for _ in 0..1000 {
                let d = 8.0f64; // mm of ground per cycle
                let dl = 0.08f64;
                cl += d / (dl * 2.0 / (1.0 + f64::from(ratio)));
                cr += d / (dl * 2.0 * f64::from(ratio) / (1.0 + f64::from(ratio)));
                let (nl, nr) = (cl.floor(), cr.floor());
                cl -= nl;
                cr -= nr;
                odo.step(nl as i32, nr as i32);
            }
            odo.pose()
        };
        let raw = run(1.0);
        let cal = run(ratio);
        // 8 m truly straight along +x.
        assert!(raw.heading < -0.05, "uncalibrated bends right: {raw:?}");
        assert!(
            cal.heading.abs() < 0.002,
            "calibrated stays straight: {cal:?}"
        );
        assert!(cal.y.abs() < 0.01 && (cal.x - 8.0).abs() < 0.01, "{cal:?}");
    }

    fn reintegrate(run: &Run, d: f32, dl: f32) -> Odometry {
        let params = OdometryParams {
            wheel_distance_mm: d,
            mm_per_pulse: dl,
            ..OdometryParams::default()
        };
        let mut odo = Odometry::new(params, Pose::default());
        let mut from_poses = 0.0f64;
        for (&l, &r) in run.nl.iter().zip(&run.nr) {
            let before = odo.pose().heading;
            let after = odo.step(l, r).heading;
            from_poses += f64::from(wrap_angle(after - before));
        }
        // The rotation total and the poses' own headings tell the same story.
        assert!((from_poses - f64::from(odo.turned_rad())).abs() < 1e-4);
        odo
    }

    /// The paper's final angular error: how far the integrated heading lags the true one in
    /// the direction of travel (the robot "stopped at 71.7° instead of 90°"), degrees.
    fn final_angular_error_deg(run: &Run, d: f32, dl: f32) -> f64 {
        let integrated = f64::from(reintegrate(run, d, dl).turned_rad());
        (run.true_rotation_rad.abs() - integrated.abs()).to_degrees()
    }

    #[test]
    fn tables_1_and_2_arithmetic_of_a_synthetic_two_lap_path() {
        // All 18 entries fit Δα = 719.7 - 738.0 (Δl/0.080)(52/d): the robot truly turned
        // 719.7° (0.3° short of two laps) while its encoders, read at d = 52, Δl = 0.080, said
        // 738.0°. The encoder-count difference ΣnR - ΣnL is a whole number of pulses: 738.0°
        // is 8372.4 pulses, so the log held 8372 or 8373; with 719.7° only 8373 fits all 18
        // entries within 0.1° (8372 misses d = 50 by 0.012°). The true wheel distance follows:
        // d_true = 8373 Δl / 719.7° = 53.326 mm ("about 53.3 mm").
        let true_rotation = 719.7f64.to_radians();
        let d_true = 8373.0 * 0.080 / true_rotation;
        let short = 0.3f64.to_radians();
        let run = two_lap_wall_following_run(d_true, 0.080, 1126, short);
        assert_eq!(run.nl.len(), 1126);
        assert!((run.true_rotation_rad + true_rotation).abs() < 1e-9);
        // The log pivots on the stopped right wheel, so printed Eq 4 (Δα = 0 at nR = 0) fails.
        assert!(run.nr.iter().zip(&run.nl).any(|(&r, &l)| r == 0 && l > 20));
        // Realistic speeds: under 100 pulses per cycle (§3.2), about 6 Khepera units.
        assert!(run.nl.iter().chain(&run.nr).all(|n| (0..100).contains(n)));
        for (table, is_dl) in [(&paper_000::TABLE_1, true), (&paper_000::TABLE_2, false)] {
            for &(value, paper) in table.iter() {
                let value = value as f32;
                let (d, dl) = if is_dl { (52.0, value) } else { (value, 0.080) };
                let ours = final_angular_error_deg(&run, d, dl);
                std::println!("d={d} dl={dl}: paper {paper:+.2} ours {ours:+.3}");
                assert!(
                    (ours - paper).abs() <= 0.1,
                    "d={d} dl={dl}: {ours} vs {paper}"
                );
            }
        }
    }

    #[test]
    fn simulated_run_reintegrated_with_true_parameters_traces_the_box() {
        let d_true = 8373.0 * 0.080 / 719.7f64.to_radians();
        let run = two_lap_wall_following_run(d_true, 0.080, 1126, 0.3f64.to_radians());
        assert!(final_angular_error_deg(&run, d_true as f32, 0.080).abs() < 0.01);
        let params = OdometryParams {
            wheel_distance_mm: d_true as f32,
            ..OdometryParams::default()
        };
        let mut odo = Odometry::new(params, Pose::default());
        let (mut min, mut max) = ((0.0f32, 0.0f32), (0.0f32, 0.0f32));
        for (&l, &r) in run.nl.iter().zip(&run.nr) {
            let p = odo.step(l, r);
            min = (min.0.min(p.x), min.1.min(p.y));
            max = (max.0.max(p.x), max.1.max(p.y));
        }
        // Clockwise from the start corner: the track spans the box minus the clearance.
        let span = (max.0 - min.0, max.1 - min.1);
        assert!(
            (span.0 - 0.650).abs() < 0.003 && (span.1 - 0.500).abs() < 0.003,
            "{span:?}"
        );
        let end = odo.pose();
        assert!(end.x.abs() < 0.003 && end.y.abs() < 0.003, "{end:?}");
    }
}
