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
        }
    }
}

/// Advances `pose` by one cycle's encoder deltas (seed 000 §3.1, Eqs 1-10).
pub fn integrate(pose: Pose, n_l: i32, n_r: i32, p: &OdometryParams) -> Pose {
    let dl = p.mm_per_pulse;
    let d = p.wheel_distance_mm;
    // Widen before summing so extreme counts cannot overflow.
    let (nl, nr) = (i64::from(n_l), i64::from(n_r));
    if nl.abs() == nr.abs() {
        // Case 1, Eqs 1-3: straight line (nL = nR) or turn on the spot (nL = -nR). The paper
        // uses the new heading α_R in cos/sin; either choice is exact here because one of the
        // rotation and the translation is zero.
        let heading = pose.heading + (nr - nl) as f32 * dl / d;
        let s_m = (nr + nl) as f32 / 2.0 * dl * 1e-3;
        return Pose {
            x: pose.x + s_m * libm::cosf(heading),
            y: pose.y + s_m * libm::sinf(heading),
            heading: wrap_angle(heading),
        };
    }
    // Case 2, Eqs 4-10 with the digest's fix: Δα = |nR - nL| Δl/d and
    // r = |(nR + nL)/(nR - nL)| d/2. (Printed Eq 4 gives Δα = 0 whenever nR = 0.)
    // nR - nL != 0 and nR + nL != 0 here, because |nL| != |nR|.
    let da = (nr - nl).abs() as f32 * dl / d;
    let r = ((nr + nl) as f32 / (nr - nl) as f32).abs() * d / 2.0;
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
    Pose {
        // Eqs 8-9
        x: pose.x + fwd * cos0 - lat * sin0,
        y: pose.y + fwd * sin0 + lat * cos0,
        // Eq 10
        heading: wrap_angle(pose.heading + da * signum(nr - nl)),
    }
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

/// Symmetric 3x3 covariance of (x [m], y [m], heading [rad]).
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
    turned_rad: f32,
    covariance: PoseCovariance,
    worst_case_m: f32,
    worst_case_rad: f32,
    cycles: u32,
}

impl Odometry {
    /// Starts at `pose` with zero uncertainty (the start pose is known, seed 000 §4.6).
    pub fn new(params: OdometryParams, pose: Pose) -> Self {
        Self {
            params,
            pose: Pose::new(pose.x, pose.y, pose.heading),
            turned_rad: 0.0,
            covariance: PoseCovariance::default(),
            worst_case_m: 0.0,
            worst_case_rad: 0.0,
            cycles: 0,
        }
    }

    /// Integrates one control cycle's encoder deltas and returns the new pose.
    pub fn step(&mut self, n_l: i32, n_r: i32) -> Pose {
        let p = self.params;
        let old = self.pose;
        let new = integrate(old, n_l, n_r, &p);
        self.turned_rad += (i64::from(n_r) - i64::from(n_l)) as f32 * p.mm_per_pulse
            / p.wheel_distance_mm;
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

    /// Total signed rotation since construction, radians, not wrapped (sum of Eq 10).
    pub fn turned_rad(&self) -> f32 {
        self.turned_rad
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

#[cfg(test)]
mod tests;
