//! Exploration by repeated reactive goal search, with map building (seed 004 §5, Fig. 4),
//! made complete.
//!
//! Layer: an autonomy behaviour above guided motion, for the micro-rato profile (compass,
//! three IR sensors, beacon). The robot knows only its start pose and the goal light's
//! position. First stage, the paper's reactive search: it heads for the goal; when a wall
//! blocks the way it saves the goal direction and follows the wall, a random, adjustable
//! timeout breaking loops; which way round "avoids history" (the side whose cells are more
//! unknown wins). The paper ends wall following when the heading comes back to the saved
//! direction, which also happens inside U-shaped traps (the robot leaves, drives back into the
//! same wall on the same side, forever). Here following ends by Bug2's rule instead: on the
//! line from the hit point towards the goal, at a point nearer the goal than the hit point,
//! with no known wall towards the goal; so every leave point makes progress. The hit cells are
//! remembered: the same cell met again goes round the other side, and a third time (or a loop
//! round an obstacle back to its hit point) plans on the robot's own partial map with unknown
//! cells taken as free (seed 004: planning works on incomplete maps), re-planning as the map
//! fills in. Arrival: the ground sensor seeing the goal area (seed 004 §3), or, on a robot
//! without one, the robot's arrival radius around the goal light.
//!
//! While it moves, it marks grid cells: the cell under the robot is free; each IR ray marks
//! the unknown cells it crosses free and the cell where it sees something an obstacle. The map
//! (and its planner) is reached through `MapMarker`, so this module needs no storage of its
//! own beyond a few remembered hit cells. Collisions, dead ends and long wall following are
//! counted in [`ExploreStats`] for the dead reckoning's confidence (seed 004 §4).
//!
//! Pure: pose, readings and time in; motor command and map marks out. Cannot fail or panic.

use crate::behaviour::{MotorCommand, XorShift32};
use crate::nav::Cell;
use crate::odometry::{wrap_angle, Point, Pose};

pub mod cell_set;
pub mod far_marks;
pub mod map;
pub mod motion;
pub mod planned;

pub use cell_set::CellSet;
pub use far_marks::{FarMarks, WithFarMarks};
pub use map::{MapMarker, RouteStep};
pub use planned::{Planned, PlannedPhase};

/// IR reading to distance, the inverse of the robot's calibrated sensor curve
/// `reading = 1023 ((range - d) / range)^exponent` (seed 004 §3: 25 cm after calibration).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IrRange {
    pub range_m: f32,
    pub exponent: f32,
    /// Readings below this are taken as "nothing within range" (noise floor).
    pub min_reading: u16,
}

impl Default for IrRange {
    fn default() -> Self {
        IrRange {
            range_m: 0.25,
            exponent: 2.0,
            min_reading: 30,
        }
    }
}

impl IrRange {
    /// Distance for a reading, or `None` when nothing is within range.
    pub fn distance(&self, reading: u16) -> Option<f32> {
        if reading < self.min_reading {
            return None;
        }
        let frac = (f32::from(reading.min(1023)) / 1023.0).max(0.0);
        let x = libm::powf(frac, 1.0 / self.exponent.max(0.1));
        Some((self.range_m * (1.0 - x)).max(0.0))
    }
}

