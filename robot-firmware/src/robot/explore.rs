//! Exploration mode (seed 004 §5): the reactive goal search drives the robot and marks the
//! robot's own map as it goes.
//!
//! Layer: part of the control cycle (`Core::decide` in `Mode::Explore`). On a compass robot
//! with a beacon sensor (micro-rato), `StartExploration` begins a run: with no map installed
//! the robot creates an all-unknown one over its arena bounds at the paper's 0.3 m cells,
//! with its start and the goal light as markers; with a map installed (a second run) it keeps
//! it, so each run adds to what the robot knows ("avoid history" prefers unknown cells). The
//! goal area is seen by the ground sensor; reaching it stops the robot, sends `GoalReached`
//! and makes the point where it stopped the map's goal (the goal light's cell is not a place
//! a plan can end). The map can be downloaded at any time, segmented and planned on.
//!
//! What can fail: `Unsupported` on a robot without compass and beacon; `CapacityExceeded` if
//! the arena needs more than the firmware's 64 x 64 cells. Never a panic.

use protocol::{Mode, NackReason, PointMm};

use super::{Core, Kit, Slot};
use crate::deadreckon::DegradeEvent;
use crate::explore::{ExploreInput, ExploreParams, ExplorePhase, ExploreStats, MapMarker};
use crate::hal::MotorCommand;
use crate::nav::{grid_bytes, Cell, Geometry, Grid, Passable, Route};
use crate::odometry::Point;
use crate::transfer::Objects;
use crate::MAP_CAPACITY;

/// Map cell size for exploration (seed 004 §5: the position error is 0.3 m, so the grid is).
const EXPLORE_CELL_M: f32 = 0.3;
const GRID_BYTES: usize = grid_bytes(MAP_CAPACITY, MAP_CAPACITY);

impl<K: Kit> Core<K> {
    /// Outside exploration, the robot still maps with its sensors whatever moves it (go-to,
    /// teleop, a plan), so that a plan can start where go-to left it. Only unknown cells are
    /// filled in: a map the operator uploaded, or one exploration made, is never contradicted
    /// by a passing reading. Idle, nothing is marked: a map just uploaded stays byte for byte
    /// what was sent until the robot moves. Robots without IR sensors, or without a map,
    /// mark nothing.
    pub(super) fn map_as_it_moves(&mut self) {
        if matches!(self.mode, Mode::Explore | Mode::Idle) || !self.objects.has_map() {
            return;
        }
        let (ir, n) = self.ir_rays();
        if n == 0 {
            return;
        }
        let input = ExploreInput {
            now_ms: self.cycle_ms,
            pose: self.pose(),
            ir: &ir[..n],
            goal: self.dead.params.beacon,
            ground: None,
            arrival_m: self.guided.arrival_m,
        };
        // Any robot with a map marks it; one without the explorer uses its default limits.
        let params = self
            .explorer
            .get()
            .map_or_else(ExploreParams::default, |e| e.params);
        crate::explore::mark_map(&input, &params, &mut UnknownOnly(&mut self.objects));
    }
}

impl<K: Kit<Explorer = crate::explore::Explorer>> Core<K> {
    /// `StartExploration` (or `SetMode(Explore)`): begins a reactive-search run.
    pub(super) fn start_exploration(&mut self) -> Result<(), NackReason> {
        let caps = protocol::caps::COMPASS | protocol::caps::BEACON;
        if !self.profile.has(caps) {
            return Err(NackReason::Unsupported);
        }
        if !self.objects.has_map() {
            self.create_exploration_map()?;
        }
        self.explorer.restart();
        self.enter(Mode::Explore);
        Ok(())
    }

    /// An all-unknown map over the dead-reckoning bounds, start and goal marked.
    fn create_exploration_map(&mut self) -> Result<(), NackReason> {
        let b = self.dead.params.bounds;
        let cells = |span: f32| libm::ceilf(span / EXPLORE_CELL_M - 1e-3).max(1.0);
        let (w, h) = (cells(b.max.x - b.min.x), cells(b.max.y - b.min.y));
        let cap = MAP_CAPACITY as f32;
        if !(w <= cap && h <= cap) {
            return Err(NackReason::CapacityExceeded);
        }
        let geometry = Geometry::from_metres(EXPLORE_CELL_M, b.min.x, b.min.y)
            .map_err(|_| NackReason::CapacityExceeded)?;
        // All unknown: cells over a constant in flash, which `set_map` copies into the robot's
        // grid in place (a 1 KB array here was most of the worst-case stack, issue 15).
        static UNKNOWN: [u8; GRID_BYTES] = [0; GRID_BYTES];
        // Both sides are at most MAP_CAPACITY (checked above), so they fit u16.
        let grid = Grid::new(w as u16, h as u16, geometry, &UNKNOWN[..])
            .map_err(|_| NackReason::CapacityExceeded)?;
        let here = self.pose();
        let mm = |v: f32| libm::roundf(v * 1000.0) as i32;
        let start = PointMm {
            x_mm: mm(here.x),
            y_mm: mm(here.y),
        };
        let beacon = self.dead.params.beacon;
        let goal = PointMm {
            x_mm: mm(beacon.x),
            y_mm: mm(beacon.y),
        };
        self.objects.set_map(&grid, Some(start), Some(goal))?;
        Ok(())
    }

