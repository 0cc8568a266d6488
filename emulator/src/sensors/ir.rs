//! Active IR proximity sensors: reading versus distance to the nearest wall, per profile.
//!
//! Each sensor sits on the body's edge facing its `Profile::ir.angle_rad` direction and sees a
//! cone, sampled by a few rays (the centre ray at full weight, off-axis rays attenuated). The
//! reading is
//!
//! `floor + gain_i * max_k(w_k * C(d_k)) + N(0, sigma)`, clamped and rounded to 0..=1023,
//!
//! with `C(d) = 1023 * ((range - d) / (range - saturate))^exponent` for `d < range`, 0 beyond,
//! so `C` is 1023 exactly at `saturate` and above it closer in (the reading saturates), falls
//! through the useful band and is 0 from `range` on, where only the floor and noise remain.
//! `gain_i` is each sensor's fabrication spread, drawn once per run.
//!
//! Curves (the exponents are not in the papers; they are chosen to fit what the papers say):
//! - Khepera, seed 000 §1.1: saturates below 1.7 cm, useful 1.7..3.3 cm, noise only beyond;
//!   exponent 1.5 (a convex fall like a real IR return); a floor of 5 counts (ambient IR)
//!   with the noise of [`super::Noise::obstacle_counts`] (about 3 counts), so a clear view
//!   reads a few counts.
//! - Micro-rato, seed 004 §3: range 25 cm, no saturation distance (reads 1023 touching);
//!   exponent 2 puts the firmware's `GuidedParams::obstacle_ir` default of 350 at 10.4 cm,
//!   inside the 10-12 cm the guided motion is tuned for.
//!
//! Invariants: readings are in 0..=1023; unused slots read 0; with no wall within reach no ray
//! is cast (one nearest-wall query decides). Cannot fail.

use robot_firmware::{Profile, KHEPERA};

use super::counts10;
use crate::arena::Pose;
use crate::geometry::{Disc, Point, SegmentSet, Vector};
use crate::rng::SimRng;

/// Most other robots one reading looks at (those within reach, in the order given): a
/// Micro-Rato contest has three robots, so two others.
const MAX_SEEN: usize = 8;

/// Full-scale reading of a 10-bit converter.
pub const FULL_SCALE: f64 = 1023.0;

/// Reading versus distance of one sensor type.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IrCurve {
    /// Below this distance from the sensor the reading saturates at 1023, metres.
    pub saturate_m: f64,
    /// From this distance on only the floor and noise remain, metres.
    pub range_m: f64,
    /// Shape of the fall through the useful band.
    pub exponent: f64,
    /// Reading with nothing in view, counts (before noise).
    pub floor_counts: f64,
}

impl IrCurve {
    /// seed 000 §1.1: saturated below 1.7 cm, useful to 3.3 cm.
    pub const KHEPERA: IrCurve = IrCurve {
        saturate_m: 0.017,
        range_m: 0.033,
        exponent: 1.5,
        floor_counts: 5.0,
    };

    /// seed 004 §3: range 25 cm after calibration; 350 counts at 10.4 cm.
    pub const MICRO_RATO: IrCurve = IrCurve {
        saturate_m: 0.0,
        range_m: 0.25,
        exponent: 2.0,
        floor_counts: 5.0,
    };

    /// The curve for a profile (by its IR range: short-range Khepera-like sensors or long).
    pub fn for_profile(profile: &Profile) -> IrCurve {
        if profile.id == KHEPERA.id {
            IrCurve::KHEPERA
        } else {
            IrCurve {
                range_m: f64::from(profile.ir_range_m),
                ..IrCurve::MICRO_RATO
            }
        }
    }

    /// Noise-free reflected signal at distance `d`, counts, before the floor and gain; may
    /// exceed 1023 (saturation happens at the clamp).
    pub fn signal(&self, d: f64) -> f64 {
        if d.is_nan() || d >= self.range_m {
            return 0.0;
        }
        let band = (self.range_m - self.saturate_m).max(1e-9);
        let x = ((self.range_m - d) / band).max(0.0);
        FULL_SCALE * x.powf(self.exponent)
    }

