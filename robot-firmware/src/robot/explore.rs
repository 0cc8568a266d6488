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
use crate::explore::{
    ExploreInput, ExploreParams, ExplorePhase, ExploreStats, MapMarker, RouteStep, SearchMode,
};
use crate::hal::MotorCommand;
use crate::nav::{grid_bytes, Cell, Geometry, Grid, GridPoint, Passable, Route};
use crate::odometry::Point;
use crate::transfer::Objects;
use crate::MAP_CAPACITY;

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

    /// An all-unknown map over the dead-reckoning bounds, start and goal marked: at the
    /// search's cell size (seed 004 §5's 0.3 m for the paper's search, 0.15 m for the planned
    /// one). The planned search's map reaches one cell past the bounds on every side and
    /// holds that ring as wall: the arena's own wall is known from the start, and a reading
    /// of it marks a cell of the ring, not the cells along it where the robot drives (on a
    /// 0.15 m map those marks closed every gap between a wall's end and the arena's wall).
    /// In an arena too large for 0.15 m, the smallest whole centimetre that fits.
    fn create_exploration_map(&mut self) -> Result<(), NackReason> {
        let b = self.dead.params.bounds;
        let mode = self
            .explorer
            .get()
            .map_or(SearchMode::Reactive, |e| e.params.mode);
        let ring = u16::from(mode == SearchMode::Planned);
        let (span_x, span_y) = (b.max.x - b.min.x, b.max.y - b.min.y);
        let cap = MAP_CAPACITY as f32;
        let inner = cap - 2.0 * f32::from(ring);
        let mut cell_m = mode.cell_m();
        if mode == SearchMode::Planned {
            let fit = libm::ceilf(span_x.max(span_y) / inner * 100.0 - 1e-3) / 100.0;
            cell_m = cell_m.max(fit);
        }
        let cells = |span: f32| libm::ceilf(span / cell_m - 1e-3).max(1.0);
        let (w, h) = (cells(span_x), cells(span_y));
        if !(w <= inner && h <= inner) {
            return Err(NackReason::CapacityExceeded);
        }
        let margin = cell_m * f32::from(ring);
        let geometry = Geometry::from_metres(cell_m, b.min.x - margin, b.min.y - margin)
            .map_err(|_| NackReason::CapacityExceeded)?;
        // All unknown: cells over a constant in flash, which `set_map` copies into the robot's
        // grid in place (a 1 KB array here was most of the worst-case stack, issue 15).
        static UNKNOWN: [u8; GRID_BYTES] = [0; GRID_BYTES];
        // Both sides are at most MAP_CAPACITY (checked above), so they fit u16.
        let (w, h) = (w as u16 + 2 * ring, h as u16 + 2 * ring);
        let grid =
            Grid::new(w, h, geometry, &UNKNOWN[..]).map_err(|_| NackReason::CapacityExceeded)?;
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
        if ring > 0 {
            if let Some(g) = self.objects.grid_mut() {
                wall_round(g);
            }
        }
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

    /// A go-to on the robot's map (the search's planner serves go-to too): the route
    /// over what the map knows, unknown cells free, replanned as it goes, instead of steering
    /// straight at the point; without a map, the exploration map is made first; `None` if it
    /// cannot be (guided motion then steers straight).
    /// Arrival is guided motion's radius; the map is marked as in every mode but exploration
    /// (`map_as_it_moves`: unknown cells only).
    pub(super) fn planned_goto(&mut self, goal: Point) -> Option<MotorCommand> {
        if !self.objects.has_map() {
            // A robot that has mapped nothing yet starts the search's all-unknown map: the
            // route is then the straight line until walls are met, and goes round them.
            self.create_exploration_map().ok()?;
        }
        let pose = self.pose();
        if pose.point().distance_to(goal) <= self.guided.arrival_m {
            self.mark_arrived();
            return Some(MotorCommand::STOP);
        }
        let (ir, n) = self.ir_rays();
        let input = ExploreInput {
            now_ms: self.cycle_ms,
            pose,
            ir: &ir[..n],
            goal,
            ground: None,
            arrival_m: self.guided.arrival_m,
        };
        let explorer = self.explorer.get_mut()?;
        Some(explorer.goto_step(&input, &mut ExploreMap(&mut self.objects)))
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

    fn cell_centre(&self, x: i32, y: i32) -> Option<Point> {
        MapMarker::cell_centre(self.0.nav().grid(), x, y)
    }

    fn cell_m(&self) -> f32 {
        MapMarker::cell_m(self.0.nav().grid())
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

    fn cell_centre(&self, x: i32, y: i32) -> Option<Point> {
        MapMarker::cell_centre(self.0.nav().grid(), x, y)
    }

    fn cell_m(&self) -> f32 {
        MapMarker::cell_m(self.0.nav().grid())
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

    /// The grid planner over free and unknown cells (no segmentation: cheap enough to run
    /// several times a second), to the goal's cell or, when that is a wall, the nearest cell
    /// that is not.
    fn route_towards(&mut self, from: Point, to: Point) -> Option<RouteStep> {
        let nav = self.0.nav_mut();
        let geo = nav.grid().geometry();
        let start = geo.metres_to_grid(from.x, from.y);
        let goal = open_near(nav.grid(), geo.metres_to_grid(to.x, to.y))?;
        let (next, cells) = nav
            .first_waypoint(Passable::FreeOrUnknown, start, goal)
            .ok()?;
        let (x, y) = geo.grid_to_metres(off_walls(nav.grid(), next));
        Some(RouteStep {
            waypoint: Point::new(x, y),
            cells,
        })
    }

    fn forget_walls(&mut self, keep: Point, keep_m: f32) {
        if let Some(grid) = self.0.grid_mut() {
            grid.forget_walls(keep, keep_m);
        }
    }

    fn forget_walls_near(&mut self, at: Point, near_m: f32) {
        if let Some(grid) = self.0.grid_mut() {
            grid.forget_walls_near(at, near_m);
        }
    }

    fn clear_line(&self, from: Point, to: Point) -> bool {
        self.0.nav().grid().clear_line(from, to)
    }

    fn open_walls_between(&mut self, from: Point, to: Point) -> usize {
        if self.0.grid_mut().is_none() {
            return 0;
        }
        let nav = self.0.nav_mut();
        let geo = nav.grid().geometry();
        let a = geo.metres_to_grid(from.x, from.y);
        let Some(b) = open_near(nav.grid(), geo.metres_to_grid(to.x, to.y)) else {
            return 0;
        };
        nav.open_between(Passable::FreeOrUnknown, a, b)
    }
}

/// A route point moved off the walls next to its cell: half a cell away from each wall cell
/// beside it (a quarter from one at a corner), at most to the cell's edge. A route's cells
/// run along the walls it goes round, and a 0.24 m robot's centre cannot be at the centre of
/// a 0.15 m cell beside a wall; moved, the point is where the robot can be, in the middle of
/// a gap two cells wide.
fn off_walls<S: AsRef<[u8]>>(grid: &Grid<S>, p: GridPoint) -> GridPoint {
    let (cx, cy) = p.cell();
    let wall = |dx: i32, dy: i32| {
        let (x, y) = (cx + dx, cy + dy);
        grid.contains(x, y) && grid.get(x as usize, y as usize) == Cell::Obstacle
    };
    let half = crate::nav::UNITS_PER_CELL / 2;
    let mut push = (0i32, 0i32);
    for dy in -1..=1i32 {
        for dx in -1..=1i32 {
            if (dx, dy) == (0, 0) || !wall(dx, dy) {
                continue;
            }
            let k = if dx != 0 && dy != 0 { half / 2 } else { half };
            push.0 -= dx * k;
            push.1 -= dy * k;
        }
    }
    let centre = GridPoint::cell_centre(cx as u16, cy as u16);
    GridPoint {
        x: centre.x + push.0.clamp(-half, half),
        y: centre.y + push.1.clamp(-half, half),
    }
}

/// Makes the grid's outermost cells walls.
fn wall_round<S: AsRef<[u8]> + AsMut<[u8]>>(g: &mut Grid<S>) {
    let (w, h) = (usize::from(g.width()), usize::from(g.height()));
    for y in 0..h {
        for x in 0..w {
            if x == 0 || y == 0 || x + 1 == w || y + 1 == h {
                // In range by the loops' bounds.
                let _ = g.set(x, y, Cell::Obstacle);
            }
        }
    }
}

/// `goal` if its cell is not a wall, else the centre of the nearest such cell within three
/// cells of it (the goal light's cell can be marked by a reading of its post or a robot).
fn open_near<S: AsRef<[u8]>>(grid: &Grid<S>, goal: GridPoint) -> Option<GridPoint> {
    let (gx, gy) = goal.cell();
    let open =
        |x: i32, y: i32| grid.contains(x, y) && grid.get(x as usize, y as usize) != Cell::Obstacle;
    if open(gx, gy) {
        return Some(goal);
    }
    for r in 1..=3i32 {
        let mut best: Option<(i32, i32, i32)> = None;
        for y in gy - r..=gy + r {
            for x in gx - r..=gx + r {
                let d = (x - gx) * (x - gx) + (y - gy) * (y - gy);
                if open(x, y) && best.is_none_or(|b| d < b.2) {
                    best = Some((x, y, d));
                }
            }
        }
        if let Some((x, y, _)) = best {
            return Some(GridPoint::cell_centre(x as u16, y as u16));
        }
    }
    None
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
