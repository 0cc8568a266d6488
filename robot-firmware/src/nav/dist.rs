//! Exact integer distances between grid points, shared by the planners (A*, the region
//! graph's edge costs, the wavefront and the smoother), so a cost computed by one is the same
//! integer in the others.
//!
//! Layer: pure arithmetic on [`GridPoint`]s (1/256 cell), no storage. Cannot fail or panic:
//! distances beyond `u32` saturate.

use super::grid::GridPoint;

/// Floor of the square root of `n`, exact on every platform.
///
/// A float estimate (hardware `sqrtsd` on x86 through `libm`) corrected by one integer step:
/// below 2^52 the estimate is within 1 of the true root, and the correction makes the result
/// the exact integer root whatever the platform's float rounding. Larger inputs (never from
/// grids within `MAX_SIDE`) take core's integer root. Profiling showed the all-integer root
/// at a third of the A* time.
#[inline]
pub(crate) fn isqrt(n: u64) -> u64 {
    if n >= 1 << 52 {
        return n.isqrt();
    }
    let r = libm::sqrt(n as f64) as u64;
    if r * r > n {
        r - 1
    } else if (r + 1) * (r + 1) <= n {
        r + 1
    } else {
        r
    }
}

/// Squared distance; saturates (only for points far outside any grid).
#[inline]
fn dist2(a: GridPoint, b: GridPoint) -> u64 {
    let dx = u64::from(a.x.abs_diff(b.x));
    let dy = u64::from(a.y.abs_diff(b.y));
    (dx * dx).saturating_add(dy * dy)
}

/// Straight-line distance in grid units, rounded down.
#[inline]
pub(crate) fn dist_floor(a: GridPoint, b: GridPoint) -> u32 {
    u32::try_from(isqrt(dist2(a, b))).unwrap_or(u32::MAX)
}

/// Straight-line distance in grid units, rounded up.
#[inline]
pub(crate) fn dist_ceil(a: GridPoint, b: GridPoint) -> u32 {
    let d2 = dist2(a, b);
    let r = isqrt(d2);
    let r = if r * r < d2 { r + 1 } else { r };
    u32::try_from(r).unwrap_or(u32::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integer_root_is_exact_around_squares_and_at_the_extremes() {
        for k in [
            0u64,
            1,
            2,
            3,
            255,
            256,
            65_535,
            1 << 20,
            3_037_000_499,
            (1 << 26) - 1,
        ] {
            let sq = k * k;
            assert_eq!(isqrt(sq), k);
            if k > 0 {
                assert_eq!(isqrt(sq - 1), k - 1);
            }
            assert_eq!(isqrt(sq + 1), k.max(1));
        }
        assert_eq!(isqrt(u64::MAX), u64::MAX.isqrt());
        let far = GridPoint {
            x: i32::MIN,
            y: i32::MIN,
        };
        let near = GridPoint {
            x: i32::MAX,
            y: i32::MAX,
        };
        assert_eq!(dist_floor(far, near), u32::MAX);
        assert_eq!(
            dist_ceil(GridPoint { x: 0, y: 0 }, GridPoint { x: 3, y: 4 }),
            5
        );
        assert_eq!(
            dist_ceil(GridPoint { x: 0, y: 0 }, GridPoint { x: 1, y: 1 }),
            2
        );
        assert_eq!(
            dist_floor(GridPoint { x: 0, y: 0 }, GridPoint { x: 1, y: 1 }),
            1
        );
    }
}
