//! Compass dead reckoning with bounds validation and beacon calibration (seed 004 §4).
//!
//! Layer: pure position arithmetic for the micro-rato profile, which has no wheel encoders.
//! [`DeadReckoner::step`] integrates `x += v dt cos θ, y += v dt sin θ` from the compass
//! heading θ, a speed looked up in a [`SpeedTable`] (nominal speed command x battery level,
//! seed 004 §4's 2-D interpolation) and the time since the previous step; the result is
//! validated against the arena bounds. [`DeadReckoner::calibrate`] blends in the position
//! implied by the goal beacon, `P = ξ P + (1-ξ) P_l`, and confidence ξ rises with calibrations
//! and falls with degrading events ([`DegradeEvent`]). No I/O, no clock (time is passed in as
//! `now_ms`), no heap.
//!
//! Invariants: the position always lies inside the validation rectangle; ξ stays in [0, 1];
//! a single step never integrates more than `max_dt_ms` (a stalled loop must not teleport the
//! robot). What can fail: a calibration with a beacon signal weaker than the model's range
//! ([`CalibrationError::SignalTooWeak`]); it leaves the state unchanged.

use crate::odometry::Point;

/// Number of nominal speeds in the speed table (seed 004 §4: 25, 50 and 75).
pub const SPEED_ROWS: usize = 3;
/// Number of battery levels in the speed table.
pub const BATTERY_COLS: usize = 3;
/// Number of points in the beacon strength -> distance model.
pub const BEACON_POINTS: usize = 8;

/// Real speed as a 2-D interpolation over nominal speed command and battery level (seed 004 §4).
///
/// Bilinear inside the table, clamped to the table's battery range, linear to zero below the
/// first nominal speed and clamped above the last; negative commands (reverse) mirror positive
/// ones. The paper gives one point (75 at average battery = 0.23 m/s); the rest of the default
/// table is a placeholder shaped like a DC motor on a sagging battery, to be replaced by the
/// robot's own measurements over the link.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpeedTable {
    /// Nominal speed commands, increasing. seed 004 §4: 25, 50, 75.
    pub nominal: [f32; SPEED_ROWS],
    /// Battery levels, increasing, as a fraction 0 (cut-off) .. 1 (full); 0.5 is "average".
    pub battery: [f32; BATTERY_COLS],
    /// Real speed in m/s, `mps[row of nominal][column of battery]`.
    pub mps: [[f32; BATTERY_COLS]; SPEED_ROWS],
}

impl Default for SpeedTable {
    fn default() -> Self {
        Self {
            nominal: [25.0, 50.0, 75.0],
            battery: [0.0, 0.5, 1.0],
            // seed 004 §4: nominal 75 at average battery (0.5) = 0.23 m/s. Other entries are
            // placeholders: low speeds lose more to friction, a flat battery ~15 % slower.
            mps: [
                [0.060, 0.070, 0.078],
                [0.130, 0.150, 0.165],
                [0.200, 0.230, 0.250],
            ],
        }
    }
}

impl SpeedTable {
    /// Real speed in m/s for a nominal speed command at a battery level.
    #[inline]
    pub fn speed_mps(&self, nominal: f32, battery: f32) -> f32 {
        let (b0, b1, tb) = bracket(&self.battery, battery);
        self.speed_on_row(&self.row(nominal), b0, b1, tb)
    }

    /// Both wheels' speeds at one battery level: [`SpeedTable::speed_mps`] of each, bit for
    /// bit, with the battery bracketed once.
    #[inline]
    pub fn speeds_mps(&self, nominal: [f32; 2], battery: f32) -> [f32; 2] {
        self.speeds_on_rows(&[self.row(nominal[0]), self.row(nominal[1])], battery)
    }

