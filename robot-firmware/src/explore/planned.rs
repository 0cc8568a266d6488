//! The search that plans on its own map (issue 32): heading for the goal along a route over
//! the robot's grid map with unknown cells taken as free, replanned as walls appear, the way a
//! micromouse floods its maze (the incremental form is D* Lite, Koenig and Likhachev 2002;
//! here the whole wave is redone, which the firmware's 64 x 64 grid makes cheap: see
//! `robot-firmware/plan-cost.sh`). What the map cannot tell yet is left to seed 004 §5's
//! reactive behaviours: with nothing known the route is the straight line to the beacon, and
//! a wall met that the map does not hold is followed, on the side the route turns to, until
//! the route leads away from it.
//!
//! Layer: inside [`super::Explorer`] (`SearchMode::Planned`, the default; the paper's reactive
//! search is `SearchMode::Reactive`) and behind a compass robot's go-to to a point, which
//! plans over what it knows the same way instead of steering straight at the point. The map
//! and its planner are reached through [`MapMarker::route_towards`]; this module holds a few
//! words of state.
//!
//! Replanning: when the map gains a wall cell, when the waypoint is reached, when a wall
//! blocks the way, and at least every `replan_ms`. When the map shows no way at all (its walls
//! hold dead-reckoning errors that close a gap), the walls away from the robot are forgotten
//! and the route planned again; the same when the route has not shortened for
//! `no_progress_ms` (a map whose errors make the robot circle). Without any route the robot
//! heads straight for the goal, as the paper's search does.
//!
//! Pure: pose, readings, time and the map in; motor command out. Cannot fail or panic.

use super::motion::{follow, front_blocked, steer};
use super::{
    mark_wall, ray_point, CellSet, ExploreInput, ExploreParams, ExploreStats, MapMarker, WallSide,
};
use crate::behaviour::MotorCommand;
use crate::nav::Cell;
use crate::odometry::{wrap_angle, Point};

/// How far inside a seen wall it is marked, m: the cell holding the wall's face is as likely
/// free space beside it, and on a 0.15 m map marking it closed the gaps of 0.3-0.4 m the
/// robot drives through.
const WALL_DEPTH_M: f32 = 0.05;
/// Cells within this of the robot's centre are ones it stands in, m (half its radius: the
/// body's own cell and a neighbour it reaches well into).
const BODY_M: f32 = 0.1;
/// Half the aperture of an IR obstacle sensor's beam (CiberRato's see 60 degrees), to four
/// places as the search's figures were measured with (`FRAC_PI_6` is another `f32`).
#[allow(clippy::approx_constant)]
const BEAM_HALF_RAD: f32 = 0.5236;

/// The planned search's map: the cells the robot stands in are free, and stay free (its
/// centre has been there, so a route may cross them whatever a later reading, shifted by the
/// position's error, says: `visited` holds them); each IR ray marks the unknown cells it
/// crosses free, as the paper's map does, and each reading marks a wall a little inside the
/// wall it sees, unless that cell is one the robot stood in: a wall of the map when the beam
/// is no wider than a cell there, a far mark beyond. Rays' free cells change no route (the
/// planner takes unknown cells as free anyway); they make the map a later plan executes on
/// (`Plan` over free cells) as wide as the space seen, not a band along the robot's track.
/// Without `visited` (marking outside a search run), a free cell is taken as stood in.
/// Returns the number of cells that became walls.
pub fn mark_visited(
    inp: &ExploreInput<'_>,
    p: &ExploreParams,
    map: &mut dyn MapMarker,
    visited: Option<&mut CellSet>,
) -> u32 {
    mark_visited_counting(inp, p, map, visited).0
}

