//! The grid planner: a wavefront (breadth-first distance transform) over cells, for maps whose
//! square segmentation needs more regions than the storage holds.
//!
//! Why it exists: seed 004 §6's squares + A* need storage per square, and a 64 x 64 grid can
//! make up to [`max_regions`](super::segment::max_regions)`(64, 64)` = 3072 squares; the
//! robot's instance holds 255 (`fixed.rs`). A* storage for 3072 regions alone would be 12 KB.
//! This planner's storage depends on the cell count only - 4 bits a cell, 2 KB for 64 x 64 -
//! and it runs in the bytes of the region map the failed segmentation leaves unused, so the
//! robot plans on every map it accepts with no memory beyond what it had. The squares stay
//! the method whenever they fit (the paper's); this is the fallback, and plans made by it say
//! so (no regions, see `transfer.rs`).
//!
//! Method (the classic grid wavefront, e.g. Latombe 1991 ch. 7 "NF1"):
//! 1. Wave from the goal cell over 4-connected passable cells. Each cell keeps its distance
//!    modulo 3 in 2 bits (3 = not reached): neighbours' distances differ by at most 1, so the
//!    residue tells a neighbour one step nearer the goal from one at the same or a larger
//!    distance. The wave's cells are two bitsets (this wave, the next one); a wave scans only
//!    the byte range its cells span. It stops when the start cell is reached.
//! 2. Descend from the start cell to the goal, each step to a neighbour one nearer (the
//!    previous direction first, so straight runs stay straight): a shortest 4-connected cell
//!    path. Corner contact is never a step: the robot cannot pass between two obstacle cells
//!    that touch at a corner.
//! 3. Waypoints: from an anchor, the path is followed while the straight segment to the next
//!    cell's centre passes [`line_of_sight`](super::smooth::line_of_sight)'s conservative test;
//!    where it fails, the last visible point becomes a waypoint. Consecutive cell centres of
//!    the path are always a feasible step, so the waypoint polyline stays in passable cells.
//!    The descent is deterministic, so the waypoints are replayed from the labels
//!    ([`WaveRoute::waypoints`]) rather than stored.
//!
//! Cost: the wave expands each cell once (4 neighbour checks) plus, per wave, a scan of the
//! frontier's byte range: O(cells + waves x frontier span / 8). Waypoints cost one line of
//! sight test per path cell: O(path x longest segment).
//!
//! What can fail (typed [`PlanError`], never a panic): start or goal not in a passable cell,
//! goal unreachable, scratch smaller than [`wave_bytes`].

use super::astar::PlanError;
use super::dist::dist_ceil;
use super::grid::{Grid, GridPoint};
use super::segment::Passable;
use super::smooth::line_of_sight_by;

/// Not reached by the wave (the 2-bit label's fourth value).
const UNREACHED: u8 = 3;

/// Bytes of scratch [`wave_plan`] needs for `cells` cells: 2 bits of label a cell and two
/// frontier bitsets (2 048 bytes for 64 x 64).
pub const fn wave_bytes(cells: usize) -> usize {
    cells.div_ceil(4) + 2 * cells.div_ceil(8)
}

/// A plan made by [`wave_plan`]: its start and goal points, the number of waypoints between
/// them, the path's length in cells and the waypoint polyline's length.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct WavePlan {
    pub start: GridPoint,
    pub goal: GridPoint,
    /// Waypoints between start and goal (cell centres).
    pub points: u32,
    /// Steps of the 4-connected cell path (its cells minus one).
    pub steps: u32,
    /// Length of start, points, goal in grid units (each segment rounded up, as `Plan::cost`).
    pub cost: u32,
}

impl WavePlan {
    /// Number of waypoints, start and goal included.
    pub const fn waypoint_count(&self) -> usize {
        self.points as usize + 2
    }
}

/// A wave plan with the labels it was made from: replays its waypoints.
pub struct WaveRoute<'a, S> {
    pub plan: WavePlan,
    grid: &'a Grid<S>,
    labels: &'a [u8],
    passable: Passable,
}

impl<'a, S: AsRef<[u8]>> WaveRoute<'a, S> {
    /// The labels `wave_plan` left in `scratch` for `plan` (same grid, same passable cells).
    pub fn new(grid: &'a Grid<S>, passable: Passable, scratch: &'a [u8], plan: WavePlan) -> Self {
        WaveRoute {
            plan,
            grid,
            labels: scratch,
            passable,
        }
    }

