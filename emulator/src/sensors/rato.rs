//! The micro-rato's compass and beacon sensor (seed 004 §3), and the battery of either robot.
//!
//! - Compass: a new reading about 5 times a second (seed 004 §3), `None` in between; the true
//!   heading plus Gaussian noise of 2 degrees RMS, rounded to the 1 degree resolution, in
//!   radians counter-clockwise from +x in (-pi, pi] (the `Hal` convention).
//! - Beacon: the real sensor is an IR receiver in a tube at the front (seed 004 §3). Modelled
//!   as a receiver with a field of view of +-60 degrees that reports the bearing (relative to
//!   the heading, positive to the left, with noise) and a strength from the firmware's own
//!   [`BeaconModel::strength_at`] curve (so the firmware's distance model is right for a
//!   nominal sensor) with relative noise. Strength 0 (bearing 0) when the beacon is outside
//!   the field of view, hidden by a wall taller than the beacon, or farther than the model's
//!   farthest point (the signal is lost in the background there). With several beacons the
//!   receiver tells them apart, as CiberRato's sensor does (`GetBeaconSensor(id)`), and reads
//!   its own: [`BeaconSensor::read_channel`].
//! - Battery: starts at `start_mv` and drains linearly with time plus a term proportional to
//!   motor effort; the reading carries Gaussian noise. Micro-rato: starts at 8.0 V, which the
//!   firmware's default battery scale (7.0 V empty .. 9.0 V full) reads as level 0.5, the
//!   "average battery" at which seed 004 §4 measured 0.23 m/s; drains 0.1 mV/s idle plus
//!   1 mV/s at full effort (a 10-minute full-speed run loses 0.66 V, a third of the scale).
//!   Khepera: four Ni-Cd cells, 4.8 V nominal (seed 000 §1.1), starting charged at 5.2 V;
//!   its speed controller makes speed independent of the battery.
//!
//! Invariants: compass readings in (-pi, pi]; strength 0..=255; voltage readings 0..=65535.
//! Cannot fail.

use robot_firmware::deadreckon::BeaconModel;
use robot_firmware::hal::BeaconReading;
use robot_firmware::params::RobotConfig;
use robot_firmware::Profile;

use crate::arena::Pose;
use crate::geometry::{Disc, Point};
use crate::physics::wrap_pi;
use crate::rng::SimRng;
use crate::world::WorldBeacon;

/// Compass period: seed 004 §3, "about 5 readings per second".
pub const COMPASS_PERIOD_US: u64 = 200_000;
/// Compass resolution: seed 004 §3, 1 degree.
pub const COMPASS_RESOLUTION_DEG: f64 = 1.0;
/// Beacon receiver half field of view (documented model choice, see the module text).
pub const BEACON_HALF_FOV_RAD: f64 = 60.0 * std::f64::consts::PI / 180.0;

/// A compass that produces a reading every [`COMPASS_PERIOD_US`].
#[derive(Clone, Debug)]
pub struct Compass {
    present: bool,
    sigma_rad: f64,
    next_us: u64,
    rng: SimRng,
}

impl Compass {
    /// A compass with noise `sigma_deg` (absent: always `None`).
    pub fn new(present: bool, sigma_deg: f64, rng: SimRng) -> Compass {
        Compass {
            present,
            sigma_rad: sigma_deg.to_radians(),
            next_us: 0,
            rng,
        }
    }

    /// A new reading if one is due at `now_us`, else `None`.
    pub fn read(&mut self, now_us: u64, true_heading: f64) -> Option<f32> {
        if !self.present || now_us < self.next_us {
            return None;
        }
        // Keep the reading grid; after a long gap restart it from now.
        self.next_us = if self.next_us + COMPASS_PERIOD_US > now_us {
            self.next_us + COMPASS_PERIOD_US
        } else {
            now_us + COMPASS_PERIOD_US
        };
        let noisy = true_heading + self.rng.gaussian(self.sigma_rad);
        let step = COMPASS_RESOLUTION_DEG.to_radians();
        let quantised = (noisy / step).round() * step;
        Some(wrap_pi(quantised) as f32)
    }
}

/// The beacon receiver.
#[derive(Clone, Debug)]
pub struct BeaconSensor {
    present: bool,
    model: BeaconModel,
    bearing_sigma_rad: f64,
    strength_sigma: f64,
    rng: SimRng,
}

impl BeaconSensor {
    /// A receiver using the firmware's default beacon curve.
    pub fn new(present: bool, bearing_deg: f64, strength_rel: f64, rng: SimRng) -> BeaconSensor {
        BeaconSensor {
            present,
            model: BeaconModel::default(),
            bearing_sigma_rad: bearing_deg.to_radians(),
            strength_sigma: strength_rel,
            rng,
        }
    }

    /// One reading; `None` on a robot without a beacon sensor.
    pub fn read(&mut self, beacon: Option<&WorldBeacon>, pose: Pose) -> Option<BeaconReading> {
        self.read_among(beacon, &[], pose)
    }

