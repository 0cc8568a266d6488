//! Rigid-body physics of a round differential-drive robot, integrated in 1 ms steps.
//!
//! Layer: std, between the world (walls) and the simulated hardware (`sim::SimHal`): motor
//! commands in, true pose, wheel rotation (encoders), collision count out. The firmware never
//! sees this state; it sees encoder counts and sensor readings only.
//!
//! Model, per step of `dt`:
//! - Motors: each wheel's rotation speed follows its commanded speed through a first-order lag
//!   with time constant `motor_tau_s` (inertia of motor, gearbox and body). Commanded speed is
//!   the profile's native unit times `motor_unit_mm_s` for a speed-controlled robot (Khepera),
//!   or the firmware's own default [`SpeedTable`] at the TRUE battery level for the micro-rato
//!   (seed 004 §4), so that a nominal robot moves exactly as the firmware believes.
//! - Ground speed = rotation speed x (1 + bias) x (1 - slip). The bias is seed 003 §2.3's
//!   constant per-wheel speed error (drawn once per run, sigma = dV/2); the encoders count
//!   ROTATION, so the bias is exactly what odometry cannot see. Slip is optional, redrawn
//!   every `slip_period_ms`.
//! - Kinematics with the TRUE wheel distance (seed 000 §3: 53.3 mm instead of the nominal
//!   52 mm reproduces Tables 1-2), midpoint rule (error ~1e-11 m per step at Khepera speeds).
//! - Walls: the body is a disc of the profile's diameter. A step that would overlap a wall is
//!   projected out along the contact normal: motion into the wall is removed, motion along it
//!   remains (a round robot slides), the wheels keep turning (encoders still count, as a real
//!   robot's do when its wheels slip against a wall). A new contact is counted once; it ends
//!   when the body is more than `CONTACT_RELEASE_M` away from every wall.
//!
//! Invariants: the body never overlaps a wall (a step that cannot be resolved is not taken);
//! the heading stays in (-pi, pi]; every state value stays finite for finite parameters
//! (checked by [`PhysicsParams::validate`]). Nothing here panics or allocates per step.

use robot_firmware::deadreckon::{SpeedRow, SpeedTable};
use robot_firmware::{MotorCommand, Profile};
use thiserror::Error;

use crate::arena::Pose;
use crate::geometry::{Nearest, Point, SegmentSet, Vector};
use crate::rng::SimRng;

/// Distance from a wall beyond which a contact has ended (hysteresis, so that sliding along a
/// wall is one collision, not one per millisecond).
pub const CONTACT_RELEASE_M: f64 = 0.002;
/// How far beyond its radius the body looks for walls when it refreshes its clearance: the
/// clearance is valid until it has moved that far, so open-space steps skip wall queries.
const CLEARANCE_LOOKAHEAD_M: f64 = 0.05;
/// Largest number of push-outs per step (a concave corner needs two).
const MAX_PUSHES: usize = 4;
/// Wheel speed error below which the motor lag is taken as settled, m/s (1 nm/s).
const SNAP_MPS: f64 = 1e-9;
/// Steps between re-deriving the heading vector from the heading angle.
const RESYNC_STEPS: u32 = 1024;

/// How commanded motor units become wheel rotation speed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SpeedModel {
    /// Speed-controlled motors: units x mm/s per unit (Khepera: 8 mm/s per unit).
    Linear {
        /// mm/s of one command unit.
        mm_s_per_unit: f64,
    },
    /// Open-loop motors whose speed depends on the battery (seed 004 §4): the firmware's table.
    Table(SpeedTable),
}

/// What is wrong with physics parameters.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum PhysicsError {
    /// A parameter outside its valid range.
    #[error("physics parameter {name} = {value} is invalid: {expected}")]
    Invalid {
        /// The parameter.
        name: &'static str,
        /// Its value.
        value: f64,
        /// What it should be.
        expected: &'static str,
    },
}

