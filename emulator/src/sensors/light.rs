//! Khepera ambient light sensors: passive IR receivers, inverted (lower = brighter).
//!
//! Model (seed 000 §5.2, Fig. 19: the value falls as the light gets closer; about 500 is dark).
//! Each sensor sits on the body's edge facing its IR direction. A light of intensity `I` at
//! distance `d` from the sensor, seen at angle `phi` off the sensor's axis, gives a brightness
//!
//! `b = I * GAIN * ((1 + cos phi) / 2) / (1 + (d / HALF_M)^2)`
//!
//! (a cardioid acceptance: full on axis, half at 90 degrees, none from behind, where the body
//! shades the receiver; inverse-square far away, finite at the lamp). Brightnesses add over
//! lights; a wall between the robot's centre and a light hides it. The reading is
//! `DARK / (1 + sum b)` plus noise, so it falls from 500 towards 0 near a light.
//!
//! Calibration to seed 000 §6.1's thresholds, for the reference lamp (`I = 1`) facing it:
//! the average of the six front sensors drops below T2 = 200 ("optimal distance") about 1 cm
//! from the body (1.4 cm); the brightest sensor drops below T1 = 470 ("source detected") at
//! about 25 cm; readings rise above T3 = 490 ("area left") beyond about 45 cm. A brighter
//! lamp stretches these distances, as §5.2 says a stronger source spreads the curve.
//!
//! Invariants: readings in 0..=1023; all zero on a robot without light sensors. Cannot fail.

use robot_firmware::Profile;

use super::counts10;
use crate::arena::{Light, Pose};
use crate::geometry::{Point, SegmentSet, Vector};
use crate::rng::SimRng;

/// Reading in the dark. seed 000 §4.1/§5.2: about 500.
pub const DARK: f64 = 500.0;
/// Brightness scale of the reference lamp, fitted so the front six average 200 at ~1 cm.
pub const GAIN: f64 = 12.0;
/// Distance at which a lamp's brightness halves from its near-field value, metres.
pub const HALF_M: f64 = 0.02;
/// Brightness under which a light is not worth a line-of-sight test (< 1 count).
const NEGLIGIBLE: f64 = 0.002;

/// A profile's ambient light sensors.
#[derive(Clone, Debug)]
pub struct AmbientLight {
    present: bool,
    angle_rad: [f64; 8],
    radius_m: f64,
    sigma: f64,
    rng: SimRng,
}

impl AmbientLight {
    /// The sensors of `profile` (absent unless it has `caps::AMBIENT_LIGHT`).
    pub fn new(profile: &Profile, sigma_counts: f64, rng: SimRng) -> AmbientLight {
        let mut angle_rad = [0.0; 8];
        for (a, p) in angle_rad.iter_mut().zip(profile.ir.angle_rad) {
            *a = f64::from(p);
        }
        AmbientLight {
            present: profile.has(protocol::caps::AMBIENT_LIGHT),
            angle_rad,
            radius_m: f64::from(profile.body_diameter_m) / 2.0,
            sigma: sigma_counts,
            rng,
        }
    }

    /// Noise-free brightness each sensor receives from `lights` at `pose`.
    pub fn brightness(&self, walls: &SegmentSet, lights: &[Light], pose: Pose) -> [f64; 8] {
        let mut b = [0.0; 8];
        let centre = Point::new(pose.x, pose.y);
        // The sensors' axes, worked out once per reading (not once per light) and only when a
        // light is bright enough to matter.
        let mut axes: Option<[Vector; 8]> = None;
        for light in lights {
            // Cheap bound first: the brightest any sensor could see this light.
            let dc = (light.position - centre).norm() - self.radius_m;
            let bound = light.intensity * GAIN / (1.0 + (dc.max(0.0) / HALF_M).powi(2));
            if bound.is_nan() || bound <= NEGLIGIBLE || walls.blocks(centre, light.position) {
                continue;
            }
            let axes = axes.get_or_insert_with(|| {
                self.angle_rad.map(|a| {
                    let (s, c) = (pose.heading + a).sin_cos();
                    Vector::new(c, s)
                })
            });
            for (slot, &axis) in b.iter_mut().zip(axes.iter()) {
                let v = light.position - (centre + axis * self.radius_m);
                let d = v.norm();
                let cos_phi = if d > 0.0 { axis.dot(&v) / d } else { 1.0 };
                let accept = (1.0 + cos_phi) / 2.0;
                *slot += light.intensity * GAIN * accept / (1.0 + (d / HALF_M).powi(2));
            }
        }
        b
    }

    /// One reading of all eight sensors.
    pub fn read(&mut self, walls: &SegmentSet, lights: &[Light], pose: Pose) -> [u16; 8] {
        if !self.present {
            return [0; 8];
        }
        let b = self.brightness(walls, lights, pose);
        let mut out = [0u16; 8];
        for (o, bi) in out.iter_mut().zip(b) {
            *o = counts10(DARK / (1.0 + bi.max(0.0)), self.sigma, &mut self.rng);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use robot_firmware::KHEPERA;

    fn reading_facing(distance_from_edge: f64) -> [u16; 8] {
        let mut s = AmbientLight::new(&KHEPERA, 0.0, SimRng::new(1, 1));
        let lamp = Light {
            position: Point::new(0.0275 + distance_from_edge, 0.0),
            height_m: 0.0,
            intensity: 1.0,
        };
        s.read(
            &SegmentSet::default(),
            &[lamp],
            Pose {
                x: 0.0,
                y: 0.0,
                heading: 0.0,
            },
        )
    }

    fn front_average(r: [u16; 8]) -> f64 {
        r[..6].iter().map(|&v| f64::from(v)).sum::<f64>() / 6.0
    }

    #[test]
    fn thresholds_of_seed_000_fall_at_the_documented_distances() {
        // T2 = 200: optimal distance about 1 cm.
        assert!(front_average(reading_facing(0.010)) < 200.0);
        assert!(front_average(reading_facing(0.025)) > 200.0);
        // T1 = 470: detected at 20 cm, not at 40 cm.
        assert!(reading_facing(0.20)[..6].iter().any(|&v| v < 470));
        assert!(reading_facing(0.40)[..6].iter().all(|&v| v >= 470));
        // Dark: 500.
        assert_eq!(reading_facing(50.0)[2], 500);
    }

    #[test]
    fn a_wall_between_robot_and_light_hides_it() {
        use crate::geometry::Segment;
        let walls = SegmentSet::new(vec![Segment::new(
            Point::new(0.05, -1.0),
            Point::new(0.05, 1.0),
        )]);
        let mut s = AmbientLight::new(&KHEPERA, 0.0, SimRng::new(1, 1));
        let lamp = Light {
            position: Point::new(0.1, 0.0),
            height_m: 0.0,
            intensity: 1.0,
        };
        let r = s.read(
            &walls,
            &[lamp],
            Pose {
                x: 0.0,
                y: 0.0,
                heading: 0.0,
            },
        );
        assert_eq!(r[2], 500);
    }
}
