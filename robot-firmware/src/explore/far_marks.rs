//! Walls seen from afar, kept beside the map: believed by the planned search's route unless
//! believing them costs a detour.
//!
//! Why (issue 32): an IR beam is wider than a 0.15 m cell beyond 0.13 m from the sensor
//! (CiberRato's sensors see 60 degrees), so a far reading's wall may be anywhere across it:
//! the end of a wall at the beam's side reads as a wall straight ahead. Marked as walls,
//! those readings closed the 0.3-0.45 m gaps round a wall's end that a route has to take
//! (real-like narrow gaps: 19 of 48 reached); left out, the route ran along walls the robot
//! had seen and it touched them more (Micro-Rato labyrinths: collisions 0.025 -> 0.135 a
//! run). Kept here, they are walls for a route that is at most `far_detour_m` longer than the
//! route without them, and nothing otherwise.
//!
//! Storage: one bit a cell of the largest map, 512 bytes, in the explorer of a robot that
//! searches (the map itself has no spare cell code: its code 3 is refused on the link).
//!
//! What can fail: nothing; cells off the map or beyond 64 x 64 are not kept.

use super::cell_set::CellSet;
use super::{MapMarker, RouteStep};
use crate::nav::Cell;
use crate::odometry::Point;

/// The cells where a far reading saw a wall and the map holds nothing yet.
pub type FarMarks = CellSet;

/// `map` with the far marks `marks` beside it: [`MapMarker::mark_far`] keeps a far reading's
/// wall, a real mark of the cell replaces it, forgetting walls forgets them, and
/// [`MapMarker::route_towards`] plans with them as walls and without, taking the first route
/// unless it is longer by more than `detour_cells`.
pub struct WithFarMarks<'a> {
    map: &'a mut dyn MapMarker,
    marks: &'a mut FarMarks,
    detour_cells: u32,
}

impl<'a> WithFarMarks<'a> {
    pub fn new(map: &'a mut dyn MapMarker, marks: &'a mut FarMarks, detour_m: f32) -> Self {
        let detour_cells = libm::roundf(detour_m / map.cell_m().max(1e-3)).max(0.0) as u32;
        WithFarMarks {
            map,
            marks,
            detour_cells,
        }
    }

    /// Draws the marks into the map as `cell` (walls, or unknown again); a marked cell the map
    /// has since learnt (free or wall) loses its mark instead.
    fn draw(&mut self, cell: Cell) {
        let mut stale = [(0i32, 0i32); 8];
        let mut n = 0;
        for c in self.marks.cells() {
            let Some(p) = self.map.cell_centre(c.0, c.1) else {
                continue;
            };
            let now = self.map.cell_at(p);
            let ours = match cell {
                Cell::Obstacle => now == Some(Cell::Unknown),
                _ => now == Some(Cell::Obstacle),
            };
            if ours {
                self.map.mark(p, cell);
            } else if let Some(s) = stale.get_mut(n) {
                *s = c;
                n += 1;
            }
        }
        for &c in stale.iter().take(n) {
            self.marks.set(c, false);
        }
    }

    /// Forgets the marks whose cell centres `forget` picks.
    fn forget_where(&mut self, forget: impl Fn(Point) -> bool) {
        let mut gone = [(0i32, 0i32); 16];
        loop {
            let mut n = 0;
            for c in self.marks.cells() {
                let picked = self.map.cell_centre(c.0, c.1).is_none_or(&forget);
                if let (true, Some(g)) = (picked, gone.get_mut(n)) {
                    *g = c;
                    n += 1;
                }
            }
            for &c in gone.iter().take(n) {
                self.marks.set(c, false);
            }
            if n < gone.len() {
                return;
            }
        }
    }
}

