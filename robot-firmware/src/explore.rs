//! Exploration by repeated reactive goal search, with map building (seed 004 §5, Fig. 4).
//!
//! Layer: an autonomy behaviour above guided motion, for the micro-rato profile (compass,
//! three IR sensors, beacon). The robot knows only its start pose and the goal light's
//! position. It heads for the goal; when a wall blocks the way it saves the goal direction
//! and follows the wall until its heading comes back to that saved direction (any path to
//! the goal around the obstacle must cross it), then heads for the goal again. A random,
//! adjustable timeout on wall following breaks the loops some obstacles cause. Which way
//! round the wall it goes "avoids history": the side whose cells are more unknown wins, so
//! the robot prefers new ground and a second run maps more.
//!
//! While it moves, it marks grid cells: the cell under the robot is free; each IR ray marks
//! the unknown cells it crosses free and the cell where it sees something an obstacle. The map
//! is reached through `MapMarker`, so this module needs no storage of its own.
//!
//! Pure: pose, readings and time in; motor command and map marks out. Cannot fail or panic.

use crate::behaviour::{units, MotorCommand, XorShift32};
use crate::nav::{Cell, Grid};
use crate::odometry::{wrap_angle, Point, Pose};

/// Where exploration reads and writes the map.
pub trait MapMarker {
    /// The (column, row) of the cell holding `p` (metres), or `None` off the map.
    fn index(&self, p: Point) -> Option<(i32, i32)>;
    /// The cell holding `p` (metres), or `None` off the map.
    fn cell_at(&self, p: Point) -> Option<Cell>;
    /// Sets the cell holding `p`; off-map points are ignored.
    fn mark(&mut self, p: Point, cell: Cell);
}

impl<S: AsRef<[u8]> + AsMut<[u8]>> MapMarker for Grid<S> {
    fn index(&self, p: Point) -> Option<(i32, i32)> {
        let (x, y) = self.geometry().metres_to_grid(p.x, p.y).cell();
        self.contains(x, y).then_some((x, y))
    }

    fn cell_at(&self, p: Point) -> Option<Cell> {
        let (x, y) = self.geometry().metres_to_grid(p.x, p.y).cell();
        self.contains(x, y)
            .then(|| self.get(x as usize, y as usize))
    }

    fn mark(&mut self, p: Point, cell: Cell) {
        let (x, y) = self.geometry().metres_to_grid(p.x, p.y).cell();
        if self.contains(x, y) {
            // `contains` bounds both coordinates, so the write cannot fail.
            let _ = self.set(x as usize, y as usize, cell);
        }
    }
}

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
    /// Distance kept from the followed wall, metres.
    pub follow_distance_m: f32,
    /// Wheel difference per metre of wall-distance error.
    pub follow_gain: f32,
    /// Heading within this of the saved direction ends wall following, radians.
    pub rejoin_rad: f32,
    /// Wall following lasts at least this long before a rejoin counts (it starts facing the
    /// saved direction), ms.
    pub min_follow_ms: u32,
    /// Random wall-following timeout range, ms (seed 004 §5: "random (adjustable)").
    pub timeout_min_ms: u32,
    pub timeout_max_ms: u32,
    /// Radius around the goal light's position counted as the goal area when the ground
    /// sensor is absent, metres (the Micro-Rato goal area is a 1 m circle).
    pub goal_radius_m: f32,
    /// Distance at which cells to either side are sampled to choose a side, metres.
    pub history_probe_m: f32,
    pub ir: IrRange,
}

impl Default for ExploreParams {
    fn default() -> Self {
        ExploreParams {
            seek_speed: 50.0,
            follow_speed: 30.0,
            heading_gain: 30.0,
            wall_ir: 290,
            follow_distance_m: 0.12,
            follow_gain: 150.0,
            rejoin_rad: 0.2,
            min_follow_ms: 1500,
            timeout_min_ms: 15_000,
            timeout_max_ms: 40_000,
            goal_radius_m: 0.5,
            history_probe_m: 0.6,
            ir: IrRange::default(),
        }
    }
}

/// Which side the followed wall is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WallSide {
    Left,
    Right,
}