/// Physical constants of one robot for one run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhysicsParams {
    /// Body radius, metres.
    pub radius_m: f64,
    /// TRUE distance between the wheels, metres.
    pub wheel_distance_m: f64,
    /// Motor time constant, seconds (0 = no inertia).
    pub motor_tau_s: f64,
    /// Constant relative speed error per wheel, left then right (seed 003 §2.3).
    pub wheel_bias: [f64; 2],
    /// Standard deviation of the slip fraction (0 = no slip).
    pub slip_sigma: f64,
    /// How often slip is redrawn, milliseconds.
    pub slip_period_ms: u32,
    /// Wheel travel per encoder pulse, metres; 0 = no encoders.
    pub pulse_m: f64,
    /// Command units -> rotation speed.
    pub speed: SpeedModel,
    /// Largest command magnitude (the firmware clamps first; this is a second guard).
    pub motor_max: i16,
}

impl PhysicsParams {
    /// Nominal parameters for a profile: no bias, no slip, the nominal wheel distance.
    ///
    /// Motor time constants are not in the papers: 30 ms for the 90 g Khepera with its
    /// speed controller, 150 ms for the heavier open-loop micro-rato.
    pub fn for_profile(profile: &Profile) -> PhysicsParams {
        let table = profile.id == protocol::ProfileId::MicroRato;
        PhysicsParams {
            radius_m: f64::from(profile.body_diameter_m) / 2.0,
            wheel_distance_m: f64::from(profile.wheel_distance_m),
            motor_tau_s: if table { 0.150 } else { 0.030 },
            wheel_bias: [0.0, 0.0],
            slip_sigma: 0.0,
            slip_period_ms: 100,
            pulse_m: f64::from(profile.pulse_m),
            speed: if table {
                SpeedModel::Table(SpeedTable::default())
            } else {
                SpeedModel::Linear {
                    mm_s_per_unit: f64::from(profile.motor_unit_mm_s),
                }
            },
            motor_max: profile.motor_max,
        }
    }

    /// Checks every value is finite and in range.
    pub fn validate(&self) -> Result<(), PhysicsError> {
        let check = |name, value: f64, ok: bool, expected| {
            if ok && value.is_finite() {
                Ok(())
            } else {
                Err(PhysicsError::Invalid {
                    name,
                    value,
                    expected,
                })
            }
        };
        let r = self.radius_m;
        check("radius_m", r, r > 0.0 && r < 100.0, "0 < r < 100 m")?;
        let d = self.wheel_distance_m;
        check("wheel_distance_m", d, d > 0.0 && d < 100.0, "0 < d < 100 m")?;
        let t = self.motor_tau_s;
        check("motor_tau_s", t, (0.0..=10.0).contains(&t), "0..=10 s")?;
        for b in self.wheel_bias {
            check("wheel_bias", b, b.abs() < 0.5, "|bias| < 0.5")?;
        }
        let s = self.slip_sigma;
        check("slip", s, (0.0..=0.5).contains(&s), "0..=0.5")?;
        let p = self.pulse_m;
        check("pulse_m", p, (0.0..1.0).contains(&p), "0 <= pulse < 1 m")?;
        if let SpeedModel::Linear { mm_s_per_unit } = self.speed {
            check(
                "mm_s_per_unit",
                mm_s_per_unit,
                mm_s_per_unit.abs() < 1e5,
                "finite",
            )?;
        }
        Ok(())
    }
}