    /// Where a nominal speed command falls among the rows. It depends on the command only,
    /// so a caller that looks speeds up far more often than the command changes (the
    /// emulator's motors, every simulated millisecond) finds it once per command and passes
    /// it to [`SpeedTable::speeds_on_rows`].
    #[inline]
    pub fn row(&self, nominal: f32) -> SpeedRow {
        let sign = if nominal < 0.0 { -1.0 } else { 1.0 };
        let n = nominal * sign;
        let below = n <= self.nominal[0];
        // Below the first row the speed is linear in the first row's: no bracket needed.
        let (r0, r1, tn) = if below {
            (0, 0, 0.0)
        } else {
            bracket(&self.nominal, n)
        };
        SpeedRow {
            sign,
            n,
            below,
            lo: self.mps[r0],
            hi: self.mps[r1],
            tn,
        }
    }

    /// Both wheels' speeds at one battery level from their rows ([`SpeedTable::row`]): the
    /// same bits as [`SpeedTable::speeds_mps`], interpolating only the rows they need.
    #[inline]
    pub fn speeds_on_rows(&self, rows: &[SpeedRow; 2], battery: f32) -> [f32; 2] {
        let (b0, b1, tb) = bracket(&self.battery, battery);
        [
            self.speed_on_row(&rows[0], b0, b1, tb),
            self.speed_on_row(&rows[1], b0, b1, tb),
        ]
    }

    /// The speed on `row` with the battery between columns `b0` and `b1` at fraction `tb`.
    #[inline]
    fn speed_on_row(&self, row: &SpeedRow, b0: usize, b1: usize, tb: f32) -> f32 {
        let at = |r: &[f32; BATTERY_COLS]| lerp(r[b0], r[b1], tb);
        let v = if row.below {
            // Below the first row: linear down to zero at a zero command.
            if self.nominal[0] > 0.0 {
                at(&row.lo) * row.n / self.nominal[0]
            } else {
                at(&row.lo)
            }
        } else {
            lerp(at(&row.lo), at(&row.hi), row.tn)
        };
        row.sign * v
    }
}

/// Where one nominal speed command falls in a [`SpeedTable`] ([`SpeedTable::row`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpeedRow {
    /// -1 for reverse (mirrored), else 1.
    sign: f32,
    /// The command's magnitude.
    n: f32,
    /// At or below the first row.
    below: bool,
    /// The rows around the command (copied: no index to check every lookup; the first
    /// row twice when `below`) and the fraction between them.
    lo: [f32; BATTERY_COLS],
    hi: [f32; BATTERY_COLS],
    tn: f32,
}

/// Indices `(i, i+1)` of `xs` around `x` and the fraction between them, clamped at both ends.
#[inline]
fn bracket<const N: usize>(xs: &[f32; N], x: f32) -> (usize, usize, f32) {
    let last = N.saturating_sub(1);
    if N < 2 || x <= xs[0] {
        return (0, 0, 0.0);
    }
    if x >= xs[last] {
        return (last, last, 0.0);
    }
    let mut i = 0;
    while i + 1 < last && x > xs[i + 1] {
        i += 1;
    }
    let span = xs[i + 1] - xs[i];
    let t = if span > 0.0 { (x - xs[i]) / span } else { 0.0 };
    (i, i + 1, t)
}

#[inline]
fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a + (b - a) * t
}

/// Goal-beacon signal strength -> distance model (seed 004 §4, Fig. 3: accuracy ±0.3 m).
///
/// Piecewise linear through `(strength[i], distance_m[i])`, strength decreasing with distance.
/// Fig. 3's curve is not in the text; the default is a placeholder of roughly inverse-square
/// shape over an 8-bit reading. The emulator should use [`BeaconModel::strength_at`] so both
/// sides agree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BeaconModel {
    /// Raw sensor readings, strictly decreasing.
    pub strength: [u16; BEACON_POINTS],
    /// Distances in metres for each reading, strictly increasing.
    pub distance_m: [f32; BEACON_POINTS],
}

impl Default for BeaconModel {
    fn default() -> Self {
        Self {
            strength: [250, 180, 130, 100, 65, 45, 25, 15],
            distance_m: [0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0],
        }
    }
}

