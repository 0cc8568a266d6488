//! [`Planner`]: segmentation, the stored region graph and A* over `Vec` storage, timed.
//!
//! Layer: owns a [`NavMap`] and everything `robot_firmware::nav` needs to plan on it many
//! times (the station's choice in nav's doctest): the region-id map and squares from
//! `segment`, the CSR adjacency from `Adjacency::build`, and per query the A* scratch with its
//! h cache. The firmware runs the very same functions in fixed arrays, so the same grid and
//! query give the same region sequence on both sides of the link.
//!
//! Timing (seed 004 §6 reports "a few seconds" on the 68HC11): `segment_us` covers the
//! segmentation and the connectivity graph, `search_us` the A* search alone, `smooth_us` the
//! optional smoothing; all wall-clock microseconds on this machine.
//!
//! What can fail: segmentation and graph storage (sized from the grid, so not expected), and
//! per query the start/goal checks of [`NavMap`] and an unreachable goal ([`NavError`]).

use std::time::{Duration, Instant};

use robot_firmware::nav::{
    find_path, segment, smooth, Adjacency, Edge, GridPoint, Plan, PlanError, Regions,
    SearchScratch, Square, UNITS_PER_CELL,
};

use super::map::{Endpoint, NavMap};
use super::{micros, NavError};

/// Smoothing keeps a quarter cell from square corners (grid units), as nav's doctest does.
pub const SMOOTH_MARGIN: u32 = UNITS_PER_CELL as u32 / 4;

/// A map segmented into squares with its stored connectivity graph.
#[derive(Clone, Debug, PartialEq)]
pub struct Planner {
    map: NavMap,
    /// Region id per cell (`u32::MAX`: none).
    ids: Vec<u32>,
    squares: Vec<Square>,
    offsets: Vec<u32>,
    edges: Vec<Edge>,
    segment_time: Duration,
}

/// The smoothed path, reported beside the raw one (seed 004's method stays visible).
#[derive(Clone, Debug, PartialEq)]
pub struct SmoothedPath {
    /// Start, corner points, goal; metres.
    pub waypoints: Vec<(f64, f64)>,
    pub length_m: f64,
    pub smooth_us: u64,
}

/// A plan in metres, map frame.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanResult {
    /// The raw plan in grid units (start, goal, region count, cost).
    pub plan: Plan,
    /// Region ids in order, start region first.
    pub path: Vec<u32>,
    /// Start, region centres, goal; metres (seed 004 §7: the trajectory).
    pub waypoints: Vec<(f64, f64)>,
    /// Length of the waypoint polyline, metres.
    pub length_m: f64,
    pub search_us: u64,
    pub smoothed: Option<SmoothedPath>,
}

impl PlanResult {
    /// Start point, metres.
    pub fn start(&self) -> (f64, f64) {
        self.waypoints.first().copied().unwrap_or_default()
    }

    /// Goal point, metres.
    pub fn goal(&self) -> (f64, f64) {
        self.waypoints.last().copied().unwrap_or_default()
    }
}

impl Planner {
    /// Segments `map` (seed 004 §6, Fig. 6) and stores its region graph.
    pub fn new(map: NavMap) -> Result<Planner, NavError> {
        let t0 = Instant::now();
        let n = map.grid.len();
        let mut ids = vec![0u32; n];
        let mut squares = vec![Square::EMPTY; n];
        let count = segment(&map.grid, &mut ids[..], &mut squares[..])?.len();
        squares.truncate(count);
        let mut offsets = vec![0u32; count + 1];
        let mut edges;
        {
            let regions = Regions::from_segmented(&map.grid, &ids[..], &squares[..])
                .ok_or(NavError::Plan(PlanError::NotSegmented))?;
            edges = vec![Edge::default(); Adjacency::edge_count(&regions)];
            Adjacency::build(regions, &mut offsets, &mut edges)?;
        }
        Ok(Planner {
            map,
            ids,
            squares,
            offsets,
            edges,
            segment_time: t0.elapsed(),
        })
    }

    /// The map planned on.
    pub fn map(&self) -> &NavMap {
        &self.map
    }

    /// The squares, indexed by region id.
    pub fn squares(&self) -> &[Square] {
        &self.squares
    }

