//! The odometry calibration's manoeuvre as a pure state machine: which command to send the
//! robot after each observation, feeding [`LapCalibrator`] and [`StraightWalls`] on the way.
//! One place for the driving sequence, used by whoever commands the robot: the emulator's
//! scenario (`bench --calibrate-odometry`, observing the simulated robot every 40 ms) and the
//! station's `station calibrate odometry` (observing the robot's telemetry).
//!
//! The sequence: hold the wall on the right ([`WallHolder`], Manual mode, a teleop command
//! each observation, as a station's joystick would, so the link failsafe keeps working)
//! until the lap calibrator asks for the other side; then turn round on the spot by half a
//! turn of the believed heading, stop, and hold the wall on the left; until the lap
//! calibrator is done. The caller sends [`Manoeuvre::start`]'s command first, then each
//! [`Step`]'s commands in order, and on `done` (or its own timeout, with
//! [`Manoeuvre::finish`]) stops the robot.
//!
//! The result: the wheel ratio from the straight walls ([`StraightWalls`], no closed lap
//! needed, free of the wheels' common speed error) once they cover
//! [`MIN_STRAIGHT_MM`], else the laps'; the wheel distance from the laps (both directions), or
//! from the laps one way with the straight walls' ratio, else the nominal one.
//!
//! Layer: pure, no I/O, no clock, no heap (`#![no_std]`).

use protocol::{Command, Mode};

use crate::behaviour::edge::EdgeParams;
use crate::behaviour::{S_LEFT, S_RIGHT};
use crate::odometry_calibration::{
    Calibration, CalibrationError, CalibrationParams, LapCalibrator, Next, Sample, WallSide,
};
use crate::odometry_stretch::{ratio_from_kappa, StraightWalls, StretchParams};
use crate::wall_holder::{HolderParams, HolderPhase, WallHolder};

/// Straight-wall travel from which the wheel ratio is the straight walls' (two walls of a
/// small box: the error bound is per stretch, more only averages it down).
pub const MIN_STRAIGHT_MM: f32 = 1000.0;

/// Motor speed unit of the holder's wheel commands, mm/s (a Khepera's: 8 mm/s).
pub const UNIT_MM_S: f32 = 8.0;

/// Turn rate of the turn round, mrad/s (about 0.6 rad/s: 16 mm/s a wheel on a Khepera).
pub const TURN_MRAD_S: i16 = 600;

/// What the robot reports, once per observation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Observation {
    /// Left and right encoder pulses since any fixed origin, unwrapped.
    pub pulses: [i64; 2],
    /// Believed heading, radians (any wrap).
    pub heading_rad: f32,
    /// IR proximity S0..S7.
    pub ir: [u16; 8],
}

/// The commands to send now (at most two, in order), and the result once done.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step {
    commands: [Option<Command>; 2],
    /// The calibration ended: stop the robot; the result.
    pub done: Option<Result<Calibration, CalibrationError>>,
    /// The calibrator now follows this side (a turn round has just begun) — for progress.
    pub turned_to: Option<WallSide>,
}

impl Step {
    const NONE: Step = Step {
        commands: [None, None],
        done: None,
        turned_to: None,
    };

