//! Plan execution with exception handling (seed 004 §7).
//!
//! Layer: above guided motion. A plan is a list of waypoints (region centres, or a smoothed
//! path); between two consecutive points the robot runs `guided_motion()`. Two heuristics
//! from the paper handle execution exceptions:
//! 1. the robot never goes more than `max_deviation_m` (0.6 m) from the ideal straight
//!    segment; at the limit it rotates to the direction orthogonal to that segment, back
//!    towards it, so that it goes round the obstacle the other way;
//! 2. long segments are split into sub-segments of at most `sub_segment_m`, which keeps the
//!    robot close to the ideal trajectory and out of dead ends.
//!
//! Pure: pose, IR and waypoints in; motor command and progress out. Cannot fail or panic.

use crate::behaviour::{units, MotorCommand};
use crate::guided::{guided_step, GuidedParams, GuidedPhase};
use crate::odometry::{wrap_angle, Point, Pose};

/// The waypoints being followed, metres: a slice, or read straight out of the robot's plan
/// object (no copy of up to 258 points in RAM).
pub trait Waypoints {
    fn count(&self) -> usize;
    fn point(&self, i: usize) -> Option<Point>;
}

impl Waypoints for [Point] {
    fn count(&self) -> usize {
        self.len()
    }

    fn point(&self, i: usize) -> Option<Point> {
        self.get(i).copied()
    }
}

/// Execution parameters (seed 004 §7 gives 0.6 m; the rest are documented defaults).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExecuteParams {
    /// Largest distance from the ideal segment before the escape turn, metres.
    pub max_deviation_m: f32,
    /// Longest sub-segment, metres.
    pub sub_segment_m: f32,
    /// An intermediate point counts as passed within this distance, metres.
    pub pass_m: f32,
    /// Escape turn is done when the heading is within this of the orthogonal, radians.
    pub escape_align_rad: f32,
    /// After the escape turn, drive straight this far before resuming guided motion.
    pub escape_drive_m: f32,
}

impl Default for ExecuteParams {
    fn default() -> Self {
        ExecuteParams {
            max_deviation_m: 0.6,
            sub_segment_m: 0.6,
            pass_m: 0.2,
            escape_align_rad: 0.15,
            escape_drive_m: 0.3,
        }
    }
}

/// Where the executor is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ExecPhase {
    /// Guided motion towards sub-point `sub` of the segment ending at waypoint `index`.
    Driving { index: usize, sub: u16 },
    /// Heuristic 1: turning to `heading`, then driving from `from` for `escape_drive_m`.
    Escaping {
        index: usize,
        heading: f32,
        aligned: bool,
        from: Point,
    },
    /// The last waypoint was reached.
    Finished,
}

/// What one step reports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExecReport {
    pub phase: ExecPhase,
    /// A waypoint was passed this cycle (its index).
    pub passed: Option<usize>,
    /// The deviation heuristic fired this cycle.
    pub escaped: bool,
}

impl<const N: usize> Waypoints for [Point; N] {
    fn point(&self, i: usize) -> Option<Point> {
        self.get(i).copied()
    }
    fn count(&self) -> usize {
        N
    }
}

/// Follows a plan's waypoints.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Executor {
    pub params: ExecuteParams,
    phase: ExecPhase,
    /// Start of the current ideal segment.
    seg_from: Point,
    escapes: u32,
}

impl Executor {
    /// Starts at `start` (the robot's pose when execution begins) with waypoint 0 next.
    pub fn new(params: ExecuteParams, start: Point) -> Self {
        Executor {
            params,
            phase: ExecPhase::Driving { index: 0, sub: 0 },
            seg_from: start,
            escapes: 0,
        }
    }

    pub fn phase(&self) -> ExecPhase {
        self.phase
    }

    /// How often heuristic 1 fired.
    pub fn escapes(&self) -> u32 {
        self.escapes
    }

    /// One control cycle.
    pub fn step<W: Waypoints + ?Sized>(
        &mut self,
        pose: Pose,
        ir: &[(u16, f32)],
        waypoints: &W,
        guided: &GuidedParams,
    ) -> (MotorCommand, ExecReport) {
        let mut report = ExecReport {
            phase: self.phase,
            passed: None,
            escaped: false,
        };
        let cmd = match self.phase {
            ExecPhase::Finished => MotorCommand::STOP,
            ExecPhase::Driving { index, sub } => {
                self.drive(pose, ir, waypoints, guided, index, sub, &mut report)
            }
            ExecPhase::Escaping {
                index,
                heading,
                aligned,
                from,
            } => self.escape(pose, ir, guided, index, heading, aligned, from),
        };
        report.phase = self.phase;
        (cmd, report)
    }