    /// Number of directed edges of the region graph.
    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }

    /// Segmentation plus graph time, microseconds.
    pub fn segment_us(&self) -> u64 {
        micros(self.segment_time)
    }

    /// The segmentation as nav's view.
    pub fn regions(&self) -> Option<Regions<'_, [u32]>> {
        Regions::from_segmented(&self.map.grid, &self.ids[..], &self.squares[..])
    }

    /// The region holding cell (`x`, `y`).
    pub fn region_at(&self, x: i32, y: i32) -> Option<u32> {
        self.regions()?.region_at(x, y)
    }

    /// Neighbours of region `id` in the stored graph.
    pub fn neighbours(&self, id: u32) -> impl Iterator<Item = u32> + '_ {
        let at = |i: usize| self.offsets.get(i).map_or(0, |&o| o as usize);
        let (lo, hi) = (at(id as usize), at(id as usize + 1));
        self.edges.get(lo..hi).unwrap_or(&[]).iter().map(|e| e.to)
    }

    /// Plans from `from` (default: the map's start) to `to` (default: the map's goal area);
    /// `smoothed` adds the smoothed path.
    pub fn plan(
        &self,
        from: Option<(f64, f64)>,
        to: Option<(f64, f64)>,
        smoothed: bool,
    ) -> Result<PlanResult, NavError> {
        let start = self.map.resolve_start(from)?;
        let goal = self.map.resolve_goal(to)?;
        self.plan_between(start, goal, smoothed)
    }

    /// Plans between two endpoints (checked or not: nav checks again). The first and last
    /// waypoints are the endpoints' millimetres, the rest the planner's points.
    pub fn plan_between(
        &self,
        start: Endpoint,
        goal: Endpoint,
        smoothed: bool,
    ) -> Result<PlanResult, NavError> {
        let ends = |mut pts: Vec<(f64, f64)>| {
            if let Some(p) = pts.first_mut() {
                *p = start.metres();
            }
            if let Some(p) = pts.last_mut() {
                *p = goal.metres();
            }
            pts
        };
        let ends_m = (start.metres(), goal.metres());
        let (start, goal) = (start.grid, goal.grid);
        let regions = self
            .regions()
            .ok_or(NavError::Plan(PlanError::NotSegmented))?;
        let graph = Adjacency::from_built(regions, &self.offsets, &self.edges)
            .ok_or(NavError::Plan(PlanError::NotSegmented))?;
        let n = regions.len();
        let (mut f, mut h) = (vec![0u32; n], vec![0u32; n]);
        let (mut parent, mut heap, mut pos) = (vec![0u32; n], vec![0u32; n], vec![0u32; n]);
        let mut scratch = SearchScratch::new(&mut f, &mut parent[..], &mut heap[..], &mut pos[..])
            .with_h_cache(&mut h);
        let mut path = vec![0u32; n];
        let t0 = Instant::now();
        let found = find_path(&graph, start, goal, &mut scratch, &mut path[..]);
        let search_us = micros(t0.elapsed());
        let plan = found.map_err(|e| self.plan_error(e, ends_m))?;
        path.truncate(plan.len as usize);
        let waypoints = ends(
            plan.waypoints(&regions, &path[..])
                .map(|p| self.map.to_metres(p))
                .collect(),
        );
        let smoothed = if smoothed {
            let t0 = Instant::now();
            let mut out = vec![GridPoint::default(); path.len() + 1];
            let s = smooth(&regions, &plan, &path[..], SMOOTH_MARGIN, &mut out)?;
            let smooth_us = micros(t0.elapsed());
            let pts = ends(s.waypoints(&out).map(|p| self.map.to_metres(p)).collect());
            Some(SmoothedPath {
                length_m: length(&pts),
                waypoints: pts,
                smooth_us,
            })
        } else {
            None
        };
        Ok(PlanResult {
            plan,
            length_m: length(&waypoints),
            waypoints,
            path,
            search_us,
            smoothed,
        })
    }

    /// Words for nav's planning errors, with the points in metres.
    fn plan_error(&self, e: PlanError, (s, g): ((f64, f64), (f64, f64))) -> NavError {
        match e {
            PlanError::Unreachable => NavError::Unreachable {
                sx: s.0,
                sy: s.1,
                gx: g.0,
                gy: g.1,
                hint: self.map.hint(),
            },
            PlanError::StartBlocked => self
                .map
                .check_point(super::End::Start, s)
                .err()
                .unwrap_or(NavError::Plan(e)),
            PlanError::GoalBlocked => self
                .map
                .check_point(super::End::Goal, g)
                .err()
                .unwrap_or(NavError::Plan(e)),
            other => NavError::Plan(other),
        }
    }

    /// Length of a raw plan's polyline as nav measures it (grid units, each segment rounded
    /// up), in metres: the A* objective.
    pub fn cost_m(&self, plan: &Plan) -> f64 {
        f64::from(plan.cost) / f64::from(UNITS_PER_CELL) * self.map.cell_m()
    }
}

/// Length of a polyline, metres.
pub fn length(points: &[(f64, f64)]) -> f64 {
    points
        .windows(2)
        .map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1))
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::MapOptions;

    #[test]
    fn micro_rato_99_plans_from_the_start_to_beside_the_beacon() {
        let map = NavMap::load(emulator::builtin::MICRO_RATO_99, &MapOptions::default())
            .expect("built in");
        let p = Planner::new(map).expect("segments");
        assert!(!p.squares().is_empty());
        let r = p.plan(None, None, true).expect("reachable");
        assert_eq!(r.waypoints.len(), r.path.len() + 2);
        assert_eq!(r.start(), (0.5, 0.5));
        let s = r.smoothed.expect("asked for");
        assert!(s.length_m <= r.length_m + 1e-9);
        assert!((p.cost_m(&r.plan) - r.length_m).abs() < 0.01);
    }

    #[test]
    fn an_enclosed_pocket_is_unreachable_with_a_clear_error() {
        use robot_firmware::nav::{Cell, Geometry, Grid};
        let mut g = Grid::new(5, 1, Geometry::SEED_004, vec![0u8; 2]).expect("fits");
        g.fill(Cell::Free);
        g.set(2, 0, Cell::Obstacle).expect("inside");
        let map = NavMap::from_grid("pocket", g, Some((0.15, 0.15)), Some((1.35, 0.15)));
        let e = Planner::new(map)
            .expect("segments")
            .plan(None, None, false)
            .expect_err("walled off");
        assert!(e.to_string().contains("unreachable"), "{e}");
    }
}