    /// The commands to send, in order.
    pub fn commands(&self) -> impl Iterator<Item = Command> + '_ {
        self.commands.iter().flatten().copied()
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Phase {
    Following,
    /// Turning round: the heading last seen and the turn so far, radians.
    Turning {
        last: f32,
        turned: f32,
    },
    Finished,
}

/// The manoeuvre (see the module text).
#[derive(Clone, Debug)]
pub struct Manoeuvre {
    cal: LapCalibrator,
    walls: StraightWalls,
    holder: WallHolder,
    was_holding: bool,
    phase: Phase,
    side: WallSide,
    wall_level: u16,
    mm_per_pulse: f32,
    nominal_distance_mm: f32,
    max_distance_error: f32,
    origin: Option<[i64; 2]>,
    last_heading: Option<f32>,
    unwrapped: f32,
    /// The farthest the believed heading has turned the enclosing wall's way (counter-clockwise
    /// with the wall on the right) since the watch began, radians (see `island`).
    watch_peak: f32,
}

/// Turned this far the wrong way for the side since the farthest the right way, the robot is
/// going round an island: a whole turn. Along an enclosing wall the turns the wrong way (round
/// a bar's or a dead end's end) undo themselves within half a turn.
const ISLAND_TURN: f32 = 2.0 * core::f32::consts::PI;

/// The command that starts holding a wall: Manual mode (the holder's teleop follows).
pub const HOLD: Command = Command::SetMode(Mode::Manual);

fn holder(side: WallSide, nominal_distance_mm: f32) -> WallHolder {
    WallHolder::new(
        HolderParams::default(),
        side == WallSide::Right,
        UNIT_MM_S,
        nominal_distance_mm,
    )
}

/// The command that stops the robot at the end, on a timeout or an interruption.
pub const STOP: Command = Command::SetMode(Mode::Idle);

impl Manoeuvre {
    /// A manoeuvre for a robot with this pulse length and nominal wheel distance.
    pub fn new(params: CalibrationParams, mm_per_pulse: f32, nominal_distance_mm: f32) -> Self {
        let cal = LapCalibrator::new(params, mm_per_pulse, nominal_distance_mm);
        Manoeuvre {
            side: cal.side(),
            holder: holder(cal.side(), nominal_distance_mm),
            cal,
            walls: StraightWalls::new(StretchParams::default()),
            was_holding: false,
            phase: Phase::Following,
            // A wall is beside when the side sensor reads what the edge follower counts as
            // found.
            wall_level: EdgeParams::default().found_level,
            mm_per_pulse,
            nominal_distance_mm,
            max_distance_error: params.max_distance_error,
            origin: None,
            last_heading: None,
            unwrapped: 0.0,
            watch_peak: 0.0,
        }
    }

    /// Whether the robot has turned a whole turn the wrong way for the side since the farthest
    /// the right way: round a block, whose laps the lap calibrator may never close (a small
    /// post keeps the side sensor off its wall at every corner, so no lap is seen at all, and
    /// the robot circled a post beside its start for the whole calibration).
    fn island(&mut self) -> bool {
        let way = match self.side {
            WallSide::Right => 1.0,
            WallSide::Left => -1.0,
        };
        let h = self.unwrapped * way;
        self.watch_peak = self.watch_peak.max(h);
        if self.watch_peak - h >= ISLAND_TURN {
            self.watch_peak = h;
            return true;
        }
        false
    }

    /// The first command: Manual mode, for the wall holder's teleop.
    pub fn start(&self) -> Command {
        HOLD
    }

    /// The straight-wall estimator (its stretches, for progress and reports).
    pub fn straight_walls(&self) -> &StraightWalls {
        &self.walls
    }

    /// The calibrator (laps closed so far, for progress).
    pub fn calibrator(&self) -> &LapCalibrator {
        &self.cal
    }

    /// The side being followed.
    pub fn side(&self) -> WallSide {
        self.side
    }

    /// Feeds one observation; returns what to send next.
    pub fn step(&mut self, o: Observation) -> Step {
        let mut out = Step::NONE;
        let origin = *self.origin.get_or_insert(o.pulses);
        let last = *self.last_heading.get_or_insert(o.heading_rad);
        self.unwrapped += crate::odometry::wrap_angle(o.heading_rad - last);
        self.last_heading = Some(o.heading_rad);
        match self.phase {
            Phase::Finished => {}
            Phase::Following => {
                let sensor = match self.side {
                    WallSide::Right => S_RIGHT,
                    WallSide::Left => S_LEFT,
                };
                let hold = self.holder.step(&o.ir, self.unwrapped);
                let holding = self.holder.phase() == HolderPhase::Holding;
                let wheels_mm = [
                    (o.pulses[0] - origin[0]) as f32 * self.mm_per_pulse,
                    (o.pulses[1] - origin[1]) as f32 * self.mm_per_pulse,
                ];
                self.walls.observe(
                    wheels_mm,
                    self.unwrapped,
                    o.ir[sensor],
                    holding && self.was_holding,
                );
                self.was_holding = holding;
                out.commands = [Some(hold), None];
                let sample = Sample {
                    pulses: o.pulses,
                    heading_rad: o.heading_rad,
                    wall_beside: o.ir[sensor] >= self.wall_level,
                };
                let before = self.cal.closed_laps().len();
                let next = self.cal.observe(sample);
                // A lap the wrong way round for the side (clockwise with the wall on the
                // right) went round an island, not along the enclosing wall: leave it, or the
                // robot circles it to the end (a small block gives no straight wall long
                // enough). Seen by the lap calibrator, or by the turning alone.
                let ccw = self.side == WallSide::Right;
                let island_lap = self
                    .cal
                    .closed_laps()
                    .get(before)
                    .is_some_and(|lap| (lap.turns > 0) != ccw);
                if self.island() || island_lap {
                    self.holder.leave(self.unwrapped);
                    self.walls.end();
                    self.watch_peak = self.unwrapped * if ccw { 1.0 } else { -1.0 };
                }
                match next {
                    Next::Follow(s) if s != self.side => {
                        // Turn round on the spot, so the wall it was following is now on its
                        // other side: the laps go the other way.
                        self.side = s;
                        self.watch_peak = f32::NEG_INFINITY;
                        self.walls.end();
                        self.holder = holder(s, self.nominal_distance_mm);
                        self.was_holding = false;
                        out.turned_to = Some(s);
                        self.phase = Phase::Turning {
                            last: o.heading_rad,
                            turned: 0.0,
                        };
                        out.commands = [Some(HOLD), Some(turn())];
                    }
                    Next::Follow(_) => {}
                    Next::Done(r) => {
                        self.phase = Phase::Finished;
                        self.walls.end();
                        out.done = Some(self.combine(r));
                        out.commands = [Some(STOP), None];
                    }
                }
            }
            Phase::Turning { last, turned } => {
                let turned = turned + crate::odometry::wrap_angle(o.heading_rad - last);
                if turned < core::f32::consts::PI {
                    self.phase = Phase::Turning {
                        last: o.heading_rad,
                        turned,
                    };
                    out.commands = [Some(turn()), None];
                } else {
                    self.phase = Phase::Following;
                    out.commands = [
                        Some(Command::Teleop {
                            v_mm_s: 0,
                            w_mrad_s: 0,
                        }),
                        None,
                    ];
                }
            }
        }
        out
    }