/// [`mark_visited`], also counting the cells the robot stands in for the first time.
fn mark_visited_counting(
    inp: &ExploreInput<'_>,
    p: &ExploreParams,
    map: &mut dyn MapMarker,
    mut visited: Option<&mut CellSet>,
) -> (u32, u32) {
    let here = inp.pose.point();
    let mut fresh = 0;
    for (dx, dy) in [
        (0.0, 0.0),
        (BODY_M, 0.0),
        (-BODY_M, 0.0),
        (0.0, BODY_M),
        (0.0, -BODY_M),
    ] {
        let q = Point::new(here.x + dx, here.y + dy);
        let new = match (visited.as_deref_mut(), map.index(q)) {
            (Some(v), Some(c)) => {
                let new = !v.contains(c);
                v.set(c, true);
                new
            }
            _ => map.cell_at(q).is_some_and(|c| c != Cell::Free),
        };
        fresh += u32::from(new);
        map.mark(q, Cell::Free);
    }
    let stood_in = |map: &dyn MapMarker, v: &Option<&mut CellSet>, q: Point| match v {
        Some(v) => map.index(q).is_some_and(|c| v.contains(c)),
        None => map.cell_at(q) == Some(Cell::Free),
    };
    // A reading is a wall of the map only where the beam is no wider than a cell (0.13 m from
    // the sensor on a 0.15 m map); farther, the wall it reports may be anywhere across the
    // beam (the end of a wall at its side reads as a wall straight ahead): a far mark
    // ([`super::far_marks`]), which cannot close a gap the route needs.
    let within = map.cell_m() / (2.0 * libm::tanf(BEAM_HALF_RAD));
    let mut walls = 0;
    for &(reading, angle) in inp.ir {
        let seen = p.ir.distance(reading);
        if visited.is_some() {
            mark_ray_free(inp, angle, seen.unwrap_or(p.ir.range_m), map);
        }
        if let Some(d) = seen {
            // The sensor sits at the body edge; the wall is d beyond it.
            let q = ray_point(inp, angle, d + 0.12 + WALL_DEPTH_M);
            if map.cell_at(q).is_some() && !stood_in(map, &visited, q) {
                if d <= within {
                    walls += mark_wall(map, q);
                } else {
                    map.mark_far(q);
                }
            }
        }
    }
    (walls, fresh)
}

/// Marks the unknown cells along the ray at `angle` free, from the body's edge to `reach` m
/// from the centre (the paper's map: space a sensor saw through is free).
fn mark_ray_free(inp: &ExploreInput<'_>, angle: f32, reach: f32, map: &mut dyn MapMarker) {
    let mut t = 0.05;
    while t < reach {
        let q = ray_point(inp, angle, t);
        if map.cell_at(q) == Some(Cell::Unknown) {
            map.mark(q, Cell::Free);
        }
        t += 0.05;
    }
}

/// What the planned search is doing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PlannedPhase {
    /// Driving to the route's next point.
    Drive,
    /// Going round a wall the route runs into (the map does not hold it yet), wall on `side`.
    Follow { side: WallSide, since_ms: u32 },
}

/// The planned search's state: the route's next point and when it was planned.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Planned {
    phase: PlannedPhase,
    /// The goal the route was planned to (a new goal is planned for at once).
    goal: Point,
    waypoint: Option<Point>,
    planned_ms: u32,
    /// The last route's length, in steps between cells.
    route_cells: u32,
    /// The shortest route (in cells) seen since `progress_ms`.
    best_cells: u32,
    progress_ms: u32,
    /// When the map last had to be forgotten whole (no way even without its far walls).
    wiped_ms: Option<u32>,
    /// Until when the paper's reactive search drives instead (the map keeps misleading).
    reactive_until_ms: Option<u32>,
    /// Where the robot was when it last moved `stuck_m`, and when.
    moved_at: Point,
    moved_ms: u32,
    /// When the robot last stood in a cell it had not stood in before.
    fresh_ms: u32,
}

impl Default for Planned {
    fn default() -> Self {
        Self::new()
    }
}

impl Planned {
    pub const fn new() -> Self {
        Planned {
            phase: PlannedPhase::Drive,
            goal: Point { x: 0.0, y: 0.0 },
            waypoint: None,
            planned_ms: 0,
            route_cells: 0,
            best_cells: u32::MAX,
            progress_ms: 0,
            wiped_ms: None,
            reactive_until_ms: None,
            moved_at: Point { x: 0.0, y: 0.0 },
            moved_ms: 0,
            fresh_ms: 0,
        }
    }