impl BeaconModel {
    /// Distance in metres for a reading; `None` below the weakest modelled reading. Readings
    /// above the strongest saturate at the nearest distance.
    pub fn distance_for(&self, strength: u16) -> Option<f32> {
        let last = BEACON_POINTS - 1;
        if strength < self.strength[last] {
            return None;
        }
        if strength >= self.strength[0] {
            return Some(self.distance_m[0]);
        }
        let mut i = 0;
        while i + 1 < last && strength < self.strength[i + 1] {
            i += 1;
        }
        let (s0, s1) = (f32::from(self.strength[i]), f32::from(self.strength[i + 1]));
        let t = if s0 > s1 {
            (s0 - f32::from(strength)) / (s0 - s1)
        } else {
            0.0
        };
        Some(lerp(self.distance_m[i], self.distance_m[i + 1], t))
    }

    /// The reading this model expects at `distance_m` (the inverse of `distance_for`).
    pub fn strength_at(&self, distance_m: f32) -> u16 {
        let (i0, i1, t) = bracket(&self.distance_m, distance_m);
        let s = lerp(
            f32::from(self.strength[i0]),
            f32::from(self.strength[i1]),
            t,
        );
        libm::roundf(s) as u16
    }
}

/// Axis-aligned validation rectangle for the robot centre, metres (seed 004 §4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// Lower-left corner of the arena's inside.
    pub min: Point,
    /// Upper-right corner of the arena's inside.
    pub max: Point,
    /// How far the robot centre stays from the walls (its radius), metres.
    pub margin_m: f32,
}

impl Default for Bounds {
    fn default() -> Self {
        Self {
            // seed 004 §2: 5 x 5 m arena
            min: Point::new(0.0, 0.0),
            max: Point::new(5.0, 5.0),
            // seed 004 §3: round robot of 24 cm diameter
            margin_m: 0.12,
        }
    }
}

impl Bounds {
    /// The closest point inside the bounds (seed 004 §4: validation); returns it and whether
    /// it differs from `p`.
    pub fn clamp(&self, p: Point) -> (Point, bool) {
        let lo = (self.min.x + self.margin_m, self.min.y + self.margin_m);
        let hi = (self.max.x - self.margin_m, self.max.y - self.margin_m);
        // A degenerate rectangle collapses to its centre instead of panicking in clamp().
        let fit = |v: f32, a: f32, b: f32| {
            if a <= b {
                v.max(a).min(b)
            } else {
                (a + b) / 2.0
            }
        };
        let q = Point::new(fit(p.x, lo.0, hi.0), fit(p.y, lo.1, hi.1));
        (q, q != p)
    }
}

/// Dead-reckoning parameters (all settable over the link).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeadReckonParams {
    /// Nominal speed x battery -> real speed (seed 004 §4).
    pub speed: SpeedTable,
    /// Beacon reading -> distance (seed 004 §4, Fig. 3).
    pub beacon_model: BeaconModel,
    /// Position of the goal beacon, metres. Default: arena centre (Micro-Rato goal area).
    pub beacon: Point,
    /// Validation rectangle (seed 004 §4).
    pub bounds: Bounds,
    /// Confidence at start: 1, the start pose is known exactly (seed 004 §5).
    pub xi_initial: f32,
    /// Confidence added by a calibration (seed 004 §4: "increased when calibration is
    /// performed"; amount not given).
    pub xi_calibration_gain: f32,
    /// Confidence removed by a collision (seed 004 §4; amount not given).
    pub xi_collision_loss: f32,
    /// Confidence removed by a dead end (seed 004 §4; amount not given).
    pub xi_dead_end_loss: f32,
    /// Longest interval one step integrates, ms; longer gaps (a stalled loop) are capped.
    pub max_dt_ms: u32,
}

