//! Occupancy rasters: the grid a file holds (ROS maps, ASCII grids) and [`rasterise`], which
//! turns any [`Arena`] into the three-state grid the planner segments (seed 004 §5-6).
//!
//! Layer: between the arena importers and the firmware's nav code (its [`Cell`] type).
//! Layout: `cells` is row-major, row 0 at the bottom (min y), `index = row * width + col`; cell
//! (col, row) covers `[origin.x + col·cell_m, origin.x + (col+1)·cell_m] x` the same in y.
//!
//! The obstacle rule of [`rasterise`], exact rather than sampled: with `C` a cell's square and
//! `r = inflate_m`, the cell is an obstacle when some wall point `q` (of a wall polygon's edges
//! or inside it, or of an enclosed arena's boundary) has
//! `distance(q, C) < r`, or lies in `C`'s open interior.
//! So a wall merely touching a cell's edge does not mark it at `r = 0` (neighbours of a wall
//! lying exactly on grid lines stay free), and a wall exactly `r` away does not either. With
//! `r` the robot's radius, a free cell is one where the robot's centre can be anywhere in the
//! cell's open interior without touching a wall: conservative for planning.
//! Outside an enclosed arena is solid, so cells straddling its boundary are obstacles.
//! Unknown: a non-obstacle cell that overlaps (with positive area) an unknown cell of the
//! arena's own raster, or extends past that raster, is unknown; everything else is free.
//!
//! What can fail: a non-finite or non-positive cell size, a negative or non-finite inflation, a
//! grid larger than [`MAX_GRID_SIDE`] a side ([`RasterError`]); never a panic.

use std::collections::BTreeMap;
use std::path::Path;

use super::{Arena, ArenaError, Cell, Wall, WorldLimit, MAX_GRID_SIDE};
use crate::geometry::{point_in_polygon, Aabb, Point, Segment};

/// A three-state occupancy grid in the map frame.
#[derive(Clone, Debug, PartialEq)]
pub struct RasterMap {
    /// Columns (x).
    pub width: u32,
    /// Rows (y).
    pub height: u32,
    /// Cell side, metres.
    pub cell_m: f64,
    /// Map-frame position of the lower-left corner of cell (0, 0).
    pub origin: [f64; 2],
    /// Row-major, row 0 at the bottom.
    pub cells: Vec<Cell>,
    /// The start point (the arena's first start pose), if any.
    pub start: Option<[f64; 2]>,
    /// The goal point, if any.
    pub goal: Option<[f64; 2]>,
}

impl RasterMap {
    /// The cell at (col, row), `None` outside the grid.
    pub fn get(&self, col: u32, row: u32) -> Option<Cell> {
        if col >= self.width || row >= self.height {
            return None;
        }
        self.cells
            .get(row as usize * self.width as usize + col as usize)
            .copied()
    }

    /// The x of grid line `col` (shared by the importers and [`rasterise`] so that edges
    /// computed on both sides are the same floats).
    pub fn line_x(&self, col: u32) -> f64 {
        self.origin[0] + f64::from(col) * self.cell_m
    }

    /// The y of grid line `row`.
    pub fn line_y(&self, row: u32) -> f64 {
        self.origin[1] + f64::from(row) * self.cell_m
    }

    /// The square of cell (col, row).
    pub fn cell_box(&self, col: u32, row: u32) -> Aabb {
        Aabb {
            min: Point::new(self.line_x(col), self.line_y(row)),
            max: Point::new(self.line_x(col + 1), self.line_y(row + 1)),
        }
    }

    /// The centre of cell (col, row).
    pub fn cell_centre(&self, col: u32, row: u32) -> [f64; 2] {
        let b = self.cell_box(col, row);
        [(b.min.x + b.max.x) / 2.0, (b.min.y + b.max.y) / 2.0]
    }

    /// The cell holding the map point (x, y), `None` outside the grid.
    pub fn cell_at(&self, x: f64, y: f64) -> Option<(u32, u32)> {
        let c = ((x - self.origin[0]) / self.cell_m).floor();
        let r = ((y - self.origin[1]) / self.cell_m).floor();
        let ok = |v: f64, n: u32| v >= 0.0 && v < f64::from(n);
        (ok(c, self.width) && ok(r, self.height)).then_some((c as u32, r as u32))
    }

    /// How many cells are in state `c`.
    pub fn count(&self, c: Cell) -> usize {
        self.cells.iter().filter(|&&x| x == c).count()
    }

