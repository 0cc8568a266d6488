//! Arbitration of the reflexive behaviours (seed 000 §4, Fig. 6).
//!
//! The motor outputs of edge following (or drift, or drive-to-light) are ADDED to obstacle
//! avoidance, which has implicit priority (its inhibition is far stronger than their ±1..6
//! corrections) and provides the base propulsion; turning on the spot suppresses all the
//! others. A behaviour whose inputs were not refreshed this cycle contributes its previous
//! output again ("stale outputs are reused"), for at most `max_stale_cycles` cycles, after
//! which it contributes nothing, so a dead sensor stops the robot instead of steering it blind.
//!
//! Invariants: one `step` per control cycle; the command is clamped to `max_units`; `Idle`,
//! a reached drift target and an arrived-at light source give a stop. The report
//! ([`BehaviourState`]) describes the cycle just computed. Cannot fail.

use super::avoid::{Avoid, AvoidOutput, AvoidParams};
use super::drift::{Drift, DriftOutput, DriftParams, DriftPhase};
use super::edge::{EdgeFollow, EdgeOutput, EdgeParams, EdgePhase};
use super::light::{DriveToLight, LightOutput, LightParams, LightPhase};
use super::turn::{TurnParams, TurnReason, Turning};
use super::{Inputs, MotorCommand, Side, XorShift32};
use crate::odometry::Point;

/// What the arbiter is asked to do.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum Mode {
    /// Motors stopped.
    #[default]
    Idle,
    /// Obstacle-avoiding wander (avoidance + turning).
    Wander,
    /// Edge following on a side (avoidance + edge following + turning).
    EdgeFollow(Side),
    /// Go to a point (avoidance + drift + turning; edge following while drift pauses).
    GoTo(Point),
    /// Drive to a light source (avoidance + drive-to-light).
    DriveToLight,
}

/// All behaviour parameters, each struct defaulting to the paper's values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArbiterParams {
    /// Obstacle avoidance (seed 000 §4.2).
    pub avoid: AvoidParams,
    /// Edge following (seed 000 §4.3).
    pub edge: EdgeParams,
    /// Drift (seed 000 §4.4).
    pub drift: DriftParams,
    /// Turning (seed 000 §4.5).
    pub turn: TurnParams,
    /// Drive to light (seed 000 §6.1).
    pub light: LightParams,
    /// Wheel command limit, units. Not in the paper: 20 (160 mm/s), well under the Khepera's
    /// top speed, above anything the behaviours ask for.
    pub max_units: i16,
    /// Cycles an output may be reused while its inputs are stale. Not in the paper: 3 (about
    /// 240 ms on a Khepera).
    pub max_stale_cycles: u8,
    /// Side followed while drift pauses (seed 000 §4.4: "amounts to an edge following").
    pub pause_side: Side,
}

impl Default for ArbiterParams {
    fn default() -> Self {
        Self {
            avoid: AvoidParams::default(),
            edge: EdgeParams::default(),
            drift: DriftParams::default(),
            turn: TurnParams::default(),
            light: LightParams::default(),
            max_units: 20,
            max_stale_cycles: 3,
            pause_side: Side::Left,
        }
    }
}

/// A set of behaviours, as bits (compact for telemetry).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct BehaviourSet(pub u8);

impl BehaviourSet {
    /// Obstacle avoidance.
    pub const AVOID: u8 = 1;
    /// Edge following.
    pub const EDGE: u8 = 2;
    /// Drift (go to point).
    pub const DRIFT: u8 = 4;
    /// Turning on the spot.
    pub const TURN: u8 = 8;
    /// Drive to light.
    pub const LIGHT: u8 = 16;

    /// Whether any of the bits in `bits` is in the set.
    pub fn contains(self, bits: u8) -> bool {
        self.0 & bits != 0
    }

    fn insert(&mut self, bit: u8) {
        self.0 |= bit;
    }
}

