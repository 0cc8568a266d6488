//! The region connectivity graph (seed 004 §6) as the planner sees it: implicit or explicit.
//!
//! Layer: between `segment.rs` and `astar.rs`. [`RegionGraph`] is what A* needs: region count,
//! centres, the region under a point, and each region's neighbours with the edge cost (the
//! distance between centres in grid units, rounded up). Two implementations give the same
//! integers:
//! - [`Regions`] itself walks a square's border in the region map on every call: no storage,
//!   the firmware's choice.
//! - [`Adjacency`] stores the graph once per segmentation in caller slices (CSR: per-region
//!   offsets into one edge list, costs precomputed): the station's choice for many queries.
//!
//! Plans do not depend on which one is used, nor on neighbour order: A*'s pop order is a total
//! order on (f, region id) (see `heap.rs`). The property tests check this byte for byte.
//!
//! What can fail: [`Adjacency::build`] with too-small storage. Never a panic.

use core::fmt;

use super::dist::dist_ceil;
use super::grid::GridPoint;
use super::ids::IdStore;
use super::segment::Regions;

/// What A* needs from the region graph.
pub trait RegionGraph {
    /// Number of regions (ids are `0 .. region_count()`).
    fn region_count(&self) -> usize;
    /// Region holding the cell under `p`, if that cell is free.
    fn region_of(&self, p: GridPoint) -> Option<u32>;
    /// Centre of region `id` (the origin for an unknown id).
    fn centre(&self, id: u32) -> GridPoint;
    /// Calls `f(neighbour, cost)` for each neighbour of `id`; `cost` is the centre-to-centre
    /// distance rounded up, in grid units.
    fn for_each_neighbour(&self, id: u32, f: impl FnMut(u32, u32));
}

impl<M: IdStore + ?Sized> RegionGraph for Regions<'_, M> {
    fn region_count(&self) -> usize {
        self.len()
    }

    fn region_of(&self, p: GridPoint) -> Option<u32> {
        Regions::region_of(self, p)
    }

    #[inline]
    fn centre(&self, id: u32) -> GridPoint {
        self.square(id).map_or(GridPoint::default(), |s| s.centre())
    }

    #[inline]
    fn for_each_neighbour(&self, id: u32, mut f: impl FnMut(u32, u32)) {
        let c = RegionGraph::centre(self, id);
        for v in self.neighbours(id) {
            f(v, dist_ceil(c, RegionGraph::centre(self, v)));
        }
    }
}

/// One directed edge of an [`Adjacency`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct Edge {
    /// Neighbour region.
    pub to: u32,
    /// Centre-to-centre distance, rounded up, in grid units.
    pub cost: u32,
}

/// Why an [`Adjacency`] could not be built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GraphError {
    /// `offsets` needs one entry per region plus one.
    OffsetsTooSmall { needed: usize },
    /// `edges` needs one entry per directed edge.
    EdgesTooSmall { needed: usize },
}

impl fmt::Display for GraphError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            GraphError::OffsetsTooSmall { needed } => {
                write!(f, "adjacency offsets need {needed} entries")
            }
            GraphError::EdgesTooSmall { needed } => write!(f, "adjacency needs {needed} edges"),
        }
    }
}

impl core::error::Error for GraphError {}

/// The connectivity graph stored in caller slices (CSR): region `r`'s edges are
/// `edges[offsets[r] .. offsets[r + 1]]`.
pub struct Adjacency<'a, M: ?Sized> {
    regions: Regions<'a, M>,
    offsets: &'a [u32],
    edges: &'a [Edge],
}

impl<'a, M: IdStore + ?Sized> Adjacency<'a, M> {
    /// Number of directed edges (twice the undirected ones): the `edges` length `build` needs.
    pub fn edge_count(regions: &Regions<'_, M>) -> usize {
        (0..regions.len() as u32)
            .map(|r| regions.neighbours(r).count())
            .sum()
    }

    /// Builds the graph of `regions` into `offsets` (at least regions + 1 entries) and `edges`
    /// (at least [`edge_count`](Self::edge_count) entries).
    pub fn build(
        regions: Regions<'a, M>,
        offsets: &'a mut [u32],
        edges: &'a mut [Edge],
    ) -> Result<Self, GraphError> {
        let n = regions.len();
        if offsets.len() < n + 1 {
            return Err(GraphError::OffsetsTooSmall { needed: n + 1 });
        }
        let mut k = 0usize;
        for r in 0..n {
            if let Some(o) = offsets.get_mut(r) {
                *o = u32::try_from(k).unwrap_or(u32::MAX);
            }
            let mut full = false;
            regions.for_each_neighbour(r as u32, |to, cost| match edges.get_mut(k) {
                Some(e) => {
                    *e = Edge { to, cost };
                    k += 1;
                }
                None => full = true,
            });
            // Offsets are u32: a graph over 2^32 edges cannot be stored either.
            if full || k >= u32::MAX as usize {
                return Err(GraphError::EdgesTooSmall {
                    needed: Self::edge_count(&regions),
                });
            }
        }
        if let Some(o) = offsets.get_mut(n) {
            *o = u32::try_from(k).unwrap_or(u32::MAX);
        }
        let offsets: &'a [u32] = offsets;
        let edges: &'a [Edge] = edges;
        Ok(Adjacency {
            regions,
            offsets: offsets.get(..=n).unwrap_or(&[]),
            edges: edges.get(..k).unwrap_or(&[]),
        })
    }

    /// The view again, over slices that [`build`](Self::build) filled for these `regions` (for
    /// a caller that keeps them in its own struct). Only sizes are checked: `None` unless
    /// `offsets` has regions + 1 entries and its last one is `edges.len()`.
    pub fn from_built(
        regions: Regions<'a, M>,
        offsets: &'a [u32],
        edges: &'a [Edge],
    ) -> Option<Self> {
        let ok = offsets.len() == regions.len() + 1
            && offsets.last().map(|&o| o as usize) == Some(edges.len());
        ok.then_some(Adjacency {
            regions,
            offsets,
            edges,
        })
    }

    /// The segmentation the graph was built from.
    pub const fn regions(&self) -> &Regions<'a, M> {
        &self.regions
    }

    /// Edges out of region `id`.
    pub fn edges(&self, id: u32) -> &'a [Edge] {
        let at = |i: usize| self.offsets.get(i).map_or(0, |&o| o as usize);
        let (lo, hi) = (at(id as usize), at(id as usize + 1));
        self.edges.get(lo..hi).unwrap_or(&[])
    }
}

impl<M: IdStore + ?Sized> RegionGraph for Adjacency<'_, M> {
    fn region_count(&self) -> usize {
        self.regions.len()
    }

    fn region_of(&self, p: GridPoint) -> Option<u32> {
        self.regions.region_of(p)
    }

    #[inline]
    fn centre(&self, id: u32) -> GridPoint {
        RegionGraph::centre(&self.regions, id)
    }

    #[inline]
    fn for_each_neighbour(&self, id: u32, mut f: impl FnMut(u32, u32)) {
        for e in self.edges(id) {
            f(e.to, e.cost);
        }
    }
}
