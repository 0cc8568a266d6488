//! Plan following (seed 004 §7): drive through the installed plan's waypoints in order.
//!
//! Layer: part of the control cycle (`Core::decide` in `Mode::ExecutePlan`). The waypoints are
//! read straight out of the installed Plan object (`transfer::Objects`), in millimetres. Each
//! leg uses the robot's existing way of reaching a point: guided motion on a compass robot
//! (seed 004 §7 `guided_motion()`, micro-rato) or the behaviour arbiter's `GoTo` on a robot
//! with encoders (seed 000 §4, khepera). Reaching the last waypoint sends `PlanFinished` and
//! `GoalReached` and stops; replacing the plan while it runs sends `PlanAborted`.
//!
//! `PlanFinished` means the robot has stopped: on a robot with a ground sensor and a beacon, a
//! plan that ends at the map's goal without the goal area in sight goes on with a final
//! approach towards the goal light, and the plan is finished only when that ends (it once
//! sent `PlanFinished` as the approach began, and the robot drove on for minutes). A plan
//! that ends anywhere else (a target the operator chose) stops at its last waypoint.
//!
//! On a compass robot the legs go through `crate::execute::Executor`, which adds seed 004
//! §7's exception heuristics to guided motion: never more than 0.6 m from the ideal segment
//! (at the limit, turn orthogonally back towards it) and long segments split into
//! sub-segments. The waypoints are read out of the plan object as they are needed (no copy:
//! 2 KB of the robot's 32); a plan replaced mid-run aborts the run (`Core::installed`), and a
//! plan of another id is never driven (`Execution::plan_id`).
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

/// The executing plan's waypoints in metres, read from its object; none if the robot holds
/// another plan now.
struct PlanPoints<'a> {
    view: protocol::object::PlanView<'a>,
    same_plan: bool,
}

