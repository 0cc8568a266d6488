//! Test helpers: ASCII grids and the pipeline over `Vec` storage.

extern crate std;

use std::vec;
use std::vec::Vec;

use crate::nav::{
    find_path, grid_bytes, segment, smooth, Adjacency, Cell, Edge, Geometry, Grid, GridPoint,
    IdStore, Plan, PlanError, RegionGraph, Regions, SearchScratch, SegmentError, Smoothed, Square,
};

/// A grid from rows of `.` (free), `#` (obstacle) and `?` (unknown); row 0 is the first line.
pub fn parse(rows: &[&str]) -> Grid<Vec<u8>> {
    let h = rows.len();
    let w = rows.first().map_or(0, |r| r.len());
    let mut g = Grid::new(
        w as u16,
        h as u16,
        Geometry::SEED_004,
        vec![0u8; grid_bytes(w, h)],
    )
    .expect("valid size");
    for (y, row) in rows.iter().enumerate() {
        assert_eq!(row.len(), w, "row {y} has a different width");
        for (x, ch) in row.chars().enumerate() {
            let c = match ch {
                '.' => Cell::Free,
                '#' => Cell::Obstacle,
                '?' => Cell::Unknown,
                _ => panic!("bad map character {ch:?}"),
            };
            g.set(x, y, c).expect("inside");
        }
    }
    g
}

/// A grid from cells in row-major order.
pub fn from_cells(w: usize, h: usize, cells: &[Cell]) -> Grid<Vec<u8>> {
    let mut g = Grid::new(
        w as u16,
        h as u16,
        Geometry::SEED_004,
        vec![0u8; grid_bytes(w, h)],
    )
    .expect("valid size");
    for (i, &c) in cells.iter().enumerate() {
        g.set(i % w, i / w, c).expect("inside");
    }
    g
}

/// Segmentation output in `Vec`s, as the station holds it.
pub struct Seg {
    pub map: Vec<u32>,
    pub squares: Vec<Square>,
}

impl Seg {
    pub fn new<S: AsRef<[u8]>>(grid: &Grid<S>) -> Result<Seg, SegmentError> {
        let mut map = vec![0u32; grid.len()];
        let mut squares = vec![Square::EMPTY; grid.len()];
        let n = segment(grid, &mut map[..], &mut squares[..])?.len();
        squares.truncate(n);
        Ok(Seg { map, squares })
    }

    pub fn regions<'a, S>(&'a self, grid: &Grid<S>) -> Regions<'a, [u32]> {
        Regions::from_parts(grid, &self.map[..], &self.squares[..])
    }
}

/// A* scratch (with the h cache) and plan stores in `Vec`s sized for `n` regions.
pub struct VecSearch {
    pub f: Vec<u32>,
    pub h: Vec<u32>,
    pub parent: Vec<u32>,
    pub heap: Vec<u32>,
    pub pos: Vec<u32>,
    pub path: Vec<u32>,
    pub points: Vec<GridPoint>,
}

impl VecSearch {
    pub fn new(n: usize) -> VecSearch {
        VecSearch {
            f: vec![0; n],
            h: vec![0; n],
            parent: vec![0; n],
            heap: vec![0; n],
            pos: vec![0; n],
            path: vec![0; n],
            points: vec![GridPoint::default(); n],
        }
    }

    pub fn plan<G: RegionGraph>(
        &mut self,
        graph: &G,
        start: GridPoint,
        goal: GridPoint,
    ) -> Result<Plan, PlanError> {
        let mut scratch = SearchScratch::new(
            &mut self.f,
            &mut self.parent[..],
            &mut self.heap[..],
            &mut self.pos[..],
        )
        .with_h_cache(&mut self.h);
        find_path(graph, start, goal, &mut scratch, &mut self.path[..])
    }

    pub fn smooth<M: IdStore + ?Sized>(
        &mut self,
        regions: &Regions<'_, M>,
        plan: &Plan,
        margin: u32,
    ) -> Result<Smoothed, PlanError> {
        smooth(regions, plan, &self.path[..], margin, &mut self.points)
    }
}

/// Runs `f` with the stored adjacency of `regions` (the station's graph).
pub fn with_adjacency<R>(
    regions: Regions<'_, [u32]>,
    f: impl FnOnce(&Adjacency<'_, [u32]>) -> R,
) -> R {
    let mut offsets = vec![0u32; regions.len() + 1];
    let mut edges = vec![Edge::default(); Adjacency::edge_count(&regions)];
    let adj = Adjacency::build(regions, &mut offsets, &mut edges).expect("sized by edge_count");
    f(&adj)
}

/// A smoothed plan's encoding as a `Vec`.
pub fn encode_smoothed(s: &Smoothed, points: &[GridPoint]) -> Vec<u8> {
    let mut out = vec![0u8; s.encoded_len()];
    let n = s.encode(points, &mut out).expect("sized");
    assert_eq!(n, out.len());
    out
}

/// The centre of cell (`x`, `y`).
pub fn centre(x: u16, y: u16) -> GridPoint {
    GridPoint::cell_centre(x, y)
}

/// A plan's encoding as a `Vec`.
pub fn encode<P: IdStore + ?Sized>(plan: &Plan, path: &P) -> Vec<u8> {
    let mut out = vec![0u8; plan.encoded_len()];
    let n = plan.encode(path, &mut out).expect("sized");
    assert_eq!(n, out.len());
    out
}

/// Square list as tuples, for compact assertions.
pub fn tuples(squares: &[Square]) -> Vec<(u16, u16, u16)> {
    squares.iter().map(|s| (s.x, s.y, s.size)).collect()
}

/// A small deterministic PRNG (splitmix64) for generated test maps.
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    pub fn below(&mut self, n: u64) -> u64 {
        self.next() % n.max(1)
    }
}

/// A grid with cell (odd, odd) of every aligned 2 x 2 block an obstacle, the rest free: the
/// worst case of `max_regions` (every free cell is a square of its own).
pub fn lattice(w: usize, h: usize) -> crate::nav::Grid<Vec<u8>> {
    use crate::nav::{grid_bytes, Cell, Geometry, Grid};
    let mut g = Grid::new(
        w as u16,
        h as u16,
        Geometry::SEED_004,
        vec![0; grid_bytes(w, h)],
    )
    .expect("valid size");
    for y in 0..h {
        for x in 0..w {
            let blocked = x % 2 == 1 && y % 2 == 1;
            let c = if blocked { Cell::Obstacle } else { Cell::Free };
            g.set(x, y, c).expect("inside");
        }
    }
    g
}