/// Exploration parameters; the paper gives the method, these values are documented defaults.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExploreParams {
    /// Nominal speed heading for the goal (seed 004 §4 speeds 25/50/75).
    pub seek_speed: f32,
    /// Nominal speed while following a wall.
    pub follow_speed: f32,
    /// Wheel difference per radian of heading error while seeking.
    pub heading_gain: f32,
    /// Front IR reading at which a wall counts as found (~12 cm with the default curve).
    pub wall_ir: u16,
    /// IR reading taken as touching a wall, a collision (seed 004 §4 lowers the confidence
    /// for it): ~1 cm with the default curve.
    pub contact_ir: u16,
    /// Distance kept from the followed wall, metres.
    pub follow_distance_m: f32,
    /// Wheel difference per metre of wall-distance error.
    pub follow_gain: f32,
    /// Wall following lasts at least this long before it may end (it starts on the line it
    /// leaves by), ms.
    pub min_follow_ms: u32,
    /// Random wall-following timeout range, ms (seed 004 §5: "random (adjustable)"). Long
    /// enough to go round a competition wall (3-5 m at follow speed, ~0.09 m/s): the
    /// leaving rule, not the timeout, is what ends a normal detour.
    pub timeout_min_ms: u32,
    pub timeout_max_ms: u32,
    /// Bug2's distance check: the leave point must be this much nearer the goal than the hit
    /// point (more than the map's cell, so dead-reckoning jitter cannot fake progress), m.
    pub leave_progress_m: f32,
    /// Half-width of the line through the hit point towards the goal (Bug2's m-line) within
    /// which the robot counts as on it, m.
    pub m_line_band_m: f32,
    /// Each period of uninterrupted wall following lowers the confidence once (seed 004 §4:
    /// accuracy degrades along walls), ms.
    pub follow_degrade_ms: u32,
    /// A plan's point counts as reached within this distance, m.
    pub waypoint_m: f32,
    /// Distance at which cells to either side are sampled to choose a side, metres.
    pub history_probe_m: f32,
    pub ir: IrRange,
    /// Which search `StartExploration` runs.
    pub mode: SearchMode,
    /// The planned search replans at least this often, ms (it learns as it goes).
    pub replan_ms: u32,
    /// ... and at most this often when the map gains walls or the way is blocked, ms.
    pub min_replan_ms: u32,
    /// A wall ahead is followed when the route's next point lies within this angle of the
    /// heading (it would drive into it); else the robot turns towards the point, rad.
    pub follow_cone_rad: f32,
    /// Following ends when the route's next point lies this far off the heading away from
    /// the wall, rad.
    pub leave_rad: f32,
    /// A route that has not got shorter for this long is taken as the map's errors making
    /// the robot circle: the far walls are forgotten, ms.
    pub no_progress_ms: u32,
    /// Walls within this distance of the robot are kept when the far ones are forgotten, m.
    pub keep_walls_m: f32,
    /// Walls seen from afar (a beam wider than a cell) are believed by the planned search's
    /// route when it is at most this much longer than the route without them, m
    /// ([`far_marks`]).
    pub far_detour_m: f32,
    /// When the planned search's map closes every way twice within this time, or it has not
    /// moved `stuck_m` in `stuck_ms`, the reactive search drives for this long, ms.
    pub reactive_ms: u32,
    /// See `reactive_ms`, m.
    pub stuck_m: f32,
    /// See `reactive_ms`, ms.
    pub stuck_ms: u32,
    /// The planned search goes reactive for `reactive_ms` when the robot has stood in no
    /// new cell for this long, ms.
    pub stale_ms: u32,
}

/// Which search exploration runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SearchMode {
    /// Seed 004 §5, Fig. 4: the paper's reactive goal search (with Bug2's leaving rule and
    /// plans when it goes round in circles), on the paper's 0.3 m map.
    Reactive,
    /// Plans on its own map as it goes, unknown cells free, on a 0.15 m map ([`planned`]).
    Planned,
}

impl SearchMode {
    /// The parameter value (`search_mode`, PROTOCOL.md §16): 0 reactive, 1 planned.
    pub const fn code(self) -> u8 {
        match self {
            SearchMode::Reactive => 0,
            SearchMode::Planned => 1,
        }
    }

    /// The mode of a parameter value; anything but 0 plans.
    pub const fn from_code(v: u8) -> SearchMode {
        match v {
            0 => SearchMode::Reactive,
            _ => SearchMode::Planned,
        }
    }

    /// Map cell size, metres. Seed 004 §5's 0.3 m for the paper's search; the planned
    /// search needs a finer grid, as a 0.3 m grid shows no gap narrower than 0.6 m as open
    /// and real labs have gaps of 0.3-0.5 m (issue 32): 0.15 m shows every gap of 0.3 m.
    pub const fn cell_m(self) -> f32 {
        match self {
            SearchMode::Reactive => 0.3,
            SearchMode::Planned => 0.15,
        }
    }
}

