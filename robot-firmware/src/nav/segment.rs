//! Square segmentation of the grid (seed 004 §6, Fig. 6) and the region connectivity graph.
//!
//! Layer: reads a [`Grid`], writes a list of [`Square`]s and a per-cell region-id map, both in
//! caller storage; [`Regions`] is the read-only result the planner and smoother use.
//!
//! Invariants of a [`Regions`] (checked by the property tests in `tests/props.rs`): every
//! square holds only free cells; squares are disjoint and cover exactly the free cells; the map
//! gives each free cell the id of its square (`id` = index in the square list) and every other
//! cell `NONE`. The connectivity graph is implicit: two regions are adjacent when they share an
//! edge segment of positive length, found by walking a square's border in the map (no O(R^2)
//! scan); `graph.rs` can also store it.
//! Diagonal corner contact does NOT count: seed 004 §6 relies on "a path through the centers of
//! connected regions is always feasible", and a segment through a shared corner only squeezes
//! between two obstacle cells. With a shared edge the segment between the centres crosses that
//! edge strictly inside it, so it stays in the two (convex) squares.
//!
//! Cost: linear in cells. Each square of side s costs s^2 cell checks to grow and claim plus at
//! most 2s + 1 checks for the failed last growth, and sum(s) <= sum(s^2) <= cells.
//!
//! What can fail: the map's length differs from the grid's cell count, or there are more squares
//! than the list (or the map's id width) can hold. No panic on any input.

use core::fmt;

use super::grid::{Cell, Geometry, Grid, GridPoint, UNITS_PER_CELL};
use super::ids::IdStore;

/// A square region: top-left (smallest row and column) cell and side, in cells.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct Square {
    pub x: u16,
    pub y: u16,
    pub size: u16,
}

impl Square {
    /// An all-zero square, for initialising fixed arrays.
    pub const EMPTY: Square = Square {
        x: 0,
        y: 0,
        size: 0,
    };

    /// The geometric centre, in grid units (seed 004 §6: the waypoint of a region).
    pub const fn centre(&self) -> GridPoint {
        let half = UNITS_PER_CELL / 2;
        GridPoint {
            x: (2 * self.x as i32 + self.size as i32) * half,
            y: (2 * self.y as i32 + self.size as i32) * half,
        }
    }

    /// Whether cell (`x`, `y`) lies inside.
    pub const fn contains(&self, x: usize, y: usize) -> bool {
        x >= self.x as usize
            && y >= self.y as usize
            && x < self.x as usize + self.size as usize
            && y < self.y as usize + self.size as usize
    }
}

/// Why segmentation failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SegmentError {
    /// The region-id map does not have one entry per grid cell.
    MapSizeMismatch { expected: usize, got: usize },
    /// More squares than the list or the map's id width can hold.
    TooManyRegions { capacity: usize },
}

impl fmt::Display for SegmentError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            SegmentError::MapSizeMismatch { expected, got } => {
                write!(f, "region map has {got} entries, grid has {expected} cells")
            }
            SegmentError::TooManyRegions { capacity } => {
                write!(f, "segmentation needs more than {capacity} regions")
            }
        }
    }
}

impl core::error::Error for SegmentError {}

/// The result of [`segment`]: squares, the region-id map and the grid's size and geometry.
pub struct Regions<'a, M: ?Sized> {
    width: u16,
    height: u16,
    geometry: Geometry,
    map: &'a M,
    squares: &'a [Square],
}

impl<M: ?Sized> Clone for Regions<'_, M> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<M: ?Sized> Copy for Regions<'_, M> {}

/// Which cells square regions are made of.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Passable {
    /// Free cells only; unknown counts as obstacle (seed 004 §6: the plans the robot executes).
    Free,
    /// Free and unknown cells: the free-space assumption of a search that plans on what it
    /// has not yet seen (exploration's way out of a trap; seed 004: planning works on
    /// incomplete maps).
    FreeOrUnknown,
}

impl Passable {
    pub(crate) fn admits(self, cell: Cell) -> bool {
        match self {
            Passable::Free => cell == Cell::Free,
            Passable::FreeOrUnknown => cell != Cell::Obstacle,
        }
    }
}

