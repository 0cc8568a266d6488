//! Where a round robot can drive: the cells of a fine raster its centre reaches from some
//! seed cells, 4-connected, over [`rasterise`]'s conservative free cells (a free cell is one
//! where the robot's centre fits anywhere in it).
//!
//! Layer: std, arena analysis. The generator checks each arena's start reaches its goal with
//! it ([`crate::arena_gen::solvable`]); the simulator picks a start that reaches the goal when
//! the arena gives none ([`crate::sim::start_pose`]).
//!
//! What can fail: the raster (a cell size or arena the raster refuses).

use std::collections::VecDeque;

use super::{rasterise, Arena, Cell, RasterError, RasterMap};
use crate::geometry::Point;

/// The cells a robot of some radius reaches from its seeds.
#[derive(Clone, Debug)]
pub struct Reach {
    map: RasterMap,
    reached: Vec<bool>,
}

impl Reach {
    /// The cells a robot of `radius` reaches from the free cells whose centres `seed` picks;
    /// the raster's cell is half the radius.
    pub fn from(
        arena: &Arena,
        radius: f64,
        seed: impl Fn(Point) -> bool,
    ) -> Result<Reach, RasterError> {
        let map = rasterise(arena, radius / 2.0, radius)?;
        let (w, h) = (map.width as usize, map.height as usize);
        let mut reached = vec![false; w * h];
        let mut queue = VecDeque::new();
        for r in 0..h {
            for c in 0..w {
                let i = r * w + c;
                if map.cells[i] == Cell::Free && seed(centre(&map, i)) {
                    reached[i] = true;
                    queue.push_back(i);
                }
            }
        }
        while let Some(i) = queue.pop_front() {
            let (c, r) = (i % w, i / w);
            let next = [
                (c > 0).then(|| i - 1),
                (c + 1 < w).then_some(i + 1),
                (r > 0).then(|| i - w),
                (r + 1 < h).then_some(i + w),
            ];
            for j in next.into_iter().flatten() {
                if !reached[j] && map.cells[j] == Cell::Free {
                    reached[j] = true;
                    queue.push_back(j);
                }
            }
        }
        Ok(Reach { map, reached })
    }

    /// Whether no cell was seeded (every seed in a wall, or none asked for).
    pub fn is_empty(&self) -> bool {
        !self.reached.iter().any(|&r| r)
    }

    /// Whether some reached cell's centre satisfies `want`.
    pub fn any(&self, want: impl Fn(Point) -> bool) -> bool {
        (0..self.reached.len()).any(|i| self.reached[i] && want(centre(&self.map, i)))
    }

    /// Whether the robot's centre at `p` is in a reached cell.
    pub fn holds(&self, p: Point) -> bool {
        self.map
            .cell_at(p.x, p.y)
            .is_some_and(|(c, r)| self.reached[r as usize * self.map.width as usize + c as usize])
    }
}

fn centre(map: &RasterMap, i: usize) -> Point {
    let w = map.width as usize;
    let [x, y] = map.cell_centre((i % w) as u32, (i / w) as u32);
    Point::new(x, y)
}
