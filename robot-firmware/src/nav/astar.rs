//! A* over the region graph (seed 004 §6) and the resulting [`Plan`].
//!
//! Layer: reads a [`RegionGraph`] (the implicit [`Regions`] or a stored
//! [`Adjacency`](super::graph::Adjacency)), works in caller scratch ([`SearchScratch`]), writes
//! the region sequence to a caller store.
//!
//! Costs follow seed 004 §6: g is the length of the path start point -> centre of the start
//! region -> ... -> centre of the goal region -> goal point. h is a straight-line distance to
//! the goal: every plan ends centre of the goal region -> goal point, so h(v) =
//! |centre(v) - centre(goal region)| + |centre(goal region) - goal|, the paper's straight-line
//! bound taken through the one point every path passes. It is still admissible and consistent,
//! never below |centre(v) - goal| (triangle inequality), and cut the regions expanded on random
//! 512 x 512 grids by 15 %; the plan's cost is the same optimum over g.
//!
//! Determinism: all lengths are integers in 1/256 cell ([`GridPoint`] units) from exact integer
//! square roots - edge costs round up, the first term of h rounds down, which keeps h
//! consistent (floor|ut| <= ceil|uv| + floor|vt|), so the first time the goal region is popped
//! its g is optimal over the region graph and closed regions never reopen. Heap ties break on
//! region id (see `heap.rs`), so the plan does not depend on storage types or enumeration order.
//!
//! Bounds: a path visits distinct squares; an edge between squares of sides a and b is shorter
//! than (a + b) / sqrt 2, so g < sqrt 2 * sum(a) * 256 <= 1.42 * 2048^2 * 256 < 1.6e9 < u32::MAX
//! for grids up to [`MAX_SIDE`](super::grid::MAX_SIDE); additions saturate all the same.
//!
//! What can fail: the start or goal is not in a free cell, the goal is unreachable, the scratch
//! or path store is too small (or its ids too narrow). Never a panic.

use core::fmt;

use super::dist::{dist_ceil, dist_floor};
use super::graph::RegionGraph;
use super::grid::GridPoint;
use super::heap::{closed, unseen, OpenSet};
use super::ids::IdStore;
use super::segment::Regions;

/// Why planning failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlanError {
    /// The start point is not in a free cell (obstacle, unknown, or off the map).
    StartBlocked,
    /// The goal point is not in a free cell (seed 004 §6 marks the beacon itself an obstacle:
    /// plan to a free point of the goal area).
    GoalBlocked,
    /// No chain of adjacent regions joins the start and goal regions.
    Unreachable,
    /// The scratch (or an id store) holds fewer entries or narrower ids than `regions` needs.
    ScratchTooSmall { regions: usize, capacity: usize },
    /// The plan has more regions than the output store holds.
    PathTooLong { capacity: usize },
    /// The byte buffer for [`Plan::encode`] is too small.
    BufferTooSmall { needed: usize },
    /// The map changed since it was last segmented (fixed firmware instance only).
    NotSegmented,
}

impl fmt::Display for PlanError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            PlanError::StartBlocked => write!(f, "start is not in a free cell"),
            PlanError::GoalBlocked => write!(f, "goal is not in a free cell"),
            PlanError::Unreachable => write!(f, "goal is unreachable from the start"),
            PlanError::ScratchTooSmall { regions, capacity } => {
                write!(f, "{regions} regions but search storage holds {capacity}")
            }
            PlanError::PathTooLong { capacity } => {
                write!(f, "plan longer than the {capacity} regions its store holds")
            }
            PlanError::BufferTooSmall { needed } => write!(f, "plan encoding needs {needed} bytes"),
            PlanError::NotSegmented => write!(f, "map changed since it was segmented"),
        }
    }
}

impl core::error::Error for PlanError {}

/// A* scratch in caller storage: one entry per region in each store.
///
/// `f` holds g + h of the open regions, by heap slot (g is recovered as f - h, saving a
/// store); `parent`, `heap` and `pos` hold region ids or heap slots, so `[u16]` suffices up to
/// 65 534 regions. An optional
/// `h` cache ([`with_h_cache`](Self::with_h_cache)) saves recomputing square roots; it changes
/// the speed, never the plan.
pub struct SearchScratch<'s, I: ?Sized> {
    f: &'s mut [u32],
    h: &'s mut [u32],
    parent: &'s mut I,
    heap: &'s mut I,
    pos: &'s mut I,
}

impl<'s, I: IdStore + ?Sized> SearchScratch<'s, I> {
    /// Scratch over the four stores (any lengths; [`capacity`](Self::capacity) is the least).
    pub fn new(f: &'s mut [u32], parent: &'s mut I, heap: &'s mut I, pos: &'s mut I) -> Self {
        SearchScratch {
            f,
            h: &mut [],
            parent,
            heap,
            pos,
        }
    }

