//! The shortest free path a round robot has from a start to a goal area, and the narrowest
//! gap it cannot avoid on the way: what makes an arena hard for a beacon search (issue 32's
//! detour ratio), measured on the arena itself, never on what a robot mapped.
//!
//! Layer: std, arena analysis beside [`super::rasterise`]; the generator uses it to draw
//! arenas over a spread of detours and the benchmark to report every arena's.
//!
//! Method: a clearance field (distance from each cell centre of a fine grid to the nearest
//! wall, 0 inside one or outside an enclosed arena); cells with clearance of at least the
//! robot's radius are where its centre may be. Dijkstra over them, 8-connected with no corner
//! cutting, then string pulling (a waypoint is dropped while the straight line past it keeps
//! the clearance): within a few percent of the Euclidean shortest path at a 5 cm cell. The
//! bottleneck is the widest-path (maximin) clearance from the start to the goal area: twice it
//! is the narrowest gap every route must pass. The start's and the goal area's own
//! surroundings do not count (a start against a wall is not a gap).
//!
//! What can fail: nothing; `None` when the robot cannot reach the goal area at all (or the
//! arena is absurdly large for the grid).

use std::cmp::{Ordering, Reverse};
use std::collections::BinaryHeap;

use super::Arena;
use crate::geometry::Point;

/// Grid cell of the clearance field, metres, at most (a small robot gets half its radius).
const MAX_CELL_M: f64 = 0.05;
/// Clearance is measured up to this far, metres (gaps wider than twice it are "wide").
const CAP_M: f64 = 1.0;
/// Most cells the field may have (a 50 x 50 m arena at 5 cm).
const MAX_CELLS: usize = 1_000_000;

/// What [`free_path`] measured.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct FreePath {
    /// Length of the shortest path of the robot's centre to the goal area, metres.
    pub length_m: f64,
    /// Straight line from the start to the goal area's edge, metres.
    pub straight_m: f64,
    /// `length_m / straight_m` (1 when the start is at or in the goal area).
    pub detour_ratio: f64,
    /// Width of the narrowest gap every route passes, metres (at most twice the 1 m cap).
    pub bottleneck_m: f64,
}

/// The robot's shortest free path from `start` to the circle (`goal`, `goal_r`) and the
/// narrowest gap on the way, for a robot of `radius`; `None` when there is none.
pub fn free_path(
    arena: &Arena,
    start: Point,
    goal: Point,
    goal_r: f64,
    radius: f64,
) -> Option<FreePath> {
    let cell = (radius / 2.0).min(MAX_CELL_M);
    if !(cell > 0.0 && cell.is_finite()) {
        return None;
    }
    let field = Field::new(arena, cell)?;
    let straight = ((start - goal).norm() - goal_r).max(0.0);
    let starts = field.near(start, radius, radius);
    // A point goal: the cells within a cell of it.
    let reach = goal_r.max(cell);
    let is_goal = |i: usize| (field.centre(i) - goal).norm() <= reach;
    let path = field.shortest(&starts, radius, &is_goal)?;
    let length_m = field.pulled_length(start, &path, radius);
    let spared = |i: usize| {
        let c = field.centre(i);
        (c - start).norm() <= 2.0 * radius || (c - goal).norm() <= reach + radius
    };
    let bottleneck = field.widest(&starts, radius, &is_goal, &spared);
    Some(FreePath {
        length_m,
        straight_m: straight,
        detour_ratio: if straight < cell {
            1.0
        } else {
            (length_m / straight).max(1.0)
        },
        bottleneck_m: 2.0 * bottleneck,
    })
}

/// The clearance of every cell centre.
struct Field {
    origin: Point,
    cell: f64,
    w: usize,
    h: usize,
    clear: Vec<f64>,
}

impl Field {
    fn new(arena: &Arena, cell: f64) -> Option<Field> {
        let b = arena.bounds;
        let w = (b.width() / cell).ceil() as usize;
        let h = (b.height() / cell).ceil() as usize;
        if w == 0 || h == 0 || w.saturating_mul(h) > MAX_CELLS {
            return None;
        }
        let walls = arena.segment_set();
        let mut f = Field {
            origin: b.min,
            cell,
            w,
            h,
            clear: vec![0.0; w * h],
        };
        for i in 0..w * h {
            let c = f.centre(i);
            f.clear[i] = if arena.is_solid(c) {
                0.0
            } else {
                walls.nearest(c, CAP_M).map_or(CAP_M, |n| n.distance)
            };
        }
        Some(f)
    }