    /// The grid as text, top row first: `#` obstacle, `.` free, `?` unknown, `S`/`G` the cells
    /// holding the start and goal points (the ASCII grid format reads this back).
    pub fn to_ascii(&self) -> String {
        let (w, h) = (self.width as usize, self.height as usize);
        let mark = |p: Option<[f64; 2]>| p.and_then(|[x, y]| self.cell_at(x, y));
        let (s, g) = (mark(self.start), mark(self.goal));
        let mut out = String::with_capacity((w + 1) * h);
        for row in (0..self.height).rev() {
            for col in 0..self.width {
                out.push(
                    match (
                        Some((col, row)) == s,
                        Some((col, row)) == g,
                        self.get(col, row),
                    ) {
                        (true, _, _) => 'S',
                        (_, true, _) => 'G',
                        (_, _, Some(Cell::Obstacle)) => '#',
                        (_, _, Some(Cell::Free)) => '.',
                        _ => '?',
                    },
                );
            }
            out.push('\n');
        }
        out
    }
}

/// Why [`rasterise`] refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RasterError {
    /// The cell size is not a finite positive length.
    #[error("cell size {0} m must be finite and > 0")]
    BadCellSize(f64),
    /// The inflation is negative or not finite.
    #[error("inflation {0} m must be finite and >= 0")]
    BadInflation(f64),
    /// The grid would be too large.
    #[error("a {width} x {height} grid exceeds {MAX_GRID_SIDE} cells a side")]
    TooLarge {
        /// Columns needed.
        width: f64,
        /// Rows needed.
        height: f64,
    },
}

/// Rasterises an arena into `cell_m` cells, marking obstacles within `inflate_m` of walls by
/// the module's exact rule. The grid starts at the arena's lower-left corner and has
/// `ceil(extent / cell_m)` cells a side (Micro-Rato'99's 5 m at 0.3 m: 17).
pub fn rasterise(arena: &Arena, cell_m: f64, inflate_m: f64) -> Result<RasterMap, RasterError> {
    if !(cell_m.is_finite() && cell_m > 0.0) {
        return Err(RasterError::BadCellSize(cell_m));
    }
    if !(inflate_m.is_finite() && inflate_m >= 0.0) {
        return Err(RasterError::BadInflation(inflate_m));
    }
    // The epsilon keeps an extent that is an exact multiple of the cell from gaining a sliver.
    let side = |extent: f64| (extent / cell_m - 1e-9).ceil().max(1.0);
    let (w, h) = (side(arena.bounds.width()), side(arena.bounds.height()));
    if !(w <= f64::from(MAX_GRID_SIDE) && h <= f64::from(MAX_GRID_SIDE)) {
        return Err(RasterError::TooLarge {
            width: w,
            height: h,
        });
    }
    let mut map = RasterMap {
        width: w as u32,
        height: h as u32,
        cell_m,
        origin: [arena.bounds.min.x, arena.bounds.min.y],
        cells: vec![Cell::Free; (w * h) as usize],
        start: arena.starts.first().map(|p| [p.x, p.y]),
        goal: arena.goal.map(|g| [g.x, g.y]),
    };
    for wall in &arena.walls {
        for edge in wall.edges() {
            mark_segment(&mut map, edge, inflate_m);
        }
        fill_polygon(&mut map, &wall.corners);
    }
    if arena.enclosed {
        for edge in arena.boundary_edges() {
            mark_segment(&mut map, edge, inflate_m);
        }
    }
    if let Some(src) = &arena.raster {
        mark_unknown(&mut map, src);
    }
    Ok(map)
}

/// The inclusive range of columns/rows whose cells overlap `[lo, hi]` (clamped to the grid).
fn cover(map: &RasterMap, lo: f64, hi: f64, origin: f64, n: u32) -> Option<(u32, u32)> {
    let a = ((lo - origin) / map.cell_m).floor().max(0.0);
    let b = ((hi - origin) / map.cell_m).floor().min(f64::from(n) - 1.0);
    // NaN fails both comparisons, so a broken wall marks nothing rather than panicking.
    (a <= b).then_some((a as u32, b as u32))
}

fn mark_segment(map: &mut RasterMap, s: Segment, r: f64) {
    let b = s.aabb().expanded(r);
    let (Some((c0, c1)), Some((r0, r1))) = (
        cover(map, b.min.x, b.max.x, map.origin[0], map.width),
        cover(map, b.min.y, b.max.y, map.origin[1], map.height),
    ) else {
        return;
    };
    for row in r0..=r1 {
        for col in c0..=c1 {
            let i = row as usize * map.width as usize + col as usize;
            if map.cells[i] != Cell::Obstacle && segment_marks_cell(s, &map.cell_box(col, row), r) {
                map.cells[i] = Cell::Obstacle;
            }
        }
    }
}

