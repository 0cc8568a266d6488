//! The control cycle: sensors, the position estimate, the mode's motor command, every
//! `Profile::cycle_us` (`Robot::step` decides when).
//!
//! Layer: the only code, with `Robot::step`, that touches the `Hal`.

use protocol::{EventCode, Mode};

use super::kit::{AliceSlot, ExplorerSlot, ForageSlot, LightCalSlot, LineCorrSlot};
use super::{ms, Core, Kit, Sensors, Slot};
use crate::behaviour::{self, BehaviourSet, Inputs};
use crate::deadreckon::{DeadReckonInput, DegradeEvent};
use crate::guided::{guided_step, GuidedPhase};
use crate::hal::{Hal, MotorCommand};
use crate::odometry::{encoder_delta, wrap_angle};

/// Minimum time between two beacon calibrations, ms (seed 004 §4 gives no rate).
const CALIBRATION_INTERVAL_MS: u32 = 1000;
/// Beacon bearing under which the beacon is taken to be straight ahead, radians (~3 degrees).
const BEACON_AHEAD_RAD: f32 = 0.05;
/// Beacon strength above which a calibration is attempted.
const CALIBRATION_MIN_STRENGTH: u8 = 20;

impl<K: Kit> Core<K> {
    pub(super) fn control_cycle<H: Hal>(&mut self, hal: &mut H, now_us: u64) {
        let now_ms = ms(now_us);
        self.cycle_ms = now_ms;
        let t = &mut self.timing;
        let cycle_us = u64::from(self.profile.cycle_us);
        if let Some(last) = t.last_cycle_us {
            t.period_us = u32::try_from(now_us.saturating_sub(last)).unwrap_or(u32::MAX);
            if u64::from(t.period_us) > cycle_us + cycle_us / 2 {
                t.overruns = t.overruns.wrapping_add(1);
            }
        }
        t.last_cycle_us = Some(now_us);
        t.cycles = t.cycles.wrapping_add(1);
        // Keep the cycle grid; after a stall of more than a cycle, restart it from now.
        t.next_cycle_us = if t.next_cycle_us + cycle_us > now_us {
            t.next_cycle_us + cycle_us
        } else {
            now_us + cycle_us
        };

        self.read_sensors(hal);
        K::Alice::read(self, hal);
        self.estimate(now_ms);
        K::Alice::sample(self, now_ms);
        K::LightCal::report_bearing(self, now_ms);
        self.map_as_it_moves();
        let cmd = match self.track_progress() {
            Some(stop) => stop,
            None => self.decide(),
        };
        let max = self.profile.motor_max;
        let cmd = cmd.clamped(max);
        self.motor = cmd;
        hal.set_motors(cmd);
        if self.profile.has(protocol::caps::GRIPPER) {
            hal.set_gripper(self.gripper_cmd);
        }
        let end = hal.now_us();
        self.timing.busy_us = u32::try_from(end.saturating_sub(now_us)).unwrap_or(u32::MAX);
    }

    pub(super) fn read_sensors<H: Hal>(&mut self, hal: &mut H) {
        let s = Sensors {
            ir: hal.ir(),
            ambient: hal.ambient(),
            compass: hal.compass(),
            ground: hal.ground(),
            line: hal.line(),
            beacon: hal.beacon(),
            battery_mv: hal.battery_mv(),
            encoders: hal.encoders(),
            gripper: hal.gripper(),
        };
        let heading = self.pose().heading;
        if let Some(forage) = self.forage.get_mut() {
            if self.mode == Mode::Forage && forage.wants_frame() {
                // Only when a landmark scan asks (the K213 gives 2 frames a second), straight
                // into the scan, so the line is not kept.
                let mut line = [0u8; crate::hal::CAMERA_PIXELS];
                let ok = hal.camera(&mut line);
                forage.take_frame(heading, ok.then_some(&line));
            }
        }
        if s.line && !self.sensors.line {
            self.line_events = self.line_events.wrapping_add(1);
            self.push_event(EventCode::LineCrossed, i32::from(self.line_events));
        }
        self.sensors = s;
    }