impl MapMarker for WithFarMarks<'_> {
    fn index(&self, p: Point) -> Option<(i32, i32)> {
        self.map.index(p)
    }

    fn cell_at(&self, p: Point) -> Option<Cell> {
        self.map.cell_at(p)
    }

    fn cell_m(&self) -> f32 {
        self.map.cell_m()
    }

    fn cell_centre(&self, x: i32, y: i32) -> Option<Point> {
        self.map.cell_centre(x, y)
    }

    fn mark(&mut self, p: Point, cell: Cell) {
        if let Some(c) = self.map.index(p) {
            self.marks.set(c, false);
        }
        self.map.mark(p, cell);
    }

    fn mark_far(&mut self, p: Point) {
        if self.map.cell_at(p) == Some(Cell::Unknown) {
            if let Some(c) = self.map.index(p) {
                self.marks.set(c, true);
            }
        }
    }

    fn plan_towards(&mut self, from: Point, to: Point) -> Option<Point> {
        self.map.plan_towards(from, to)
    }

    fn route_towards(&mut self, from: Point, to: Point) -> Option<RouteStep> {
        let without = self.map.route_towards(from, to);
        if self.marks.is_empty() {
            return without;
        }
        self.draw(Cell::Obstacle);
        let with = self.map.route_towards(from, to);
        self.draw(Cell::Unknown);
        match (with, without) {
            (Some(w), Some(o)) if w.cells <= o.cells.saturating_add(self.detour_cells) => Some(w),
            _ => without,
        }
    }

    fn forget_walls(&mut self, keep: Point, keep_m: f32) {
        self.forget_where(|c| c.distance_to(keep) > keep_m);
        self.map.forget_walls(keep, keep_m);
    }

    fn forget_walls_near(&mut self, at: Point, near_m: f32) {
        self.forget_where(|c| c.distance_to(at) <= near_m);
        self.map.forget_walls_near(at, near_m);
    }

    fn clear_line(&self, from: Point, to: Point) -> bool {
        self.map.clear_line(from, to)
    }

    fn open_walls_between(&mut self, from: Point, to: Point) -> usize {
        self.map.open_walls_between(from, to)
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::nav::{wave_bytes, wave_first_waypoint, Geometry, Grid, Passable};
    use std::vec;
    use std::vec::Vec;

    /// A grid with the search's planner: the wave over free and unknown cells.
    struct Planning(Grid<Vec<u8>>);

    impl MapMarker for Planning {
        fn index(&self, p: Point) -> Option<(i32, i32)> {
            self.0.index(p)
        }
        fn cell_at(&self, p: Point) -> Option<Cell> {
            MapMarker::cell_at(&self.0, p)
        }
        fn cell_m(&self) -> f32 {
            self.0.cell_m()
        }
        fn cell_centre(&self, x: i32, y: i32) -> Option<Point> {
            self.0.cell_centre(x, y)
        }
        fn mark(&mut self, p: Point, cell: Cell) {
            self.0.mark(p, cell)
        }
        fn route_towards(&mut self, from: Point, to: Point) -> Option<RouteStep> {
            let geo = self.0.geometry();
            let (a, b) = (
                geo.metres_to_grid(from.x, from.y),
                geo.metres_to_grid(to.x, to.y),
            );
            let mut scratch = vec![0u8; wave_bytes(self.0.len())];
            let (next, cells) =
                wave_first_waypoint(&self.0, Passable::FreeOrUnknown, a, b, &mut scratch).ok()?;
            let (x, y) = geo.grid_to_metres(next);
            Some(RouteStep {
                waypoint: Point::new(x, y),
                cells,
            })
        }
        fn forget_walls_near(&mut self, at: Point, near_m: f32) {
            self.0.forget_walls_near(at, near_m)
        }
    }

    /// A map with a wall across it at column 5, with a gap at row 1 that a far mark closes.
    fn walled_with_far_mark(marks: &mut FarMarks) -> (Planning, Point) {
        let bytes = crate::nav::grid_bytes(11, 8);
        let mut g = Grid::new(11, 8, Geometry::SEED_004, vec![0u8; bytes]).expect("grid");
        for y in 0..8 {
            if y != 1 {
                g.set(5, y, Cell::Obstacle).expect("in grid");
            }
        }
        let mut map = Planning(g);
        let gap = map.cell_centre(5, 1).expect("in grid");
        WithFarMarks::new(&mut map, marks, 0.0).mark_far(gap);
        (map, gap)
    }

    #[test]
    fn a_far_mark_is_a_wall_only_while_the_way_round_it_is_short() {
        let mut marks = FarMarks::new();
        let (mut map, gap) = walled_with_far_mark(&mut marks);
        assert_eq!(marks.len(), 1);
        let from = map.cell_centre(2, 1).expect("in grid");
        let to = map.cell_centre(8, 1).expect("in grid");
        // Detours of four cells and of one.
        let (long, short) = (4.0 * map.cell_m(), map.cell_m());
        // The far mark closes the only gap: the route without it is taken.
        let step = WithFarMarks::new(&mut map, &mut marks, long).route_towards(from, to);
        assert_eq!(step.map(|s| s.cells), Some(6));
        // The map is as it was: the mark was drawn in for the plan and taken out.
        assert_eq!(map.cell_at(gap), Some(Cell::Unknown));
        assert_eq!(marks.len(), 1);
        // A second gap two rows down: believed, the route goes through it.
        map.0.set(5, 3, Cell::Unknown).expect("in grid");
        let step = WithFarMarks::new(&mut map, &mut marks, long).route_towards(from, to);
        assert_eq!(step.map(|s| s.cells), Some(10));
        // Too long a way round for a detour of one cell: the mark is not believed.
        let step = WithFarMarks::new(&mut map, &mut marks, short).route_towards(from, to);
        assert_eq!(step.map(|s| s.cells), Some(6));
    }

    #[test]
    fn a_real_mark_or_forgetting_walls_ends_a_far_mark() {
        let mut marks = FarMarks::new();
        let (mut map, gap) = walled_with_far_mark(&mut marks);
        WithFarMarks::new(&mut map, &mut marks, 1.0).mark(gap, Cell::Free);
        assert!(marks.is_empty());
        // A cell the map knows takes no far mark.
        WithFarMarks::new(&mut map, &mut marks, 1.0).mark_far(gap);
        assert!(marks.is_empty());
        map.0.set(5, 1, Cell::Unknown).expect("in grid");
        let mut m = WithFarMarks::new(&mut map, &mut marks, 1.0);
        m.mark_far(gap);
        m.forget_walls_near(gap, 0.1);
        assert!(marks.is_empty());
    }
}
