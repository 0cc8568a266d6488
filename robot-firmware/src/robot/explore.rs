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

use super::Core;
use crate::explore::{ExploreInput, ExplorePhase};
use crate::hal::MotorCommand;
use crate::nav::{grid_bytes, Geometry, Grid};
use crate::MAP_CAPACITY;

/// Map cell size for exploration (seed 004 §5: the position error is 0.3 m, so the grid is).
const EXPLORE_CELL_M: f32 = 0.3;
const GRID_BYTES: usize = grid_bytes(MAP_CAPACITY, MAP_CAPACITY);

impl Core {
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
        // Both sides are at most MAP_CAPACITY (checked above), so they fit u16.
        let grid = Grid::new(w as u16, h as u16, geometry, [0u8; GRID_BYTES])
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
            on_goal_area: self.sensors.ground,
        };
        let Some(grid) = self.objects.grid_mut() else {
            return MotorCommand::STOP;
        };
        let cmd = self.explorer.step(&input, grid);
        if self.explorer.phase() == ExplorePhase::Arrived {
            if !self.arrived {
                self.record_goal_found(input.pose.point());
            }
            self.mark_arrived();
            return MotorCommand::STOP;
        }
        cmd
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