/// Report of one arbitration cycle, carried by telemetry.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct BehaviourState {
    /// Mode in force.
    pub mode: Mode,
    /// Behaviours engaged this cycle (avoidance only when reacting to an obstacle).
    pub active: BehaviourSet,
    /// Behaviours whose output was reused from an earlier cycle.
    pub stale: BehaviourSet,
    /// Final command sent to the motors.
    pub output: MotorCommand,
    /// Avoidance's command (propulsion minus inhibition).
    pub avoid: MotorCommand,
    /// Edge following's correction.
    pub edge: MotorCommand,
    /// Drift's correction, or its turn on the spot.
    pub drift: MotorCommand,
    /// Drive-to-light's excitation.
    pub light: MotorCommand,
    /// Turning's command (zero when not turning).
    pub turn: MotorCommand,
    /// Avoidance thresholds of the left and right neuron.
    pub avoid_thresholds: [u16; 2],
    /// Edge-following phase.
    pub edge_phase: EdgePhase,
    /// Drift phase (meaningful in `GoTo`).
    pub drift_phase: DriftPhase,
    /// Drive-to-light phase (meaningful in `DriveToLight`).
    pub light_phase: LightPhase,
    /// Why turning runs, if it does.
    pub turn_reason: Option<TurnReason>,
    /// A dead end was detected this cycle (a degrading event for position, seed 004 §4).
    pub dead_end: bool,
}

/// A behaviour's last output and how many cycles it has been reused.
#[derive(Clone, Copy, Debug, Default)]
struct Held<T> {
    out: T,
    age: u8,
}

impl<T: Copy + Default> Held<T> {
    fn fresh(&mut self, out: T) -> T {
        self.out = out;
        self.age = 0;
        out
    }

    /// The previous output while young enough, else the default (no contribution).
    fn reuse(&mut self, max_age: u8) -> T {
        self.age = self.age.saturating_add(1);
        if self.age <= max_age {
            self.out
        } else {
            T::default()
        }
    }
}

/// Owns the behaviours and combines them once per control cycle.
#[derive(Clone, Copy, Debug)]
pub struct Arbiter {
    /// Parameters in use (settable over the link).
    pub params: ArbiterParams,
    mode: Mode,
    rng: XorShift32,
    avoid: Avoid,
    edge: EdgeFollow,
    drift: Drift,
    turning: Turning,
    light: DriveToLight,
    held_avoid: Held<AvoidOutput>,
    held_edge: Held<EdgeOutput>,
    held_drift: Held<DriftOutput>,
    held_light: Held<LightOutput>,
    held_turn: Held<MotorCommand>,
    state: BehaviourState,
    /// Consecutive go-to cycles in which avoidance and drift cancelled to a standstill.
    standstill: u16,
}

impl Arbiter {
    /// Idle arbiter; `seed` makes the random thresholds and turn directions reproducible.
    pub fn new(params: ArbiterParams, seed: u32) -> Self {
        let mut rng = XorShift32::new(seed);
        let avoid = Avoid::new(&params.avoid, &mut rng);
        Self {
            params,
            mode: Mode::Idle,
            rng,
            avoid,
            edge: EdgeFollow::new(params.pause_side),
            drift: Drift::new(Point::new(0.0, 0.0)),
            turning: Turning::new(),
            light: DriveToLight::new(),
            held_avoid: Held::default(),
            held_edge: Held::default(),
            held_drift: Held::default(),
            held_light: Held::default(),
            held_turn: Held::default(),
            state: BehaviourState::default(),
            standstill: 0,
        }
    }

    /// Switches mode and resets the behaviours it uses (edge following starts with a reset).
    pub fn set_mode(&mut self, mode: Mode) {
        self.mode = mode;
        self.turning.reset();
        self.edge = EdgeFollow::new(match mode {
            Mode::EdgeFollow(side) => side,
            _ => self.params.pause_side,
        });
        if let Mode::GoTo(target) = mode {
            self.drift = Drift::new(target);
        }
        if mode == Mode::DriveToLight {
            self.light = DriveToLight::new();
        }
        self.held_edge = Held::default();
        self.held_drift = Held::default();
        self.held_light = Held::default();
        self.held_turn = Held::default();
        self.standstill = 0;
    }

