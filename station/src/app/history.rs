//! Time series of telemetry for the charts, and the tracks for the map.
//!
//! Layer: app state, no I/O. Telemetry frames are kept whole in a bounded ring (the charts pick
//! their series when they draw), so choosing another series shows its past too. Tracks keep a
//! point only when the robot moved, so a parked robot does not fill them. Bounded; cannot fail.

use std::collections::VecDeque;

use protocol::Telemetry;

/// Telemetry frames kept: 60 s at 20 Hz.
pub const HISTORY: usize = 1200;
/// Track points kept per track.
pub const TRACK: usize = 4000;
/// Smallest move recorded in a track, metres.
const TRACK_STEP_M: f64 = 0.005;

/// Recent telemetry with station times (seconds).
#[derive(Debug, Default)]
pub struct History {
    frames: VecDeque<(f64, Telemetry)>,
}

impl History {
    pub fn push(&mut self, t_s: f64, t: Telemetry) {
        if self.frames.len() == HISTORY {
            self.frames.pop_front();
        }
        self.frames.push_back((t_s, t));
    }

    /// `(t, value)` points of one series.
    pub fn series(&self, s: Series) -> Vec<(f64, f64)> {
        self.frames.iter().map(|(t, f)| (*t, s.value(f))).collect()
    }

    /// Time span held, seconds.
    pub fn span(&self) -> Option<(f64, f64)> {
        Some((self.frames.front()?.0, self.frames.back()?.0))
    }

    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }
}

/// One chartable quantity of a telemetry frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Series {
    Ir(usize),
    Light(usize),
    SpeedLeft,
    SpeedRight,
    MotorLeft,
    MotorRight,
    HeadingDeg,
    CompassDeg,
    BatteryMv,
    BeaconStrength,
    BeaconBearingDeg,
    SigmaMm,
    CyclePeriodMs,
    CycleBusyMs,
}

impl Series {
    pub fn label(&self) -> String {
        match self {
            Series::Ir(i) => format!("IR{i}"),
            Series::Light(i) => format!("L{i}"),
            Series::SpeedLeft => "speed L mm/s".into(),
            Series::SpeedRight => "speed R mm/s".into(),
            Series::MotorLeft => "motor L mm/s".into(),
            Series::MotorRight => "motor R mm/s".into(),
            Series::HeadingDeg => "heading °".into(),
            Series::CompassDeg => "compass °".into(),
            Series::BatteryMv => "battery mV".into(),
            Series::BeaconStrength => "beacon strength".into(),
            Series::BeaconBearingDeg => "beacon bearing °".into(),
            Series::SigmaMm => "σ xy mm".into(),
            Series::CyclePeriodMs => "cycle period ms".into(),
            Series::CycleBusyMs => "cycle busy ms".into(),
        }
    }

    /// The capability bits a robot needs for this series to mean anything (0: every robot).
    pub fn needs(&self) -> u32 {
        use protocol::caps;
        match self {
            Series::Ir(_) => caps::IR_PROXIMITY,
            Series::Light(_) => caps::AMBIENT_LIGHT,
            Series::CompassDeg => caps::COMPASS,
            Series::BatteryMv => caps::BATTERY,
            Series::BeaconStrength | Series::BeaconBearingDeg => caps::BEACON,
            _ => 0,
        }
    }

    /// Whether a robot with `capabilities` has this sensor.
    pub fn offered(&self, capabilities: u32) -> bool {
        capabilities & self.needs() == self.needs()
    }

    pub fn value(&self, t: &Telemetry) -> f64 {
        let at = |v: [u16; 8], i: usize| f64::from(v.get(i).copied().unwrap_or(0));
        match *self {
            Series::Ir(i) => at(t.ir.values(), i),
            Series::Light(i) => at(t.light.values(), i),
            Series::SpeedLeft => f64::from(t.wheels.speed_mm_s[0]),
            Series::SpeedRight => f64::from(t.wheels.speed_mm_s[1]),
            Series::MotorLeft => f64::from(t.behaviour.motor_mm_s[0]),
            Series::MotorRight => f64::from(t.behaviour.motor_mm_s[1]),
            Series::HeadingDeg => {
                f64::from(t.pose.heading_mrad) / 1000.0 * 180.0 / std::f64::consts::PI
            }
            Series::CompassDeg => f64::from(t.compass_ddeg) / 10.0,
            Series::BatteryMv => f64::from(t.battery_mv),
            Series::BeaconStrength => f64::from(t.beacon.strength),
            Series::BeaconBearingDeg => f64::from(t.beacon.bearing_ddeg) / 10.0,
            Series::SigmaMm => f64::from(t.sigma.xy_mm),
            Series::CyclePeriodMs => f64::from(t.cycle.period_us) / 1000.0,
            Series::CycleBusyMs => f64::from(t.cycle.busy_us) / 1000.0,
        }
    }
}