/// Cells whose centre is inside the polygon: a cell no edge marked is either wholly inside or
/// wholly outside, and its centre says which.
fn fill_polygon(map: &mut RasterMap, corners: &[Point]) {
    let Some(b) = Aabb::around(corners.iter().copied()) else {
        return;
    };
    let (Some((c0, c1)), Some((r0, r1))) = (
        cover(map, b.min.x, b.max.x, map.origin[0], map.width),
        cover(map, b.min.y, b.max.y, map.origin[1], map.height),
    ) else {
        return;
    };
    for row in r0..=r1 {
        for col in c0..=c1 {
            let i = row as usize * map.width as usize + col as usize;
            let [x, y] = map.cell_centre(col, row);
            if map.cells[i] != Cell::Obstacle && point_in_polygon(Point::new(x, y), corners) {
                map.cells[i] = Cell::Obstacle;
            }
        }
    }
}

/// The module's rule for one segment and one closed cell square.
pub(crate) fn segment_marks_cell(s: Segment, cell: &Aabb, r: f64) -> bool {
    match clip(s, cell) {
        Some((t0, t1)) => {
            // The clipped piece meets the open interior iff its midpoint does (a piece lying
            // wholly on the square's boundary lies on one side of it).
            let m = s.a + s.direction() * ((t0 + t1) / 2.0);
            let inside =
                m.x > cell.min.x && m.x < cell.max.x && m.y > cell.min.y && m.y < cell.max.y;
            inside || r > 0.0
        }
        None => r > 0.0 && segment_box_distance(s, cell) < r,
    }
}