    /// Marks the map ([`mark_visited`]); a cell the robot stands in for the first time is
    /// progress (see `stale_ms`). Returns the number of cells that became walls.
    pub fn mark(
        &mut self,
        inp: &ExploreInput<'_>,
        p: &ExploreParams,
        map: &mut dyn MapMarker,
        visited: &mut CellSet,
    ) -> u32 {
        let (walls, fresh) = mark_visited_counting(inp, p, map, Some(visited));
        if fresh > 0 {
            self.fresh_ms = inp.now_ms;
        }
        walls
    }

    /// Whether the paper's reactive search drives now: the map closed every way twice within
    /// `reactive_ms` (its walls hold errors that re-form as fast as they are forgotten), so
    /// for `reactive_ms` the search goes by wall following, which finds a gap by touch.
    pub fn reactive(&mut self, now_ms: u32) -> bool {
        match self.reactive_until_ms {
            Some(t) if now_ms.wrapping_sub(t) < 0x8000_0000 => {
                self.reactive_until_ms = None;
                self.phase = PlannedPhase::Drive;
                self.waypoint = None;
                false
            }
            Some(_) => true,
            None => false,
        }
    }

    pub fn phase(&self) -> PlannedPhase {
        self.phase
    }

    /// The route's next point, if there is a route.
    pub fn waypoint(&self) -> Option<Point> {
        self.waypoint
    }

    /// The last route's length in steps between cells, if it found one.
    pub fn route_cells(&self) -> Option<u32> {
        self.waypoint.map(|_| self.route_cells)
    }

    /// One control cycle towards `inp.goal`; `new_walls` says the map gained wall cells this
    /// cycle. Arrival is the caller's (the explorer's ground sensor or radius).
    pub fn step(
        &mut self,
        p: &ExploreParams,
        inp: &ExploreInput<'_>,
        map: &mut dyn MapMarker,
        new_walls: bool,
        stats: &mut ExploreStats,
    ) -> MotorCommand {
        let here = inp.pose.point();
        let blocked = front_blocked(p, inp);
        let reached = self
            .waypoint
            .is_some_and(|w| here.distance_to(w) <= p.waypoint_m);
        if inp.goal != self.goal {
            *self = Planned::new();
            self.goal = inp.goal;
            self.progress_ms = inp.now_ms;
            self.moved_at = here;
            self.moved_ms = inp.now_ms;
            self.fresh_ms = inp.now_ms;
        }
        if inp.now_ms.wrapping_sub(self.fresh_ms) >= p.stale_ms {
            // Driving round in what it has seen for long: the map keeps sending the robot
            // back and forth (its marks close a way it has not found by touch yet).
            self.fresh_ms = inp.now_ms;
            self.reactive_until_ms = Some(inp.now_ms.wrapping_add(p.reactive_ms));
            stats.timeouts = stats.timeouts.wrapping_add(1);
        }
        if here.distance_to(self.moved_at) >= p.stuck_m {
            self.moved_at = here;
            self.moved_ms = inp.now_ms;
        } else if inp.now_ms.wrapping_sub(self.moved_ms) >= p.stuck_ms {
            // Turning on the spot where the route's points and the walls keep the robot from
            // leaving (a tight corner the map cannot show): the reactive search's wall
            // following gets it out by touch.
            self.moved_ms = inp.now_ms;
            self.reactive_until_ms = Some(inp.now_ms.wrapping_add(p.reactive_ms));
            stats.timeouts = stats.timeouts.wrapping_add(1);
        }
        let since = inp.now_ms.wrapping_sub(self.planned_ms);
        // The route's point is kept while the map shows the way to it clear: replanning on
        // every mark turned the robot to and fro where marks come and go (a narrow gap).
        let lost = self.waypoint.is_none_or(|w| !map.clear_line(here, w));
        let due = reached
            || (lost && (self.waypoint.is_none() || since >= p.min_replan_ms))
            || (blocked && since >= p.min_replan_ms)
            || (since >= p.replan_ms && new_walls);
        if due {
            self.replan(p, inp, map, stats);
        }
        let target = self.waypoint.unwrap_or(inp.goal);
        let bearing = wrap_angle(here.bearing_to(target) - inp.pose.heading);
        match self.phase {
            PlannedPhase::Drive => {
                if blocked && libm::fabsf(bearing) < p.follow_cone_rad {
                    // The route runs into a wall the map does not show yet: go round it on
                    // the side the route turns to (to the left: the wall on the right).
                    let side = if bearing >= 0.0 {
                        WallSide::Right
                    } else {
                        WallSide::Left
                    };
                    stats.walls_found = stats.walls_found.wrapping_add(1);
                    self.phase = PlannedPhase::Follow {
                        side,
                        since_ms: inp.now_ms,
                    };
                    return follow(p, inp, side);
                }
                steer(p, inp, target)
            }
            PlannedPhase::Follow { side, since_ms } => {
                let elapsed = inp.now_ms.wrapping_sub(since_ms);
                // Away from the wall: the route turns off it (or back past it).
                let off = match side {
                    WallSide::Right => bearing,
                    WallSide::Left => -bearing,
                };
                let leaves = off > p.leave_rad || libm::fabsf(bearing) > p.follow_cone_rad * 2.0;
                if elapsed >= p.min_follow_ms / 2 && !blocked && leaves {
                    stats.rejoins = stats.rejoins.wrapping_add(1);
                    self.phase = PlannedPhase::Drive;
                    return steer(p, inp, target);
                }
                follow(p, inp, side)
            }
        }
    }

