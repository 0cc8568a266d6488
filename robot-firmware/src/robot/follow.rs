//! Plan following (seed 004 §7): drive through the installed plan's waypoints in order.
//!
//! Layer: part of the control cycle (`Core::decide` in `Mode::ExecutePlan`). The waypoints are
//! read straight out of the installed Plan object (`transfer::Objects`), in millimetres. Each
//! leg uses the robot's existing way of reaching a point: guided motion on a compass robot
//! (seed 004 §7 `guided_motion()`, micro-rato) or the behaviour arbiter's `GoTo` on a robot
//! with encoders (seed 000 §4, khepera). Reaching the last waypoint sends `PlanFinished` and
//! `GoalReached` and stops; replacing the plan while it runs sends `PlanAborted`.
//!
//! On a compass robot the legs go through `crate::execute::Executor`, which adds seed 004
//! §7's exception heuristics to guided motion: never more than 0.6 m from the ideal segment
//! (at the limit, turn orthogonally back towards it) and long segments split into
//! sub-segments. The plan's waypoints are copied out of the plan object when execution
//! starts, so a plan replaced mid-run cannot change the points being driven to.
//!
//! What can fail: `ExecutePlan` is refused (`NoPlan`, `PlanIdMismatch`, `Unsupported`) and
//! then changes nothing; a plan that vanishes mid-run stops the robot. Never a panic.

use protocol::{EventCode, Mode, NackReason};

use super::{Core, Kit};
use crate::behaviour::{self, drift::DriftPhase};
use crate::execute::{ExecPhase, Executor, Waypoints};
use crate::guided::{guided_step, GuidedPhase};
use crate::hal::MotorCommand;
use crate::odometry::Point;

/// Where the robot is in the plan it executes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Execution {
    /// The id of the plan being executed.
    pub plan_id: u32,
    /// Index of the waypoint being driven to.
    pub next: u16,
    /// Number of waypoints.
    pub count: u16,
    /// Past the last waypoint without seeing the goal area: heading for the goal light.
    pub approaching: bool,
}

/// The executing plan's waypoints, metres, read from the installed plan object (which stays
/// while it executes: a new plan aborts the execution); `None`: the plan is gone.
struct PlanPoints<'a>(Option<protocol::object::PlanView<'a>>);

impl Waypoints for PlanPoints<'_> {
    fn point(&self, i: usize) -> Option<Point> {
        let p = self.0?.waypoint(u16::try_from(i).ok()?)?;
        Some(Point::new(p.x_mm as f32 / 1000.0, p.y_mm as f32 / 1000.0))
    }
    fn count(&self) -> usize {
        self.0.map_or(0, |v| usize::from(v.waypoint_count()))
    }
}

impl<K: Kit> Core<K> {
    /// `Command::ExecutePlan`: starts the installed plan if it has this id.
    pub(super) fn start_plan(&mut self, plan_id: u32) -> Result<(), NackReason> {
        let (id, view) = self.objects.plan().ok_or(NackReason::NoPlan)?;
        if id != plan_id {
            return Err(NackReason::PlanIdMismatch);
        }
        if !self.profile.has(protocol::caps::ENCODERS) && !self.profile.has(protocol::caps::COMPASS)
        {
            return Err(NackReason::Unsupported);
        }
        let count = view.waypoint_count();
        self.exec = Some(Execution {
            plan_id,
            next: 0,
            count,
            approaching: false,
        });
        self.executor = Executor::new(self.executor.params, self.pose().point());
        // Entering the mode (again) starts from the first waypoint.
        self.enter(Mode::ExecutePlan);
        Ok(())
    }

    /// Whether legs are driven by guided motion (no encoders) rather than the arbiter.
    pub(super) fn plan_guided(&self) -> bool {
        !self.profile.has(protocol::caps::ENCODERS)
    }

    /// The arbiter's mode on entering `ExecutePlan`.
    pub(super) fn plan_arbiter_mode(&self) -> behaviour::Mode {
        match self.exec.and_then(|e| self.waypoint(e.next)) {
            Some(p) if !self.plan_guided() => behaviour::Mode::GoTo(p),
            _ => behaviour::Mode::Idle,
        }
    }

    /// Waypoint `i` of the plan being executed, metres; `None` if that plan is gone.
    fn waypoint(&self, i: u16) -> Option<Point> {
        let exec = self.exec?;
        let (id, view) = self.objects.plan()?;
        let p = view.waypoint(i).filter(|_| id == exec.plan_id)?;
        Some(Point::new(p.x_mm as f32 / 1000.0, p.y_mm as f32 / 1000.0))
    }

    /// This cycle's motor command in `Mode::ExecutePlan`.
    pub(super) fn plan_command(&mut self) -> MotorCommand {
        let Some(exec) = self.exec else {
            return MotorCommand::STOP;
        };
        if self.arrived {
            return MotorCommand::STOP;
        }
        if !exec.approaching && self.waypoint(exec.next).is_none() {
            self.abort_plan();
            return MotorCommand::STOP;
        }
        if self.plan_guided() {
            self.guided_leg()
        } else {
            self.arbiter_leg()
        }
    }