    /// Mode in force.
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// Report of the last cycle.
    pub fn state(&self) -> &BehaviourState {
        &self.state
    }

    /// The drift state (meaningful in `GoTo`).
    pub fn drift(&self) -> &Drift {
        &self.drift
    }

    /// Leave the light source reached in `DriveToLight` (seed 000 §6.1, up to T3).
    pub fn release_light(&mut self) {
        self.light.release();
    }

    /// One control cycle: combine the behaviours into a motor command.
    pub fn step(&mut self, inp: &Inputs) -> MotorCommand {
        let mut st = BehaviourState {
            mode: self.mode,
            ..BehaviourState::default()
        };
        let cmd = if self.mode == Mode::Idle {
            MotorCommand::STOP
        } else if let Some(turn) = self.turning_step(inp, &mut st) {
            turn
        } else {
            self.combine(inp, &mut st)
        };
        st.output = cmd.clamped(self.params.max_units);
        st.avoid_thresholds = self.avoid.thresholds();
        st.edge_phase = self.edge.phase();
        st.drift_phase = self.drift.phase();
        st.light_phase = self.light.phase();
        self.state = st;
        st.output
    }

    /// Turning first: while it runs nothing else is stepped (§4: it suppresses the others).
    fn turning_step(&mut self, inp: &Inputs, st: &mut BehaviourState) -> Option<MotorCommand> {
        let was_turning = self.turning.active().is_some();
        let cmd = if inp.pose_fresh {
            let monitor = match self.mode {
                Mode::Idle => false,
                Mode::Wander | Mode::EdgeFollow(_) => true,
                Mode::GoTo(_) => matches!(
                    self.drift.phase(),
                    DriftPhase::Driving | DriftPhase::Paused { .. }
                ),
                Mode::DriveToLight => {
                    matches!(
                        self.light.phase(),
                        LightPhase::Searching | LightPhase::Leaving
                    )
                }
            };
            // Stale IR must not re-trigger the dead-end pattern: look at no obstacles instead.
            let ir = if inp.ir_fresh { inp.ir } else { [0; 8] };
            let p = &self.params.turn;
            let out = self.turning.step(&ir, inp.pose, monitor, p, &mut self.rng);
            st.dead_end = out.dead_end;
            let half_turn = matches!(
                self.turning.active().map(|t| t.reason),
                Some(TurnReason::Circle | TurnReason::DeadEnd)
            );
            if !was_turning && half_turn && matches!(self.mode, Mode::GoTo(_)) {
                // A 180° turn means the robot was trapped: one more sign of cyclic
                // behaviour for drift's escalation (seed 000 §4.4).
                self.drift.cyclic(&self.params.drift);
            }
            out.cmd.map(|c| self.held_turn.fresh(c))
        } else if was_turning {
            st.stale.insert(BehaviourSet::TURN);
            Some(self.held_turn.reuse(self.params.max_stale_cycles))
        } else {
            None
        };
        if was_turning && self.turning.active().is_none() {
            // Back from a turn: edge following starts over with a reset (§4.3).
            self.edge.reset();
        }
        let cmd = cmd?;
        st.active.insert(BehaviourSet::TURN);
        st.turn = cmd;
        st.turn_reason = self.turning.active().map(|t| t.reason);
        Some(cmd)
    }