/// The most squares [`segment`] can make of a `width` x `height` grid, whatever its cells
/// (and whichever [`Passable`]): `width * height - (width / 2) * (height / 2)`; 3072 for
/// 64 x 64, 588 for 28 x 28, 217 for 17 x 17. Fixed storage sized by it never fails with
/// `TooManyRegions`.
///
/// Why (a checkerboard's 2048 of 64 x 64 is NOT the worst case): cut the grid into aligned
/// 2 x 2 blocks, cells (2i..2i+1, 2j..2j+1), with the odd last row or column left over. A
/// block holds at most 3 square top-left cells. If all 4 of its cells are passable and its
/// first cell a = (2i, 2j) starts a square, that square grows to side 2 (and then covers the
/// block: 1 start) unless one of b = (2i+1, 2j), c = (2i, 2j+1), d = (2i+1, 2j+1) is already
/// claimed when a is scanned. Only squares started earlier claim cells, i.e. in an earlier
/// row, or in row 2j left of a; the latter would cover a. An earlier-row square covering c
/// covers a (it spans rows < 2j through 2j+1 in column 2i), and one covering d covers b. So
/// a starts a side-1 square only when b is claimed by an earlier square, and then b starts
/// none: at most 3 starts. A block with a blocked cell has at most 3 passable cells. Leftover
/// cells are at most one square each. Hence squares <= W*H - floor(W/2)*floor(H/2), and the
/// bound is reached: block cell (odd, odd) of every block and leave the rest passable; every
/// 2 x 2 window then holds a blocked cell, so every passable cell is a square of its own.
/// `tests/segmentation.rs` checks the bound on every grid up to 16 cells and the pattern on
/// 64 x 64.
pub const fn max_regions(width: usize, height: usize) -> usize {
    width * height - (width / 2) * (height / 2)
}

/// Segments `grid` into squares by the rule of seed 004 §6, Fig. 6.
///
/// Writes the squares to the front of `squares` and one region id per cell to `map`
/// (`M::NONE` for cells in no region); region id `k` is `squares[k]`.
pub fn segment<'a, S, M>(
    grid: &Grid<S>,
    map: &'a mut M,
    squares: &'a mut [Square],
) -> Result<Regions<'a, M>, SegmentError>
where
    S: AsRef<[u8]>,
    M: IdStore + ?Sized,
{
    segment_with(grid, map, squares, Passable::Free)
}

/// [`segment`] with a choice of which cells count as passable.
pub fn segment_with<'a, S, M>(
    grid: &Grid<S>,
    map: &'a mut M,
    squares: &'a mut [Square],
    passable: Passable,
) -> Result<Regions<'a, M>, SegmentError>
where
    S: AsRef<[u8]>,
    M: IdStore + ?Sized,
{
    let expected = grid.len();
    if map.len() != expected {
        return Err(SegmentError::MapSizeMismatch {
            expected,
            got: map.len(),
        });
    }
    map.fill(M::NONE);
    let count = scan(grid, map, squares, passable)?;
    let squares: &'a [Square] = squares;
    Ok(Regions {
        width: grid.width(),
        height: grid.height(),
        geometry: grid.geometry(),
        map,
        squares: squares.get(..count).unwrap_or(&[]),
    })
}