impl Default for DeadReckonParams {
    fn default() -> Self {
        Self {
            speed: SpeedTable::default(),
            beacon_model: BeaconModel::default(),
            beacon: Point::new(2.5, 2.5),
            bounds: Bounds::default(),
            xi_initial: 1.0,
            xi_calibration_gain: 0.2,
            xi_collision_loss: 0.1,
            xi_dead_end_loss: 0.25,
            // five compass readings per second (seed 004 §3): 200 ms; allow a missed one
            max_dt_ms: 500,
        }
    }
}

/// Inputs of one dead-reckoning step.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct DeadReckonInput {
    /// Compass heading θ, radians counter-clockwise from +x (the profile converts compass
    /// degrees to this).
    pub heading_rad: f32,
    /// Nominal speed command of each wheel, left and right (seed 004 §4: 25, 50, 75;
    /// negative = reverse). Each wheel goes through the speed table before averaging, since
    /// the table is not linear: a turning robot's forward speed is the mean of its wheels'.
    pub nominal: [f32; 2],
    /// Battery level, same scale as [`SpeedTable::battery`].
    pub battery: f32,
}

/// Events that degrade position accuracy (seed 004 §4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DegradeEvent {
    /// Bumped into a wall or another robot.
    Collision,
    /// Ended up in a dead end.
    DeadEnd,
}

/// Why a calibration was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CalibrationError {
    /// The beacon reading is below the model's weakest point: distance unknown.
    SignalTooWeak,
}

impl core::fmt::Display for CalibrationError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::SignalTooWeak => f.write_str("beacon signal below the distance model's range"),
        }
    }
}

/// Compass dead-reckoning state (seed 004 §4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeadReckoner {
    /// Parameters in use.
    pub params: DeadReckonParams,
    position: Point,
    xi: f32,
    last_ms: Option<u32>,
    clamped: bool,
    /// The position as given (start or `set_position`), before validation, kept until the
    /// robot moves: bounds that arrive later (the arena's, after the robot was built with
    /// the default 5 x 5 m) validate the given point again, not its clamp into the old ones.
    given: Option<Point>,
}

impl DeadReckoner {
    /// Starts at `start` (validated) with confidence `xi_initial`.
    pub fn new(params: DeadReckonParams, start: Point) -> Self {
        let (position, _) = params.bounds.clamp(start);
        Self {
            params,
            position,
            xi: params.xi_initial.clamp(0.0, 1.0),
            last_ms: None,
            clamped: false,
            given: Some(start),
        }
    }

    /// Replaces the validation rectangle (seed 004 §4) and validates the position again: a
    /// position given before the robot moved is re-validated as given, so a start outside the
    /// old bounds but inside the new ones is kept exactly.
    pub fn set_bounds(&mut self, bounds: Bounds) {
        self.params.bounds = bounds;
        self.bounds_changed();
    }

    /// Validates the position again after `params.bounds` changed in place (a parameter set
    /// over the link).
    pub fn bounds_changed(&mut self) {
        let p = self.given.unwrap_or(self.position);
        (self.position, _) = self.params.bounds.clamp(p);
    }

    /// Integrates from the previous call to `now_ms` (wrapping) at the given heading and
    /// speed, validates the result, and returns it. The first call only sets the time origin.
    pub fn step(&mut self, now_ms: u32, input: DeadReckonInput) -> Point {
        let dt_ms = match self.last_ms {
            Some(last) => now_ms.wrapping_sub(last).min(self.params.max_dt_ms),
            None => 0,
        };
        self.last_ms = Some(now_ms);
        let [l, r] = input
            .nominal
            .map(|n| self.params.speed.speed_mps(n, input.battery));
        let v = (l + r) * 0.5;
        // seed 004 §4: Δs = v Δt; x += Δs cos θ; y += Δs sin θ
        let ds = v * dt_ms as f32 * 1e-3;
        let moved = Point::new(
            self.position.x + ds * libm::cosf(input.heading_rad),
            self.position.y + ds * libm::sinf(input.heading_rad),
        );
        // seed 004 §4: outside the arena -> the closest point inside.
        let (p, clamped) = self.params.bounds.clamp(moved);
        if ds != 0.0 {
            // Moved: the estimate is the robot's own now, validated in the bounds it has.
            self.given = None;
        }
        self.position = p;
        self.clamped = clamped;
        p
    }