    /// The grid's cell size and origin (for waypoints in the map frame).
    pub fn geometry(&self) -> super::grid::Geometry {
        self.grid.geometry()
    }

    /// Every waypoint in order: start, the cell centres, goal (exactly
    /// [`WavePlan::waypoint_count`] of them).
    pub fn waypoints(&self) -> Waypoints<'a, S> {
        let walk = Walk::new(self.grid, self.labels, self.passable, self.plan);
        Waypoints {
            walk,
            left: self.plan.waypoint_count(),
            begun: false,
        }
    }
}

/// Iterator of [`WaveRoute::waypoints`].
pub struct Waypoints<'a, S> {
    walk: Walk<'a, S>,
    left: usize,
    begun: bool,
}

impl<S: AsRef<[u8]>> Iterator for Waypoints<'_, S> {
    type Item = GridPoint;

    fn next(&mut self) -> Option<GridPoint> {
        if self.left == 0 {
            return None;
        }
        self.left -= 1;
        if !self.begun {
            self.begun = true;
            return Some(self.walk.start);
        }
        // The count was taken by the same walk, so the points run out exactly at the goal.
        if self.left == 0 {
            return Some(self.walk.goal);
        }
        Some(self.walk.next_point().unwrap_or(self.walk.goal))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        (self.left, Some(self.left))
    }
}

impl<S: AsRef<[u8]>> ExactSizeIterator for Waypoints<'_, S> {}

/// Plans from `start` to `goal` over the cells `passable` admits, in `scratch` (at least
/// [`wave_bytes`]`(grid.len())` bytes, which keep the labels for [`WaveRoute`]).
pub fn wave_plan<S: AsRef<[u8]>>(
    grid: &Grid<S>,
    passable: Passable,
    start: GridPoint,
    goal: GridPoint,
    scratch: &mut [u8],
) -> Result<WavePlan, PlanError> {
    label_route(grid, passable, start, goal, scratch)?;
    let mut plan = WavePlan {
        start,
        goal,
        points: 0,
        steps: 0,
        cost: 0,
    };
    // The counting pass: the same walk the route replays.
    let mut walk = Walk::new(grid, &*scratch, passable, plan);
    let (mut prev, mut cost, mut points) = (start, 0u32, 0u32);
    while let Some(p) = walk.next_point() {
        cost = cost.saturating_add(dist_ceil(prev, p));
        prev = p;
        points = points.saturating_add(1);
    }
    plan.points = points;
    plan.steps = walk.steps;
    plan.cost = cost.saturating_add(dist_ceil(prev, goal));
    Ok(plan)
}

/// The first waypoint of [`wave_plan`]'s route from `start` to `goal` (the farthest route
/// point in line of sight of `start`, or `goal`) and the route's length in steps, without the
/// walk over the whole route that counting its waypoints takes: what a search that replans
/// as it drives needs.
pub fn wave_first_waypoint<S: AsRef<[u8]>>(
    grid: &Grid<S>,
    passable: Passable,
    start: GridPoint,
    goal: GridPoint,
    scratch: &mut [u8],
) -> Result<(GridPoint, u32), PlanError> {
    let steps = label_route(grid, passable, start, goal, scratch)?;
    let plan = WavePlan {
        start,
        goal,
        points: 0,
        steps,
        cost: 0,
    };
    let mut walk = Walk::new(grid, &*scratch, passable, plan);
    Ok((walk.next_point().unwrap_or(goal), steps))
}

/// Checks the scratch and the ends, then labels the cells with the wave from `goal` until it
/// reaches `start`; returns the route's length in steps.
fn label_route<S: AsRef<[u8]>>(
    grid: &Grid<S>,
    passable: Passable,
    start: GridPoint,
    goal: GridPoint,
    scratch: &mut [u8],
) -> Result<u32, PlanError> {
    let cells = grid.len();
    if scratch.len() < wave_bytes(cells) {
        return Err(PlanError::ScratchTooSmall {
            regions: cells,
            capacity: scratch.len().saturating_mul(2),
        });
    }
    let s = cell_index(grid, passable, start).ok_or(PlanError::StartBlocked)?;
    let g = cell_index(grid, passable, goal).ok_or(PlanError::GoalBlocked)?;
    wave(grid, passable, g, s, scratch)
}

/// Index of the passable cell under `p`.
fn cell_index<S: AsRef<[u8]>>(grid: &Grid<S>, passable: Passable, p: GridPoint) -> Option<usize> {
    let (x, y) = p.cell();
    if !grid.contains(x, y) {
        return None;
    }
    let i = y as usize * usize::from(grid.width()) + x as usize;
    passable.admits(grid.cell_at(i)).then_some(i)
}