impl Default for ExploreParams {
    fn default() -> Self {
        ExploreParams {
            seek_speed: 50.0,
            follow_speed: 30.0,
            heading_gain: 30.0,
            wall_ir: 290,
            contact_ir: 940,
            follow_distance_m: 0.12,
            follow_gain: 150.0,
            min_follow_ms: 1500,
            timeout_min_ms: 30_000,
            timeout_max_ms: 60_000,
            leave_progress_m: 0.35,
            m_line_band_m: 0.08,
            follow_degrade_ms: 10_000,
            waypoint_m: 0.15,
            history_probe_m: 0.6,
            ir: IrRange::default(),
            mode: SearchMode::Planned,
            replan_ms: 1000,
            min_replan_ms: 200,
            follow_cone_rad: 1.0,
            leave_rad: 0.35,
            no_progress_ms: 6_000_000,
            keep_walls_m: 0.5,
            far_detour_m: 0.3,
            reactive_ms: 60_000,
            stuck_m: 0.15,
            stuck_ms: 15_000,
            stale_ms: 45_000,
        }
    }
}

/// Which side the followed wall is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WallSide {
    Left,
    Right,
}

impl WallSide {
    fn other(self) -> WallSide {
        match self {
            WallSide::Left => WallSide::Right,
            WallSide::Right => WallSide::Left,
        }
    }
}

/// What exploration is doing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ExplorePhase {
    /// Heading for the goal light.
    Seek,
    /// Going round an obstacle met at `hit`, until a point of the line from `hit` towards
    /// the goal (`saved_dir`) that is nearer the goal (Bug2's leaving rule).
    Follow {
        side: WallSide,
        saved_dir: f32,
        hit: Point,
        since_ms: u32,
        timeout_ms: u32,
        /// Left the hit point's neighbourhood (so coming back to it closes a loop).
        away: bool,
        /// Confidence-lowering periods already counted.
        degraded: u8,
    },
    /// Driving to `waypoint`, the next point of a plan on the robot's own map (the hit cell
    /// recurred: the reactive search is going round in circles).
    Plan { waypoint: Point, since_ms: u32 },
    /// In the goal area: stopped.
    Arrived,
}

/// One cycle's inputs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExploreInput<'a> {
    pub now_ms: u32,
    pub pose: Pose,
    /// IR readings with their directions (radians, positive to the left), as the profile
    /// mounts them.
    pub ir: &'a [(u16, f32)],
    /// The goal light's known position (seed 004 §5: known from the start).
    pub goal: Point,
    /// The ground sensor's reading (it sees the goal area, seed 004 §3); `None` on a robot
    /// without one.
    pub ground: Option<bool>,
    /// Without a ground sensor: arrival within this distance of `goal` (the robot's arrival
    /// radius, the one guided motion uses), m.
    pub arrival_m: f32,
}

/// Counters for telemetry, tests and the confidence (seed 004 §4 events).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ExploreStats {
    pub walls_found: u16,
    pub rejoins: u16,
    pub timeouts: u16,
    /// Touching a wall (IR at `contact_ir`), counted once per contact.
    pub collisions: u16,
    /// Dead ends: a hit cell met again, or a loop round an obstacle back to its hit point.
    pub dead_ends: u16,
    /// Periods of `follow_degrade_ms` of uninterrupted wall following.
    pub long_follows: u16,
    /// Plans made on the robot's own map.
    pub plans: u16,
}

/// A cell where a wall was met, with the attempts made from it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct HitRecord {
    col: u8,
    row: u8,
    /// Times the search met a wall in this cell before (0 = an empty slot).
    tries: u8,
    /// The side taken last time (true = wall on the left).
    left: bool,
}

/// Hit cells remembered: the last few, oldest replaced first.
const HIT_MEMORY: usize = 4;

/// The reactive search with mapping.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Explorer {
    pub params: ExploreParams,
    phase: ExplorePhase,
    rng: XorShift32,
    stats: ExploreStats,
    hits: [HitRecord; HIT_MEMORY],
    next_hit: u8,
    touching: bool,
    planned: Planned,
    /// The planned search's walls seen from afar.
    far: FarMarks,
    /// The cells the robot has stood in during this run: free whatever a later reading says.
    visited: CellSet,
}