    /// The result with the laps and straight walls so far (the caller's time is up).
    pub fn finish(&mut self) -> Result<Calibration, CalibrationError> {
        self.walls.end();
        let laps = self.cal.finish();
        self.combine(laps)
    }

    /// The straight walls' ratio with the laps' wheel distance (module text).
    fn combine(
        &self,
        laps: Result<Calibration, CalibrationError>,
    ) -> Result<Calibration, CalibrationError> {
        let Some(kappa) = self.walls.kappa(MIN_STRAIGHT_MM) else {
            return laps;
        };
        let ratio = ratio_from_kappa(kappa, self.nominal_distance_mm);
        let b = self.nominal_distance_mm;
        let b_max = self.max_distance_error;
        let distance = self
            .walls
            .lap_distance(ratio, kappa, 0.3, 500.0)
            .filter(|d| libm::fabsf(d / b - 1.0) <= b_max)
            .or_else(|| self.lap_distance(ratio));
        Ok(match laps {
            Ok(c) => Calibration {
                wheel_ratio: ratio,
                wheel_distance_mm: distance.unwrap_or(c.wheel_distance_mm),
                ..c
            },
            Err(_) => Calibration {
                wheel_ratio: ratio,
                wheel_distance_mm: distance.unwrap_or(b),
                both_directions: false,
                laps: [crate::odometry_calibration::NO_LAP; 2],
                median_of: 0,
            },
        })
    }