    /// This cycle's motor command in `Mode::Explore`.
    pub(super) fn explore_command(&mut self) -> MotorCommand {
        let (ir, n) = self.ir_rays();
        let input = ExploreInput {
            now_ms: self.cycle_ms,
            pose: self.pose(),
            ir: &ir[..n],
            goal: self.dead.params.beacon,
            ground: self
                .profile
                .has(protocol::caps::GROUND_SENSOR)
                .then_some(self.sensors.ground),
            arrival_m: self.guided.arrival_m,
        };
        if !self.objects.has_map() {
            return MotorCommand::STOP;
        }
        let before = self.explorer.stats();
        let cmd = self
            .explorer
            .step(&input, &mut ExploreMap(&mut self.objects));
        self.degrade_for(before, self.explorer.stats());
        if self.explorer.phase() == ExplorePhase::Arrived {
            if !self.arrived {
                self.record_goal_found(input.pose.point());
            }
            self.mark_arrived();
            return MotorCommand::STOP;
        }
        cmd
    }

    /// Seed 004 §4: collisions, dead ends and long wall following lower the confidence xi,
    /// so that the next beacon calibration corrects the position by more.
    fn degrade_for(&mut self, before: ExploreStats, after: ExploreStats) {
        let n = |a: u16, b: u16| b.wrapping_sub(a);
        let collisions = n(before.collisions, after.collisions)
            .saturating_add(n(before.long_follows, after.long_follows));
        for _ in 0..collisions.min(4) {
            self.dead.degrade(DegradeEvent::Collision);
        }
        for _ in 0..n(before.dead_ends, after.dead_ends).min(4) {
            self.dead.degrade(DegradeEvent::DeadEnd);
        }
    }

    /// Makes where the robot found the goal area the map's goal, so that a `Plan` with no
    /// `to` (and the station's planner, which reads the map's goal) aims at a cell the robot
    /// has stood in. The goal light's own cell is no target: seed 004 §6 marks the beacon as
    /// an obstacle, and the ground sensor stops the robot at the area's edge, so the light's
    /// cell is usually still unknown, which planning treats as an obstacle.
    fn record_goal_found(&mut self, here: crate::odometry::Point) {
        let mm = |v: f32| libm::roundf(v * 1000.0) as i32;
        self.objects.set_goal(PointMm {
            x_mm: mm(here.x),
            y_mm: mm(here.y),
        });
    }
}

/// The robot's map as the other modes mark it: unknown cells only.
struct UnknownOnly<'a>(&'a mut Objects);

impl MapMarker for UnknownOnly<'_> {
    fn index(&self, p: Point) -> Option<(i32, i32)> {
        MapMarker::index(self.0.nav().grid(), p)
    }

    fn cell_at(&self, p: Point) -> Option<Cell> {
        MapMarker::cell_at(self.0.nav().grid(), p)
    }

    fn mark(&mut self, p: Point, cell: Cell) {
        if cell != Cell::Unknown && self.cell_at(p) == Some(Cell::Unknown) {
            if let Some(grid) = self.0.grid_mut() {
                grid.mark(p, cell);
            }
        }
    }
}

/// The robot's map as exploration sees it: the grid to mark, and the planner over it.
struct ExploreMap<'a>(&'a mut Objects);