impl Explorer {
    pub fn new(params: ExploreParams, seed: u32) -> Self {
        Explorer {
            params,
            phase: ExplorePhase::Seek,
            rng: XorShift32::new(seed),
            stats: ExploreStats::default(),
            hits: [HitRecord::default(); HIT_MEMORY],
            next_hit: 0,
            touching: false,
            planned: Planned::new(),
            far: FarMarks::new(),
            visited: CellSet::new(),
        }
    }

    /// The planned search's state (its route's next point).
    pub fn planned(&self) -> &Planned {
        &self.planned
    }

    pub fn phase(&self) -> ExplorePhase {
        self.phase
    }

    pub fn stats(&self) -> ExploreStats {
        self.stats
    }

    #[cfg(test)]
    fn restart_phase_for_test(&mut self) {
        self.phase = ExplorePhase::Seek;
    }

    /// Starts a new run (Fig. 4's outer loop begins again).
    pub fn restart(&mut self) {
        self.phase = ExplorePhase::Seek;
        self.hits = [HitRecord::default(); HIT_MEMORY];
        self.planned = Planned::new();
        self.far.clear();
        self.visited.clear();
    }

    /// One control cycle of the search `params.mode` selects: marks the map and returns the
    /// motor command (nominal units).
    pub fn step(&mut self, inp: &ExploreInput<'_>, map: &mut dyn MapMarker) -> MotorCommand {
        let mode = self.params.mode;
        self.step_as(mode, inp, map)
    }

    /// One control cycle of a go-to on the map: the planned search towards `inp.goal`
    /// whatever the search mode. The caller marks the map and decides arrival.
    pub fn goto_step(&mut self, inp: &ExploreInput<'_>, map: &mut dyn MapMarker) -> MotorCommand {
        self.count_contact(inp);
        let p = self.params;
        self.planned.step(&p, inp, map, false, &mut self.stats)
    }

    /// Counts a collision when a sensor starts touching a wall.
    fn count_contact(&mut self, inp: &ExploreInput<'_>) {
        let touching = inp.ir.iter().any(|&(r, _)| r >= self.params.contact_ir);
        if touching && !self.touching {
            self.stats.collisions = self.stats.collisions.wrapping_add(1);
        }
        self.touching = touching;
    }

    fn step_as(
        &mut self,
        mode: SearchMode,
        inp: &ExploreInput<'_>,
        map: &mut dyn MapMarker,
    ) -> MotorCommand {
        let p = self.params;
        let new_walls = if mode == SearchMode::Planned {
            let mut map = WithFarMarks::new(map, &mut self.far, p.far_detour_m);
            self.planned.mark(inp, &p, &mut map, &mut self.visited) > 0
        } else {
            mark_map(inp, &self.params, map) > 0
        };
        let here = inp.pose.point();
        self.count_contact(inp);
        // seed 004 §3: a robot with a ground sensor is in the goal area when the sensor sees
        // it, not when it believes itself near the light.
        let arrived = match inp.ground {
            Some(seen) => seen,
            None => here.distance_to(inp.goal) <= inp.arrival_m,
        };
        if arrived {
            self.phase = ExplorePhase::Arrived;
        }
        // The planned search drives unless a reactive spell is on (its own phases then run).
        let planned = mode == SearchMode::Planned
            && self.phase != ExplorePhase::Arrived
            && !self.planned.reactive(inp.now_ms);
        if planned {
            self.phase = ExplorePhase::Seek;
            let mut map = WithFarMarks::new(map, &mut self.far, p.far_detour_m);
            return self
                .planned
                .step(&p, inp, &mut map, new_walls, &mut self.stats);
        }
        self.reactive_step(inp, map)
    }