    /// The effective wheel distance with the wheel ratio known, the median over the closed
    /// laps (either direction): the odometry scales the counts to `2 L / (1 + r)` and
    /// `2 r R / (1 + r)` and turns by their difference over the distance parameter, the truth
    /// by `kl (r R - L) / B_true`, so a lap of `k` whole turns gives the parameter
    /// `2 (r R - L) / ((1 + r) 2 pi k)` (= `B_true / mean wheel factor`). One direction is
    /// enough: the ratio, not the other direction, separates the wheels. `None` without
    /// laps or outside `max_distance_error`.
    fn lap_distance(&self, ratio: f32) -> Option<f32> {
        let mut d = [0.0f32; crate::odometry_calibration::MAX_LAPS];
        let mut n = 0;
        for lap in self.cal.closed_laps() {
            if lap.turns == 0 {
                continue;
            }
            let turn = 2.0 * core::f32::consts::PI * lap.turns as f32;
            d[n] = 2.0 * (ratio * lap.right_mm - lap.left_mm) / ((1.0 + ratio) * turn);
            n += 1;
        }
        let v = &mut d[..n];
        v.sort_unstable_by(f32::total_cmp);
        let median = match n {
            0 => return None,
            n if n % 2 == 1 => v[n / 2],
            n => (v[n / 2 - 1] + v[n / 2]) / 2.0,
        };
        let b = self.nominal_distance_mm;
        (libm::fabsf(median / b - 1.0) <= self.max_distance_error).then_some(median)
    }
}

fn turn() -> Command {
    Command::Teleop {
        v_mm_s: 0,
        w_mrad_s: TURN_MRAD_S,
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use core::f32::consts::PI;
    use std::vec::Vec;

    /// Reading of a Khepera-like sensor at `d` mm from the body's edge (useful 17-33 mm).
    fn reading(d: f32) -> u16 {
        if d >= 33.0 {
            return 5;
        }
        let x = ((33.0 - d) / 16.0).max(0.0);
        (5.0 + 1023.0 * libm::powf(x, 1.5)).min(1023.0) as u16
    }

    /// A synthetic robot in a 1000 x 800 mm box obeying the manoeuvre's commands every 40
    /// ms: teleop to whole motor units (8 mm/s) as the firmware does, the right wheel truly
    /// 0.37 % faster than the left over the same encoder counts, the belief integrated from
    /// the counts with the nominal 52 mm, IR readings from the centre ray of each sensor.
    #[test]
    fn holds_the_wall_both_ways_turns_round_and_measures_the_ratio_on_straight_walls() {
        let (kr, kl, b) = (1.0037_f32, 0.9990_f32, 52.0_f32);
        let (w, h, radius) = (1000.0f32, 800.0f32, 27.5f32);
        let angles = [90.0f32, 45.0, 10.0, -10.0, -45.0, -90.0, 180.0, 180.0];
        let mut m = Manoeuvre::new(CalibrationParams::default(), 0.08, b);
        assert_eq!(m.start(), HOLD);
        let (mut x, mut y, mut th) = (500.0f32, 400.0f32, 0.3f32);
        let mut pulses = [0i64; 2];
        let mut believed = 0.3f32;
        let mut teleop = (0i16, 0i16);
        let mut idle = false;
        let mut sent: Vec<Command> = Vec::new();
        let mut turned = None;
        let mut done = None;
        for _ in 0..15_000 {
            let mut ir = [0u16; 8];
            for (r, a) in ir.iter_mut().zip(angles) {
                let (sa, ca) = libm::sincosf(th + a * PI / 180.0);
                let mut t = f32::MAX;
                if ca > 1e-6 {
                    t = t.min((w - x) / ca);
                } else if ca < -1e-6 {
                    t = t.min(-x / ca);
                }
                if sa > 1e-6 {
                    t = t.min((h - y) / sa);
                } else if sa < -1e-6 {
                    t = t.min(-y / sa);
                }
                *r = reading(t - radius);
            }
            let step = m.step(Observation {
                pulses,
                heading_rad: libm::remainderf(believed, 2.0 * PI),
                ir,
            });
            if step.turned_to.is_some() {
                turned = step.turned_to;
            }
            for c in step.commands() {
                sent.push(c);
                match c {
                    Command::Teleop { v_mm_s, w_mrad_s } => teleop = (v_mm_s, w_mrad_s),
                    Command::SetMode(Mode::Idle) => idle = true,
                    _ => {}
                }
            }
            if let Some(r) = step.done {
                done = Some(r);
                break;
            }
            if idle {
                continue;
            }
            // The firmware's teleop: whole units a wheel; 4 pulses a unit in 40 ms.
            let turn = f32::from(teleop.1) / 1000.0 * b / 2.0;
            let units = |mm_s: f32| libm::roundf(mm_s / 8.0) as i64;
            let (ul, ur) = (
                units(f32::from(teleop.0) - turn),
                units(f32::from(teleop.0) + turn),
            );
            pulses[0] += ul * 4;
            pulses[1] += ur * 4;
            believed += (ur - ul) as f32 * 4.0 * 0.08 / b;
            let (vl, vr) = (ul as f32 * 8.0 * kl, ur as f32 * 8.0 * kr);
            th += (vr - vl) / b * 0.04;
            let v = (vl + vr) / 2.0 * 0.04;
            x = (x + v * libm::cosf(th)).clamp(radius, w - radius);
            y = (y + v * libm::sinf(th)).clamp(radius, h - radius);
        }
        let c = done.expect("done in time").expect("a result");
        assert!(
            (c.wheel_ratio - kr / kl).abs() < 3e-4,
            "{c:?} {:?}",
            m.straight_walls().stretches()
        );
        assert!(m.straight_walls().total_mm() >= MIN_STRAIGHT_MM);
        assert_eq!(turned, Some(WallSide::Left));
        assert_eq!(sent.last(), Some(&STOP));
        // Turning round: Manual, then the spin, before the left wall is held.
        let k = sent.iter().position(|c| *c == HOLD).expect("turned round");
        assert_eq!(sent[k + 1], turn());
    }
}
