//! Optional smoothing of a raw plan, reported beside it so the paper's method stays visible.
//!
//! Layer: after `astar.rs`; reads [`Regions`] and a raw [`Plan`] (seed 004 §6-7: the
//! trajectory through region centres), writes points to a caller store ([`Smoothed`]).
//!
//! Two passes:
//! 1. Funnel (string pulling) through the plan's portals - the edge each pair of consecutive
//!    squares shares: the shortest path from start to goal that crosses those edges in order.
//!    It stays inside the plan's squares (a segment between two points of a convex square stays
//!    in it), so it is collision-free by the same argument as seed 004 §6's "a path through the
//!    centers of connected regions is always feasible". `margin` (grid units) pulls each portal
//!    end inwards, so bends stay about that far from the squares' corners, where obstacle
//!    corners are (a robot is not a point); it is not a clearance guarantee along walls.
//! 2. Drop: from an anchor, skip ahead over waypoints while the straight segment to the next
//!    one passes [`line_of_sight`]; consecutive funnel segments are never tested (already
//!    proved feasible), so this pass only ever shortens.
//!
//! If rounding ever made the result longer than the raw plan, the raw centres are returned:
//! the smoothed length is never above the raw one. All arithmetic is exact integer arithmetic
//! on grid units, so both sides of the link get the same points.
//!
//! [`line_of_sight`] is conservative: every cell whose closed square meets the segment must be
//! free, so a segment that grazes an obstacle's corner or runs along its edge is refused.
//!
//! What can fail: the output store is too small for the points. Never a panic.

use super::astar::{Plan, PlanError};
use super::dist::dist_ceil;
use super::grid::{GridPoint, UNITS_PER_CELL};
use super::ids::IdStore;
use super::segment::{Regions, Square};

/// A smoothed plan: the start, `len` points at the front of the caller's point store, the goal.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Smoothed {
    pub start: GridPoint,
    pub goal: GridPoint,
    pub len: u32,
    /// Length of the polyline in grid units (each segment rounded up).
    pub cost: u32,
}

impl Smoothed {
    /// Number of waypoints (points plus start and goal).
    pub const fn waypoint_count(&self) -> usize {
        self.len as usize + 2
    }

    /// Waypoint `i`, in grid units.
    pub fn waypoint(&self, points: &[GridPoint], i: usize) -> Option<GridPoint> {
        match i {
            0 => Some(self.start),
            _ if i == self.len as usize + 1 => Some(self.goal),
            _ if i <= self.len as usize => points.get(i - 1).copied(),
            _ => None,
        }
    }

    /// The waypoints in order, in grid units.
    pub fn waypoints<'x>(
        &'x self,
        points: &'x [GridPoint],
    ) -> impl Iterator<Item = GridPoint> + 'x {
        (0..self.waypoint_count()).filter_map(move |i| self.waypoint(points, i))
    }

    /// Length of the encoding: 24-byte header plus 8 bytes per point.
    pub const fn encoded_len(&self) -> usize {
        Plan::HEADER_BYTES.saturating_add((self.len as usize).saturating_mul(8))
    }

    /// Serialises like [`Plan::encode`], with points (x, y as i32) instead of region ids.
    pub fn encode(&self, points: &[GridPoint], out: &mut [u8]) -> Result<usize, PlanError> {
        let needed = self.encoded_len();
        let out = out
            .get_mut(..needed)
            .ok_or(PlanError::BufferTooSmall { needed })?;
        let head = [self.start.x, self.start.y, self.goal.x, self.goal.y]
            .map(i32::to_le_bytes)
            .into_iter()
            .chain([self.len.to_le_bytes(), self.cost.to_le_bytes()]);
        let pts = (0..self.len as usize)
            .filter_map(|i| points.get(i))
            .flat_map(|p| [p.x.to_le_bytes(), p.y.to_le_bytes()]);
        for (chunk, bytes) in out.chunks_exact_mut(4).zip(head.chain(pts)) {
            chunk.copy_from_slice(&bytes);
        }
        Ok(needed)
    }
}