/// Named sets of series; `c` steps through them.
pub const CHART_PRESETS: &[(&str, &[Series])] = &[
    (
        "IR proximity",
        &[Series::Ir(0), Series::Ir(2), Series::Ir(3), Series::Ir(5)],
    ),
    (
        "Ambient light",
        &[
            Series::Light(0),
            Series::Light(2),
            Series::Light(3),
            Series::Light(5),
        ],
    ),
    (
        "Wheels",
        &[
            Series::SpeedLeft,
            Series::SpeedRight,
            Series::MotorLeft,
            Series::MotorRight,
        ],
    ),
    ("Heading", &[Series::HeadingDeg, Series::CompassDeg]),
    (
        "Beacon",
        &[Series::BeaconStrength, Series::BeaconBearingDeg],
    ),
    ("Battery", &[Series::BatteryMv]),
    ("Uncertainty", &[Series::SigmaMm]),
    (
        "Control cycle",
        &[Series::CyclePeriodMs, Series::CycleBusyMs],
    ),
];

/// The series of `preset` a robot with `capabilities` has (None: not yet known, all).
pub fn offered_series(preset: usize, capabilities: Option<u32>) -> Vec<Series> {
    CHART_PRESETS
        .get(preset)
        .map(|(_, series)| {
            series
                .iter()
                .filter(|s| capabilities.is_none_or(|c| s.offered(c)))
                .copied()
                .collect()
        })
        .unwrap_or_default()
}

/// The first preset from `from` on (wrapping) with a series the robot has: charts of sensors
/// it lacks are not offered.
pub fn offered_preset(from: usize, capabilities: Option<u32>) -> usize {
    let n = CHART_PRESETS.len();
    (0..n)
        .map(|i| (from + i) % n)
        .find(|&i| !offered_series(i, capabilities).is_empty())
        .unwrap_or(0)
}

/// A polyline of poses, metres.
#[derive(Debug, Default)]
pub struct Track {
    points: VecDeque<(f64, f64)>,
}

impl Track {
    pub fn push(&mut self, x: f64, y: f64) {
        if let Some(&(lx, ly)) = self.points.back() {
            if (x - lx).hypot(y - ly) < TRACK_STEP_M {
                return;
            }
        }
        if self.points.len() == TRACK {
            self.points.pop_front();
        }
        self.points.push_back((x, y));
    }

    pub fn points(&self) -> impl Iterator<Item = &(f64, f64)> {
        self.points.iter()
    }

    pub fn len(&self) -> usize {
        self.points.len()
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    pub fn clear(&mut self) {
        self.points.clear();
    }
}

/// Unwraps the wire's 16-bit encoder counts into cumulative counts.
#[derive(Debug, Default, Clone, Copy)]
pub struct EncoderUnwrap {
    last: Option<[u16; 2]>,
    pub total: [i64; 2],
}

impl EncoderUnwrap {
    pub fn push(&mut self, raw: [u16; 2]) {
        if let Some(last) = self.last {
            for (i, (r, l)) in raw.iter().zip(last).enumerate() {
                // The shortest way round the 2^16 circle is the wheel's motion.
                let d = i64::from(r.wrapping_sub(l) as i16);
                if let Some(t) = self.total.get_mut(i) {
                    *t += d;
                }
            }
        } else {
            self.total = [i64::from(raw[0]), i64::from(raw[1])];
        }
        self.last = Some(raw);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn encoders_unwrap_across_the_16_bit_boundary_both_ways() {
        let mut e = EncoderUnwrap::default();
        e.push([65_530, 10]);
        e.push([4, 65_530]);
        assert_eq!(e.total, [65_540, -6]);
    }

    #[test]
    fn charts_are_offered_only_for_sensors_the_robot_has() {
        use protocol::caps;
        // Dom Dinis: compass, IR, beacon; no ambient light, no battery sensor.
        let dom = caps::COMPASS | caps::IR_PROXIMITY | caps::BEACON;
        let names = |c: Option<u32>| -> Vec<&str> {
            let mut seen = Vec::new();
            let mut i = offered_preset(0, c);
            for _ in 0..CHART_PRESETS.len() {
                if !seen.contains(&CHART_PRESETS[i].0) {
                    seen.push(CHART_PRESETS[i].0);
                }
                i = offered_preset(i + 1, c);
            }
            seen
        };
        let offered = names(Some(dom));
        assert!(!offered.contains(&"Ambient light"), "{offered:?}");
        assert!(!offered.contains(&"Battery"), "{offered:?}");
        assert!(offered.contains(&"Beacon") && offered.contains(&"IR proximity"));
        assert_eq!(
            names(None).len(),
            CHART_PRESETS.len(),
            "before the handshake: all"
        );
        // A robot without a compass still charts its heading, without the compass series.
        let heading = CHART_PRESETS.iter().position(|p| p.0 == "Heading").unwrap();
        assert_eq!(offered_series(heading, Some(0)), [Series::HeadingDeg]);
    }

    #[test]
    fn a_track_ignores_jitter_below_five_millimetres() {
        let mut t = Track::default();
        t.push(0.0, 0.0);
        t.push(0.001, 0.0);
        t.push(0.01, 0.0);
        assert_eq!(t.len(), 2);
    }
}