    /// Goal behaviour (edge, drift or light) added to avoidance.
    fn combine(&mut self, inp: &Inputs, st: &mut BehaviourState) -> MotorCommand {
        let mut propulsion = 1.0;
        let mut correction = MotorCommand::STOP;
        match self.mode {
            Mode::Idle | Mode::Wander => {}
            Mode::EdgeFollow(_) => correction = self.edge_step(inp, st),
            Mode::GoTo(_) => {
                let was_paused = matches!(self.drift.phase(), DriftPhase::Paused { .. });
                let d = if inp.pose_fresh {
                    let out = self
                        .drift
                        .step(inp.pose, &self.params.drift, &self.params.turn);
                    self.held_drift.fresh(out)
                } else {
                    st.stale.insert(BehaviourSet::DRIFT);
                    self.held_drift.reuse(self.params.max_stale_cycles)
                };
                st.drift = d.cmd;
                match d.phase {
                    DriftPhase::Reached => return MotorCommand::STOP,
                    DriftPhase::Paused { .. } => {
                        if !was_paused {
                            // Follow the obstacle's edge, searching for it first; the side
                            // alternates between failures.
                            let side = self.drift.pause_side(self.params.pause_side);
                            self.edge = EdgeFollow::seeking(side);
                        }
                        correction = self.edge_step(inp, st);
                    }
                    DriftPhase::Aligning | DriftPhase::Driving => {
                        st.active.insert(BehaviourSet::DRIFT);
                        if d.turning {
                            // The drift's own turn on the spot suppresses the others (§4.5).
                            return d.cmd;
                        }
                        correction = d.cmd;
                    }
                }
                propulsion = d.propulsion;
            }
            Mode::DriveToLight => {
                let l = if inp.light_fresh {
                    let out = self.light.step(&inp.light, &self.params.light);
                    self.held_light.fresh(out)
                } else {
                    st.stale.insert(BehaviourSet::LIGHT);
                    self.held_light.reuse(self.params.max_stale_cycles)
                };
                if l.phase == LightPhase::Arrived {
                    st.active.insert(BehaviourSet::LIGHT);
                    return MotorCommand::STOP;
                }
                if l.phase == LightPhase::Approaching {
                    st.active.insert(BehaviourSet::LIGHT);
                }
                st.light = l.delta;
                correction = l.delta;
                propulsion = l.propulsion;
            }
        }
        let a = if inp.ir_fresh {
            let p = &self.params.avoid;
            let out = self.avoid.step(&inp.ir, propulsion, p, &mut self.rng);
            self.held_avoid.fresh(out)
        } else {
            st.stale.insert(BehaviourSet::AVOID);
            self.held_avoid.reuse(self.params.max_stale_cycles)
        };
        if a.active() {
            st.active.insert(BehaviourSet::AVOID);
        }
        st.avoid = a.cmd;
        let cmd = a.cmd.plus(correction);
        if matches!(self.mode, Mode::GoTo(_)) {
            self.watch_standstill(cmd);
        }
        cmd
    }

    /// Avoidance and drift cancelling each other (the robot pressed against a wall across
    /// its way, turned away by one as much as towards the target by the other) leave the
    /// robot standing still: a sign of cyclic behaviour for drift's escalation (seed 000
    /// §4.4), given after `standstill_cycles` instead of the circle criterion's N (§4.5).
    fn watch_standstill(&mut self, cmd: MotorCommand) {
        let still = cmd.left.abs() <= 1 && cmd.right.abs() <= 1;
        let driving = self.drift.phase() == DriftPhase::Driving;
        self.standstill = if still && driving {
            self.standstill.saturating_add(1)
        } else {
            0
        };
        if self.standstill >= self.params.drift.standstill_cycles.max(1) {
            self.standstill = 0;
            self.drift.cyclic(&self.params.drift);
        }
    }

    fn edge_step(&mut self, inp: &Inputs, st: &mut BehaviourState) -> MotorCommand {
        let e = if inp.ir_fresh {
            let out = self.edge.step(&inp.ir, &self.params.edge);
            self.held_edge.fresh(out)
        } else {
            st.stale.insert(BehaviourSet::EDGE);
            self.held_edge.reuse(self.params.max_stale_cycles)
        };
        st.active.insert(BehaviourSet::EDGE);
        st.edge = e.delta;
        e.delta
    }
}

#[cfg(test)]
mod tests;