    /// The paper's reactive search, one cycle in its phase (seed 004 §5, Fig. 4).
    fn reactive_step(&mut self, inp: &ExploreInput<'_>, map: &mut dyn MapMarker) -> MotorCommand {
        let here = inp.pose.point();
        match self.phase {
            ExplorePhase::Arrived => MotorCommand::STOP,
            ExplorePhase::Seek => self.seek(inp, map),
            ExplorePhase::Plan { waypoint, since_ms } => {
                self.plan_step(inp, map, waypoint, since_ms)
            }
            ExplorePhase::Follow {
                side,
                saved_dir,
                hit,
                since_ms,
                timeout_ms,
                away,
                degraded,
            } => {
                let p = self.params;
                let elapsed = inp.now_ms.wrapping_sub(since_ms);
                let periods = (elapsed / p.follow_degrade_ms.max(1)).min(255) as u8;
                if periods > degraded {
                    self.stats.long_follows = self.stats.long_follows.wrapping_add(1);
                }
                let from_hit = here.distance_to(hit);
                let away = away || from_hit > 2.0 * p.leave_progress_m;
                if elapsed >= timeout_ms {
                    // The paper's loop breaker; the detour was longer than the random timeout,
                    // so the reactive search is not getting past this wall: plan.
                    self.stats.timeouts = self.stats.timeouts.wrapping_add(1);
                    return self.start_plan(inp, map, side);
                }
                if away && from_hit < p.leave_progress_m * 0.5 {
                    // Round the whole obstacle back to the hit point without a leave point:
                    // the reactive search cannot get past it; plan.
                    self.stats.dead_ends = self.stats.dead_ends.wrapping_add(1);
                    return self.start_plan(inp, map, side);
                }
                if elapsed >= p.min_follow_ms && self.may_leave(inp, map, hit, saved_dir) {
                    self.stats.rejoins = self.stats.rejoins.wrapping_add(1);
                    self.phase = ExplorePhase::Seek;
                    return self.seek(inp, map);
                }
                self.phase = ExplorePhase::Follow {
                    side,
                    saved_dir,
                    hit,
                    since_ms,
                    timeout_ms,
                    away,
                    degraded: periods.max(degraded),
                };
                motion::follow(&self.params, inp, side)
            }
        }
    }

    /// Bug2's leaving rule: on the line from the hit point towards the goal, ahead of the hit
    /// point, nearer the goal than the hit point by `leave_progress_m`, and the map shows no
    /// wall one cell towards the goal. Every leave point is nearer the goal than the last hit
    /// point, so the search cannot circle between the same walls (the paper's "heading back
    /// to the saved direction" also fires inside U-shaped traps).
    fn may_leave(&self, inp: &ExploreInput<'_>, map: &dyn MapMarker, hit: Point, dir: f32) -> bool {
        let p = &self.params;
        let here = inp.pose.point();
        let (c, s) = (libm::cosf(dir), libm::sinf(dir));
        let (dx, dy) = (here.x - hit.x, here.y - hit.y);
        let along = dx * c + dy * s;
        let across = libm::fabsf(-dx * s + dy * c);
        if along <= 0.0 || across > p.m_line_band_m {
            return false;
        }
        if here.distance_to(inp.goal) > hit.distance_to(inp.goal) - p.leave_progress_m {
            return false;
        }
        let to_goal = here.bearing_to(inp.goal);
        let ahead = Point::new(
            here.x + 0.3 * libm::cosf(to_goal),
            here.y + 0.3 * libm::sinf(to_goal),
        );
        map.cell_at(ahead) != Some(Cell::Obstacle)
    }

    fn seek(&mut self, inp: &ExploreInput<'_>, map: &mut dyn MapMarker) -> MotorCommand {
        let here = inp.pose.point();
        let dir = here.bearing_to(inp.goal);
        if motion::front_blocked(&self.params, inp) {
            return self.wall_found(inp, map, dir);
        }
        motion::steer(&self.params, inp, inp.goal)
    }

    /// A wall ahead while seeking: go round it on a side chosen from what happened here
    /// before, or plan when this hit cell has been met already.
    fn wall_found(
        &mut self,
        inp: &ExploreInput<'_>,
        map: &mut dyn MapMarker,
        dir: f32,
    ) -> MotorCommand {
        let here = inp.pose.point();
        self.stats.walls_found = self.stats.walls_found.wrapping_add(1);
        let record = self.remember_hit(map.index(here));
        let side = match record {
            Some(r) if r.tries > 0 => {
                // The same hit cell again: a dead end for the reactive search (seed 004 §4
                // lowers the confidence for it). Plan on the map; without a plan, try the side
                // not taken last time.
                self.stats.dead_ends = self.stats.dead_ends.wrapping_add(1);
                let last = if r.left {
                    WallSide::Left
                } else {
                    WallSide::Right
                };
                return self.start_plan(inp, map, last);
            }
            _ => self.choose_side(inp.pose, dir, map),
        };
        self.note_side(map.index(here), side);
        self.start_follow(inp, side, dir)
    }

