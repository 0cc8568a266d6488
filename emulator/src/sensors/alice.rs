//! ALICE's sensors (seed 001 §3.1): 24 binary whiskers and 24 uncalibrated photoresistors,
//! evenly spaced around the 40 cm body, sensor `i` looking `i * 15` degrees anticlockwise
//! from the robot's forward axis.
//!
//! - Whisker: 17 cm beyond the body; it triggers when a wall lies within its reach along its
//!   direction. "Fuzzy triggering": the reach jitters by `WHISKER_JITTER_M` each reading, so
//!   a wall at the edge of the reach triggers now and then, and neighbours of a glancing
//!   contact trigger together (the thesis's effective resolution of 15-30 degrees).
//! - Photoresistor: about a 20 degree cone; each visible lamp adds intensity / distance^2
//!   times a Gaussian lobe of the angle off the sensor's axis (sigma 10 degrees, so the cone's
//!   full width at half maximum is about 24 degrees); walls and the pillar cast shadows. The
//!   response is non-linear (saturating) and each sensor has its own gain (uncalibrated),
//!   plus noise.

use crate::arena::Light;
use crate::geometry::{Point, SegmentSet, Vector};
use crate::rng::SimRng;

/// Sensors of each kind.
pub const COUNT: usize = 24;
/// Body radius, metres (40 cm body).
pub const BODY_RADIUS_M: f64 = 0.20;
/// Whisker length beyond the body, metres.
pub const WHISKER_M: f64 = 0.17;
/// Reach jitter of a whisker reading, metres (ours: the thesis says only "fuzzy").
pub const WHISKER_JITTER_M: f64 = 0.03;
/// Photoresistor lobe, radians (sigma).
pub const LIGHT_LOBE_RAD: f64 = 10.0 * std::f64::consts::PI / 180.0;
/// Height of the photoresistors above the floor, metres.
pub const LIGHT_SENSOR_HEIGHT_M: f64 = 0.3;
/// Reading noise (sigma, on the 0..1 reading).
pub const LIGHT_NOISE: f64 = 0.02;
/// Saturation constant of the response `1 - exp(-x / k)` (x in lamp intensity / m^2).
pub const LIGHT_SATURATION: f64 = 0.6;

/// The whiskers as the robot's port reads them: bit `i` for whisker `i`.
pub fn whisker_bits(touch: &[bool; COUNT]) -> u32 {
    touch
        .iter()
        .enumerate()
        .fold(0, |bits, (i, &t)| bits | (u32::from(t) << i))
}

/// The photoresistors as the robot's 8-bit converter reads them: 0 (dark) ..= 255.
pub fn light_bytes(light: &[f64; COUNT]) -> [u8; COUNT] {
    light.map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
}

/// One robot's sensor set: the per-sensor gains drawn once.
#[derive(Clone, Debug)]
pub struct Sensors {
    gains: [f64; COUNT],
    rng: SimRng,
}

impl Sensors {
    /// Gains drawn from `rng` (uniform 0.85..1.15), the rest of `rng` for the noise.
    pub fn new(mut rng: SimRng) -> Self {
        let mut gains = [1.0; COUNT];
        for g in &mut gains {
            *g = 0.85 + 0.3 * rng.uniform();
        }
        Sensors { gains, rng }
    }

    /// Whisker contacts at the true pose.
    pub fn whiskers(&mut self, walls: &SegmentSet, at: Point, heading: f64) -> [bool; COUNT] {
        let mut out = [false; COUNT];
        for (i, o) in out.iter_mut().enumerate() {
            let a = heading + i as f64 * std::f64::consts::TAU / COUNT as f64;
            let reach =
                BODY_RADIUS_M + WHISKER_M + WHISKER_JITTER_M * (2.0 * self.rng.uniform() - 1.0);
            *o = walls
                .ray_cast(at, Vector::new(a.cos(), a.sin()), reach)
                .is_some();
        }
        out
    }

    /// Photoresistor readings (0..1) at the true pose.
    pub fn light(
        &mut self,
        walls: &SegmentSet,
        lights: &[Light],
        at: Point,
        heading: f64,
    ) -> [f64; COUNT] {
        let mut raw = [0.0; COUNT];
        for l in lights {
            if walls.blocks(at, l.position) {
                continue;
            }
            let d = l.position - at;
            let dh = l.height_m - LIGHT_SENSOR_HEIGHT_M;
            let r2 = d.norm_squared() + dh * dh;
            let bearing = d.y.atan2(d.x);
            for (i, v) in raw.iter_mut().enumerate() {
                let axis = heading + i as f64 * std::f64::consts::TAU / COUNT as f64;
                let off = world_model::model::wrap(bearing - axis);
                *v += l.intensity / r2
                    * (-(off * off) / (2.0 * LIGHT_LOBE_RAD * LIGHT_LOBE_RAD)).exp();
            }
        }
        let mut out = [0.0; COUNT];
        for i in 0..COUNT {
            let v = 1.0 - (-self.gains[i] * raw[i] / LIGHT_SATURATION).exp();
            out[i] = (v + self.rng.gaussian(LIGHT_NOISE)).clamp(0.0, 1.0);
        }
        out
    }
}