/// What exploration is doing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ExplorePhase {
    /// Heading for the goal light.
    Seek,
    /// Going round an obstacle until the heading returns to `saved_dir`.
    Follow {
        side: WallSide,
        saved_dir: f32,
        since_ms: u32,
        timeout_ms: u32,
    },
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
    /// The ground sensor sees the goal area.
    pub on_goal_area: bool,
}

/// Counters for telemetry and tests.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ExploreStats {
    pub walls_found: u32,
    pub rejoins: u32,
    pub timeouts: u32,
}

/// The reactive search with mapping.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Explorer {
    pub params: ExploreParams,
    phase: ExplorePhase,
    rng: XorShift32,
    stats: ExploreStats,
}

impl Explorer {
    pub fn new(params: ExploreParams, seed: u32) -> Self {
        Explorer {
            params,
            phase: ExplorePhase::Seek,
            rng: XorShift32::new(seed),
            stats: ExploreStats::default(),
        }
    }

    pub fn phase(&self) -> ExplorePhase {
        self.phase
    }

    pub fn stats(&self) -> ExploreStats {
        self.stats
    }

    /// Starts a new run (Fig. 4's outer loop begins again).
    pub fn restart(&mut self) {
        self.phase = ExplorePhase::Seek;
    }

    /// One control cycle: marks the map and returns the motor command (nominal units).
    pub fn step(&mut self, inp: &ExploreInput<'_>, map: &mut dyn MapMarker) -> MotorCommand {
        mark_map(inp, &self.params, map);
        let here = inp.pose.point();
        if inp.on_goal_area || here.distance_to(inp.goal) <= self.params.goal_radius_m {
            self.phase = ExplorePhase::Arrived;
        }
        match self.phase {
            ExplorePhase::Arrived => MotorCommand::STOP,
            ExplorePhase::Seek => self.seek(inp, map),
            ExplorePhase::Follow {
                side,
                saved_dir,
                since_ms,
                timeout_ms,
            } => {
                let elapsed = inp.now_ms.wrapping_sub(since_ms);
                let heading_back =
                    libm::fabsf(wrap_angle(inp.pose.heading - saved_dir)) <= self.params.rejoin_rad;
                if elapsed >= timeout_ms {
                    self.stats.timeouts += 1;
                    self.phase = ExplorePhase::Seek;
                    return self.seek(inp, map);
                }
                if elapsed >= self.params.min_follow_ms && heading_back && !self.front_blocked(inp)
                {
                    self.stats.rejoins += 1;
                    self.phase = ExplorePhase::Seek;
                    return self.seek(inp, map);
                }
                self.follow(inp, side)
            }
        }
    }

    fn front_blocked(&self, inp: &ExploreInput<'_>) -> bool {
        inp.ir
            .iter()
            .any(|&(r, a)| libm::fabsf(a) < 0.35 && r >= self.params.wall_ir)
    }