/// Whether the last wave in `scratch` reached cell `i` (after a plan, or after an
/// `Unreachable` one: then the cells reachable from its goal).
pub(crate) fn reached(scratch: &[u8], i: usize) -> bool {
    label(scratch, i) != UNREACHED
}

#[inline]
fn label(labels: &[u8], i: usize) -> u8 {
    labels
        .get(i / 4)
        .map_or(UNREACHED, |b| (b >> (2 * (i % 4))) & 3)
}

#[inline]
fn set_label(labels: &mut [u8], i: usize, v: u8) {
    if let Some(b) = labels.get_mut(i / 4) {
        let shift = 2 * (i % 4);
        *b = (*b & !(3 << shift)) | (v << shift);
    }
}

/// A frontier bitset and the byte range its bits lie in.
struct Frontier {
    /// Offset of the bitset in the scratch.
    at: usize,
    lo: usize,
    hi: usize,
}

impl Frontier {
    fn empty(at: usize) -> Self {
        Frontier {
            at,
            lo: usize::MAX,
            hi: 0,
        }
    }

    fn add(&mut self, scratch: &mut [u8], i: usize) {
        let byte = i / 8;
        if let Some(b) = scratch.get_mut(self.at + byte) {
            *b |= 1 << (i % 8);
        }
        self.lo = self.lo.min(byte);
        self.hi = self.hi.max(byte);
    }

    fn is_empty(&self) -> bool {
        self.lo > self.hi
    }
}

/// Labels cells with their distance from `goal` modulo 3 until `start` is reached; returns
/// that distance.
fn wave<S: AsRef<[u8]>>(
    grid: &Grid<S>,
    passable: Passable,
    goal: usize,
    start: usize,
    scratch: &mut [u8],
) -> Result<u32, PlanError> {
    let cells = grid.len();
    let (lab_len, set_len) = (cells.div_ceil(4), cells.div_ceil(8));
    if let Some(l) = scratch.get_mut(..lab_len) {
        l.fill(0xFF);
    }
    if let Some(f) = scratch.get_mut(lab_len..lab_len + 2 * set_len) {
        f.fill(0);
    }
    let w = usize::from(grid.width());
    let mut cur = Frontier::empty(lab_len);
    let mut next = Frontier::empty(lab_len + set_len);
    set_label(scratch, goal, 0);
    cur.add(scratch, goal);
    let mut d = 0u8;
    let mut waves = 0u32;
    while !cur.is_empty() {
        if label(scratch, start) != UNREACHED {
            return Ok(waves);
        }
        let nd = (d + 1) % 3;
        for byte in cur.lo..=cur.hi {
            let bits = scratch.get(cur.at + byte).copied().unwrap_or(0);
            if bits == 0 {
                continue;
            }
            if let Some(b) = scratch.get_mut(cur.at + byte) {
                *b = 0;
            }
            for k in 0..8 {
                if bits & (1 << k) == 0 {
                    continue;
                }
                let i = byte * 8 + k;
                let (x, y) = (i % w, i / w);
                let mut reach = |j: usize| {
                    if label(scratch, j) == UNREACHED && passable.admits(grid.cell_at(j)) {
                        set_label(scratch, j, nd);
                        next.add(scratch, j);
                    }
                };
                if x + 1 < w {
                    reach(i + 1);
                }
                if x > 0 {
                    reach(i - 1);
                }
                if i + w < cells {
                    reach(i + w);
                }
                if y > 0 {
                    reach(i - w);
                }
            }
        }
        core::mem::swap(&mut cur, &mut next);
        next.lo = usize::MAX;
        next.hi = 0;
        d = nd;
        waves += 1;
    }
    if label(scratch, start) != UNREACHED {
        Ok(waves)
    } else {
        Err(PlanError::Unreachable)
    }
}

/// The descent and the line-of-sight waypoint choice (steps 2 and 3 of the module notes).
struct Walk<'a, S> {
    grid: &'a Grid<S>,
    labels: &'a [u8],
    passable: Passable,
    start: GridPoint,
    goal: GridPoint,
    /// The path cell whose centre is the next candidate; `None` once the goal was offered.
    cell: Option<usize>,
    /// Whether the start cell's own centre has been offered.
    entered: bool,
    /// Direction of the last step (index into `DIRS`).
    dir: usize,
    steps: u32,
    anchor: GridPoint,
    last: GridPoint,
    pending: Option<GridPoint>,
    done: bool,
}