/// The robot's true physical state.
#[derive(Clone, Debug)]
pub struct Body {
    params: PhysicsParams,
    pose: Pose,
    /// Wheel rotation speeds (what encoders measure), m/s.
    rotation_mps: [f64; 2],
    /// Cumulative wheel rotation, metres.
    rotation_m: [f64; 2],
    slip: [f64; 2],
    slip_left_ms: u32,
    collisions: u32,
    in_contact: bool,
    distance_m: f64,
    /// Distance to the nearest wall when last measured (capped at radius + lookahead).
    clearance_m: f64,
    /// Distance moved since the clearance was measured.
    moved_m: f64,
    contacts: Vec<Nearest>,
    /// (cos, sin) of the heading, rotated incrementally.
    dir: (f64, f64),
    resync: u32,
    /// Cached (dt, lag factor).
    alpha: (f64, f64),
    /// The table speed model's rows for the last (clamped) command: the command changes
    /// once a control cycle at most, the lookup runs every step (the rows' brackets and
    /// divisions were a tenth of a micro-rato run).
    rows: Option<((i16, i16), [SpeedRow; 2])>,
}

impl Body {
    /// A body at rest at `pose`; the caller has checked the pose is free.
    pub fn new(params: PhysicsParams, pose: Pose) -> Body {
        Body {
            params,
            pose,
            rotation_mps: [0.0; 2],
            rotation_m: [0.0; 2],
            slip: [0.0; 2],
            slip_left_ms: 0,
            collisions: 0,
            in_contact: false,
            distance_m: 0.0,
            // Zero clearance forces a wall query on the first step.
            clearance_m: 0.0,
            moved_m: 0.0,
            contacts: Vec::with_capacity(8),
            dir: (pose.heading.cos(), pose.heading.sin()),
            resync: 0,
            alpha: (f64::NAN, 1.0),
            rows: None,
        }
    }

    /// Lifts the robot and sets it down at rest at `pose` (an operator carrying it back to
    /// the start between runs). Encoders and counters keep their values; the caller has
    /// checked the pose is free.
    pub fn place(&mut self, pose: Pose) {
        self.pose = pose;
        self.rotation_mps = [0.0; 2];
        self.in_contact = false;
        self.clearance_m = 0.0;
        self.moved_m = 0.0;
        self.dir = (pose.heading.cos(), pose.heading.sin());
        self.resync = 0;
    }

    /// The parameters in force.
    pub fn params(&self) -> &PhysicsParams {
        &self.params
    }

    /// True pose.
    pub fn pose(&self) -> Pose {
        self.pose
    }

    /// The unit vector of the heading, `(cos, sin)`, as the body keeps it (rotated each step,
    /// re-derived every `RESYNC_STEPS`: within about 1e-13 of `sin_cos`), free to read.
    pub fn heading_vector(&self) -> Vector {
        Vector::new(self.dir.0, self.dir.1)
    }

    /// Contacts with walls so far.
    pub fn collisions(&self) -> u32 {
        self.collisions
    }

    /// Whether the body is touching (or just left) a wall.
    pub fn in_contact(&self) -> bool {
        self.in_contact
    }

    /// Ground distance travelled, metres.
    pub fn distance_m(&self) -> f64 {
        self.distance_m
    }

    /// Wheel rotation speeds, m/s (left, right).
    pub fn rotation_mps(&self) -> [f64; 2] {
        self.rotation_mps
    }

    /// Cumulative wheel rotation, metres (left, right).
    pub fn rotation_m(&self) -> [f64; 2] {
        self.rotation_m
    }

    /// Encoder counts (wrapping i32, as a 32-bit hardware counter would); `None` without
    /// encoders.
    pub fn encoders(&self) -> Option<[i32; 2]> {
        if self.params.pulse_m <= 0.0 {
            return None;
        }
        // f64 -> i64 saturates; i64 -> i32 keeps the low 32 bits, i.e. wraps like the counter.
        let count = |m: f64| (m / self.params.pulse_m).floor() as i64 as i32;
        Some([count(self.rotation_m[0]), count(self.rotation_m[1])])
    }