    #[allow(clippy::too_many_arguments)]
    fn drive<W: Waypoints + ?Sized>(
        &mut self,
        pose: Pose,
        ir: &[(u16, f32)],
        waypoints: &W,
        guided: &GuidedParams,
        index: usize,
        sub: u16,
        report: &mut ExecReport,
    ) -> MotorCommand {
        let Some(end) = waypoints.point(index) else {
            self.phase = ExecPhase::Finished;
            return MotorCommand::STOP;
        };
        let here = pose.point();
        let p = self.params;
        // Heuristic 1: too far from the ideal segment.
        let (dev, foot) = deviation(self.seg_from, end, here);
        if dev > p.max_deviation_m {
            let heading = here.bearing_to(foot);
            self.escapes += 1;
            report.escaped = true;
            self.phase = ExecPhase::Escaping {
                index,
                heading,
                aligned: false,
                from: here,
            };
            return self.escape(pose, ir, guided, index, heading, false, here);
        }
        // Heuristic 2: aim at the next sub-point, not the far end. Sub-points the robot is
        // already past (measured along the segment) are skipped, so it never turns back.
        let seg_len = self.seg_from.distance_to(end);
        let subs = sub_count(seg_len, p.sub_segment_m);
        let along = progress(self.seg_from, end, here) + p.pass_m / seg_len.max(1e-3);
        let past = libm::floorf(along * subs as f32).max(0.0) as u32;
        let sub = u16::try_from(past.min(subs.saturating_sub(1)))
            .unwrap_or(u16::MAX)
            .max(sub);
        self.phase = ExecPhase::Driving { index, sub };
        let target = if u32::from(sub) + 1 >= subs {
            end
        } else {
            lerp(self.seg_from, end, (f32::from(sub) + 1.0) / subs as f32)
        };
        let is_last_waypoint = index + 1 >= waypoints.count();
        let is_end = target == end;
        let mut g = *guided;
        if !(is_end && is_last_waypoint) {
            // Intermediate points are passed, not stopped at.
            g.arrival_m = p.pass_m;
            g.approach_m = 0.0;
        }
        let (cmd, phase) = guided_step(pose, target, ir, &g);
        if phase == GuidedPhase::Arrived {
            if is_end {
                report.passed = Some(index);
                self.seg_from = end;
                self.phase = if is_last_waypoint {
                    ExecPhase::Finished
                } else {
                    ExecPhase::Driving {
                        index: index + 1,
                        sub: 0,
                    }
                };
                if self.phase == ExecPhase::Finished {
                    return MotorCommand::STOP;
                }
            } else {
                self.phase = ExecPhase::Driving {
                    index,
                    sub: sub.saturating_add(1),
                };
            }
        }
        cmd
    }

    #[allow(clippy::too_many_arguments)]
    fn escape(
        &mut self,
        pose: Pose,
        ir: &[(u16, f32)],
        guided: &GuidedParams,
        index: usize,
        heading: f32,
        aligned: bool,
        from: Point,
    ) -> MotorCommand {
        let p = self.params;
        let err = wrap_angle(heading - pose.heading);
        if !aligned {
            if libm::fabsf(err) <= p.escape_align_rad {
                self.phase = ExecPhase::Escaping {
                    index,
                    heading,
                    aligned: true,
                    from: pose.point(),
                };
                return MotorCommand::STOP;
            }
            let s = if err > 0.0 {
                guided.turn_speed
            } else {
                -guided.turn_speed
            };
            return MotorCommand::new(units(-s), units(s));
        }
        if pose.point().distance_to(from) >= p.escape_drive_m {
            self.phase = ExecPhase::Driving { index, sub: 0 };
            // The ideal segment now starts where the robot is, back near the trajectory.
            self.seg_from = pose.point();
            return MotorCommand::STOP;
        }
        // Drive along the orthogonal; guided motion's reactions still avoid what it meets.
        let ahead = Point::new(pose.x + libm::cosf(heading), pose.y + libm::sinf(heading));
        guided_step(pose, ahead, ir, guided).0
    }
}

/// How far along `a`-`b` the projection of `p` lies, 0..=1.
fn progress(a: Point, b: Point, p: Point) -> f32 {
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    let len2 = dx * dx + dy * dy;
    if len2 > 0.0 {
        (((p.x - a.x) * dx + (p.y - a.y) * dy) / len2).clamp(0.0, 1.0)
    } else {
        1.0
    }
}