/// The scan of Fig. 6 over a map cleared to `NONE`; returns the number of squares.
fn scan<S, M>(
    grid: &Grid<S>,
    map: &mut M,
    squares: &mut [Square],
    passable: Passable,
) -> Result<usize, SegmentError>
where
    S: AsRef<[u8]>,
    M: IdStore + ?Sized,
{
    // Ids run 0 ..= NONE - 1, so at most NONE squares fit the map's id width.
    let capacity = squares.len().min(M::NONE as usize);
    let (w, h) = (usize::from(grid.width()), usize::from(grid.height()));
    let mut count = 0usize;
    // seed 004 §6, Fig. 6: "for i := 1 to Nrow do for j := 1 to Ncol do" - rows, then columns.
    for y in 0..h {
        let mut x = 0;
        while x < w {
            let i = y * w + x;
            // "if cell (i,j) is not yet included in a previously created square region" - and
            // only free cells start one: unknown counts as obstacle (seed 004 §6).
            if map.get(i) != M::NONE || !passable.admits(grid.cell_at(i)) {
                x += 1;
                continue;
            }
            let slot = squares
                .get_mut(count)
                .filter(|_| count < capacity)
                .ok_or(SegmentError::TooManyRegions { capacity })?;
            let size = largest_square(grid, map, x, y, passable);
            *slot = Square {
                x: u16::try_from(x).unwrap_or(u16::MAX),
                y: u16::try_from(y).unwrap_or(u16::MAX),
                size,
            };
            claim(map, w, *slot, count as u32);
            count += 1;
            // The cells x .. x + size of this row now belong to the new square.
            x += usize::from(size).max(1);
        }
    }
    Ok(count)
}

/// Side of the largest square of free, still unclaimed cells with top-left cell (`x`, `y`),
/// which is itself free and unclaimed (seed 004 §6, Fig. 6: "determine and create the largest
/// square region composed of only free space cells and having cell (i,j) as its top-left
/// vertex"; a cell already in an earlier square cannot join a new one).
fn largest_square<S, M>(grid: &Grid<S>, map: &M, x: usize, y: usize, passable: Passable) -> u16
where
    S: AsRef<[u8]>,
    M: IdStore + ?Sized,
{
    let (w, h) = (usize::from(grid.width()), usize::from(grid.height()));
    let open = |cx: usize, cy: usize| {
        let i = cy * w + cx;
        passable.admits(grid.cell_at(i)) && map.get(i) == M::NONE
    };
    let mut s = 1usize;
    // Grow from s to s + 1 while the new bottom row and right column are open.
    while x + s < w && y + s < h {
        let row_open = (x..=x + s).all(|cx| open(cx, y + s));
        if !row_open || !(y..y + s).all(|cy| open(x + s, cy)) {
            break;
        }
        s += 1;
    }
    u16::try_from(s).unwrap_or(u16::MAX)
}

/// Writes `id` into the map for every cell of `sq`.
fn claim<M: IdStore + ?Sized>(map: &mut M, width: usize, sq: Square, id: u32) {
    let (x, y, s) = (usize::from(sq.x), usize::from(sq.y), usize::from(sq.size));
    for cy in y..y + s {
        for cx in x..x + s {
            map.set(cy * width + cx, id);
        }
    }
}

impl<'a, M: IdStore + ?Sized> Regions<'a, M> {
    /// The view again, over a map and squares that [`segment`] wrote for this `grid` (for a
    /// caller that keeps them in its own struct). Only sizes are checked: `None` if the map's
    /// length is not the grid's cell count or there are more squares than ids. Parts that did
    /// not come from `segment` give meaningless plans, but still no panic.
    pub fn from_segmented<S>(grid: &Grid<S>, map: &'a M, squares: &'a [Square]) -> Option<Self> {
        let ok = map.len() == grid.len() && squares.len() <= M::NONE as usize;
        ok.then(|| Self::from_parts(grid, map, squares))
    }

    /// A view over a map and squares that [`segment`] produced from `grid` (fixed instance).
    pub(crate) fn from_parts<S>(grid: &Grid<S>, map: &'a M, squares: &'a [Square]) -> Self {
        Regions {
            width: grid.width(),
            height: grid.height(),
            geometry: grid.geometry(),
            map,
            squares,
        }
    }

    /// Grid columns.
    pub const fn width(&self) -> u16 {
        self.width
    }

    /// Grid rows.
    pub const fn height(&self) -> u16 {
        self.height
    }

    /// The grid's cell size and origin.
    pub const fn geometry(&self) -> Geometry {
        self.geometry
    }

    /// Number of regions.
    pub const fn len(&self) -> usize {
        self.squares.len()
    }

    /// Whether there are no regions (no free cell in the grid).
    pub const fn is_empty(&self) -> bool {
        self.squares.is_empty()
    }