    /// Plans again; with no way on the map, forgets its far walls and plans once more.
    fn replan(
        &mut self,
        p: &ExploreParams,
        inp: &ExploreInput<'_>,
        map: &mut dyn MapMarker,
        stats: &mut ExploreStats,
    ) {
        let here = inp.pose.point();
        self.planned_ms = inp.now_ms;
        stats.plans = stats.plans.wrapping_add(1);
        let stale = inp.now_ms.wrapping_sub(self.progress_ms) >= p.no_progress_ms;
        let mut step = map.route_towards(here, inp.goal);
        if step.is_none() && map.open_walls_between(here, inp.goal) > 0 {
            // Marks one cell thick closed the last way between the robot's region and the
            // goal's (a narrow gap, narrowed by the position's error): reopened.
            step = map.route_towards(here, inp.goal);
        }
        if step.is_none() {
            // The way closed under the latest marks, those of the walls around the robot: a
            // gap it is passing, narrowed by its position's error. Forget them; they are
            // marked again as it drives on.
            map.forget_walls_near(here, p.keep_walls_m);
            step = map.route_towards(here, inp.goal);
        }
        if step.is_none() || stale {
            // Still no way (or the robot circles): the map's walls hold errors. Forget them
            // all; a second time soon after, let the reactive search find the way.
            map.forget_walls(here, 0.0);
            stats.dead_ends = stats.dead_ends.wrapping_add(1);
            self.best_cells = u32::MAX;
            self.progress_ms = inp.now_ms;
            let again = self
                .wiped_ms
                .is_some_and(|t| inp.now_ms.wrapping_sub(t) < p.reactive_ms);
            self.wiped_ms = Some(inp.now_ms);
            if again {
                self.reactive_until_ms = Some(inp.now_ms.wrapping_add(p.reactive_ms));
                stats.timeouts = stats.timeouts.wrapping_add(1);
            }
            step = map.route_towards(here, inp.goal);
        }
        match step {
            Some(s) => {
                self.route_cells = s.cells;
                if s.cells < self.best_cells {
                    self.best_cells = s.cells;
                    self.progress_ms = inp.now_ms;
                }
                self.waypoint = Some(s.waypoint);
            }
            None => self.waypoint = None,
        }
    }
}
