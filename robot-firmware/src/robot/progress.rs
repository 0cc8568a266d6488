//! Motion progress: what the mode in force is doing (for the station's status line) and
//! giving up when a mode with a target makes none.
//!
//! Layer: part of the control cycle. Every cycle `Core::track_progress` measures the distance
//! left to the mode's target (GoTo: the point; ExecutePlan: along the waypoints still ahead,
//! or to the goal light on the final approach; Explore: to the goal light) and remembers when
//! it last shrank by `stuck_progress_m`. A GoTo or ExecutePlan that has not progressed for
//! `stuck_limit_s` ends: a `NoProgress` event (value: the milliseconds without progress), the
//! motors stopped, mode Idle. Reactive motion can oscillate at a wall for minutes (guided
//! motion turns away, the heading correction turns back); this is what ends it. Explore is
//! reported but never given up: its wall following may lead away from the light for long, by
//! design, and it breaks its own loops (seed 004 §5 timeouts, planning).
//!
//! About once a second while a mode other than Idle runs, `Message::Progress` (PROTOCOL.md §6
//! kind 14) carries the waypoint k of n, distance left, time in mode and time without
//! progress; telemetry stays small.
//!
//! The watchdog itself and its defaults are `crate::motion_progress`.
//! Cannot fail or panic.

use protocol::{EventCode, Mode};

use super::{Core, Kit, Slot};
use crate::hal::MotorCommand;
use crate::odometry::Point;

impl<K: Kit> Core<K> {
    /// The distance left to the mode's target, metres; `None` for a mode without one.
    pub(super) fn distance_left(&self) -> Option<f32> {
        let here = self.pose().point();
        match self.mode {
            // A go-to on the map (compass robots): along its route, which may lead away from
            // the point for long (round a wall); else straight to it.
            Mode::GoTo => self
                .planned_route_left()
                .or_else(|| self.goal.map(|g| here.distance_to(g))),
            Mode::ExecutePlan => self.plan_distance_left(here),
            Mode::Explore => Some(here.distance_to(self.dead.params.beacon)),
            _ => None,
        }
    }

    /// The planned go-to's route length, metres (its cells times the map's cell).
    fn planned_route_left(&self) -> Option<f32> {
        let cells = self.explorer.get()?.planned().route_cells()?;
        let cell_m = self.objects.nav().grid().geometry().cell_size_m();
        Some(cells as f32 * cell_m)
    }

    /// Along the plan: to the next waypoint, then leg by leg to the last; on the final
    /// approach, to the goal light.
    fn plan_distance_left(&self, here: Point) -> Option<f32> {
        let exec = self.exec?;
        if exec.approaching {
            return Some(here.distance_to(self.dead.params.beacon));
        }
        let mut at = here;
        let mut total = 0.0;
        for i in exec.next..exec.count {
            let p = self.waypoint(i)?;
            total += at.distance_to(p);
            at = p;
        }
        Some(total)
    }

    /// (waypoint being driven to, 1-based; count) for the report, (0, 0) outside a plan.
    pub(super) fn plan_position(&self) -> (u16, u16) {
        match self.exec {
            Some(e) if self.mode == Mode::ExecutePlan => (
                e.next.saturating_add(1).min(e.count.saturating_add(1)),
                e.count,
            ),
            _ => (0, 0),
        }
    }

    /// Measures progress; a target mode stuck for its limit gives up: `NoProgress`, Idle,
    /// motors stopped. Returns the command to use instead of the mode's, if it gave up.
    pub(super) fn track_progress(&mut self) -> Option<MotorCommand> {
        let now = self.cycle_ms;
        let left = self.distance_left();
        let stuck_ms = self.progress.observe(now, left);
        if self.arrived || !self.progress.stuck(self.mode, now) {
            return None;
        }
        let value = i32::try_from(stuck_ms).unwrap_or(i32::MAX);
        self.push_event(EventCode::NoProgress, value);
        if self.mode == Mode::ExecutePlan {
            self.exec = None;
        }
        self.enter(Mode::Idle);
        Some(MotorCommand::STOP)
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;

    #[test]
    fn a_go_to_against_a_wall_gives_up_at_its_limit_and_stops_the_motors() {
        use crate::robot::follow::tests::{robot_on_open_map, run};
        use crate::scripted::ScriptedHal;
        use protocol::{Command, PointMm};
        // Issue 16: go-to oscillated at a wall for minutes with no word. Every IR sensor sees
        // the wall: guided motion turns away, and gets no nearer.
        let mut robot = robot_on_open_map(None, 0.0);
        let mut hal = ScriptedHal {
            compass: Some(0.0),
            ir: [900; 8],
            ..ScriptedHal::default()
        };
        let goal = PointMm {
            x_mm: 4000,
            y_mm: 4000,
        };
        let _ = robot.core.apply(Command::GoTo(goal), 0);
        assert_eq!(robot.core.mode, Mode::GoTo);
        let limit_ms = 120_000;
        let events = run(&mut robot, &mut hal, 2600);
        let gave_up: std::vec::Vec<_> = events
            .iter()
            .filter(|e| e.0 == EventCode::NoProgress)
            .collect();
        assert_eq!(gave_up.len(), 1, "{events:?}");
        let (_, stuck_ms, motor, at_ms) = *gave_up[0];
        assert!(stuck_ms >= limit_ms, "{stuck_ms}");
        assert!(
            (120_000..=121_000).contains(&at_ms),
            "gave up at {at_ms} ms"
        );
        assert_eq!(motor, MotorCommand::STOP);
        assert_eq!(robot.core.mode, Mode::Idle);
        assert_eq!(hal.motors, MotorCommand::STOP);
    }

    #[test]
    fn a_progress_report_says_where_the_plan_is() {
        use crate::robot::follow::tests::robot_on_open_map;
        use protocol::{Command, PointMm};
        let mut robot = robot_on_open_map(
            Some(PointMm {
                x_mm: 4000,
                y_mm: 4000,
            }),
            0.0,
        );
        let core = &mut robot.core;
        let _ = core.apply(
            Command::Plan {
                from: None,
                to: None,
            },
            0,
        );
        let (plan_id, view) = core.objects.plan().unwrap();
        let n = view.waypoint_count();
        let _ = core.apply(Command::ExecutePlan { plan_id }, 0);
        core.track_progress();
        let r = core.progress.report(core.mode, 0, core.plan_position());
        assert_eq!((r.mode, r.waypoint, r.waypoints), (Mode::ExecutePlan, 1, n));
        // From (0.5, 0.5) through the waypoints to (4, 4): at least the straight line.
        let left = r.distance_left_mm.unwrap();
        assert!((4949..6000).contains(&left), "{left}");
        assert_eq!(r.give_up_ms, 120_000);
    }
}