    pub(super) fn estimate(&mut self, now_ms: u32) {
        let period_s = (self.timing.period_us as f32) * 1e-6;
        if let Some(enc) = self.sensors.encoders {
            if let Some(prev) = self.prev_encoders {
                let dl = encoder_delta(prev[0], enc[0]);
                let dr = encoder_delta(prev[1], enc[1]);
                self.odometry.step(dl, dr);
                K::LineCorr::line_correct(self, dl, dr, now_ms);
                if period_s > 0.0 {
                    let mm = self.odometry.params.mm_per_pulse;
                    self.wheel_speed_mm_s = [
                        behaviour::units(dl as f32 * mm / period_s),
                        behaviour::units(dr as f32 * mm / period_s),
                    ];
                }
            }
            self.prev_encoders = Some(enc);
        }
        if !self.profile.has(protocol::caps::ENCODERS) {
            if let Some(h) = self.sensors.compass {
                self.compass_heading = wrap_angle(h);
            }
            let battery = self.battery_level();
            self.dead.step(
                now_ms,
                DeadReckonInput {
                    heading_rad: self.compass_heading,
                    nominal: [f32::from(self.motor.left), f32::from(self.motor.right)],
                    battery,
                },
            );
            let speed = |u: i16| {
                let mps = self.dead.params.speed.speed_mps(f32::from(u), battery);
                behaviour::units(mps * 1000.0)
            };
            self.wheel_speed_mm_s = [speed(self.motor.left), speed(self.motor.right)];
            self.calibrate_on_beacon(now_ms);
        }
    }

    /// Seed 004 §4: with the beacon straight ahead, its strength gives the distance and the
    /// compass the direction, an alternative position blended in by the confidence xi.
    pub(super) fn calibrate_on_beacon(&mut self, now_ms: u32) {
        let Some(b) = self.sensors.beacon else { return };
        let recent = self
            .last_calibration_ms
            .is_some_and(|t| now_ms.wrapping_sub(t) < CALIBRATION_INTERVAL_MS);
        if recent
            || b.strength < CALIBRATION_MIN_STRENGTH
            || libm::fabsf(b.bearing_rad) > BEACON_AHEAD_RAD
        {
            return;
        }
        let bearing = wrap_angle(self.compass_heading + b.bearing_rad);
        if self.dead.calibrate(u16::from(b.strength), bearing).is_ok() {
            self.last_calibration_ms = Some(now_ms);
            let xi = libm::roundf(self.dead.confidence() * 1000.0) as i32;
            self.push_event(EventCode::BeaconCalibration, xi);
        }
    }

    /// Battery level 0..=1 from the voltage, for the speed table.
    pub(super) fn battery_level(&self) -> f32 {
        let (lo, hi) = (self.config.battery_empty_mv, self.config.battery_full_mv);
        if hi <= lo || self.sensors.battery_mv == 0 {
            // Unknown battery: assume average, the paper's reference point.
            return 0.5;
        }
        let v = f32::from(self.sensors.battery_mv.saturating_sub(lo)) / f32::from(hi - lo);
        v.clamp(0.0, 1.0)
    }

    /// The motor command for this cycle, by mode.
    pub(super) fn decide(&mut self) -> MotorCommand {
        let cmd = self.mode_command();
        // A task that ended this cycle (it arrived) left the robot Idle: stopped at once.
        if self.mode == Mode::Idle {
            MotorCommand::STOP
        } else {
            cmd
        }
    }

    pub(super) fn mode_command(&mut self) -> MotorCommand {
        if self.mode == Mode::Wander {
            // ALICE wanders by its whiskers; the others by the arbiter's IR behaviours.
            if let Some(cmd) = K::Alice::wander(self) {
                return cmd;
            }
        }
        match self.mode {
            Mode::Idle => MotorCommand::STOP,
            Mode::Manual => {
                if self.failsafe {
                    MotorCommand::STOP
                } else {
                    self.teleop_command()
                }
            }
            Mode::GoTo if self.guided_active => self.guided_command(),
            Mode::GoTo
            | Mode::Wander
            | Mode::EdgeFollowLeft
            | Mode::EdgeFollowRight
            | Mode::SeekLight => self.behaviour_command(),
            Mode::ExecutePlan => self.plan_command(),
            Mode::Explore => K::Explorer::command(self),
            Mode::Forage => K::Forage::command(self),
            Mode::Survey => K::LineCorr::survey_command(self),
            Mode::CalibrateLight => K::LightCal::command(self),
        }
    }

