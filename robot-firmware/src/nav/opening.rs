//! Reopening a way the map has closed: the wall cells that alone part two points' regions.
//!
//! Why: a search that marks walls from a moving robot's readings closes narrow gaps with
//! marks its position's error has shifted (issue 32); when its planner then finds no way at
//! all, the culprits are most likely the walls one cell thick that touch both the region the
//! robot can reach and the region the goal can, not the walls around it nor all walls.
//!
//! Method: the grid planner's wave ([`wave_plan`]) from `b` labels the cells `b` reaches; they
//! are kept as a bitset; a second wave from `a` labels `a`'s; every wall cell with one of its
//! four neighbours in each is made unknown. Storage: the wave's scratch plus one bitset,
//! [`opening_bytes`] (2 560 bytes for 64 x 64, inside the region map the planner uses).
//!
//! What can fail: nothing; a point off the map or in a wall opens nothing.

use super::grid::{Cell, Grid, GridPoint};
use super::segment::Passable;
use super::wave::{reached, wave_bytes, wave_plan};

/// Bytes of scratch [`open_between`] needs for `cells` cells.
pub const fn opening_bytes(cells: usize) -> usize {
    wave_bytes(cells) + cells.div_ceil(8)
}

/// Makes unknown every wall cell of `grid` that touches (4-connected) both a cell reachable
/// from `a` and one reachable from `b` over `passable` cells; returns how many. Nothing when
/// `a` and `b` are already joined or `scratch` is smaller than [`opening_bytes`].
pub fn open_between<S: AsRef<[u8]> + AsMut<[u8]>>(
    grid: &mut Grid<S>,
    passable: Passable,
    a: GridPoint,
    b: GridPoint,
    scratch: &mut [u8],
) -> usize {
    let n = grid.len();
    if scratch.len() < opening_bytes(n) {
        return 0;
    }
    let (waves, kept) = scratch.split_at_mut(wave_bytes(n));
    // Cells `b` reaches: the labels of a wave from `b` that cannot reach `a`.
    match wave_plan(grid, passable, a, b, waves) {
        Err(super::PlanError::Unreachable) => {}
        _ => return 0,
    }
    kept.fill(0);
    for i in 0..n {
        if reached(waves, i) {
            if let Some(byte) = kept.get_mut(i / 8) {
                *byte |= 1 << (i % 8);
            }
        }
    }
    if !matches!(
        wave_plan(grid, passable, b, a, waves),
        Err(super::PlanError::Unreachable)
    ) {
        return 0;
    }
    let in_b = |i: usize| {
        kept.get(i / 8)
            .is_some_and(|byte| byte & (1 << (i % 8)) != 0)
    };
    let (w, h) = (usize::from(grid.width()), usize::from(grid.height()));
    let mut opened = 0;
    for y in 0..h {
        for x in 0..w {
            if grid.get(x, y) != Cell::Obstacle {
                continue;
            }
            let i = y * w + x;
            let around = [
                (x > 0).then(|| i - 1),
                (x + 1 < w).then_some(i + 1),
                (y > 0).then(|| i - w),
                (y + 1 < h).then_some(i + w),
            ];
            let touches_a = around.iter().flatten().any(|&j| reached(waves, j));
            let touches_b = around.iter().flatten().any(|&j| in_b(j));
            if touches_a && touches_b {
                // In range by the loops' bounds.
                let _ = grid.set(x, y, Cell::Unknown);
                opened += 1;
            }
        }
    }
    opened
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::nav::Geometry;
    use std::vec;

    #[test]
    fn a_wall_one_cell_thick_between_two_regions_is_opened_and_a_thick_one_is_not() {
        let (w, h) = (9u16, 5u16);
        let bytes = crate::nav::grid_bytes(w.into(), h.into());
        let mut g = Grid::new(w, h, Geometry::SEED_004, vec![0u8; bytes]).expect("grid");
        // A wall across at x = 4, one cell thick.
        for y in 0..5 {
            g.set(4, y, Cell::Obstacle).expect("in grid");
        }
        let (a, b) = (GridPoint::cell_centre(1, 2), GridPoint::cell_centre(7, 2));
        let mut scratch = vec![0u8; opening_bytes(g.len())];
        assert_eq!(
            open_between(&mut g, Passable::FreeOrUnknown, a, b, &mut scratch),
            5
        );
        assert!((0..5).all(|y| g.get(4, y) == Cell::Unknown));
        // Two cells thick: nothing touches both sides.
        for y in 0..5 {
            g.set(4, y, Cell::Obstacle).expect("in grid");
            g.set(5, y, Cell::Obstacle).expect("in grid");
        }
        assert_eq!(
            open_between(&mut g, Passable::FreeOrUnknown, a, b, &mut scratch),
            0
        );
        // Joined already: nothing to open.
        g.set(4, 0, Cell::Unknown).expect("in grid");
        g.set(5, 0, Cell::Unknown).expect("in grid");
        assert_eq!(
            open_between(&mut g, Passable::FreeOrUnknown, a, b, &mut scratch),
            0
        );
    }
}