impl MapMarker for ExploreMap<'_> {
    fn index(&self, p: Point) -> Option<(i32, i32)> {
        MapMarker::index(self.0.nav().grid(), p)
    }

    fn cell_at(&self, p: Point) -> Option<Cell> {
        MapMarker::cell_at(self.0.nav().grid(), p)
    }

    fn mark(&mut self, p: Point, cell: Cell) {
        // Only a real change counts as one: the map's id is recomputed after changes.
        if self.cell_at(p).is_some_and(|c| c != cell) {
            if let Some(grid) = self.0.grid_mut() {
                grid.mark(p, cell);
            }
        }
    }

    /// Seed 004 §6 on the incomplete map with unknown cells free; the first point of the
    /// smoothed plan (a corner in line of sight), or its first region centre; on a map whose
    /// squares do not fit, the grid planner's first waypoint. The segmentation is forgotten
    /// afterwards: a `Plan` command must segment with unknown as obstacle.
    fn plan_towards(&mut self, from: Point, to: Point) -> Option<Point> {
        let nav = self.0.nav_mut();
        let point = (|| {
            let geo = nav.grid().geometry();
            let start = geo.metres_to_grid(from.x, from.y);
            let goal = geo.metres_to_grid(to.x, to.y);
            let next = match nav.route_with(Passable::FreeOrUnknown, start, goal).ok()? {
                // A quarter cell from square corners, as the station smooths.
                Route::Squares(plan) => {
                    match nav.smooth(&plan, crate::nav::UNITS_PER_CELL as u32 / 4) {
                        Ok(sm) => sm.waypoint(nav.smoothed_points(), 1),
                        Err(_) => {
                            let regions = nav.regions()?;
                            let i = 2.min(plan.waypoint_count() - 1);
                            plan.waypoint(&regions, nav.path(), i)
                        }
                    }
                }
                Route::Grid(plan) => nav.wave_route(plan)?.waypoints().nth(1),
            }?;
            let (x, y) = geo.grid_to_metres(next);
            Some(Point::new(x, y))
        })();
        nav.forget_segmentation();
        point
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::Reply;
    use crate::robot::follow::tests::run;
    use crate::robot::DomDinis;
    use crate::scripted::ScriptedHal;
    use crate::{odometry::Pose, Robot, RobotOptions, MICRO_RATO};
    use protocol::Command;

    #[test]
    fn after_a_go_to_the_robot_can_plan_from_where_it_stopped() {
        // Issue 16: after reaching a spot by go-to, `O` answered "start is in an unknown cell":
        // only exploration marked the map. A robot with an explored (here: all-unknown) map
        // drives by go-to, then plans back from where it stopped.
        let mut robot = Robot::<DomDinis>::new(RobotOptions {
            profile: &MICRO_RATO,
            seed: 1,
            start: Pose::new(0.5, 0.5, 0.0),
            emulated: false,
            firmware_version: "test",
        });
        let mut hal = ScriptedHal {
            compass: Some(0.0),
            ..ScriptedHal::default()
        };
        let core = &mut robot.core;
        assert!(matches!(
            core.apply(Command::StartExploration, 0),
            Reply::Ack(_)
        ));
        assert!(matches!(core.apply(Command::Stop, 0), Reply::Ack(_)));
        let to = PointMm {
            x_mm: 2000,
            y_mm: 500,
        };
        assert!(matches!(core.apply(Command::GoTo(to), 0), Reply::Ack(_)));
        run(&mut robot, &mut hal, 400);
        let core = &mut robot.core;
        assert!(core.arrived, "{:?}", core.pose());
        assert_eq!(core.mode, Mode::Idle, "a go-to that arrived ends in Idle");
        let here = core.pose().point();
        assert_eq!(
            MapMarker::cell_at(core.objects.nav().grid(), here),
            Some(Cell::Free)
        );
        let back = PointMm {
            x_mm: 500,
            y_mm: 500,
        };
        let reply = core.apply(
            Command::Plan {
                from: None,
                to: Some(back),
            },
            0,
        );
        assert!(matches!(reply, Reply::Ack(_)), "{reply:?}");
    }

    #[test]
    fn an_idle_robot_leaves_its_map_as_uploaded() {
        let mut robot = Robot::<DomDinis>::new(RobotOptions {
            profile: &MICRO_RATO,
            seed: 1,
            start: Pose::new(0.5, 0.5, 0.0),
            emulated: false,
            firmware_version: "test",
        });
        let core = &mut robot.core;
        assert!(matches!(
            core.apply(Command::StartExploration, 0),
            Reply::Ack(_)
        ));
        assert!(matches!(core.apply(Command::Stop, 0), Reply::Ack(_)));
        let before = core.objects.map().map(|m| m.id);
        core.map_as_it_moves();
        assert_eq!(core.objects.map().map(|m| m.id), before);
    }

    #[test]
    fn passing_readings_never_overwrite_what_the_map_knows() {
        let mut robot = Robot::<DomDinis>::new(RobotOptions {
            profile: &MICRO_RATO,
            seed: 1,
            start: Pose::new(0.5, 0.5, 0.0),
            emulated: false,
            firmware_version: "test",
        });
        let core = &mut robot.core;
        assert!(matches!(
            core.apply(Command::StartExploration, 0),
            Reply::Ack(_)
        ));
        assert!(matches!(core.apply(Command::Stop, 0), Reply::Ack(_)));
        let here = core.pose().point();
        if let Some(g) = core.objects.grid_mut() {
            g.mark(here, Cell::Obstacle);
        }
        let teleop = Command::Teleop {
            v_mm_s: 0,
            w_mrad_s: 0,
        };
        assert!(matches!(core.apply(teleop, 0), Reply::Ack(_)));
        let before = core.objects.map().map(|m| m.id);
        core.map_as_it_moves();
        // The cell stays; the cells the rays cross are filled in (the map changed).
        assert_ne!(core.objects.map().map(|m| m.id), before);
        assert_eq!(
            MapMarker::cell_at(core.objects.nav().grid(), here),
            Some(Cell::Obstacle)
        );
    }
}