    fn centre(&self, i: usize) -> Point {
        let (c, r) = (i % self.w, i / self.w);
        Point::new(
            self.origin.x + (c as f64 + 0.5) * self.cell,
            self.origin.y + (r as f64 + 0.5) * self.cell,
        )
    }

    fn index(&self, p: Point) -> Option<usize> {
        let c = ((p.x - self.origin.x) / self.cell).floor();
        let r = ((p.y - self.origin.y) / self.cell).floor();
        (c >= 0.0 && r >= 0.0 && (c as usize) < self.w && (r as usize) < self.h)
            .then(|| r as usize * self.w + c as usize)
    }

    /// Cells the robot's centre may hold within `within` of `p` (a start against a wall).
    fn near(&self, p: Point, within: f64, radius: f64) -> Vec<usize> {
        let k = (within / self.cell).ceil() as i64 + 1;
        let Some(i0) = self.index(p) else {
            return Vec::new();
        };
        let (c0, r0) = ((i0 % self.w) as i64, (i0 / self.w) as i64);
        let mut out = Vec::new();
        for r in (r0 - k).max(0)..=(r0 + k).min(self.h as i64 - 1) {
            for c in (c0 - k).max(0)..=(c0 + k).min(self.w as i64 - 1) {
                let i = r as usize * self.w + c as usize;
                if self.clear[i] >= radius && (self.centre(i) - p).norm() <= within {
                    out.push(i);
                }
            }
        }
        out
    }

    /// The 8 neighbours of `i` a robot may step to (a diagonal needs both sides open), with
    /// the step's length in cells.
    fn steps(&self, i: usize, radius: f64) -> impl Iterator<Item = (usize, f64)> + '_ {
        let (c, r) = ((i % self.w) as i64, (i / self.w) as i64);
        let open = move |c: i64, r: i64| {
            (c >= 0 && r >= 0 && (c as usize) < self.w && (r as usize) < self.h)
                .then(|| r as usize * self.w + c as usize)
                .filter(|&j| self.clear[j] >= radius)
        };
        const D: [(i64, i64); 8] = [
            (1, 0),
            (-1, 0),
            (0, 1),
            (0, -1),
            (1, 1),
            (1, -1),
            (-1, 1),
            (-1, -1),
        ];
        D.into_iter().filter_map(move |(dc, dr)| {
            let j = open(c + dc, r + dr)?;
            if dc != 0 && dr != 0 {
                open(c + dc, r)?;
                open(c, r + dr)?;
                Some((j, std::f64::consts::SQRT_2))
            } else {
                Some((j, 1.0))
            }
        })
    }

    /// Dijkstra from `starts` to the first goal cell; the cells of the path, start first.
    fn shortest(
        &self,
        starts: &[usize],
        radius: f64,
        is_goal: &dyn Fn(usize) -> bool,
    ) -> Option<Vec<usize>> {
        let n = self.w * self.h;
        let mut dist = vec![f64::INFINITY; n];
        let mut from = vec![usize::MAX; n];
        let mut heap = BinaryHeap::new();
        for &s in starts {
            dist[s] = 0.0;
            heap.push(Reverse(Entry(0.0, s)));
        }
        while let Some(Reverse(Entry(d, i))) = heap.pop() {
            if d > dist[i] {
                continue;
            }
            if is_goal(i) {
                let mut path = vec![i];
                let mut k = i;
                while from[k] != usize::MAX {
                    k = from[k];
                    path.push(k);
                }
                path.reverse();
                return Some(path);
            }
            for (j, step) in self.steps(i, radius) {
                let nd = d + step;
                if nd < dist[j] {
                    dist[j] = nd;
                    from[j] = i;
                    heap.push(Reverse(Entry(nd, j)));
                }
            }
        }
        None
    }

    /// Whether the robot's centre can go straight from `a` to `b` (sampled at half a cell).
    fn clear_line(&self, a: Point, b: Point, radius: f64) -> bool {
        let n = ((b - a).norm() / (self.cell / 2.0)).ceil().max(1.0) as usize;
        (0..=n).all(|k| {
            let p = a + (b - a) * (k as f64 / n as f64);
            self.index(p).is_some_and(|i| self.clear[i] >= radius)
        })
    }

    /// The path's length after string pulling, from `start` itself.
    fn pulled_length(&self, start: Point, path: &[usize], radius: f64) -> f64 {
        let pts: Vec<Point> = path.iter().map(|&i| self.centre(i)).collect();
        let Some(&last) = pts.last() else {
            return 0.0;
        };
        let mut length = 0.0;
        let mut anchor = pts[0];
        let mut k = 0;
        while k + 1 < pts.len() {
            // The farthest path point in line of sight of the anchor.
            let mut far = k + 1;
            while far + 1 < pts.len() && self.clear_line(anchor, pts[far + 1], radius) {
                far += 1;
            }
            length += (pts[far] - anchor).norm();
            anchor = pts[far];
            k = far;
        }
        debug_assert!((anchor - last).norm() < 1e-9);
        length + (pts[0] - start).norm()
    }

    /// The largest clearance `c` such that a path from `starts` to a goal cell keeps at least
    /// `c` everywhere except on `spared` cells (and at least `radius` there).
    fn widest(
        &self,
        starts: &[usize],
        radius: f64,
        is_goal: &dyn Fn(usize) -> bool,
        spared: &dyn Fn(usize) -> bool,
    ) -> f64 {
        let n = self.w * self.h;
        let mut best = vec![-1.0f64; n];
        let mut heap = BinaryHeap::new();
        for &s in starts {
            best[s] = CAP_M;
            heap.push(Entry(CAP_M, s));
        }
        while let Some(Entry(b, i)) = heap.pop() {
            if b < best[i] {
                continue;
            }
            if is_goal(i) {
                return b;
            }
            for (j, _) in self.steps(i, radius) {
                let own = if spared(j) { CAP_M } else { self.clear[j] };
                let nb = b.min(own);
                if nb > best[j] {
                    best[j] = nb;
                    heap.push(Entry(nb, j));
                }
            }
        }
        0.0
    }
}