/// Liang-Barsky: the parameter interval of `s` inside the closed box, if any.
fn clip(s: Segment, b: &Aabb) -> Option<(f64, f64)> {
    let d = s.direction();
    let (mut t0, mut t1) = (0.0_f64, 1.0_f64);
    for (p, q) in [
        (-d.x, s.a.x - b.min.x),
        (d.x, b.max.x - s.a.x),
        (-d.y, s.a.y - b.min.y),
        (d.y, b.max.y - s.a.y),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let t = q / p;
            if p < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    (t0 <= t1).then_some((t0, t1))
}

/// Distance between a segment and a box that do not meet: it is reached at an end of the
/// segment or a corner of the box.
fn segment_box_distance(s: Segment, b: &Aabb) -> f64 {
    let corners = [
        b.min,
        Point::new(b.max.x, b.min.y),
        b.max,
        Point::new(b.min.x, b.max.y),
    ];
    let from_corners = corners
        .iter()
        .map(|&c| s.distance_to_point(c))
        .fold(f64::INFINITY, f64::min);
    from_corners
        .min(b.distance_to_point(s.a))
        .min(b.distance_to_point(s.b))
}

fn mark_unknown(map: &mut RasterMap, src: &RasterMap) {
    // Source cells overlapping the open interval (lo, hi); the epsilon ignores cells that only
    // touch it at an edge through rounding.
    let span = |lo: f64, hi: f64, origin: f64, cell: f64| -> (f64, f64) {
        (
            ((lo - origin) / cell + 1e-9).floor(),
            ((hi - origin) / cell - 1e-9).ceil() - 1.0,
        )
    };
    for row in 0..map.height {
        for col in 0..map.width {
            let i = row as usize * map.width as usize + col as usize;
            if map.cells[i] == Cell::Obstacle {
                continue;
            }
            let b = map.cell_box(col, row);
            let (c0, c1) = span(b.min.x, b.max.x, src.origin[0], src.cell_m);
            let (r0, r1) = span(b.min.y, b.max.y, src.origin[1], src.cell_m);
            let outside =
                c0 < 0.0 || r0 < 0.0 || c1 >= f64::from(src.width) || r1 >= f64::from(src.height);
            let unknown = outside
                || (r0 as u32..=r1 as u32)
                    .any(|r| (c0 as u32..=c1 as u32).any(|c| src.get(c, r) == Some(Cell::Unknown)));
            if unknown {
                map.cells[i] = Cell::Unknown;
            }
        }
    }
}

/// Obstacle cells merged into rectangles (runs along a row, then equal runs stacked over
/// consecutive rows), as walls of unknown height.
pub fn obstacle_walls(map: &RasterMap) -> Vec<Wall> {
    let mut rects = Vec::new();
    obstacle_rects(map, |r| {
        rects.push(r);
        true
    });
    rects.sort_by_key(|&(c0, r0, _, _)| (r0, c0));
    rects
        .into_iter()
        .map(|(c0, r0, c1, r1)| {
            let b = Aabb {
                min: Point::new(map.line_x(c0), map.line_y(r0)),
                max: Point::new(map.line_x(c1), map.line_y(r1)),
            };
            Wall::rectangle(b, None)
        })
        .collect()
}

/// [`obstacle_walls`] for a world with a limit: the rectangles are counted first (memory:
/// one row's runs), and a map that would make more walls than `limit` takes is refused,
/// naming `path` and the sizes, before any wall is built.
pub fn obstacle_walls_within(
    path: &Path,
    map: &RasterMap,
    limit: Option<WorldLimit>,
) -> Result<Vec<Wall>, ArenaError> {
    if let Some(l) = limit {
        let mut n = 0usize;
        obstacle_rects(map, |_| {
            n += 1;
            n <= l.max_walls
        });
        if n > l.max_walls {
            return Err(ArenaError::at_file(
                path,
                format!(
                    "a {} x {} grid map's obstacle cells, merged into rectangles, make more than \
                     {} walls: the emulator's world takes at most {} walls (refused before \
                     building them); use a coarser or cleaner map",
                    map.width, map.height, l.max_walls, l.max_walls
                ),
            ));
        }
    }
    Ok(obstacle_walls(map))
}

/// Calls `each` with every maximal rectangle `(c0, r0, c1, r1)` (cells `c0..c1` x `r0..r1`)
/// of obstacle cells, in the order they close, until it returns false. Memory: the open
/// rectangles, at most one row's runs.
fn obstacle_rects(map: &RasterMap, mut each: impl FnMut((u32, u32, u32, u32)) -> bool) {
    let (w, h) = (map.width as usize, map.height as usize);
    // Open rectangles keyed by their column run, valued by the row they started on.
    let mut open: BTreeMap<(u32, u32), u32> = BTreeMap::new();
    for row in 0..=h {
        let mut runs = Vec::new();
        if row < h {
            // `get`: a hand-built map whose `cells` is short simply has no obstacles there.
            let line = map.cells.get(row * w..(row + 1) * w).unwrap_or(&[]);
            let mut c = 0;
            while c < line.len() {
                if line[c] == Cell::Obstacle {
                    let start = c;
                    while c < line.len() && line[c] == Cell::Obstacle {
                        c += 1;
                    }
                    runs.push((start as u32, c as u32));
                } else {
                    c += 1;
                }
            }
        }
        let mut next = BTreeMap::new();
        for run in runs {
            let since = open.remove(&run).unwrap_or(row as u32);
            next.insert(run, since);
        }
        for ((c0, c1), r0) in std::mem::replace(&mut open, next) {
            if !each((c0, r0, c1, row as u32)) {
                return;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cell() -> Aabb {
        Aabb {
            min: Point::new(0.0, 0.0),
            max: Point::new(1.0, 1.0),
        }
    }

    fn seg(ax: f64, ay: f64, bx: f64, by: f64) -> Segment {
        Segment::new(Point::new(ax, ay), Point::new(bx, by))
    }

    #[test]
    fn a_wall_on_the_cell_edge_marks_it_only_when_inflated() {
        assert!(!segment_marks_cell(seg(1.0, -1.0, 1.0, 2.0), &cell(), 0.0));
        assert!(segment_marks_cell(seg(1.0, -1.0, 1.0, 2.0), &cell(), 0.01));
        assert!(segment_marks_cell(seg(0.99, -1.0, 0.99, 2.0), &cell(), 0.0));
    }

    #[test]
    fn a_wall_exactly_inflation_away_does_not_mark() {
        assert!(!segment_marks_cell(seg(1.5, -1.0, 1.5, 2.0), &cell(), 0.5));
        assert!(segment_marks_cell(
            seg(1.5, -1.0, 1.5, 2.0),
            &cell(),
            0.5000001
        ));
        // Diagonally off a corner the distance is to the corner.
        let d = 0.5_f64.hypot(0.5);
        assert!(!segment_marks_cell(seg(1.5, 1.5, 3.0, 1.5), &cell(), d));
        assert!(segment_marks_cell(
            seg(1.5, 1.5, 3.0, 1.5),
            &cell(),
            d + 1e-9
        ));
    }

    #[test]
    fn obstacle_cells_merge_into_rectangles() {
        use Cell::{Free as F, Obstacle as O};
        let map = RasterMap {
            width: 4,
            height: 3,
            cell_m: 0.5,
            origin: [1.0, 2.0],
            cells: vec![O, O, F, O, O, O, F, F, F, F, O, O],
            start: None,
            goal: None,
        };
        let walls = obstacle_walls(&map);
        let boxes: Vec<_> = walls
            .iter()
            .map(|w| Aabb::around(w.corners.iter().copied()).unwrap())
            .collect();
        assert_eq!(boxes.len(), 3);
        assert_eq!(
            boxes[0],
            Aabb {
                min: Point::new(1.0, 2.0),
                max: Point::new(2.0, 3.0)
            }
        );
        assert_eq!(
            boxes[1],
            Aabb {
                min: Point::new(2.5, 2.0),
                max: Point::new(3.0, 2.5)
            }
        );
        assert_eq!(
            boxes[2],
            Aabb {
                min: Point::new(2.0, 3.0),
                max: Point::new(3.0, 3.5)
            }
        );
    }
}