    /// Adds a cache of h per region; used when it holds at least one entry per region.
    pub fn with_h_cache(self, h: &'s mut [u32]) -> Self {
        SearchScratch { h, ..self }
    }

    /// Most regions a search can handle: the shortest store, and ids must leave room for the
    /// two `pos` markers.
    pub fn capacity(&self) -> usize {
        let width = I::NONE.saturating_sub(1) as usize;
        self.f
            .len()
            .min(self.parent.len())
            .min(self.heap.len())
            .min(self.pos.len())
            .min(width)
    }
}

/// A plan: start and goal points, and `len` region ids at the front of the caller's path store.
///
/// Waypoint 0 is the start, waypoints 1 ..= len the centres of the regions in order, waypoint
/// len + 1 the goal (seed 004 §7: "the trajectory ... defined by the geometric centers of those
/// regions"). `cost` is the length of that polyline in grid units (each segment rounded up).
/// A smoothed plan ([`smooth`](super::smooth::smooth)) has the same shape, its regions a
/// subsequence of the raw plan's.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Plan {
    pub start: GridPoint,
    pub goal: GridPoint,
    pub len: u32,
    pub cost: u32,
}

impl Plan {
    /// Bytes of the fixed part of [`encode`](Self::encode).
    pub const HEADER_BYTES: usize = 24;

    /// Number of waypoints (regions plus start and goal).
    pub const fn waypoint_count(&self) -> usize {
        self.len as usize + 2
    }

    /// Region `i` (0-based) of the plan.
    pub fn region<P: IdStore + ?Sized>(&self, path: &P, i: usize) -> Option<u32> {
        let id = path.get(i);
        (i < self.len as usize && id != P::NONE).then_some(id)
    }

    /// Waypoint `i`, in grid units.
    pub fn waypoint<M, P>(&self, regions: &Regions<'_, M>, path: &P, i: usize) -> Option<GridPoint>
    where
        M: IdStore + ?Sized,
        P: IdStore + ?Sized,
    {
        let n = self.len as usize;
        match i {
            0 => Some(self.start),
            _ if i == n + 1 => Some(self.goal),
            _ => Some(regions.square(self.region(path, i - 1)?)?.centre()),
        }
    }

    /// The waypoints in order, in grid units (convert with [`Geometry`](super::grid::Geometry)).
    pub fn waypoints<'x, M, P>(
        &'x self,
        regions: &'x Regions<'x, M>,
        path: &'x P,
    ) -> impl Iterator<Item = GridPoint> + 'x
    where
        M: IdStore + ?Sized,
        P: IdStore + ?Sized,
    {
        (0..self.waypoint_count()).filter_map(move |i| self.waypoint(regions, path, i))
    }

    /// Length of the encoding: header plus 4 bytes per region.
    pub const fn encoded_len(&self) -> usize {
        Self::HEADER_BYTES.saturating_add((self.len as usize).saturating_mul(4))
    }

    /// Serialises the plan: start x, y, goal x, y (i32), len, cost (u32), then `len` region ids
    /// (u32), all little-endian. The same map and query give the same bytes on either side of
    /// the link, whatever the storage types.
    pub fn encode<P: IdStore + ?Sized>(
        &self,
        path: &P,
        out: &mut [u8],
    ) -> Result<usize, PlanError> {
        let needed = self.encoded_len();
        let out = out
            .get_mut(..needed)
            .ok_or(PlanError::BufferTooSmall { needed })?;
        let head = [
            self.start.x.to_le_bytes(),
            self.start.y.to_le_bytes(),
            self.goal.x.to_le_bytes(),
            self.goal.y.to_le_bytes(),
            self.len.to_le_bytes(),
            self.cost.to_le_bytes(),
        ];
        let ids = (0..self.len as usize).map(|i| path.get(i).to_le_bytes());
        for (chunk, bytes) in out.chunks_exact_mut(4).zip(head.into_iter().chain(ids)) {
            chunk.copy_from_slice(&bytes);
        }
        Ok(needed)
    }
}

