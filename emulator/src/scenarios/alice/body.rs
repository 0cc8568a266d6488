//! ALICE's body in the scenarios: a 40 cm disc at 25 cm/s, and its odometry's drift.
//!
//! Drive: ALICE had six driven, steerable wheels (omnidirectional); here the drive stays
//! differential (the emulator's, and the firmware's, only drive): it drives straight along its
//! heading and turns on the spot. Turning adds a heading error of `TURN_NOISE` of the angle
//! turned, which ALICE (steering its wheels, not its body) did not have; it is small beside
//! the drift below.
//!
//! Odometry drift (§3.1, §4.5.3: "position drift-error of 20 to 25 % and rotational drift of
//! up to 0.5 degrees/metre"): the thesis gives rates, not a process; ours is
//! - translational: the odometry's displacement is the true one plus `e x distance`, `e` a
//!   2-D error in the robot's frame that wanders (an Ornstein-Uhlenbeck process over
//!   distance, correlation length `DRIFT_CORRELATION_M`) with an r.m.s. size drawn per run
//!   in 20..25 %. A constant scale error would not do: in a bounded arena it stays bounded;
//! - rotational: a constant rate per run, drawn in 0.25..0.5 degrees/metre with a random sign.

use crate::geometry::{Point, SegmentSet};
use crate::rng::SimRng;

use super::wrap;
use crate::sensors::alice::BODY_RADIUS_M;

/// Driving speed, m/s (§3.1: 25 cm/s, nearly constant).
pub const SPEED_M_S: f64 = 0.25;
/// Turning rate on the spot, rad/s (ours).
pub const TURN_RAD_S: f64 = 1.5;
/// Heading error per radian turned on the spot (ours; see the module doc).
pub const TURN_NOISE: f64 = 0.01;
/// Distance over which the translational error forgets itself, metres (ours).
pub const DRIFT_CORRELATION_M: f64 = 2.0;
/// Physics steps per sensor sample (3 samples/s -> 30 Hz motion).
pub const SUBSTEPS: usize = 10;

/// The true pose, the odometry's pose, and the drift state.
#[derive(Clone, Debug)]
pub struct Body {
    /// True position and heading.
    pub at: Point,
    /// True heading, radians.
    pub heading: f64,
    /// Odometry pose (x, y, heading).
    pub odo: (f64, f64, f64),
    /// Translational error r.m.s. (fraction of the distance) this run.
    pub trans_drift: f64,
    /// Rotational drift this run, rad/m.
    pub rot_drift: f64,
    /// Static drift the odometry does not see, rad/m: the true path curves while the
    /// odometry's heading stays (unequal wheels; §5.3's simulator "static drift model").
    /// Zero unless a scenario sets it.
    pub curve: f64,
    err: (f64, f64),
    rng: SimRng,
    /// Metres driven.
    pub distance_m: f64,
}

impl Body {
    /// A body at `at`, drift drawn from `rng` (or none).
    pub fn new(at: Point, heading: f64, mut rng: SimRng, drift: bool) -> Self {
        let trans_drift = if drift {
            0.20 + 0.05 * rng.uniform()
        } else {
            0.0
        };
        let sign = if rng.chance(0.5) { 1.0 } else { -1.0 };
        let rot_drift = if drift {
            sign * (0.25 + 0.25 * rng.uniform()).to_radians()
        } else {
            0.0
        };
        let s = trans_drift / std::f64::consts::SQRT_2;
        let err = (rng.gaussian(s), rng.gaussian(s));
        Body {
            at,
            heading,
            odo: (at.x, at.y, heading),
            trans_drift,
            rot_drift,
            curve: 0.0,
            err,
            rng,
            distance_m: 0.0,
        }
    }

    /// Drive forward `ds` metres if the way is free; false (and no motion) when it is not.
    pub fn forward(&mut self, walls: &SegmentSet, ds: f64) -> bool {
        let next =
            self.at + crate::geometry::Vector::new(self.heading.cos(), self.heading.sin()) * ds;
        if walls.circle_collides(next, BODY_RADIUS_M) {
            return false;
        }
        self.at = next;
        self.distance_m += ds;
        // The wandering error, per unit distance (OU over distance).
        let a = (-ds / DRIFT_CORRELATION_M).exp();
        let s = self.trans_drift / std::f64::consts::SQRT_2 * (1.0 - a * a).sqrt();
        self.err = (
            a * self.err.0 + self.rng.gaussian(s),
            a * self.err.1 + self.rng.gaussian(s),
        );
        let (fx, fy) = (ds * (1.0 + self.err.0), ds * self.err.1);
        let (sn, cs) = self.odo.2.sin_cos();
        self.odo.0 += cs * fx - sn * fy;
        self.odo.1 += sn * fx + cs * fy;
        self.odo.2 = wrap(self.odo.2 + self.rot_drift * ds);
        if self.curve != 0.0 {
            self.heading = wrap(self.heading + self.curve * ds);
        }
        true
    }

    /// Turn on the spot by `da` radians.
    pub fn turn(&mut self, da: f64) {
        self.heading = wrap(self.heading + da);
        let noise = self.rng.gaussian(TURN_NOISE * da.abs());
        self.odo.2 = wrap(self.odo.2 + da + noise);
    }
}