    /// Differential-drive kinematics: wheel speeds from forward speed and turn rate.
    pub(super) fn teleop_command(&self) -> MotorCommand {
        let (v, w) = self.teleop;
        let half_base_mm = self.profile.wheel_distance_m * 500.0;
        let max = self.config.teleop_max_mm_s;
        let turn = f32::from(w) / 1000.0 * half_base_mm;
        let left = (f32::from(v) - turn).clamp(-max, max);
        let right = (f32::from(v) + turn).clamp(-max, max);
        MotorCommand::new(
            self.profile.motor_units(left),
            self.profile.motor_units(right),
        )
    }

    pub(super) fn behaviour_command(&mut self) -> MotorCommand {
        let inputs = Inputs::fresh(self.sensors.ir, self.sensors.ambient, self.pose());
        let cmd = self.arbiter.step(&inputs);
        let st = self.arbiter.state();
        let dead_end = st.dead_end;
        let reached = st.drift_phase == behaviour::drift::DriftPhase::Reached;
        if dead_end && !self.prev_dead_end {
            self.dead.degrade(DegradeEvent::DeadEnd);
        }
        self.prev_dead_end = dead_end;
        if self.mode == Mode::GoTo && reached {
            self.mark_arrived();
        }
        cmd
    }

    /// The IR readings with their mounting directions (radians, positive to the left), as
    /// guided motion, plan execution and exploration take them; `n` of the slots are in use.
    pub(super) fn ir_rays(&self) -> ([(u16, f32); 8], usize) {
        let mut ir = [(0u16, 0.0f32); 8];
        let n = self.profile.ir.count.min(8);
        for (i, slot) in ir.iter_mut().enumerate().take(n) {
            *slot = (self.sensors.ir[i], self.profile.ir.angle_rad[i]);
        }
        (ir, n)
    }

    pub(super) fn guided_command(&mut self) -> MotorCommand {
        let Some(goal) = self.goal else {
            return MotorCommand::STOP;
        };
        if let Some(cmd) = K::Explorer::goto(self, goal) {
            return cmd;
        }
        let (ir, n) = self.ir_rays();
        let (cmd, phase) = guided_step(self.pose(), goal, &ir[..n], &self.guided);
        if phase == GuidedPhase::Arrived {
            self.mark_arrived();
        }
        cmd
    }

    /// The task is done: `GoalReached`, and the robot goes Idle with its motors stopped, so
    /// that its mode, its progress reports (none in Idle) and the station's status line say
    /// the task is over instead of counting time without progress at its end. `arrived`
    /// stays set until the next mode begins: it says the last task ended by arriving.
    pub(super) fn mark_arrived(&mut self) {
        if !self.arrived {
            self.push_event(EventCode::GoalReached, 0);
            self.enter(Mode::Idle);
            self.arrived = true;
        }
    }

    /// The behaviour bits and motor output telemetry reports.
    pub fn behaviour_report(&self) -> (u8, MotorCommand) {
        use protocol::behaviours as b;
        let mut bits = 0u8;
        let arbiter_driven = match self.mode {
            Mode::GoTo => !self.guided_active,
            Mode::Wander | Mode::EdgeFollowLeft | Mode::EdgeFollowRight | Mode::SeekLight => true,
            Mode::ExecutePlan => !self.plan_guided(),
            Mode::Forage => true,
            _ => false,
        };
        if arbiter_driven {
            let active = self.arbiter.state().active;
            for (from, to) in [
                (BehaviourSet::AVOID, b::AVOID),
                (BehaviourSet::EDGE, b::EDGE),
                (BehaviourSet::DRIFT, b::DRIFT),
                (BehaviourSet::TURN, b::TURN),
                (BehaviourSet::LIGHT, b::LIGHT),
            ] {
                if active.contains(from) {
                    bits |= to;
                }
            }
        }
        if (self.guided_active && self.mode == Mode::GoTo)
            || (self.mode == Mode::ExecutePlan && self.plan_guided())
        {
            bits |= b::GUIDED;
        }
        (bits, self.motor)
    }
}