    fn start_follow(&mut self, inp: &ExploreInput<'_>, side: WallSide, dir: f32) -> MotorCommand {
        let span = self
            .params
            .timeout_max_ms
            .saturating_sub(self.params.timeout_min_ms);
        let timeout_ms = self.params.timeout_min_ms + self.rng.next_u32() % span.max(1);
        self.phase = ExplorePhase::Follow {
            side,
            saved_dir: dir,
            hit: inp.pose.point(),
            since_ms: inp.now_ms,
            timeout_ms,
            away: false,
            degraded: 0,
        };
        motion::follow(&self.params, inp, side)
    }

    /// Plans on the robot's own map towards the goal; without a plan, follows the wall on
    /// the side not taken last (`last`).
    fn start_plan(
        &mut self,
        inp: &ExploreInput<'_>,
        map: &mut dyn MapMarker,
        last: WallSide,
    ) -> MotorCommand {
        let here = inp.pose.point();
        match map.plan_towards(here, inp.goal) {
            Some(waypoint) => {
                self.stats.plans = self.stats.plans.wrapping_add(1);
                self.phase = ExplorePhase::Plan {
                    waypoint,
                    since_ms: inp.now_ms,
                };
                self.plan_step(inp, map, waypoint, inp.now_ms)
            }
            None => {
                let side = last.other();
                self.note_side(map.index(here), side);
                self.start_follow(inp, side, here.bearing_to(inp.goal))
            }
        }
    }

    /// Drives to the plan's next point, planning again there, when the way is blocked (the
    /// map has just learnt the wall) or every few seconds (it learns as it goes).
    fn plan_step(
        &mut self,
        inp: &ExploreInput<'_>,
        map: &mut dyn MapMarker,
        waypoint: Point,
        since_ms: u32,
    ) -> MotorCommand {
        let here = inp.pose.point();
        let blocked = motion::front_blocked(&self.params, inp);
        let stale = inp.now_ms.wrapping_sub(since_ms) >= 3 * self.params.min_follow_ms;
        let mut target = waypoint;
        if blocked || stale || here.distance_to(waypoint) <= self.params.waypoint_m {
            match map.plan_towards(here, inp.goal) {
                Some(w) => {
                    target = w;
                    self.phase = ExplorePhase::Plan {
                        waypoint: w,
                        since_ms: inp.now_ms,
                    };
                }
                None => {
                    // No way through what the map shows (it holds dead-reckoning errors):
                    // back to the reactive search, which marks the map anew.
                    self.hits = [HitRecord::default(); HIT_MEMORY];
                    self.phase = ExplorePhase::Seek;
                    return self.seek(inp, map);
                }
            }
        }
        if blocked {
            // A wall the map does not show yet (the IR sees it inside the robot's own cell):
            // go round it as the reactive search does, on the side the plan's point is on.
            let dir = here.bearing_to(target);
            let side = if wrap_angle(dir - inp.pose.heading) >= 0.0 {
                WallSide::Right
            } else {
                WallSide::Left
            };
            self.remember_hit(map.index(here));
            self.note_side(map.index(here), side);
            return self.start_follow(inp, side, here.bearing_to(inp.goal));
        }
        motion::steer(&self.params, inp, target)
    }

    /// Records a wall met in `cell`; returns its record as it was before (tries so far).
    fn remember_hit(&mut self, cell: Option<(i32, i32)>) -> Option<HitRecord> {
        let (col, row) = cell_u8(cell)?;
        if let Some(r) = self
            .hits
            .iter_mut()
            .find(|r| r.tries > 0 && (r.col, r.row) == (col, row))
        {
            let before = *r;
            r.tries = r.tries.saturating_add(1);
            return Some(before);
        }
        let slot = usize::from(self.next_hit) % HIT_MEMORY;
        self.next_hit = ((slot + 1) % HIT_MEMORY) as u8;
        if let Some(r) = self.hits.get_mut(slot) {
            *r = HitRecord {
                col,
                row,
                tries: 1,
                left: false,
            };
        }
        None
    }