    /// One reading with other robots' bodies (`others`) able to stand between the receiver
    /// and the beacon: a robot in the line of sight hides it (the beacon is a 940 nm light at
    /// the goal's centre, seed 004 §2, and the robots are as tall as their sensors).
    pub fn read_among(
        &mut self,
        beacon: Option<&WorldBeacon>,
        others: &[Disc],
        pose: Pose,
    ) -> Option<BeaconReading> {
        if !self.present {
            return None;
        }
        let none = BeaconReading {
            bearing_rad: 0.0,
            strength: 0,
        };
        let Some(b) = beacon else { return Some(none) };
        let Some((distance, bearing)) = self.sees(b, others, pose) else {
            return Some(none);
        };
        let nominal = f64::from(self.model.strength_at(distance as f32));
        let strength = nominal * (1.0 + self.rng.gaussian(self.strength_sigma));
        let noisy_bearing = wrap_pi(bearing + self.rng.gaussian(self.bearing_sigma_rad));
        Some(BeaconReading {
            bearing_rad: noisy_bearing as f32,
            strength: strength.round().clamp(0.0, 255.0) as u8,
        })
    }

    /// The reading of beacon `id` of several (CiberRato's `GetBeaconSensor(id)`: beacons are
    /// told apart, numbered in the lab file's order), with other robots able to hide it
    /// ([`BeaconSensor::read_among`]); no beacon `id`: nothing seen. A receiver that locked on
    /// the strongest signal instead read the nearer of two beacons while the robot corrected
    /// its position against the first: pose jumps of the beacons' distance (issue 32).
    pub fn read_channel(
        &mut self,
        beacons: &[WorldBeacon],
        id: usize,
        others: &[Disc],
        pose: Pose,
    ) -> Option<BeaconReading> {
        self.read_among(beacons.get(id), others, pose)
    }

    /// Distance and bearing (relative to the heading) of a beacon the receiver sees: inside
    /// its field of view and range, not hidden by a wall as tall as the beacon.
    fn sees(&self, b: &WorldBeacon, others: &[Disc], pose: Pose) -> Option<(f64, f64)> {
        let here = Point::new(pose.x, pose.y);
        let v = b.position - here;
        let distance = v.norm();
        let bearing = wrap_pi(v.y.atan2(v.x) - pose.heading);
        let farthest = f64::from(self.model.distance_m.last().copied().unwrap_or(0.0));
        let seen = !distance.is_nan()
            && distance <= farthest
            && bearing.abs() <= BEACON_HALF_FOV_RAD
            && b.visible_from(here)
            && !others.iter().any(|o| o.blocks(here, b.position));
        seen.then_some((distance, bearing))
    }
}

/// A draining battery.
#[derive(Clone, Debug)]
pub struct Battery {
    present: bool,
    mv: f64,
    idle_mv_per_s: f64,
    effort_mv_per_s: f64,
    sigma_mv: f64,
    /// The firmware's default empty and full voltages (for the true battery level).
    empty_mv: f64,
    full_mv: f64,
    rng: SimRng,
}

impl Battery {
    /// The battery of `profile` (see the module text for the numbers).
    pub fn for_profile(profile: &Profile, sigma_mv: f64, rng: SimRng) -> Battery {
        let rato = profile.id == protocol::ProfileId::MicroRato;
        let cfg = RobotConfig::default();
        Battery {
            present: profile.has(protocol::caps::BATTERY),
            mv: if rato { 8000.0 } else { 5200.0 },
            idle_mv_per_s: 0.1,
            effort_mv_per_s: 1.0,
            sigma_mv,
            empty_mv: f64::from(cfg.battery_empty_mv),
            full_mv: f64::from(cfg.battery_full_mv),
            rng,
        }
    }

    /// True voltage, millivolts.
    pub fn true_mv(&self) -> f64 {
        self.mv
    }

    /// True level on the firmware's default scale, 0..=1 (what the speed table is indexed by).
    pub fn level(&self) -> f64 {
        let span = self.full_mv - self.empty_mv;
        if span <= 0.0 {
            return 0.5;
        }
        ((self.mv - self.empty_mv) / span).clamp(0.0, 1.0)
    }

    /// Drains for `dt_s` seconds at motor `effort` (0 = stopped, 1 = both motors at maximum).
    pub fn drain(&mut self, dt_s: f64, effort: f64) {
        let e = effort.clamp(0.0, 1.0);
        let used = (self.idle_mv_per_s + self.effort_mv_per_s * e) * dt_s.max(0.0);
        self.mv = (self.mv - used).max(0.0);
    }

    /// The reading, millivolts; 0 without a battery monitor.
    pub fn read(&mut self) -> u16 {
        if !self.present {
            return 0;
        }
        (self.mv + self.rng.gaussian(self.sigma_mv))
            .round()
            .clamp(0.0, f64::from(u16::MAX)) as u16
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compass_reads_every_200_ms_rounded_to_a_degree() {
        let mut c = Compass::new(true, 0.0, SimRng::new(1, 1));
        assert!(c.read(0, 0.3).is_some());
        assert!(c.read(50_000, 0.3).is_none());
        assert!(c.read(199_999, 0.3).is_none());
        let h = c.read(200_000, 0.3).unwrap_or(f32::NAN);
        assert!((f64::from(h) - 17f64.to_radians()).abs() < 1e-6, "{h}");
        assert!(Compass::new(false, 0.0, SimRng::new(1, 1))
            .read(0, 0.0)
            .is_none());
    }

    #[test]
    fn battery_level_starts_average_for_the_micro_rato() {
        let b = Battery::for_profile(&robot_firmware::MICRO_RATO, 0.0, SimRng::new(1, 1));
        assert!((b.level() - 0.5).abs() < 1e-12);
        let mut b2 = b.clone();
        b2.drain(600.0, 1.0);
        assert!((b2.true_mv() - (8000.0 - 660.0)).abs() < 1e-6);
    }
}