    /// Beacon calibration (seed 004 §4): `strength` read while facing the beacon along the
    /// compass bearing `bearing_rad` gives `P_l = beacon - dist (cos b, sin b)`; then
    /// `P = ξ P + (1-ξ) P_l` with the current ξ, after which ξ rises by the calibration gain.
    pub fn calibrate(
        &mut self,
        strength: u16,
        bearing_rad: f32,
    ) -> Result<Point, CalibrationError> {
        let dist = self
            .params
            .beacon_model
            .distance_for(strength)
            .ok_or(CalibrationError::SignalTooWeak)?;
        let b = self.params.beacon;
        let (p_l, _) = self.params.bounds.clamp(Point::new(
            b.x - dist * libm::cosf(bearing_rad),
            b.y - dist * libm::sinf(bearing_rad),
        ));
        let xi = self.xi;
        let blended = Point::new(
            xi * self.position.x + (1.0 - xi) * p_l.x,
            xi * self.position.y + (1.0 - xi) * p_l.y,
        );
        (self.position, _) = self.params.bounds.clamp(blended);
        self.given = None;
        self.xi = (xi + self.params.xi_calibration_gain).clamp(0.0, 1.0);
        Ok(p_l)
    }

    /// Lowers the confidence for an event that degrades accuracy (seed 004 §4).
    pub fn degrade(&mut self, event: DegradeEvent) {
        let loss = match event {
            DegradeEvent::Collision => self.params.xi_collision_loss,
            DegradeEvent::DeadEnd => self.params.xi_dead_end_loss,
        };
        self.xi = (self.xi - loss).clamp(0.0, 1.0);
    }

    /// Current position estimate, metres.
    pub fn position(&self) -> Point {
        self.position
    }

    /// Replaces the position (validated), e.g. from a known start area.
    pub fn set_position(&mut self, p: Point) {
        (self.position, _) = self.params.bounds.clamp(p);
        self.given = Some(p);
    }

    /// Confidence ξ in [0, 1].
    pub fn confidence(&self) -> f32 {
        self.xi
    }