    fn seek(&mut self, inp: &ExploreInput<'_>, map: &dyn MapMarker) -> MotorCommand {
        let here = inp.pose.point();
        let dir = here.bearing_to(inp.goal);
        if self.front_blocked(inp) {
            let side = self.choose_side(inp.pose, dir, map);
            let span = self
                .params
                .timeout_max_ms
                .saturating_sub(self.params.timeout_min_ms);
            let timeout_ms = self.params.timeout_min_ms + self.rng.next_u32() % span.max(1);
            self.stats.walls_found += 1;
            self.phase = ExplorePhase::Follow {
                side,
                saved_dir: dir,
                since_ms: inp.now_ms,
                timeout_ms,
            };
            return self.follow(inp, side);
        }
        let err = wrap_angle(dir - inp.pose.heading);
        let p = &self.params;
        if libm::fabsf(err) > 1.0 {
            let s = if err > 0.0 {
                p.follow_speed
            } else {
                -p.follow_speed
            };
            return MotorCommand::new(units(-s), units(s));
        }
        // Side sensors push the robot off walls it passes while heading for the goal.
        let mut push = 0.0;
        for &(r, a) in inp.ir {
            if libm::fabsf(a) >= 0.35 && r >= p.wall_ir {
                push += if a > 0.0 { -1.0 } else { 1.0 };
            }
        }
        let turn = p.heading_gain * err + push * p.heading_gain * 0.5;
        MotorCommand::new(units(p.seek_speed - turn), units(p.seek_speed + turn))
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

    /// Wall following with three IR sensors: keep `follow_distance_m` from the wall on `side`;
    /// turn away on the spot when the front is blocked; curve in when the wall is lost.
    fn follow(&self, inp: &ExploreInput<'_>, side: WallSide) -> MotorCommand {
        let p = &self.params;
        // +1 turns left (counter-clockwise): away from a wall on the right.
        let away = match side {
            WallSide::Left => -1.0,
            WallSide::Right => 1.0,
        };
        if self.front_blocked(inp) {
            let s = p.follow_speed * away;
            return MotorCommand::new(units(-s), units(s));
        }
        let side_reading = inp
            .ir
            .iter()
            .filter(|&&(_, a)| match side {
                WallSide::Left => a >= 0.35,
                WallSide::Right => a <= -0.35,
            })
            .map(|&(r, _)| r)
            .max()
            .unwrap_or(0);
        // A side sensor at 60 degrees sees the wall at d / sin(60) along its ray.
        let turn = match p.ir.distance(side_reading) {
            Some(d) => {
                let wall = d * 0.866;
                // Too close: turn away; too far: turn towards.
                (p.follow_distance_m - wall) * p.follow_gain * away
            }
            None => -away * p.follow_speed * 0.6,
        };
        MotorCommand::new(units(p.follow_speed - turn), units(p.follow_speed + turn))
    }
}

/// Marks the cell under the robot free, unknown cells along each IR ray free, and the cell
/// where a ray sees something an obstacle (never the robot's own cell).
fn mark_map(inp: &ExploreInput<'_>, p: &ExploreParams, map: &mut dyn MapMarker) {
    let here = inp.pose.point();
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
            let r = d + 0.12;
            let q = Point::new(here.x + r * c, here.y + r * s);
            if map.index(q) != map.index(here) {
                map.mark(q, Cell::Obstacle);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::nav::Geometry;
    use std::vec;
    use std::vec::Vec;

    fn map17() -> Grid<Vec<u8>> {
        let bytes = crate::nav::grid_bytes(17, 17);
        Grid::new(17, 17, Geometry::SEED_004, vec![0u8; bytes]).expect("grid")
    }

    const CLEAR: [(u16, f32); 3] = [(0, 1.047), (0, 0.0), (0, -1.047)];

    fn input<'a>(now_ms: u32, pose: Pose, ir: &'a [(u16, f32)]) -> ExploreInput<'a> {
        ExploreInput {
            now_ms,
            pose,
            ir,
            goal: Point::new(3.0, 2.6),
            on_goal_area: false,
        }
    }

    #[test]
    fn in_open_space_it_heads_for_the_goal() {
        let mut e = Explorer::new(ExploreParams::default(), 1);
        let mut map = map17();
        let pose = Pose::new(0.5, 2.6, 0.0);
        let cmd = e.step(&input(0, pose, &CLEAR), &mut map);
        assert_eq!(e.phase(), ExplorePhase::Seek);
        assert_eq!((cmd.left, cmd.right), (50, 50));
        // Goal to the left of the heading: the right wheel runs faster.
        let cmd = e.step(&input(10, Pose::new(0.5, 2.0, 0.0), &CLEAR), &mut map);
        assert!(cmd.right > cmd.left);
    }

    #[test]
    fn a_wall_ahead_saves_the_goal_direction_and_starts_following() {
        let mut e = Explorer::new(ExploreParams::default(), 1);
        let mut map = map17();
        let pose = Pose::new(0.5, 2.6, 0.0);
        let wall = [(0, 1.047), (600, 0.0), (0, -1.047)];
        e.step(&input(0, pose, &wall), &mut map);
        match e.phase() {
            ExplorePhase::Follow {
                saved_dir,
                since_ms,
                timeout_ms,
                ..
            } => {
                assert!((saved_dir - pose.point().bearing_to(Point::new(3.0, 2.6))).abs() < 1e-6);
                assert_eq!(since_ms, 0);
                assert!((15_000..40_000).contains(&timeout_ms));
            }
            other => panic!("expected Follow, got {other:?}"),
        }
        assert_eq!(e.stats().walls_found, 1);
    }