    /// Noise-free reading at distance `d` with unit gain (what a perfect sensor reads).
    pub fn reading(&self, d: f64) -> u16 {
        (self.floor_counts + self.signal(d))
            .round()
            .clamp(0.0, FULL_SCALE) as u16
    }
}

/// Rays sampling a sensor's cone: (offset from its axis in radians, weight).
const KHEPERA_CONE: [(f64, f64); 3] = [(0.0, 1.0), (0.35, 0.6), (-0.35, 0.6)];
/// The micro-rato's sensors are wider (CiberRato's have a 60 degree aperture).
const RATO_CONE: [(f64, f64); 5] = [
    (0.0, 1.0),
    (0.26, 0.8),
    (-0.26, 0.8),
    (0.52, 0.5),
    (-0.52, 0.5),
];

/// A profile's IR sensors with their per-run gains and noise.
#[derive(Clone, Debug)]
pub struct IrArray {
    curve: IrCurve,
    count: usize,
    angle_rad: [f64; 8],
    gain: [f64; 8],
    cone: &'static [(f64, f64)],
    radius_m: f64,
    sigma: f64,
    rng: SimRng,
    /// Walls near the body, gathered once per reading for all its rays (reused buffer).
    near: Vec<u32>,
    /// `(cos, sin)` of each sensor's ray angles off the heading (its axis plus each cone
    /// offset): a reading rotates the heading by them instead of a `sin_cos` per ray.
    rays: [[(f64, f64); MAX_CONE]; 8],
}

/// Most rays in a sensor's cone.
const MAX_CONE: usize = 5;