    /// Whether the last step had to pull the position back inside the bounds.
    pub fn was_clamped(&self) -> bool {
        self.clamped
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table's lookup as it was written before rows were found once per command: every
    /// row interpolated at the battery level, then the command's rows.
    fn speed_by_column(t: &SpeedTable, nominal: f32, battery: f32) -> f32 {
        let (b0, b1, tb) = bracket(&t.battery, battery);
        let column = t.mps.map(|row| lerp(row[b0], row[b1], tb));
        let sign = if nominal < 0.0 { -1.0 } else { 1.0 };
        let n = nominal * sign;
        let v = if n <= t.nominal[0] {
            if t.nominal[0] > 0.0 {
                column[0] * n / t.nominal[0]
            } else {
                column[0]
            }
        } else {
            let (r0, r1, tn) = bracket(&t.nominal, n);
            lerp(column[r0], column[r1], tn)
        };
        sign * v
    }

    #[test]
    fn rows_found_once_give_the_same_bits_as_the_whole_column() {
        let odd = SpeedTable {
            nominal: [0.0, 40.0, 40.0],
            battery: [0.2, 0.2, 0.9],
            mps: [[0.01, 0.02, 0.03], [0.1, 0.3, 0.2], [0.5, 0.4, 0.6]],
        };
        for t in [SpeedTable::default(), odd] {
            for cmd in -130i16..=130 {
                let row = t.row(f32::from(cmd));
                for b in 0..=24 {
                    let battery = b as f32 / 20.0 - 0.1;
                    let want = speed_by_column(&t, f32::from(cmd), battery);
                    let both = t.speeds_on_rows(&[row, t.row(7.0)], battery);
                    assert_eq!(both[0].to_bits(), want.to_bits(), "{cmd} at {battery}");
                    assert_eq!(
                        t.speed_mps(f32::from(cmd), battery).to_bits(),
                        want.to_bits()
                    );
                    let pair = t.speeds_mps([7.0, f32::from(cmd)], battery);
                    assert_eq!(pair[1].to_bits(), want.to_bits());
                }
            }
        }
    }

    fn reckoner_at(x: f32, y: f32) -> DeadReckoner {
        DeadReckoner::new(DeadReckonParams::default(), Point::new(x, y))
    }

    fn input(heading_rad: f32, nominal_speed: f32) -> DeadReckonInput {
        DeadReckonInput {
            heading_rad,
            nominal: [nominal_speed; 2],
            battery: 0.5,
        }
    }

    #[test]
    fn nominal_75_at_average_battery_is_0_23_metres_per_second() {
        let t = SpeedTable::default();
        assert!((t.speed_mps(75.0, 0.5) - 0.23).abs() < 1e-6);
        assert!((t.speed_mps(-75.0, 0.5) + 0.23).abs() < 1e-6);
        assert_eq!(t.speed_mps(0.0, 0.5), 0.0);
    }

    #[test]
    fn speed_interpolates_bilinearly_and_clamps_outside_the_table() {
        let t = SpeedTable::default();
        // Halfway between 50 and 75 at battery 0.75 (halfway between 0.5 and 1.0).
        let want = ((0.150 + 0.165) / 2.0 + (0.230 + 0.250) / 2.0) / 2.0;
        assert!((t.speed_mps(62.5, 0.75) - want).abs() < 1e-6);
        assert!((t.speed_mps(12.5, 0.5) - 0.035).abs() < 1e-6);
        assert_eq!(t.speed_mps(100.0, 2.0), 0.250);
        assert_eq!(t.speed_mps(75.0, -1.0), 0.200);
    }

    #[test]
    fn step_moves_along_the_compass_heading_for_the_elapsed_time() {
        let mut r = reckoner_at(1.0, 1.0);
        assert_eq!(r.step(1000, input(0.0, 75.0)), Point::new(1.0, 1.0));
        let p = r.step(1400, input(core::f32::consts::FRAC_PI_2, 75.0));
        assert!((p.x - 1.0).abs() < 1e-6 && (p.y - 1.092).abs() < 1e-6);
        let p = r.step(1600, input(core::f32::consts::PI, 75.0));
        assert!((p.x - (1.0 - 0.046)).abs() < 1e-6);
    }

    #[test]
    fn a_stalled_loop_integrates_at_most_max_dt() {
        let mut r = reckoner_at(1.0, 1.0);
        r.step(0, input(0.0, 75.0));
        let p = r.step(60_000, input(0.0, 75.0));
        assert!((p.x - (1.0 + 0.23 * 0.5)).abs() < 1e-6);
    }

    #[test]
    fn clock_wrap_is_a_short_interval() {
        let mut r = reckoner_at(1.0, 1.0);
        r.step(u32::MAX - 99, input(0.0, 75.0));
        let p = r.step(100, input(0.0, 75.0));
        assert!((p.x - (1.0 + 0.23 * 0.2)).abs() < 1e-6);
    }

    #[test]
    fn position_outside_the_arena_becomes_the_closest_inside_point() {
        let mut r = reckoner_at(4.8, 0.5);
        r.step(0, input(0.0, 75.0));
        let p = r.step(500, input(0.0, 75.0));
        // 4.8 + 0.115 is beyond 5 - 0.12: pulled back to the wall line, y unchanged.
        assert_eq!(p, Point::new(4.88, 0.5));
        assert!(r.was_clamped());
        let (corner, moved) = Bounds::default().clamp(Point::new(-1.0, 7.0));
        assert!(moved);
        assert_eq!(corner, Point::new(0.12, 4.88));
        assert_eq!(
            Bounds::default().clamp(Point::new(2.0, 2.0)),
            (Point::new(2.0, 2.0), false)
        );
    }

    #[test]
    fn bounds_set_after_the_start_validate_the_start_as_given() {
        // An 8 x 4 m lab: the robot is built with the default 5 x 5 m bounds, then told the
        // arena's. The start x 7.00 must survive (it was clamped to 4.88 and kept).
        let mut r = reckoner_at(7.0, 1.0);
        assert_eq!(r.position(), Point::new(4.88, 1.0));
        let lab = Bounds {
            min: Point::new(0.0, 0.0),
            max: Point::new(8.0, 4.0),
            margin_m: 0.12,
        };
        r.set_bounds(lab);
        assert_eq!(r.position(), Point::new(7.0, 1.0));
        // Bounds set one coordinate at a time (link parameters) end at the same place.
        let mut r = reckoner_at(7.0, 3.0);
        r.params.bounds.max.x = 8.0;
        r.bounds_changed();
        r.params.bounds.max.y = 4.0;
        r.bounds_changed();
        assert_eq!(r.position(), Point::new(7.0, 3.0));
        // Once the robot has moved, new bounds validate the current estimate.
        r.step(0, input(0.0, 75.0));
        r.step(500, input(0.0, 75.0));
        let moved = r.position();
        r.set_bounds(Bounds::default());
        assert_eq!(r.position(), Point::new(4.88, moved.y));
    }

    #[test]
    fn beacon_model_interpolates_and_refuses_weak_signals() {
        let m = BeaconModel::default();
        assert_eq!(m.distance_for(100), Some(1.0));
        assert_eq!(m.distance_for(1023), Some(0.25));
        assert!((m.distance_for(115).unwrap_or(0.0) - 0.875).abs() < 1e-6);
        assert_eq!(m.distance_for(14), None);
        for s in [250u16, 180, 115, 65, 20, 15] {
            let d = m.distance_for(s).unwrap_or(f32::NAN);
            assert!(m.strength_at(d).abs_diff(s) <= 1, "{s}");
        }
    }

    #[test]
    fn calibration_blends_with_the_beacon_position_by_confidence() {
        let mut r = reckoner_at(1.0, 2.5);
        r.degrade(DegradeEvent::DeadEnd); // xi 1.0 -> 0.75
        r.degrade(DegradeEvent::DeadEnd); // -> 0.5
        assert!((r.confidence() - 0.5).abs() < 1e-6);
        // Facing the beacon at (2.5, 2.5) along +x, 1.0 m away: P_l = (1.5, 2.5).
        let p_l = r.calibrate(100, 0.0);
        assert_eq!(p_l, Ok(Point::new(1.5, 2.5)));
        assert!((r.position().x - 1.25).abs() < 1e-6 && (r.position().y - 2.5).abs() < 1e-6);
        assert!((r.confidence() - 0.7).abs() < 1e-6);
    }

    #[test]
    fn full_confidence_keeps_the_position_and_zero_confidence_takes_the_beacons() {
        let mut r = reckoner_at(1.0, 1.0);
        assert_eq!(r.calibrate(100, 0.0), Ok(Point::new(1.5, 2.5)));
        assert_eq!(r.position(), Point::new(1.0, 1.0));
        for _ in 0..20 {
            r.degrade(DegradeEvent::Collision);
        }
        assert_eq!(r.confidence(), 0.0);
        r.calibrate(100, 0.0).ok();
        assert_eq!(r.position(), Point::new(1.5, 2.5));
        assert!((r.confidence() - 0.2).abs() < 1e-6);
    }

    #[test]
    fn confidence_is_capped_at_one_and_weak_signals_leave_the_state_alone() {
        let mut r = reckoner_at(1.0, 1.0);
        r.calibrate(250, 1.0).ok();
        assert_eq!(r.confidence(), 1.0);
        r.degrade(DegradeEvent::Collision);
        let before = r;
        assert_eq!(r.calibrate(3, 0.0), Err(CalibrationError::SignalTooWeak));
        assert_eq!(r, before);
    }
}