/// Smooths `plan` (whose regions are at the front of `path`), keeping `margin` grid units from
/// the corners of the squares it passes; the points go to the front of `out`.
pub fn smooth<M, P>(
    regions: &Regions<'_, M>,
    plan: &Plan,
    path: &P,
    margin: u32,
    out: &mut [GridPoint],
) -> Result<Smoothed, PlanError>
where
    M: IdStore + ?Sized,
    P: IdStore + ?Sized,
{
    let (start, goal) = (plan.start, plan.goal);
    let pulled = funnel(regions, plan, path, margin, out)?;
    let mut len = match pulled {
        Some(k) => drop_pass(regions, start, goal, out, k),
        None => raw_centres(regions, plan, path, out)?,
    };
    let points = |n: usize| out.get(..n).unwrap_or(&[]).iter().copied();
    let mut cost = polyline_length(Some(start).into_iter().chain(points(len)).chain(Some(goal)));
    if cost > plan.cost {
        len = raw_centres(regions, plan, path, out)?;
        cost = plan.cost;
    }
    Ok(Smoothed {
        start,
        goal,
        len: u32::try_from(len).unwrap_or(u32::MAX),
        cost,
    })
}

/// Writes the raw plan's centres to `out`; returns their number.
fn raw_centres<M, P>(
    regions: &Regions<'_, M>,
    plan: &Plan,
    path: &P,
    out: &mut [GridPoint],
) -> Result<usize, PlanError>
where
    M: IdStore + ?Sized,
    P: IdStore + ?Sized,
{
    let n = plan.len as usize;
    let slots = out.get_mut(..n).ok_or(PlanError::PathTooLong {
        capacity: n.saturating_sub(1),
    })?;
    for (i, slot) in slots.iter_mut().enumerate() {
        *slot = plan.waypoint(regions, path, i + 1).unwrap_or(plan.goal);
    }
    Ok(n)
}

/// Twice the signed area of triangle o, a, b: positive when b is left of the ray o -> a.
#[inline]
fn cross(o: GridPoint, a: GridPoint, b: GridPoint) -> i64 {
    let (ax, ay) = (
        i64::from(a.x) - i64::from(o.x),
        i64::from(a.y) - i64::from(o.y),
    );
    let (bx, by) = (
        i64::from(b.x) - i64::from(o.x),
        i64::from(b.y) - i64::from(o.y),
    );
    ax * by - ay * bx
}

/// The edge shared by square `a` (left) and square `b` (entered) as (left end, right end) seen
/// along the direction of travel, each end pulled in by `margin` (at most to the midpoint);
/// `None` if the squares do not share an edge of positive length.
fn portal(a: Square, b: Square, margin: u32) -> Option<(GridPoint, GridPoint)> {
    let u = UNITS_PER_CELL;
    let lo = |s: Square| (i32::from(s.x) * u, i32::from(s.y) * u);
    let hi = |s: Square| {
        let (x, y) = lo(s);
        (x + i32::from(s.size) * u, y + i32::from(s.size) * u)
    };
    let ((ax0, ay0), (ax1, ay1)) = (lo(a), hi(a));
    let ((bx0, by0), (bx1, by1)) = (lo(b), hi(b));
    let m = i32::try_from(margin).unwrap_or(i32::MAX);
    let shrink = |l: i32, h: i32| {
        if (h - l) / 2 > m {
            (l + m, h - m)
        } else {
            ((l + h) / 2, (l + h) / 2)
        }
    };
    let p = |x: i32, y: i32| GridPoint { x, y };
    if ax1 == bx0 || bx1 == ax0 {
        let (l, h) = (ay0.max(by0), ay1.min(by1));
        if l >= h {
            return None;
        }
        let (l, h) = shrink(l, h);
        // Moving +x, left is +y; moving -x, left is -y.
        return Some(if ax1 == bx0 {
            (p(bx0, h), p(bx0, l))
        } else {
            (p(ax0, l), p(ax0, h))
        });
    }
    if ay1 == by0 || by1 == ay0 {
        let (l, h) = (ax0.max(bx0), ax1.min(bx1));
        if l >= h {
            return None;
        }
        let (l, h) = shrink(l, h);
        // Moving +y, left is -x; moving -y, left is +x.
        return Some(if ay1 == by0 {
            (p(l, by0), p(h, by0))
        } else {
            (p(h, ay0), p(l, ay0))
        });
    }
    None
}