    /// Guided motion through the waypoints with the §7 heuristics (`Executor`).
    fn guided_leg(&mut self) -> MotorCommand {
        let (ir, n) = self.ir_rays();
        if self.profile.has(protocol::caps::GROUND_SENSOR) && self.sensors.ground {
            // In the goal area (seed 004 §3 ground sensor): the task is done, wherever the
            // plan's last point was.
            if let Some(exec) = self.exec.as_mut() {
                exec.next = exec.count;
            }
            self.finish_plan();
            return MotorCommand::STOP;
        }
        if self.exec.is_some_and(|e| e.approaching) {
            return self.final_approach(&ir[..n]);
        }
        let pose = self.pose();
        let plan = self
            .objects
            .plan()
            .filter(|(id, _)| self.exec.is_some_and(|e| e.plan_id == *id));
        let points = PlanPoints(plan.map(|(_, view)| view));
        let (cmd, report) = self.executor.step(pose, &ir[..n], &points, &self.guided);
        if let (Some(i), Some(exec)) = (report.passed, self.exec.as_mut()) {
            exec.next = u16::try_from(i + 1).unwrap_or(u16::MAX).min(exec.count);
        }
        if report.phase == ExecPhase::Finished {
            let approach = self
                .profile
                .has(protocol::caps::GROUND_SENSOR | protocol::caps::BEACON);
            if let Some(exec) = self.exec.as_mut() {
                exec.next = exec.count;
                if approach && !exec.approaching {
                    // The plan ends near where the goal area was found; the area itself is
                    // what counts (seed 004 §2), so finish the approach towards the light.
                    exec.approaching = true;
                    let count = i32::from(exec.count);
                    self.push_event(EventCode::PlanFinished, count);
                    return self.final_approach(&ir[..n]);
                }
            }
            self.finish_plan();
            return MotorCommand::STOP;
        }
        cmd
    }

    /// After the last waypoint: guided motion towards the goal light until the ground sensor
    /// sees the goal area.
    fn final_approach(&mut self, ir: &[(u16, f32)]) -> MotorCommand {
        let (cmd, phase) = guided_step(self.pose(), self.dead.params.beacon, ir, &self.guided);
        if phase == GuidedPhase::Arrived {
            // At the light without seeing the area: nothing more to drive to.
            self.finish_plan();
            return MotorCommand::STOP;
        }
        cmd
    }

    /// The task is done: `PlanFinished` (unless the approach already sent it), then
    /// `GoalReached`, and stop.
    fn finish_plan(&mut self) {
        if let Some(exec) = self.exec {
            if !exec.approaching {
                self.push_event(EventCode::PlanFinished, i32::from(exec.count));
            }
        }
        self.mark_arrived();
    }

    /// The arbiter's `GoTo` towards the current waypoint; the next one is set when the drift
    /// behaviour reports it reached. Waypoints already within the arrival radius (the start,
    /// a centre the robot sits on) are passed first, so the robot does not stop a cycle at each.
    fn arbiter_leg(&mut self) -> MotorCommand {
        let radius = self.arbiter.params.drift.arrival_radius_m;
        let count = self.exec.map_or(0, |e| e.count);
        for _ in 0..count {
            let Some(target) = self.exec.and_then(|e| self.waypoint(e.next)) else {
                return MotorCommand::STOP;
            };
            if self.pose().point().distance_to(target) >= radius {
                break;
            }
            match self.advance() {
                Some(next) => self.arbiter.set_mode(behaviour::Mode::GoTo(next)),
                None => return MotorCommand::STOP,
            }
        }
        let cmd = self.behaviour_command();
        if self.arbiter.state().drift_phase != DriftPhase::Reached {
            return cmd;
        }
        if let Some(next) = self.advance() {
            self.arbiter.set_mode(behaviour::Mode::GoTo(next));
        }
        MotorCommand::STOP
    }

    /// Moves to the next waypoint and returns it; after the last, reports the plan finished.
    fn advance(&mut self) -> Option<Point> {
        let exec = self.exec.as_mut()?;
        exec.next = exec.next.saturating_add(1);
        if exec.next < exec.count {
            return self.waypoint(self.exec?.next);
        }
        let count = i32::from(exec.count);
        self.push_event(EventCode::PlanFinished, count);
        self.mark_arrived();
        None
    }

    /// Abandons the plan being executed (it was replaced or vanished): `PlanAborted` with the
    /// waypoint index, motors stopped, mode `Idle`.
    pub(super) fn abort_plan(&mut self) {
        if self.mode == Mode::ExecutePlan {
            if !self.arrived {
                let at = self.exec.map_or(0, |e| i32::from(e.next));
                self.push_event(EventCode::PlanAborted, at);
            }
            self.enter(Mode::Idle);
        }
        self.exec = None;
    }
}