    /// Target rotation speeds of the wheels for a command, m/s.
    fn commanded_mps(&mut self, cmd: MotorCommand, battery_level: f64) -> [f64; 2] {
        if cmd.left == 0 && cmd.right == 0 {
            // Stopped is zero at any battery level: no table lookup.
            return [0.0; 2];
        }
        let max = self.params.motor_max.max(0);
        let (l, r) = (cmd.left.clamp(-max, max), cmd.right.clamp(-max, max));
        match &self.params.speed {
            SpeedModel::Linear { mm_s_per_unit } => [
                f64::from(l) * mm_s_per_unit * 1e-3,
                f64::from(r) * mm_s_per_unit * 1e-3,
            ],
            // Both wheels in one lookup, by reference, on the rows found once per command:
            // the same bits as `speeds_mps`.
            SpeedModel::Table(t) => {
                let rows = match self.rows {
                    Some((key, rows)) if key == (l, r) => rows,
                    _ => {
                        let rows = [t.row(f32::from(l)), t.row(f32::from(r))];
                        self.rows = Some(((l, r), rows));
                        rows
                    }
                };
                let [vl, vr] = t.speeds_on_rows(&rows, battery_level as f32);
                [f64::from(vl), f64::from(vr)]
            }
        }
    }

    /// Advances `dt_s` seconds under `cmd`, against `walls`. `battery_level` (0..1) matters
    /// only for the table speed model; `rng` draws slip.
    pub fn step(
        &mut self,
        cmd: MotorCommand,
        battery_level: f64,
        walls: &SegmentSet,
        dt_s: f64,
        rng: &mut SimRng,
    ) {
        if !(dt_s > 0.0 && dt_s.is_finite()) {
            return;
        }
        let alpha = self.lag_alpha(dt_s);
        let target = self.commanded_mps(cmd, battery_level);
        for (v, t) in self.rotation_mps.iter_mut().zip(target) {
            *v += (t - *v) * alpha;
            // Snap the exponential tail, so a stopped robot is exactly at rest.
            if (t - *v).abs() < SNAP_MPS {
                *v = t;
            }
        }
        if self.rotation_mps == [0.0, 0.0] {
            return;
        }
        self.update_slip(dt_s, rng);
        let p = &self.params;
        let mut ground = [0.0; 2];
        for (i, g) in ground.iter_mut().enumerate() {
            self.rotation_m[i] += self.rotation_mps[i] * dt_s;
            *g = self.rotation_mps[i] * (1.0 + p.wheel_bias[i]) * (1.0 - self.slip[i]);
        }
        let v = (ground[0] + ground[1]) / 2.0;
        let dtheta = (ground[1] - ground[0]) / p.wheel_distance_m * dt_s;
        // Midpoint rule: move along the heading halfway through the step's turn.
        let (sh, ch) = small_sin_cos(dtheta / 2.0);
        let (c, s) = self.dir;
        let mid = Vector::new(c * ch - s * sh, s * ch + c * sh);
        // Full turn by the double-angle formulas: no further trigonometry this step.
        let (sf, cf) = (2.0 * sh * ch, ch * ch - sh * sh);
        self.dir = (c * cf - s * sf, s * cf + c * sf);
        self.pose.heading = wrap_pi(self.pose.heading + dtheta);
        self.resync = self.resync.wrapping_add(1);
        if self.resync % RESYNC_STEPS == 0 {
            // Rounding drift of the rotated vector stays ~1e-13; re-derive it now and then.
            let (s, c) = self.pose.heading.sin_cos();
            self.dir = (c, s);
        }
        // `mid` is a unit vector, so the step's length is |v| dt without a square root.
        self.translate(mid * (v * dt_s), (v * dt_s).abs(), walls);
    }

    /// The motor lag's per-step factor `1 - exp(-dt / tau)`, cached for the last `dt`.
    fn lag_alpha(&mut self, dt_s: f64) -> f64 {
        if self.alpha.0 != dt_s {
            let tau = self.params.motor_tau_s;
            let a = if tau > 0.0 {
                1.0 - (-dt_s / tau).exp()
            } else {
                1.0
            };
            self.alpha = (dt_s, a);
        }
        self.alpha.1
    }