    /// The squares, indexed by region id.
    pub const fn squares(&self) -> &'a [Square] {
        self.squares
    }

    /// The per-cell region-id map.
    pub const fn map(&self) -> &'a M {
        self.map
    }

    /// The square of region `id`.
    #[inline]
    pub fn square(&self, id: u32) -> Option<Square> {
        self.squares.get(id as usize).copied()
    }

    /// Region holding cell (`x`, `y`), if the cell is free.
    #[inline]
    pub fn region_at(&self, x: i32, y: i32) -> Option<u32> {
        let (w, h) = (i32::from(self.width), i32::from(self.height));
        if x < 0 || y < 0 || x >= w || y >= h {
            return None;
        }
        let id = self.map.get(y as usize * self.width as usize + x as usize);
        (id != M::NONE).then_some(id)
    }

    /// Region holding the cell under point `p`.
    pub fn region_of(&self, p: GridPoint) -> Option<u32> {
        let (cx, cy) = p.cell();
        self.region_at(cx, cy)
    }

    /// Regions sharing an edge segment of positive length with region `id` (each once).
    pub fn neighbours(&self, id: u32) -> Neighbours<'a, M> {
        Neighbours {
            regions: *self,
            sq: self.square(id).unwrap_or(Square::EMPTY),
            side: 0,
            k: 0,
        }
    }

    /// Calls `f(a, b)` once for every edge of the connectivity graph, with `a < b`.
    pub fn for_each_edge(&self, mut f: impl FnMut(u32, u32)) {
        for a in 0..self.squares.len() as u32 {
            for b in self.neighbours(a).filter(|&b| b > a) {
                f(a, b);
            }
        }
    }
}

/// Iterator over a region's neighbours, walking the four sides of its square in the map.
///
/// A neighbour square touches one side only (touching two would make it overlap the corner
/// cell of this square) and covers a contiguous run of it, so the walk jumps over the run
/// and yields each neighbour exactly once. Cost: O(obstacle cells on the border + neighbours).
pub struct Neighbours<'a, M: ?Sized> {
    regions: Regions<'a, M>,
    sq: Square,
    /// 0 top (row y - 1), 1 right (column x + s), 2 bottom (row y + s), 3 left (column x - 1).
    side: u8,
    /// Offset along the current side.
    k: usize,
}

impl<M: IdStore + ?Sized> Iterator for Neighbours<'_, M> {
    type Item = u32;

    fn next(&mut self) -> Option<u32> {
        let r = &self.regions;
        let (x, y, s) = (
            i32::from(self.sq.x),
            i32::from(self.sq.y),
            usize::from(self.sq.size),
        );
        while self.side < 4 {
            if self.k >= s {
                self.side += 1;
                self.k = 0;
                continue;
            }
            let k = self.k as i32;
            let horizontal = self.side % 2 == 0;
            let (cx, cy) = match self.side {
                0 => (x + k, y - 1),
                1 => (x + s as i32, y + k),
                2 => (x + k, y + s as i32),
                _ => (x - 1, y + k),
            };
            let Some(id) = r.region_at(cx, cy) else {
                // Outside the grid: the whole side is off the map; else one blocked cell.
                if !r.contains_any(cx, cy, horizontal) {
                    self.k = s;
                } else {
                    self.k += 1;
                }
                continue;
            };
            // Jump past the neighbour's run along this side (always at least one step).
            let n = r.square(id).unwrap_or(Square::EMPTY);
            let (start, off) = if horizontal { (n.x, x) } else { (n.y, y) };
            let end = (i32::from(start) + i32::from(n.size) - off).max(k + 1);
            self.k = end as usize;
            return Some(id);
        }
        None
    }
}

impl<M: ?Sized> Regions<'_, M> {
    /// Whether the line through (`cx`, `cy`) along a side (row if `horizontal`) is in the grid.
    fn contains_any(&self, cx: i32, cy: i32, horizontal: bool) -> bool {
        if horizontal {
            cy >= 0 && cy < i32::from(self.height)
        } else {
            cx >= 0 && cx < i32::from(self.width)
        }
    }
}