impl Waypoints for PlanPoints<'_> {
    fn count(&self) -> usize {
        if self.same_plan {
            usize::from(self.view.waypoint_count())
        } else {
            0
        }
    }

    fn point(&self, i: usize) -> Option<Point> {
        let p = self
            .view
            .waypoint(u16::try_from(i).ok()?)
            .filter(|_| self.same_plan)?;
        Some(Point::new(p.x_mm as f32 / 1000.0, p.y_mm as f32 / 1000.0))
    }
}

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
    pub(super) fn waypoint(&self, i: u16) -> Option<Point> {
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
        let last = self
            .exec
            .and_then(|e| self.waypoint(e.count.checked_sub(1)?));
        if self.profile.has(protocol::caps::GROUND_SENSOR)
            && self.sensors.ground
            && self.plan_ends_at_map_goal(last)
        {
            // In the goal area (seed 004 §3 ground sensor) on a plan to it: the task is done,
            // wherever the plan's last point was. A plan to another target crosses it.
            if let Some(exec) = self.exec.as_mut() {
                exec.next = exec.count;
            }
            self.finish_plan();
            return MotorCommand::STOP;
        }
        if self.exec.is_some_and(|e| e.approaching) {
            return self.final_approach(&ir[..n]);
        }
        let Some((plan_id, view)) = self.objects.plan() else {
            return MotorCommand::STOP;
        };
        let points = PlanPoints {
            view,
            same_plan: self.exec.is_some_and(|e| e.plan_id == plan_id),
        };
        let (cmd, report) = self
            .executor
            .step(self.pose(), &ir[..n], &points, &self.guided);
        if let (Some(i), Some(exec)) = (report.passed, self.exec.as_mut()) {
            exec.next = u16::try_from(i + 1).unwrap_or(u16::MAX).min(exec.count);
        }
        if report.phase == ExecPhase::Finished {
            let approach = self
                .profile
                .has(protocol::caps::GROUND_SENSOR | protocol::caps::BEACON)
                && self.plan_ends_at_map_goal(last);
            if let Some(exec) = self.exec.as_mut() {
                exec.next = exec.count;
                if approach && !exec.approaching {
                    // The plan ends near where the goal area was found; the area itself is
                    // what counts (seed 004 §2), so finish the approach towards the light.
                    // Not finished yet: `finish_plan` says so when the robot stops.
                    exec.approaching = true;
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

    /// Whether the plan's last point is the map's goal (within the arrival radius: plan points
    /// are whole millimetres of grid units), so that the goal area lies beyond it.
    fn plan_ends_at_map_goal(&self, last: Option<Point>) -> bool {
        let goal = self.objects.map_goal();
        match (last, goal) {
            (Some(p), Some(g)) => {
                let g = Point::new(g.x_mm as f32 / 1000.0, g.y_mm as f32 / 1000.0);
                p.distance_to(g) <= self.guided.arrival_m
            }
            _ => false,
        }
    }

    /// The task is done and the robot stops: `PlanFinished`, then `GoalReached`.
    fn finish_plan(&mut self) {
        if let Some(exec) = self.exec {
            if !self.arrived {
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

#[cfg(test)]
pub(super) mod tests {
    extern crate std;
    use super::*;
    use crate::nav::{grid_bytes, Cell, Geometry, Grid};
    use crate::robot::DomDinis;
    use crate::scripted::ScriptedHal;
    use crate::{odometry::Pose, Robot, RobotOptions, MAP_CAPACITY, MICRO_RATO};
    use protocol::{Command, Event, PointMm};

    /// A micro-rato at (0.5, 0.5) facing north-east, holding an all-free 5 x 5 m map whose
    /// goal is `goal`; the compass keeps reading north-east, so guided motion drives straight.
    pub(in crate::robot) fn robot_on_open_map(
        goal: Option<PointMm>,
        heading: f32,
    ) -> Robot<DomDinis> {
        let mut robot = Robot::new(RobotOptions {
            profile: &MICRO_RATO,
            seed: 1,
            start: Pose::new(0.5, 0.5, heading),
            emulated: false,
            firmware_version: "test",
        });
        let geo = Geometry::from_metres(0.3, 0.0, 0.0).unwrap();
        let storage = [0u8; grid_bytes(MAP_CAPACITY, MAP_CAPACITY)];
        let mut grid = Grid::new(17, 17, geo, storage).unwrap();
        for y in 0..17 {
            for x in 0..17 {
                grid.set(x, y, Cell::Free).unwrap();
            }
        }
        robot.core.objects.set_map(&grid, None, goal).unwrap();
        robot
    }

    /// Runs `cycles` control cycles, the compass turning as the wheels command (0.2 m track,
    /// 3.07 mm/s a nominal unit); returns every event with the motor command of the cycle
    /// that raised it and the time, ms.
    pub(in crate::robot) fn run(
        robot: &mut Robot<DomDinis>,
        hal: &mut ScriptedHal,
        cycles: u32,
    ) -> std::vec::Vec<(EventCode, i32, MotorCommand, u64)> {
        let mut out = std::vec::Vec::new();
        let period = u64::from(robot.core.profile.cycle_us);
        for _ in 0..cycles {
            hal.now_us += period;
            let now = hal.now_us;
            robot.core.control_cycle(hal, now);
            let m = robot.core.motor;
            let w = f32::from(m.right - m.left) * 0.00307 / 0.2;
            let dt = period as f32 * 1e-6;
            hal.compass = hal.compass.map(|h| crate::odometry::wrap_angle(h + w * dt));
            while let Some(Event { code, value }) = robot.core.events.pop_front() {
                out.push((code, value, robot.core.motor, now / 1000));
            }
        }
        out
    }

    fn plan_and_execute(robot: &mut Robot<DomDinis>, to: PointMm) {
        let core = &mut robot.core;
        assert!(matches!(
            core.apply(
                Command::Plan {
                    from: None,
                    to: Some(to)
                },
                0
            ),
            crate::link::Reply::Ack(_)
        ));
        let (plan_id, _) = core.objects.plan().unwrap();
        assert!(matches!(
            core.apply(Command::ExecutePlan { plan_id }, 0),
            crate::link::Reply::Ack(_)
        ));
    }

    /// `PlanFinished` is said once, when the motors stop, and they stay stopped.
    fn assert_finished_only_when_stopped(events: &[(EventCode, i32, MotorCommand, u64)]) {
        let finished: std::vec::Vec<_> = events
            .iter()
            .filter(|e| e.0 == EventCode::PlanFinished)
            .collect();
        assert_eq!(finished.len(), 1, "{events:?}");
        let (_, _, motor, at) = *finished[0];
        assert_eq!(
            motor,
            MotorCommand::STOP,
            "PlanFinished at {at} ms while driving"
        );
    }

    #[test]
    fn a_plan_to_the_maps_goal_is_finished_only_when_the_final_approach_stops() {
        // Issue 16: "plan finished" 0.1 s after X while the robot drove on for minutes. The
        // plan ends at the map's goal, short of the goal light (2.5, 2.5, straight ahead), and
        // the ground sensor never sees the area: the robot approaches the light, then stops.
        let goal = PointMm {
            x_mm: 1000,
            y_mm: 1000,
        };
        let mut robot = robot_on_open_map(Some(goal), core::f32::consts::FRAC_PI_4);
        let mut hal = ScriptedHal {
            compass: Some(core::f32::consts::FRAC_PI_4),
            ..ScriptedHal::default()
        };
        plan_and_execute(&mut robot, goal);
        let events = run(&mut robot, &mut hal, 3000);
        assert_finished_only_when_stopped(&events);
        let here = robot.core.pose().point();
        let light = robot.core.dead.params.beacon;
        assert!(
            here.distance_to(light) <= robot.core.guided.arrival_m + 0.05,
            "{here:?}"
        );
        assert!(robot.core.arrived);
        // The task is over: Idle, and no progress report counts on at its end.
        assert_eq!(robot.core.mode, Mode::Idle);
        let now = robot.core.cycle_ms.wrapping_add(5000);
        assert_eq!(
            robot.core.progress.report_due(Mode::Idle, now, (0, 0)),
            None
        );
        let finished = events.iter().position(|e| e.0 == EventCode::PlanFinished);
        let reached = events.iter().position(|e| e.0 == EventCode::GoalReached);
        assert!(finished < reached, "{events:?}");
    }

    #[test]
    fn a_plan_to_a_chosen_target_stops_there_without_heading_for_the_light() {
        let mut robot = robot_on_open_map(
            Some(PointMm {
                x_mm: 4000,
                y_mm: 4000,
            }),
            core::f32::consts::FRAC_PI_4,
        );
        let mut hal = ScriptedHal {
            compass: Some(core::f32::consts::FRAC_PI_4),
            ..ScriptedHal::default()
        };
        plan_and_execute(
            &mut robot,
            PointMm {
                x_mm: 1000,
                y_mm: 1000,
            },
        );
        let events = run(&mut robot, &mut hal, 3000);
        assert_finished_only_when_stopped(&events);
        let here = robot.core.pose().point();
        assert!(here.distance_to(Point::new(1.0, 1.0)) <= 0.2, "{here:?}");
    }
}
