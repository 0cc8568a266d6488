//! Optional smoothing of a plan: drop waypoints while the shortcut stays collision-free.
//!
//! Layer: after `astar.rs`; reads [`Regions`] (a cell is free exactly when it has a region) and
//! a raw [`Plan`], writes a second region list, so the paper's raw plan (seed 004 §6-7: the
//! trajectory through region centres) stays available beside the smoothed one.
//!
//! Rule: greedy string pulling. From an anchor waypoint, extend to the next waypoint while the
//! straight segment from the anchor to it passes [`line_of_sight`]; when it does not, the last
//! reachable waypoint becomes the new anchor. Segments between consecutive raw waypoints are
//! never tested: seed 004 §6 proves them feasible ("a path through the centers of connected
//! regions is always feasible"), so smoothing never fails for lack of sight and the smoothed
//! length is at most the raw one (rounded-up segment lengths obey the triangle inequality).
//!
//! [`line_of_sight`] is conservative: every cell whose closed square meets the segment must be
//! free, so a segment that grazes an obstacle's corner or runs along its edge is refused.
//! All arithmetic is exact integer arithmetic on grid units.
//!
//! What can fail: the output store is shorter (or its ids narrower) than the plan needs.

use super::astar::{dist_ceil, Plan, PlanError};
use super::grid::{GridPoint, UNITS_PER_CELL};
use super::ids::IdStore;
use super::segment::Regions;

/// Smooths `plan` (whose regions are at the front of `path`); the kept regions go to the front
/// of `out`. The result has the same start and goal, and `cost` is the smoothed length.
pub fn smooth<M, P, Q>(
    regions: &Regions<'_, M>,
    plan: &Plan,
    path: &P,
    out: &mut Q,
) -> Result<Plan, PlanError>
where
    M: IdStore + ?Sized,
    P: IdStore + ?Sized,
    Q: IdStore + ?Sized,
{
    if regions.len() > Q::NONE as usize {
        return Err(PlanError::ScratchTooSmall {
            regions: regions.len(),
            capacity: Q::NONE as usize,
        });
    }
    let last = plan.waypoint_count() - 1;
    let at = |i: usize| plan.waypoint(regions, path, i).unwrap_or(plan.goal);
    let (mut anchor, mut kept, mut cost) = (0usize, 0usize, 0u32);
    let mut j = 1usize;
    while j < last {
        if line_of_sight(regions, at(anchor), at(j + 1)) {
            j += 1;
            continue;
        }
        // Waypoint j (1 ..= len) is region j - 1 of the raw plan.
        if kept >= out.len() {
            return Err(PlanError::PathTooLong {
                capacity: out.len(),
            });
        }
        out.set(kept, path.get(j - 1));
        kept += 1;
        cost = cost.saturating_add(dist_ceil(at(anchor), at(j)));
        anchor = j;
        j = anchor + 1;
    }
    cost = cost.saturating_add(dist_ceil(at(anchor), plan.goal));
    Ok(Plan {
        start: plan.start,
        goal: plan.goal,
        len: u32::try_from(kept).unwrap_or(u32::MAX),
        cost,
    })
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
    let (a, b) = if a.x <= b.x { (a, b) } else { (b, a) };
    let u = i64::from(UNITS_PER_CELL);
    // An endpoint off the map is in no free cell; this also bounds every product below by
    // (2048 * 256)^2 * 2 < 2^40.
    let (w, h) = (
        i64::from(regions.width()) * u,
        i64::from(regions.height()) * u,
    );
    let inside =
        |p: GridPoint| (0..w).contains(&i64::from(p.x)) && (0..h).contains(&i64::from(p.y));
    if !inside(a) || !inside(b) {
        return false;
    }
    let (x0, y0, x1, y1) = (
        i64::from(a.x),
        i64::from(a.y),
        i64::from(b.x),
        i64::from(b.y),
    );
    let (dx, dy) = (x1 - x0, y1 - y0);
    // Column c's closed x-range [c u, (c + 1) u] meets [x0, x1].
    let (c_lo, c_hi) = (ceil_div(x0, u) - 1, x1.div_euclid(u));
    for c in c_lo..=c_hi {
        let (xa, xb) = (x0.max(c * u), x1.min((c + 1) * u));
        // y over [xa, xb] as numerators over `den` (den = dx, or 1 for a vertical segment).
        let (lo, hi, den) = if dx == 0 {
            (y0.min(y1), y0.max(y1), 1)
        } else {
            let ya = y0 * dx + (xa - x0) * dy;
            let yb = y0 * dx + (xb - x0) * dy;
            (ya.min(yb), ya.max(yb), dx)
        };
        // Row r's closed y-range [r u, (r + 1) u] meets [lo, hi] / den.
        let (r_lo, r_hi) = (ceil_div(lo, den * u) - 1, hi.div_euclid(den * u));
        for r in r_lo..=r_hi {
            let free = match (i32::try_from(c), i32::try_from(r)) {
                (Ok(cx), Ok(cy)) => regions.region_at(cx, cy).is_some(),
                _ => false,
            };
            if !free {
                return false;
            }
        }
    }
    true
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