/// Distance from `p` to the segment `a`-`b`, and the closest point on it.
fn deviation(a: Point, b: Point, p: Point) -> (f32, Point) {
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p.x - a.x) * dx + (p.y - a.y) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let foot = Point::new(a.x + t * dx, a.y + t * dy);
    (p.distance_to(foot), foot)
}

fn sub_count(len: f32, max: f32) -> u32 {
    if !(len.is_finite() && max > 0.0) {
        return 1;
    }
    // Bounded: a 1 km segment at 1 cm sub-segments is 1e5, far inside u32.
    (libm::ceilf(len / max) as u32).max(1)
}

fn lerp(a: Point, b: Point, t: f32) -> Point {
    Point::new(a.x + (b.x - a.x) * t, a.y + (b.y - a.y) * t)
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;

    const CLEAR: [(u16, f32); 3] = [(0, 1.047), (0, 0.0), (0, -1.047)];

    /// Drives a unicycle with the executor's commands (nominal unit = 3.07 mm/s, 0.2 m base).
    fn simulate(exec: &mut Executor, pose: Pose, wps: &[Point], steps: u32) -> (Pose, u32) {
        simulate_with(exec, pose, wps, steps, |_| {})
    }

    /// [`simulate`], calling `visit` with every pose.
    fn simulate_with(
        exec: &mut Executor,
        mut pose: Pose,
        wps: &[Point],
        steps: u32,
        mut visit: impl FnMut(Pose),
    ) -> (Pose, u32) {
        let g = GuidedParams::default();
        let mut passed = 0;
        for _ in 0..steps {
            let (cmd, r) = exec.step(pose, &CLEAR, wps, &g);
            passed += u32::from(r.passed.is_some());
            let (vl, vr) = (
                f32::from(cmd.left) * 0.00307,
                f32::from(cmd.right) * 0.00307,
            );
            let dt = 0.05;
            let v = (vl + vr) / 2.0;
            let w = (vr - vl) / 0.2;
            pose = Pose::new(
                pose.x + v * dt * libm::cosf(pose.heading),
                pose.y + v * dt * libm::sinf(pose.heading),
                pose.heading + w * dt,
            );
            visit(pose);
            if exec.phase() == ExecPhase::Finished {
                break;
            }
        }
        (pose, passed)
    }

    #[test]
    fn it_follows_the_waypoints_to_the_end_and_stops() {
        let wps = [
            Point::new(1.0, 0.0),
            Point::new(1.0, 1.5),
            Point::new(2.5, 1.5),
        ];
        let mut e = Executor::new(ExecuteParams::default(), Point::new(0.0, 0.0));
        let (end, passed) = simulate(&mut e, Pose::new(0.0, 0.0, 0.0), &wps, 4000);
        assert_eq!(e.phase(), ExecPhase::Finished);
        assert_eq!(passed, 3);
        assert!(end.point().distance_to(wps[2]) <= GuidedParams::default().arrival_m + 0.02);
        assert_eq!(e.escapes(), 0);
    }

    #[test]
    fn long_segments_are_split_into_sub_segments() {
        let wps = [Point::new(2.0, 0.0)];
        let mut e = Executor::new(ExecuteParams::default(), Point::new(0.0, 0.0));
        let g = GuidedParams::default();
        // Standing at the first sub-point (0.5 m of 2 m in 4 pieces) moves on to the next.
        e.step(Pose::new(0.5, 0.0, 0.0), &CLEAR, &wps[..], &g);
        assert_eq!(e.phase(), ExecPhase::Driving { index: 0, sub: 1 });
    }

    #[test]
    fn beyond_0_6_m_from_the_segment_it_turns_orthogonally_back() {
        let wps = [Point::new(3.0, 0.0)];
        let mut e = Executor::new(ExecuteParams::default(), Point::new(0.0, 0.0));
        let g = GuidedParams::default();
        let (_, r) = e.step(Pose::new(1.0, 0.7, 0.0), &CLEAR, &wps[..], &g);
        assert!(r.escaped);
        match e.phase() {
            ExecPhase::Escaping { heading, .. } => {
                // Orthogonal to the x axis, towards it: -90 degrees.
                assert!((heading + core::f32::consts::FRAC_PI_2).abs() < 1e-4);
            }
            other => panic!("expected Escaping, got {other:?}"),
        }
        // It gets back within the limit and finishes.
        let (end, _) = simulate(&mut e, Pose::new(1.0, 0.7, 0.0), &wps, 4000);
        assert_eq!(e.phase(), ExecPhase::Finished);
        assert!(end.point().distance_to(wps[0]) < 0.2);
    }

    #[test]
    fn an_empty_plan_is_finished_at_once() {
        let mut e = Executor::new(ExecuteParams::default(), Point::new(0.0, 0.0));
        let (cmd, r) = e.step(
            Pose::new(0.0, 0.0, 0.0),
            &CLEAR,
            &[][..],
            &GuidedParams::default(),
        );
        assert_eq!(cmd, MotorCommand::STOP);
        assert_eq!(r.phase, ExecPhase::Finished);
    }

    /// A 64 x 64 map: the worst case of the square segmentation (cell (odd, odd) of every
    /// 2 x 2 block blocked), with `extra` of every 1000 other cells blocked at random.
    fn grid64(extra: u64, seed: u64) -> crate::nav::Grid<std::vec::Vec<u8>> {
        use crate::nav::{grid_bytes, Cell, Geometry, Grid};
        let mut g =
            Grid::new(64, 64, Geometry::SEED_004, std::vec![0; grid_bytes(64, 64)]).expect("fits");
        let mut s = seed;
        for y in 0..64 {
            for x in 0..64 {
                s = s
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                let random = (s >> 33) % 1000 < extra;
                let blocked = (x % 2 == 1 && y % 2 == 1) || random;
                let c = if blocked { Cell::Obstacle } else { Cell::Free };
                g.set(x, y, c).expect("inside");
            }
        }
        g.set(0, 0, Cell::Free).expect("inside");
        g
    }

    #[test]
    fn it_follows_a_grid_planner_route_across_a_64_by_64_map_whose_squares_do_not_fit() {
        use crate::nav::{max_regions, segment, wave_bytes, wave_plan, GridPoint, Passable};
        use crate::nav::{Cell, Square, WaveRoute};
        for (extra, seed) in [(0, 0), (30, 1), (30, 2), (60, 3)] {
            let g = grid64(extra, seed);
            // More squares than the robot holds (the worst case has max_regions(64, 64)).
            let mut map = std::vec![0u32; g.len()];
            let mut squares = std::vec![Square::EMPTY; g.len()];
            let n = segment(&g, &mut map[..], &mut squares[..])
                .expect("fits")
                .len();
            assert!(n > crate::nav::fixed::NAV64_REGIONS, "{n} squares");
            assert!(n <= max_regions(64, 64), "{n} squares");
            // The farthest free cell reachable from (0, 0) in the last rows.
            let mut scratch = std::vec![0u8; wave_bytes(g.len())];
            let start = GridPoint::cell_centre(0, 0);
            let plan = (0..64u16)
                .rev()
                .flat_map(|y| (0..64u16).rev().map(move |x| (x, y)))
                .filter(|&(x, y)| x + y >= 100)
                .find_map(|(x, y)| {
                    let goal = GridPoint::cell_centre(x, y);
                    wave_plan(&g, Passable::Free, start, goal, &mut scratch).ok()
                })
                .expect("a far cell is reachable");
            let geo = g.geometry();
            let wps: std::vec::Vec<Point> = WaveRoute::new(&g, Passable::Free, &scratch, plan)
                .waypoints()
                .skip(1)
                .map(|p| {
                    let (x, y) = geo.grid_to_metres(p);
                    Point::new(x, y)
                })
                .collect();
            let begin = geo.grid_to_metres(start);
            let mut e = Executor::new(ExecuteParams::default(), Point::new(begin.0, begin.1));
            let pose = Pose::new(begin.0, begin.1, 0.0);
            // The robot's centre never enters a blocked cell (corners are cut only within
            // the free cells around a bend).
            let mut worst = (0u32, Pose::new(0.0, 0.0, 0.0));
            let (end, passed) = simulate_with(&mut e, pose, &wps, 100_000, |p| {
                let (cx, cy) = geo.metres_to_grid(p.x, p.y).cell();
                let free = g.contains(cx, cy) && g.get(cx as usize, cy as usize) == Cell::Free;
                if !free {
                    worst = (worst.0 + 1, p);
                }
            });
            assert_eq!(
                worst.0, 0,
                "map {extra}/{seed}: in a blocked cell at {:?}",
                worst.1
            );
            assert_eq!(e.phase(), ExecPhase::Finished, "map {extra}/{seed}");
            assert_eq!(passed as usize, wps.len(), "map {extra}/{seed}");
            let goal = wps[wps.len() - 1];
            assert!(end.point().distance_to(goal) <= GuidedParams::default().arrival_m + 0.02);
            assert_eq!(
                e.escapes(),
                0,
                "map {extra}/{seed}: never 0.6 m off the route"
            );
        }
    }
}