    #[test]
    fn it_goes_round_on_the_side_with_more_unknown_cells() {
        let mut map = map17();
        let pose = Pose::new(1.05, 2.55, 0.0);
        // Everything to the left (north) is already explored.
        for x in 0..17 {
            for y in 9..17 {
                map.set(x, y, Cell::Free).expect("in map");
            }
        }
        let mut e = Explorer::new(ExploreParams::default(), 1);
        let wall = [(0, 1.047), (600, 0.0), (0, -1.047)];
        e.step(&input(0, pose, &wall), &mut map);
        // Unknown ground lies to the right: it turns right, keeping the wall on its left.
        assert!(
            matches!(
                e.phase(),
                ExplorePhase::Follow {
                    side: WallSide::Left,
                    ..
                }
            ),
            "{:?}",
            e.phase()
        );
    }

    #[test]
    fn following_ends_when_the_heading_returns_to_the_saved_direction() {
        let mut e = Explorer::new(ExploreParams::default(), 1);
        let mut map = map17();
        let wall = [(0, 1.047), (600, 0.0), (0, -1.047)];
        let start = Pose::new(0.5, 2.6, 0.0);
        e.step(&input(0, start, &wall), &mut map);
        // Going round: heading away from the saved direction, then back to it.
        let side_wall = [(400, 1.047), (0, 0.0), (0, -1.047)];
        e.step(
            &input(1000, Pose::new(0.6, 2.4, -1.2), &side_wall),
            &mut map,
        );
        assert!(matches!(e.phase(), ExplorePhase::Follow { .. }));
        e.step(&input(2000, Pose::new(0.9, 2.3, 0.2), &CLEAR), &mut map);
        assert_eq!(e.phase(), ExplorePhase::Seek);
        assert_eq!(e.stats().rejoins, 1);
    }

    #[test]
    fn a_timeout_reinitialises_the_search() {
        let mut e = Explorer::new(
            ExploreParams {
                timeout_min_ms: 1000,
                timeout_max_ms: 1001,
                ..ExploreParams::default()
            },
            1,
        );
        let mut map = map17();
        let wall = [(0, 1.047), (600, 0.0), (0, -1.047)];
        e.step(&input(0, Pose::new(0.5, 2.6, 0.0), &wall), &mut map);
        let side_wall = [(400, 1.047), (0, 0.0), (0, -1.047)];
        e.step(&input(1000, Pose::new(0.5, 2.6, 2.5), &side_wall), &mut map);
        assert_eq!(e.stats().timeouts, 1);
        assert_eq!(e.phase(), ExplorePhase::Seek);
    }

    #[test]
    fn the_map_records_free_space_and_the_wall_the_sensors_see() {
        let mut e = Explorer::new(ExploreParams::default(), 1);
        let mut map = map17();
        // Robot in cell (1, 8) facing +x; front sensor sees a wall 0.15 m from its body edge:
        // 0.27 m from the centre at x = 0.45 + 0.27 = 0.72, i.e. cell (2, 8).
        let pose = Pose::new(0.45, 2.55, 0.0);
        let ir = [(0, 1.047), (IR_AT_15CM, 0.0), (0, -1.047)];
        e.step(&input(0, pose, &ir), &mut map);
        assert_eq!(map.get(1, 8), Cell::Free);
        assert_eq!(map.get(2, 8), Cell::Obstacle);
        // Left ray (60 degrees) saw nothing within 25 cm: the cells it crosses are free.
        assert_eq!(map.get(1, 9), Cell::Free);
        assert_eq!(map.get(5, 5), Cell::Unknown);
    }

    /// 1023 (0.10 / 0.25)^2: a wall 15 cm away with the default curve.
    const IR_AT_15CM: u16 = 164;

    #[test]
    fn ir_range_inverts_the_calibrated_curve() {
        let r = IrRange::default();
        assert_eq!(r.distance(10), None);
        let d = r.distance(IR_AT_15CM).expect("in range");
        assert!((d - 0.15).abs() < 0.002, "{d}");
        assert_eq!(r.distance(1023), Some(0.0));
    }

    #[test]
    fn the_goal_area_stops_the_robot() {
        let mut e = Explorer::new(ExploreParams::default(), 1);
        let mut map = map17();
        let mut inp = input(0, Pose::new(1.0, 1.0, 0.0), &CLEAR);
        inp.on_goal_area = true;
        assert_eq!(e.step(&inp, &mut map), MotorCommand::STOP);
        assert_eq!(e.phase(), ExplorePhase::Arrived);
    }
}