/// Step directions: +x, +y, -x, -y.
const DIRS: [(i32, i32); 4] = [(1, 0), (0, 1), (-1, 0), (0, -1)];

impl<'a, S: AsRef<[u8]>> Walk<'a, S> {
    fn new(grid: &'a Grid<S>, labels: &'a [u8], passable: Passable, plan: WavePlan) -> Self {
        Walk {
            grid,
            labels,
            passable,
            start: plan.start,
            goal: plan.goal,
            cell: cell_index(grid, passable, plan.start),
            entered: false,
            dir: 0,
            steps: 0,
            anchor: plan.start,
            last: plan.start,
            pending: None,
            done: false,
        }
    }

    fn free(&self, x: i32, y: i32) -> bool {
        self.grid.contains(x, y) && {
            let i = y as usize * usize::from(self.grid.width()) + x as usize;
            self.passable.admits(self.grid.cell_at(i))
        }
    }

    fn visible(&self, a: GridPoint, b: GridPoint) -> bool {
        let free = |x: i32, y: i32| self.free(x, y);
        line_of_sight_by(self.grid.width(), self.grid.height(), free, a, b)
    }

    /// The next candidate point: the start cell's centre, each later path cell's centre, then
    /// the goal point (`true`), then nothing.
    fn candidate(&mut self) -> Option<(GridPoint, bool)> {
        let i = self.cell?;
        let w = usize::from(self.grid.width());
        let centre = |i: usize| {
            let (x, y) = (i % w, i / w);
            GridPoint::cell_centre(x as u16, y as u16)
        };
        if !self.entered {
            self.entered = true;
            return Some((centre(i), false));
        }
        let goal_cell = cell_index(self.grid, self.passable, self.goal);
        if Some(i) == goal_cell || self.steps as usize >= self.grid.len() {
            self.cell = None;
            return Some((self.goal, true));
        }
        let l = label(self.labels, i);
        let want = (l + 2) % 3;
        let (x, y) = ((i % w) as i32, (i / w) as i32);
        let order = [self.dir, 0, 1, 2, 3];
        let step = order.into_iter().find_map(|k| {
            let (dx, dy) = DIRS.get(k).copied()?;
            let (nx, ny) = (x + dx, y + dy);
            let j = (ny as usize).wrapping_mul(w).wrapping_add(nx as usize);
            (self.free(nx, ny) && label(self.labels, j) == want).then_some((k, j))
        });
        let Some((k, j)) = step else {
            // Only on labels that are not this grid's wave: end at the goal all the same.
            self.cell = None;
            return Some((self.goal, true));
        };
        self.dir = k;
        self.steps += 1;
        self.cell = Some(j);
        Some((centre(j), false))
    }

    /// Whether the next path cell's centre `p` continues the visible segment anchor -> last
    /// straight on: the closed segment anchor -> p is then anchor -> last plus the step between
    /// two neighbouring path cells' centres, so it meets no other cells and is visible without
    /// the test (which on a Cortex-M4 costs two 64-bit divisions a column: this made straight
    /// corridors quadratic).
    fn extends(&self, p: GridPoint) -> bool {
        let (a, l) = (self.anchor, self.last);
        let (ux, uy) = (i64::from(l.x - a.x), i64::from(l.y - a.y));
        let (vx, vy) = (i64::from(p.x - l.x), i64::from(p.y - l.y));
        l != a && ux * vy == uy * vx && ux * vx + uy * vy > 0
    }

    /// The next waypoint strictly between start and goal.
    fn next_point(&mut self) -> Option<GridPoint> {
        if let Some(p) = self.pending.take() {
            return Some(p);
        }
        while !self.done {
            let Some((p, is_goal)) = self.candidate() else {
                self.done = true;
                break;
            };
            if is_goal {
                self.done = true;
            }
            if p == self.anchor {
                continue;
            }
            if (!is_goal && self.extends(p)) || self.visible(self.anchor, p) {
                self.last = p;
                continue;
            }
            let mut out = None;
            if self.last != self.anchor {
                out = Some(self.last);
                self.anchor = self.last;
            }
            if self.visible(self.anchor, p) {
                self.last = p;
            } else if !is_goal {
                // A step between neighbouring cells' centres: feasible without the test.
                self.anchor = p;
                self.last = p;
                match out {
                    None => out = Some(p),
                    Some(_) => self.pending = Some(p),
                }
            }
            if out.is_some() {
                return out;
            }
        }
        None
    }
}