/// A heap entry ordered by its value: the widest path pops the largest clearance, Dijkstra
/// (through `Reverse`) the smallest distance.
#[derive(Clone, Copy, PartialEq)]
struct Entry(f64, usize);

impl Eq for Entry {}

impl PartialOrd for Entry {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

impl Ord for Entry {
    fn cmp(&self, o: &Self) -> Ordering {
        self.0.total_cmp(&o.0).then(self.1.cmp(&o.1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::arena::{ArenaFormat, Wall};
    use crate::geometry::Aabb;

    /// A 4 x 2 m enclosed lab with a wall across at x = 2 from y = 0 up to `top`.
    fn lab(top: f64) -> Arena {
        Arena {
            name: "t".into(),
            source: "t".into(),
            format: ArenaFormat::CiberRato,
            bounds: Aabb::from_corners(Point::new(0.0, 0.0), Point::new(4.0, 2.0)),
            enclosed: true,
            walls: vec![Wall::rectangle(
                Aabb::from_corners(Point::new(1.95, 0.0), Point::new(2.05, top)),
                None,
            )],
            raster: None,
            beacons: Vec::new(),
            targets: Vec::new(),
            lights: Vec::new(),
            starts: Vec::new(),
            goal: None,
            unit_m: 1.0,
            warnings: Vec::new(),
        }
    }

    #[test]
    fn the_path_goes_round_the_wall_and_the_gap_is_measured() {
        let (s, g) = (Point::new(1.0, 0.5), Point::new(3.0, 0.5));
        let open = free_path(&lab(0.5), s, g, 0.2, 0.12).expect("a route");
        // Round the wall's end at y = 0.5 (+ the radius): a little over the straight 1.8 m.
        assert!(open.detour_ratio < 1.2, "{open:?}");
        let f = free_path(&lab(1.6), s, g, 0.2, 0.12).expect("a route");
        // Up to the corner (1.95, 1.6) + the radius, across and down to the area's edge:
        // 1.55 + 0.1 + 1.35 = 3.0 m (the 5 cm grid adds a few percent).
        assert!((f.length_m - 3.0).abs() < 0.15, "{f:?}");
        assert!(f.detour_ratio > 1.3, "{f:?}");
        // The gap above the wall is 0.4 m.
        assert!((f.bottleneck_m - 0.4).abs() < 0.06, "{f:?}");
        assert!(
            free_path(&lab(1.8), s, g, 0.2, 0.12).is_none(),
            "a 0.2 m gap: no way"
        );
    }
}