/// The funnel: an apex and the two sides (point and portal index) seen from it.
struct Funnel {
    apex: GridPoint,
    left: (GridPoint, usize),
    right: (GridPoint, usize),
}

impl Funnel {
    /// A funnel with its apex at portal `k`'s point `p` and both sides closed on it.
    fn at(p: GridPoint, k: usize) -> Funnel {
        Funnel {
            apex: p,
            left: (p, k),
            right: (p, k),
        }
    }

    /// Narrows the funnel to portal `k`'s ends `l`, `r`; returns the corner (point, portal)
    /// where the path must bend if one side crossed the other.
    fn narrow(&mut self, l: GridPoint, r: GridPoint, k: usize) -> Option<(GridPoint, usize)> {
        let (apex, left, right) = (self.apex, self.left.0, self.right.0);
        // Right side: narrow it, or, if it crosses the left side, the left end is a corner.
        if cross(apex, right, r) >= 0 {
            if apex == right || cross(apex, left, r) < 0 {
                self.right = (r, k);
            } else {
                return Some(self.left);
            }
        }
        // Left side likewise (against the possibly narrowed right side).
        if cross(apex, left, l) <= 0 {
            if apex == left || cross(apex, self.right.0, l) > 0 {
                self.left = (l, k);
            } else {
                return Some(self.right);
            }
        }
        None
    }
}

/// The funnel algorithm over portals 0 (the start) ..= n (the goal); writes the corner points
/// to `out` and returns their number, or `None` if two consecutive regions share no edge.
///
/// Each restart moves the apex to a later portal, so it ends after at most n restarts.
fn funnel<M, P>(
    regions: &Regions<'_, M>,
    plan: &Plan,
    path: &P,
    margin: u32,
    out: &mut [GridPoint],
) -> Result<Option<usize>, PlanError>
where
    M: IdStore + ?Sized,
    P: IdStore + ?Sized,
{
    let n = plan.len as usize;
    let (start, goal) = (plan.start, plan.goal);
    let square = |i: usize| plan.region(path, i).and_then(|id| regions.square(id));
    let gate = |k: usize| match k {
        0 => Some((start, start)),
        _ if k >= n => Some((goal, goal)),
        _ => portal(square(k - 1)?, square(k)?, margin),
    };
    let (mut count, capacity) = (0usize, out.len());
    let mut funnel = Funnel::at(start, 0);
    let mut k = 1usize;
    while k <= n {
        let Some((l, r)) = gate(k) else {
            return Ok(None);
        };
        let Some((c, ck)) = funnel.narrow(l, r, k) else {
            k += 1;
            continue;
        };
        // A corner equal to the apex adds nothing; one equal to the goal is where the narrowed
        // funnel ends (collinear sides count as crossing), and the goal closes the path anyway.
        if c != funnel.apex && c != goal {
            let slot = out
                .get_mut(count)
                .ok_or(PlanError::PathTooLong { capacity })?;
            *slot = c;
            count += 1;
        }
        funnel = Funnel::at(c, ck);
        k = ck + 1;
    }
    Ok(Some(count))
}

/// Drops points while the shortcut passes [`line_of_sight`], compacting `pts[..k]` in place;
/// returns the number kept.
fn drop_pass<M: IdStore + ?Sized>(
    regions: &Regions<'_, M>,
    start: GridPoint,
    goal: GridPoint,
    pts: &mut [GridPoint],
    k: usize,
) -> usize {
    // Waypoint j: 0 the start, 1 ..= k the points, k + 1 the goal.
    let at = |pts: &[GridPoint], j: usize| match j {
        0 => start,
        _ => pts.get(j - 1).copied().filter(|_| j <= k).unwrap_or(goal),
    };
    let (mut anchor, mut kept, mut j) = (start, 0usize, 1usize);
    while j <= k {
        if line_of_sight(regions, anchor, at(pts, j + 1)) {
            j += 1;
            continue;
        }
        // Keep waypoint j; writing slot `kept` <= j - 1 never touches a point still to read.
        let p = at(pts, j);
        if let Some(slot) = pts.get_mut(kept) {
            *slot = p;
        }
        kept += 1;
        anchor = p;
        j += 1;
    }
    kept
}

