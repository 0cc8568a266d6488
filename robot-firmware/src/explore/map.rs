//! The map exploration reads, marks and plans on, as a trait ([`MapMarker`]), so that the
//! search needs no storage of its own; the firmware's grid is one.
//!
//! Layer: pure, over caller storage. Off-map points are ignored, never an error.

use crate::nav::{Cell, Grid, GridPoint};
use crate::odometry::Point;

/// Where exploration reads and writes the map, and plans on it.
pub trait MapMarker {
    /// The (column, row) of the cell holding `p` (metres), or `None` off the map.
    fn index(&self, p: Point) -> Option<(i32, i32)>;
    /// The cell holding `p` (metres), or `None` off the map.
    fn cell_at(&self, p: Point) -> Option<Cell>;
    /// Sets the cell holding `p`; off-map points are ignored.
    fn mark(&mut self, p: Point, cell: Cell);
    /// The side of a cell, metres.
    fn cell_m(&self) -> f32;
    /// The centre of cell (`x`, `y`), or `None` off the map.
    fn cell_centre(&self, x: i32, y: i32) -> Option<Point>;
    /// A wall seen at `p` by a reading whose beam is wider than a cell there: kept apart
    /// from the map's walls where there is a place for it
    /// ([`far_marks`](super::far_marks)), else nothing.
    fn mark_far(&mut self, _p: Point) {}
    /// The first point to drive to on a plan from `from` to `to` over this map with unknown
    /// cells taken as free (seed 004 §6 planning on an incomplete map), or `None` when there
    /// is no such plan or no planner.
    fn plan_towards(&mut self, _from: Point, _to: Point) -> Option<Point> {
        None
    }
    /// The first point to drive to on the grid planner's route from `from` to `to` over free
    /// and unknown cells, replanned often by the search that plans as it goes
    /// ([`planned`](super::planned)); `None` when the map shows no way or there is no planner.
    fn route_towards(&mut self, _from: Point, _to: Point) -> Option<RouteStep> {
        None
    }
    /// Makes every wall cell farther than `keep_m` from `keep` unknown again (walls that hold
    /// dead-reckoning errors and close the way).
    fn forget_walls(&mut self, _keep: Point, _keep_m: f32) {}
    /// Makes every wall cell within `near_m` of `at` unknown again.
    fn forget_walls_near(&mut self, _at: Point, _near_m: f32) {}
    /// Whether the straight line from `from` to `to` meets no wall cell of the map (unknown
    /// cells count as free); `false` off the map.
    fn clear_line(&self, _from: Point, _to: Point) -> bool {
        false
    }
    /// Makes unknown the wall cells one cell thick that alone part `from`'s region from
    /// `to`'s (unknown cells free); returns how many.
    fn open_walls_between(&mut self, _from: Point, _to: Point) -> usize {
        0
    }
}

/// A route's next point and its length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RouteStep {
    /// The first point to drive to (the farthest one of the route in line of sight).
    pub waypoint: Point,
    /// The route's length in steps between cells.
    pub cells: u32,
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

    fn cell_m(&self) -> f32 {
        self.geometry().cell_size_m()
    }

    fn cell_centre(&self, x: i32, y: i32) -> Option<Point> {
        let (cx, cy) = (u16::try_from(x).ok()?, u16::try_from(y).ok()?);
        self.contains(x, y).then(|| {
            let (mx, my) = self
                .geometry()
                .grid_to_metres(GridPoint::cell_centre(cx, cy));
            Point::new(mx, my)
        })
    }

    fn mark(&mut self, p: Point, cell: Cell) {
        let (x, y) = self.geometry().metres_to_grid(p.x, p.y).cell();
        if self.contains(x, y) {
            // `contains` bounds both coordinates, so the write cannot fail.
            let _ = self.set(x as usize, y as usize, cell);
        }
    }

    /// The outermost cells are kept: the planned search's map holds the arena's own wall
    /// there.
    fn forget_walls(&mut self, keep: Point, keep_m: f32) {
        forget_where(self, |c| c.distance_to(keep) > keep_m);
    }

    fn forget_walls_near(&mut self, at: Point, near_m: f32) {
        forget_where(self, |c| c.distance_to(at) <= near_m);
    }

    fn clear_line(&self, from: Point, to: Point) -> bool {
        let geo = self.geometry();
        let open = |x: i32, y: i32| {
            self.contains(x, y) && self.get(x as usize, y as usize) != Cell::Obstacle
        };
        crate::nav::smooth::line_of_sight_by(
            self.width(),
            self.height(),
            open,
            geo.metres_to_grid(from.x, from.y),
            geo.metres_to_grid(to.x, to.y),
        )
    }
}

/// Makes the wall cells whose centres `forget` picks unknown, the outermost cells aside.
fn forget_where<S: AsRef<[u8]> + AsMut<[u8]>>(grid: &mut Grid<S>, forget: impl Fn(Point) -> bool) {
    let geo = grid.geometry();
    let cell = geo.cell_size_m();
    let (w, h) = (usize::from(grid.width()), usize::from(grid.height()));
    let (ox, oy) = geo.origin_mm();
    for y in 1..h.saturating_sub(1) {
        for x in 1..w.saturating_sub(1) {
            let centre = Point::new(
                ox as f32 / 1000.0 + (x as f32 + 0.5) * cell,
                oy as f32 / 1000.0 + (y as f32 + 0.5) * cell,
            );
            if grid.get(x, y) == Cell::Obstacle && forget(centre) {
                // In range by the loops' bounds.
                let _ = grid.set(x, y, Cell::Unknown);
            }
        }
    }
}