    fn update_slip(&mut self, dt_s: f64, rng: &mut SimRng) {
        if self.params.slip_sigma <= 0.0 {
            return;
        }
        let step_ms = (dt_s * 1000.0).round().max(1.0) as u32;
        if self.slip_left_ms == 0 {
            // Slip only ever loses ground travel; clamped so a wheel never runs backwards.
            for s in &mut self.slip {
                *s = rng.gaussian(self.params.slip_sigma).abs().min(0.9);
            }
            self.slip_left_ms = self.params.slip_period_ms.max(1);
        }
        self.slip_left_ms = self.slip_left_ms.saturating_sub(step_ms);
    }

    /// Moves the centre by `d` (of length `len`), resolving wall contacts.
    fn translate(&mut self, d: Vector, len: f64, walls: &SegmentSet) {
        let r = self.params.radius_m;
        if !len.is_finite() {
            return;
        }
        let from = Point::new(self.pose.x, self.pose.y);
        // Fast path: still far from every wall since the clearance was measured.
        if self.moved_m + len + CONTACT_RELEASE_M < self.clearance_m - r {
            self.moved_m += len;
            self.pose.x += d.x;
            self.pose.y += d.y;
            self.distance_m += len;
            self.in_contact = false;
            return;
        }
        let to = from + d;
        let look = r + CLEARANCE_LOOKAHEAD_M;
        // Usually the new spot is near walls but clear of them: one query decides.
        let (to, touched, clearance) = match walls.nearest(to, look) {
            None => (to, false, look),
            Some(n) if n.distance > r => (to, false, n.distance),
            Some(_) => {
                let (to, touched) = self.resolve(from, to, walls);
                let c = walls.nearest(to, look).map_or(look, |n| n.distance);
                (to, touched, c)
            }
        };
        self.distance_m += (to - from).norm();
        self.pose.x = to.x;
        self.pose.y = to.y;
        self.clearance_m = clearance;
        self.moved_m = 0.0;
        if touched && !self.in_contact {
            self.collisions = self.collisions.saturating_add(1);
            self.in_contact = true;
        } else if self.in_contact && self.clearance_m > r + CONTACT_RELEASE_M {
            self.in_contact = false;
        }
    }

    /// Where the body ends when it tries to move from `from` to `to`, and whether it touched a
    /// wall. `from` is free (the invariant); the result is free.
    fn resolve(&mut self, from: Point, to: Point, walls: &SegmentSet) -> (Point, bool) {
        let r = self.params.radius_m;
        let mut q = to;
        let mut touched = false;
        for _ in 0..MAX_PUSHES {
            walls.contacts(q, r, &mut self.contacts);
            let Some(n) = self.contacts.first().copied() else {
                break;
            };
            touched = true;
            if n.distance >= r {
                break; // touching, not overlapping
            }
            let away = q - n.point;
            let dist = away.norm();
            if dist < 1e-12 {
                return (from, true); // centre on a wall line: no sensible normal, stay put
            }
            // Out to exactly the radius (a hair more, so rounding cannot leave an overlap).
            q = n.point + away * ((r * (1.0 + 1e-12)) / dist);
        }
        let overlaps = walls
            .nearest(q, r)
            .is_some_and(|n| n.distance < r * (1.0 - 1e-9));
        if overlaps || !(q.x.is_finite() && q.y.is_finite()) {
            (from, true)
        } else {
            (q, touched)
        }
    }
}

/// Contact with other robots (the fleet's physics, `crate::fleet::contact`): the fleet moves
/// a body out of another robot's way after its own step.
impl Body {
    /// Moves the centre to `p` (the heading and the wheels untouched: they keep turning, as
    /// against a wall) and forgets the wall clearance, so the next step measures it again.
    /// `step_from` is where the step that is being corrected began: the ground distance then
    /// counts the step as from there to `p`. The caller has checked that `p` is free of walls.
    pub fn displace_to(&mut self, p: Point, step_from: Point) {
        if !(p.x.is_finite() && p.y.is_finite()) {
            return;
        }
        let at = Point::new(self.pose.x, self.pose.y);
        let counted = (at - step_from).norm();
        self.distance_m = (self.distance_m - counted + (p - step_from).norm()).max(0.0);
        self.pose.x = p.x;
        self.pose.y = p.y;
        self.clearance_m = 0.0;
        self.moved_m = 0.0;
    }
}