/// Whether every cell whose closed square meets the segment `a`-`b` is free.
///
/// Walks the columns the segment spans; in each, the rows between the segment's lowest and
/// highest y there (exact rational bounds, so touching a cell's edge or corner counts).
/// Cost: O(cells along the segment).
pub fn line_of_sight<M: IdStore + ?Sized>(
    regions: &Regions<'_, M>,
    a: GridPoint,
    b: GridPoint,
) -> bool {
    let free = |cx: i32, cy: i32| regions.region_at(cx, cy).is_some();
    line_of_sight_by(regions.width(), regions.height(), free, a, b)
}

/// [`line_of_sight`] over any `width` x `height` cell test `free(x, y)` (the grid planner's,
/// `wave.rs`, whose cells are in no square).
pub(crate) fn line_of_sight_by(
    width: u16,
    height: u16,
    free: impl Fn(i32, i32) -> bool,
    a: GridPoint,
    b: GridPoint,
) -> bool {
    let (a, b) = if a.x <= b.x { (a, b) } else { (b, a) };
    let u = i64::from(UNITS_PER_CELL);
    // An endpoint off the map is in no free cell; this also bounds every product below by
    // (2048 * 256)^2 * 2 < 2^40.
    let (w, h) = (i64::from(width) * u, i64::from(height) * u);
    let inside =
        |p: GridPoint| (0..w).contains(&i64::from(p.x)) && (0..h).contains(&i64::from(p.y));
    if !inside(a) || !inside(b) {
        return false;
    }
    let (x0, x1) = (i64::from(a.x), i64::from(b.x));
    // Column c's closed x-range [c u, (c + 1) u] meets [x0, x1].
    let (c_lo, c_hi) = (ceil_div(x0, u) - 1, x1.div_euclid(u));
    (c_lo..=c_hi).all(|c| {
        let (r_lo, r_hi) = rows_in_column(a, b, c);
        (r_lo..=r_hi).all(|r| match (i32::try_from(c), i32::try_from(r)) {
            (Ok(cx), Ok(cy)) => free(cx, cy),
            _ => false,
        })
    })
}

/// Rows whose closed cells in column `c` meet the segment `a`-`b` (`a.x <= b.x`, both inside
/// the grid, and the column within the segment's x-range), as an inclusive range.
fn rows_in_column(a: GridPoint, b: GridPoint, c: i64) -> (i64, i64) {
    let u = i64::from(UNITS_PER_CELL);
    let (x0, y0, x1, y1) = (
        i64::from(a.x),
        i64::from(a.y),
        i64::from(b.x),
        i64::from(b.y),
    );
    let (dx, dy) = (x1 - x0, y1 - y0);
    let (xa, xb) = (x0.max(c * u), x1.min((c + 1) * u));
    // y over [xa, xb] as numerators over `den` (den = dx, or 1 for a vertical segment); exact.
    let (lo, hi, den) = if dx == 0 {
        (y0.min(y1), y0.max(y1), 1)
    } else {
        let ya = y0 * dx + (xa - x0) * dy;
        let yb = y0 * dx + (xb - x0) * dy;
        (ya.min(yb), ya.max(yb), dx)
    };
    // Row r's closed y-range [r u, (r + 1) u] meets [lo, hi] / den.
    (ceil_div(lo, den * u) - 1, hi.div_euclid(den * u))
}

/// Ceiling of `n / d` for `d > 0`.
#[inline]
fn ceil_div(n: i64, d: i64) -> i64 {
    -(-n).div_euclid(d)
}

/// Length of a polyline given by its points, in grid units (segments rounded up).
pub fn polyline_length(points: impl IntoIterator<Item = GridPoint>) -> u32 {
    let mut it = points.into_iter();
    let Some(mut prev) = it.next() else {
        return 0;
    };
    let mut total = 0u32;
    for p in it {
        total = total.saturating_add(dist_ceil(prev, p));
        prev = p;
    }
    total
}