    /// Remembers the side taken at the hit cell.
    fn note_side(&mut self, cell: Option<(i32, i32)>, side: WallSide) {
        let Some((col, row)) = cell_u8(cell) else {
            return;
        };
        if let Some(r) = self
            .hits
            .iter_mut()
            .find(|r| r.tries > 0 && (r.col, r.row) == (col, row))
        {
            r.left = side == WallSide::Left;
        }
    }

    /// Avoiding history (seed 004 §5): go round on the side with more unknown cells ahead of
    /// it; on a tie, the side that turns less away from the goal.
    fn choose_side(&mut self, pose: Pose, dir: f32, map: &dyn MapMarker) -> WallSide {
        let unknown = |turn: f32| -> u32 {
            let mut n = 0;
            for k in 1..=3 {
                let r = self.params.history_probe_m * k as f32 / 3.0;
                for da in [-0.4f32, 0.0, 0.4] {
                    let a = pose.heading + turn + da;
                    let p = Point::new(pose.x + r * libm::cosf(a), pose.y + r * libm::sinf(a));
                    if map.cell_at(p) == Some(Cell::Unknown) {
                        n += 1;
                    }
                }
            }
            n
        };
        let half_pi = core::f32::consts::FRAC_PI_2;
        // Turning left keeps the wall on the right, and the other way round.
        let left_new = unknown(half_pi);
        let right_new = unknown(-half_pi);
        if left_new != right_new {
            return if left_new > right_new {
                WallSide::Right
            } else {
                WallSide::Left
            };
        }
        if wrap_angle(dir - pose.heading) >= 0.0 {
            WallSide::Right
        } else {
            WallSide::Left
        }
    }
}

/// A map cell's column and row as bytes (the map is at most 64 x 64).
fn cell_u8(cell: Option<(i32, i32)>) -> Option<(u8, u8)> {
    let (x, y) = cell?;
    Some((u8::try_from(x).ok()?, u8::try_from(y).ok()?))
}

/// Marks the cell under the robot free, unknown cells along each IR ray free, and the cell
/// where a ray sees something an obstacle (never the robot's own cell); returns the number of
/// cells that became obstacles.
pub fn mark_map(inp: &ExploreInput<'_>, p: &ExploreParams, map: &mut dyn MapMarker) -> u32 {
    if p.mode == SearchMode::Planned {
        return planned::mark_visited(inp, p, map, None);
    }
    let here = inp.pose.point();
    let mut walls = 0;
    map.mark(here, Cell::Free);
    for &(reading, angle) in inp.ir {
        let a = inp.pose.heading + angle;
        let (c, s) = (libm::cosf(a), libm::sinf(a));
        let seen = p.ir.distance(reading);
        let reach = seen.unwrap_or(p.ir.range_m);
        // Step along the ray at a few centimetres, from the body edge outwards.
        let mut t = 0.05;
        while t < reach {
            let q = Point::new(here.x + t * c, here.y + t * s);
            if map.cell_at(q) == Some(Cell::Unknown) {
                map.mark(q, Cell::Free);
            }
            t += 0.05;
        }
        if let Some(d) = seen {
            // The sensor sits at the body edge; the wall is d beyond it.
            let q = ray_point(inp, angle, d + 0.12);
            if map.index(q) != map.index(here) {
                walls += mark_wall(map, q);
            }
        }
    }
    walls
}

/// The point `r` from the robot's centre along the ray at `angle` (radians, left positive).
pub(crate) fn ray_point(inp: &ExploreInput<'_>, angle: f32, r: f32) -> Point {
    let a = inp.pose.heading + angle;
    let here = inp.pose.point();
    Point::new(here.x + r * libm::cosf(a), here.y + r * libm::sinf(a))
}

/// Marks the cell at `q` a wall; 1 if it was not one, else 0.
pub(crate) fn mark_wall(map: &mut dyn MapMarker, q: Point) -> u32 {
    let before = map.cell_at(q);
    map.mark(q, Cell::Obstacle);
    let now = map.cell_at(q);
    u32::from(before.is_some_and(|b| b != Cell::Obstacle) && now == Some(Cell::Obstacle))
}

#[cfg(test)]
mod tests;