/// `(sin x, cos x)`; a Taylor polynomial for the small angles of one step (|x| < 0.05 rad:
/// truncation error below 1e-17), the library otherwise.
fn small_sin_cos(x: f64) -> (f64, f64) {
    if x.abs() >= 0.05 {
        return x.sin_cos();
    }
    // Reciprocals, so that a step multiplies instead of dividing seven times (a division
    // costs as much as several multiplications; they were a tenth of `Body::step`).
    const K: [f64; 7] = [
        1.0 / 6.0,
        1.0 / 20.0,
        1.0 / 42.0,
        1.0 / 2.0,
        1.0 / 12.0,
        1.0 / 30.0,
        1.0 / 56.0,
    ];
    let x2 = x * x;
    let s = x * (1.0 - x2 * K[0] * (1.0 - x2 * K[1] * (1.0 - x2 * K[2])));
    let c = 1.0 - x2 * K[3] * (1.0 - x2 * K[4] * (1.0 - x2 * K[5] * (1.0 - x2 * K[6])));
    (s, c)
}

/// Wraps an angle into (-pi, pi].
pub fn wrap_pi(a: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    if a > -PI && a <= PI {
        return a;
    }
    let w = (a + PI).rem_euclid(TAU) - PI;
    if w <= -PI {
        w + TAU
    } else {
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Segment;
    use robot_firmware::{KHEPERA, MICRO_RATO};

    fn step_ms(body: &mut Body, cmd: MotorCommand, walls: &SegmentSet, ms: u32) {
        let mut rng = SimRng::new(1, 1);
        for _ in 0..ms {
            body.step(cmd, 0.5, walls, 1e-3, &mut rng);
        }
    }

    #[test]
    fn straight_drive_reaches_commanded_speed_with_the_motor_lag() {
        let params = PhysicsParams::for_profile(&KHEPERA);
        let mut b = Body::new(
            params,
            Pose {
                x: 0.0,
                y: 0.0,
                heading: 0.0,
            },
        );
        let walls = SegmentSet::default();
        step_ms(&mut b, MotorCommand::new(10, 10), &walls, 30);
        // After one time constant: 1 - 1/e of 80 mm/s.
        let v = b.rotation_mps()[0];
        assert!((v - 0.08 * (1.0 - (-1.0f64).exp())).abs() < 1e-3, "{v}");
        step_ms(&mut b, MotorCommand::new(10, 10), &walls, 970);
        assert!((b.pose().y).abs() < 1e-12 && b.pose().heading == 0.0);
        // 1 s at 80 mm/s minus the lag's 30 ms deficit.
        assert!(
            (b.pose().x - 0.08 * (1.0 - 0.03)).abs() < 1e-3,
            "{}",
            b.pose().x
        );
    }

    #[test]
    fn a_new_command_is_looked_up_anew_not_served_from_the_last_ones_rows() {
        let mut params = PhysicsParams::for_profile(&MICRO_RATO);
        params.motor_tau_s = 0.0;
        let SpeedModel::Table(table) = params.speed else {
            panic!("micro-rato has a speed table")
        };
        let pose = Pose {
            x: 0.0,
            y: 0.0,
            heading: 0.0,
        };
        let mut b = Body::new(params, pose);
        let walls = SegmentSet::default();
        for (cmd, level) in [
            ((75, 75), 0.5),
            ((30, 75), 0.5),
            ((-40, 60), 0.2),
            ((75, 75), 0.9),
        ] {
            let cmd = MotorCommand::new(cmd.0, cmd.1);
            b.step(cmd, level, &walls, 1e-3, &mut SimRng::new(1, 1));
            let want = table.speeds_mps([f32::from(cmd.left), f32::from(cmd.right)], level as f32);
            assert_eq!(b.rotation_mps(), want.map(f64::from), "{cmd:?} at {level}");
        }
    }

    #[test]
    fn micro_rato_speed_follows_the_firmware_table_at_the_battery_level() {
        let mut params = PhysicsParams::for_profile(&MICRO_RATO);
        params.motor_tau_s = 0.0;
        let mut b = Body::new(
            params,
            Pose {
                x: 0.0,
                y: 0.0,
                heading: 0.0,
            },
        );
        step_ms(
            &mut b,
            MotorCommand::new(75, 75),
            &SegmentSet::default(),
            1000,
        );
        // seed 004 §4: 75 at average battery is 0.23 m/s.
        assert!((b.pose().x - 0.23).abs() < 1e-6, "{}", b.pose().x);
    }

    #[test]
    fn a_wall_stops_the_body_without_overlap_and_counts_one_contact() {
        let params = PhysicsParams::for_profile(&KHEPERA);
        let r = params.radius_m;
        let walls = SegmentSet::new(vec![Segment::new(
            Point::new(0.1, -1.0),
            Point::new(0.1, 1.0),
        )]);
        let mut b = Body::new(
            params,
            Pose {
                x: 0.0,
                y: 0.0,
                heading: 0.0,
            },
        );
        step_ms(&mut b, MotorCommand::new(10, 10), &walls, 3000);
        assert!(b.pose().x <= 0.1 - r + 1e-9 && b.pose().x > 0.1 - r - 1e-6);
        assert_eq!(b.collisions(), 1);
        // Wheels kept turning against the wall: encoders count more than the body moved.
        let enc = b.encoders().expect("khepera has encoders");
        assert!(f64::from(enc[0]) * 0.000_08 > 0.2);
        // Back off and drive in again: a second contact.
        step_ms(&mut b, MotorCommand::new(-10, -10), &walls, 500);
        step_ms(&mut b, MotorCommand::new(10, 10), &walls, 1000);
        assert_eq!(b.collisions(), 2);
    }

    #[test]
    fn a_wider_true_wheel_base_turns_less_than_the_encoders_say() {
        // seed 000 §3: odometry with the nominal d = 52 mm on a robot whose true wheel distance
        // is 53.3 mm overestimates every turn by 53.3 / 52 (Tables 1-2).
        let mut params = PhysicsParams::for_profile(&KHEPERA);
        params.wheel_distance_m = 0.0533;
        params.motor_tau_s = 0.0;
        let mut b = Body::new(
            params,
            Pose {
                x: 0.0,
                y: 0.0,
                heading: 0.0,
            },
        );
        step_ms(
            &mut b,
            MotorCommand::new(-5, 5),
            &SegmentSet::default(),
            500,
        );
        let enc = b.encoders().expect("khepera has encoders");
        let believed = f64::from(enc[1] - enc[0]) * 0.000_08 / 0.052;
        let ratio = believed / b.pose().heading;
        // Within a pulse of quantisation out of 500.
        assert!((ratio - 53.3 / 52.0).abs() < 3e-3, "{ratio}");
    }

    #[test]
    fn small_sin_cos_matches_the_library() {
        for i in -100..=100 {
            let x = f64::from(i) * 0.001;
            let (s, c) = small_sin_cos(x);
            assert!(
                (s - x.sin()).abs() < 1e-16 && (c - x.cos()).abs() < 1e-16,
                "{x}"
            );
        }
    }

    #[test]
    fn wrap_pi_stays_in_the_half_open_interval() {
        use std::f64::consts::PI;
        assert_eq!(wrap_pi(PI), PI);
        assert!((wrap_pi(-PI) - PI).abs() < 1e-12);
        assert!((wrap_pi(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-12);
        assert!(wrap_pi(f64::NAN).is_nan());
    }
}