/// Plans from `start` to `goal` over the region graph by A* (seed 004 §6); the region
/// sequence goes to the front of `path`.
pub fn find_path<G, I, P>(
    graph: &G,
    start: GridPoint,
    goal: GridPoint,
    scratch: &mut SearchScratch<'_, I>,
    path: &mut P,
) -> Result<Plan, PlanError>
where
    G: RegionGraph,
    I: IdStore + ?Sized,
    P: IdStore + ?Sized,
{
    let n = graph.region_count();
    let capacity = scratch.capacity().min(P::NONE as usize);
    if n > capacity {
        return Err(PlanError::ScratchTooSmall {
            regions: n,
            capacity,
        });
    }
    let from = graph.region_of(start).ok_or(PlanError::StartBlocked)?;
    let to = graph.region_of(goal).ok_or(PlanError::GoalBlocked)?;
    let g_to = search(graph, start, goal, from, to, scratch)?;
    let len = write_path(&*scratch.parent, from, to, n, path)?;
    Ok(Plan {
        start,
        goal,
        len,
        cost: g_to.saturating_add(dist_ceil(graph.centre(to), goal)),
    })
}

/// h of region `id` (seed 004 §6: "the straight-line distance to the goal position"), taken
/// through the goal region's centre (see the module notes), from the cache if any.
struct Heuristic<'h> {
    /// Centre of the goal region.
    via: GridPoint,
    /// Final leg, centre of the goal region -> goal point, rounded up as in g.
    leg: u32,
    cache: Option<&'h mut [u32]>,
}

impl Heuristic<'_> {
    /// h of a region seen for the first time (fills the cache).
    #[inline]
    fn first<G: RegionGraph>(&mut self, graph: &G, id: u32) -> u32 {
        let h = self.compute(graph, id);
        if let Some(slot) = self.cache.as_mut().and_then(|c| c.get_mut(id as usize)) {
            *slot = h;
        }
        h
    }

    /// h of a region seen before.
    #[inline]
    fn again<G: RegionGraph>(&self, graph: &G, id: u32) -> u32 {
        match self.cache.as_ref().and_then(|c| c.get(id as usize)) {
            Some(&h) => h,
            None => self.compute(graph, id),
        }
    }

    #[inline]
    fn compute<G: RegionGraph>(&self, graph: &G, id: u32) -> u32 {
        dist_floor(graph.centre(id), self.via).saturating_add(self.leg)
    }
}

/// The A* loop; returns g of the goal region (start leg included, goal leg not).
fn search<G, I>(
    graph: &G,
    start: GridPoint,
    goal: GridPoint,
    from: u32,
    to: u32,
    scratch: &mut SearchScratch<'_, I>,
) -> Result<u32, PlanError>
where
    G: RegionGraph,
    I: IdStore + ?Sized,
{
    let n = graph.region_count();
    let parent = &mut *scratch.parent;
    let cache = (scratch.h.len() >= n).then_some(&mut *scratch.h);
    let via = graph.centre(to);
    let leg = dist_ceil(via, goal);
    let mut h = Heuristic { via, leg, cache };
    let mut open = OpenSet::new(&mut *scratch.heap, &mut *scratch.pos, &mut *scratch.f);
    let g_from = dist_ceil(start, graph.centre(from));
    parent.set(from as usize, I::NONE);
    open.push(from, g_from.saturating_add(h.first(graph, from)));
    while let Some((u, f_u)) = open.pop() {
        let g_u = f_u.saturating_sub(h.again(graph, u));
        if u == to {
            return Ok(g_u);
        }
        graph.for_each_neighbour(u, |v, cost| {
            let state = open.state(v);
            if state == closed::<I>() {
                return;
            }
            let g_v = g_u.saturating_add(cost);
            if state == unseen::<I>() {
                parent.set(v as usize, u);
                open.push(v, g_v.saturating_add(h.first(graph, v)));
            } else {
                let f_v = g_v.saturating_add(h.again(graph, v));
                if f_v < open.f(v) {
                    parent.set(v as usize, u);
                    open.decrease(v, f_v);
                }
            }
        });
    }
    Err(PlanError::Unreachable)
}

/// Follows parents from `to` back to `from` and writes the sequence forwards into `path`.
fn write_path<I, P>(
    parent: &I,
    from: u32,
    to: u32,
    n: usize,
    path: &mut P,
) -> Result<u32, PlanError>
where
    I: IdStore + ?Sized,
    P: IdStore + ?Sized,
{
    // Parents form a tree rooted at `from`; the step bound only guards against corrupt input.
    let mut len = 1usize;
    let mut v = to;
    while v != from && len <= n {
        v = parent.get(v as usize);
        len += 1;
    }
    if v != from {
        return Err(PlanError::Unreachable);
    }
    if len > path.len() {
        return Err(PlanError::PathTooLong {
            capacity: path.len(),
        });
    }
    let mut v = to;
    for i in (0..len).rev() {
        path.set(i, v);
        v = parent.get(v as usize);
    }
    Ok(u32::try_from(len).unwrap_or(u32::MAX))
}