impl IrArray {
    /// The sensors of `profile`; gains are drawn from `run_rng` with relative sigma
    /// `gain_spread` (clamped to +-3 sigma), noise from `rng`.
    pub fn new(
        profile: &Profile,
        sigma_counts: f64,
        gain_spread: f64,
        run_rng: &mut SimRng,
        rng: SimRng,
    ) -> IrArray {
        let count = if profile.has(protocol::caps::IR_PROXIMITY) {
            profile.ir.count.min(8)
        } else {
            0
        };
        let mut angle_rad = [0.0; 8];
        let mut gain = [1.0; 8];
        for i in 0..count {
            angle_rad[i] = f64::from(profile.ir.angle_rad[i]);
            gain[i] = 1.0
                + run_rng
                    .gaussian(gain_spread)
                    .clamp(-3.0 * gain_spread, 3.0 * gain_spread);
        }
        let curve = IrCurve::for_profile(profile);
        let cone: &'static [(f64, f64)] = if curve.range_m > 0.1 {
            &RATO_CONE
        } else {
            &KHEPERA_CONE
        };
        let mut rays = [[(1.0, 0.0); MAX_CONE]; 8];
        for (sensor, &axis) in rays.iter_mut().zip(&angle_rad) {
            for (ray, &(offset, _)) in sensor.iter_mut().zip(cone) {
                let (s, c) = (axis + offset).sin_cos();
                *ray = (c, s);
            }
        }
        IrArray {
            curve,
            count,
            angle_rad,
            gain,
            cone,
            radius_m: f64::from(profile.body_diameter_m) / 2.0,
            sigma: sigma_counts,
            rng,
            near: Vec::new(),
            rays,
        }
    }

    /// The same sensors read through `curve` instead of the profile's (a scenario whose
    /// paper gives its own simulated sensor; the cone stays the profile's).
    pub fn with_curve(mut self, curve: IrCurve) -> IrArray {
        self.curve = curve;
        self
    }

    /// The curve in use.
    pub fn curve(&self) -> &IrCurve {
        &self.curve
    }

    /// Per-sensor gains drawn for this run.
    pub fn gains(&self) -> [f64; 8] {
        self.gain
    }

    /// Distance along each sensor's axis to the nearest wall within range (from the body's
    /// edge), for tests and displays.
    pub fn axis_distances(&self, walls: &SegmentSet, pose: Pose) -> [Option<f64>; 8] {
        let mut out = [None; 8];
        for (i, slot) in out.iter_mut().enumerate().take(self.count) {
            let (o, d) = self.ray(pose, self.angle_rad[i]);
            *slot = walls.ray_cast(o, d, self.curve.range_m).map(|h| h.distance);
        }
        out
    }

    /// One reading of every sensor at `pose`.
    pub fn read(&mut self, walls: &SegmentSet, pose: Pose) -> [u16; 8] {
        self.read_among(walls, &[], pose)
    }

    /// One reading of every sensor at `pose` among walls and other robots' bodies (`others`;
    /// their light-coloured shells reflect like the walls, seed 004 §2). Each ray sees the
    /// nearer of the two. With no other robot in reach exactly [`IrArray::read`]'s reading,
    /// and the same noise draws either way.
    pub fn read_among(&mut self, walls: &SegmentSet, others: &[Disc], pose: Pose) -> [u16; 8] {
        let mut out = [0u16; 8];
        let centre = Point::new(pose.x, pose.y);
        let reach = self.radius_m + self.curve.range_m;
        // Every ray starts on the body's edge and reaches `range` at most, so it stays within
        // radius + range of the centre: the walls there, gathered once, are all a ray can hit
        // (one gathering instead of a grid walk or a scan of every wall per ray: the readings
        // were a quarter of a reach-beacon run). None near: every ray would miss.
        let mut near = std::mem::take(&mut self.near);
        walls.near_ids(centre, reach, &mut near);
        let in_reach = |d: &&Disc| (d.centre - centre).norm() - d.radius <= reach;
        let mut bodies = [None::<Disc>; MAX_SEEN];
        for (slot, d) in bodies.iter_mut().zip(others.iter().filter(in_reach)) {
            *slot = Some(*d);
        }
        let any_body = bodies[0].is_some();
        let (hs, hc) = pose.heading.sin_cos();
        for (i, slot) in out.iter_mut().enumerate().take(self.count) {
            let mut signal: f64 = 0.0;
            if !near.is_empty() || any_body {
                for (&(_, weight), &(c, s)) in self.cone.iter().zip(&self.rays[i]) {
                    // The ray's direction: the heading turned by the ray's angle (within an
                    // ulp or two of `sin_cos` of the sum).
                    let d = Vector::new(hc * c - hs * s, hs * c + hc * s);
                    let o = centre + d * self.radius_m;
                    let wall = if near.is_empty() {
                        None
                    } else {
                        walls
                            .ray_cast_among(&near, o, d, self.curve.range_m)
                            .map(|h| h.distance)
                    };
                    let body = bodies
                        .iter()
                        .flatten()
                        .filter_map(|b| b.ray_hit(o, d))
                        .filter(|&t| t <= self.curve.range_m)
                        .fold(None, |m: Option<f64>, t| Some(m.map_or(t, |m| m.min(t))));
                    let nearest = match (wall, body) {
                        (Some(w), Some(b)) => Some(w.min(b)),
                        (w, b) => w.or(b),
                    };
                    if let Some(dist) = nearest {
                        signal = signal.max(weight * self.curve.signal(dist));
                    }
                }
            }
            let value = self.curve.floor_counts + self.gain[i] * signal;
            *slot = counts10(value, self.sigma, &mut self.rng);
        }
        self.near = near;
        out
    }

    /// Origin (on the body's edge, along the sensor's axis) and unit direction of a ray.
    fn ray(&self, pose: Pose, angle: f64) -> (Point, Vector) {
        let axis = pose.heading + angle;
        let (s, c) = axis.sin_cos();
        let d = Vector::new(c, s);
        (Point::new(pose.x, pose.y) + d * self.radius_m, d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use robot_firmware::guided::GuidedParams;

    #[test]
    fn khepera_curve_saturates_at_1_7_cm_and_is_floor_beyond_3_3_cm() {
        let c = IrCurve::KHEPERA;
        assert_eq!(c.reading(0.010), 1023);
        assert_eq!(c.reading(0.017), 1023);
        assert!(c.reading(0.025) > 300 && c.reading(0.025) < 500);
        assert_eq!(c.reading(0.033), 5);
        assert_eq!(c.reading(0.5), 5);
    }

    #[test]
    fn micro_rato_obstacle_threshold_is_about_ten_centimetres() {
        let c = IrCurve::MICRO_RATO;
        let threshold = GuidedParams::default().obstacle_ir;
        let at = |d: f64| c.reading(d);
        assert!(at(0.10) >= threshold && at(0.12) < threshold);
        assert_eq!(at(0.25), 5);
    }
}
