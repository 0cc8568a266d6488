//! The Plan object (PROTOCOL.md §12): header, the nav `Plan::encode` block, waypoints in mm.
//!
//! Invariants: region and waypoint counts are bounded by the bytes before any offset is
//! computed from them, so an absurd count is an error, never an overflow or a panic.

use super::{
    check_len, check_prefix, i32_at, output, point_at, put, put_point, u16_at, u32_at, u8_at,
    ObjectError, Problem, OBJECT_VERSION, PLAN_HEADER_LEN, PLAN_NAV_HEADER_LEN, WAYPOINT_LEN,
};
use crate::msg::{ObjectKind, PointMm};

/// Plan flag: the waypoints are a smoothed path, not the region centres.
const PLAN_SMOOTHED: u8 = 1 << 0;

/// The Plan header fields outside the navigation block.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PlanMeta {
    /// The waypoints are a smoothed path (else: start, region centres, goal; seed 004 §7).
    pub smoothed: bool,
    /// Id of the map the plan was made on; 0 when unknown.
    pub map_id: u32,
}

/// The fixed part of the navigation block (`robot_firmware::nav::Plan`): points in 1/256 of a
/// cell relative to the map's origin corner, the region count and the cost in the same unit.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NavPlan {
    pub start: [i32; 2],
    pub goal: [i32; 2],
    pub regions: u32,
    pub cost: u32,
}

/// Length of a plan object with `regions` region ids and `waypoints` waypoints.
pub fn plan_object_len(regions: u32, waypoints: usize) -> Option<usize> {
    let ids = usize::try_from(regions).ok()?.checked_mul(4)?;
    let pts = waypoints.checked_mul(WAYPOINT_LEN)?;
    (PLAN_HEADER_LEN + PLAN_NAV_HEADER_LEN + 4)
        .checked_add(ids)?
        .checked_add(pts)
}

/// Reads the navigation block's fixed part at `at`.
fn nav_at(b: &[u8], at: usize) -> Result<NavPlan, ObjectError> {
    Ok(NavPlan {
        start: [i32_at(b, at)?, i32_at(b, at + 4)?],
        goal: [i32_at(b, at + 8)?, i32_at(b, at + 12)?],
        regions: u32_at(b, at + 16)?,
        cost: u32_at(b, at + 20)?,
    })
}

/// Completes a plan object in place. `out[8..8 + nav_len]` must already hold the navigation
/// block as `robot_firmware::nav::Plan::encode` writes it (24 bytes + 4 per region); this
/// writes the 8-byte header in front and the waypoint list after it. Returns the length.
pub fn finish_plan<W>(
    out: &mut [u8],
    meta: PlanMeta,
    nav_len: usize,
    waypoints: W,
) -> Result<usize, ObjectError>
where
    W: IntoIterator<Item = PointMm>,
    W::IntoIter: ExactSizeIterator,
{
    let waypoints = waypoints.into_iter();
    let count = waypoints.len();
    let nav = nav_at(out, PLAN_HEADER_LEN)?;
    let tail = PLAN_HEADER_LEN + nav_len;
    if plan_object_len(nav.regions, 0) != Some(tail + 4) {
        return Err(ObjectError::at(
            PLAN_HEADER_LEN + 16,
            Problem::CountMismatch,
        ));
    }
    let n = u16::try_from(count).map_err(|_| ObjectError::at(tail, Problem::CountMismatch))?;
    if n == 0 {
        return Err(ObjectError::at(tail, Problem::NoWaypoints));
    }
    let needed = tail + 4 + count * WAYPOINT_LEN;
    let out = output(out, needed)?;
    let flags = if meta.smoothed { PLAN_SMOOTHED } else { 0 };
    put(out, 0, &[OBJECT_VERSION, ObjectKind::Plan as u8, flags, 0]);
    put(out, 4, &meta.map_id.to_le_bytes());
    put(out, tail, &n.to_le_bytes());
    put(out, tail + 2, &[0, 0]);
    for (i, p) in waypoints.enumerate().take(count) {
        put_point(out, tail + 4 + i * WAYPOINT_LEN, p);
    }
    Ok(needed)
}

/// Encodes a whole plan object from its parts (for writers without the nav code).
pub fn encode_plan<R, W>(
    meta: PlanMeta,
    nav: &NavPlan,
    regions: R,
    waypoints: W,
    out: &mut [u8],
) -> Result<usize, ObjectError>
where
    R: IntoIterator<Item = u32>,
    R::IntoIter: ExactSizeIterator,
    W: IntoIterator<Item = PointMm>,
    W::IntoIter: ExactSizeIterator,
{
    let (regions, waypoints) = (regions.into_iter(), waypoints.into_iter());
    if u32::try_from(regions.len()) != Ok(nav.regions) {
        return Err(ObjectError::at(
            PLAN_HEADER_LEN + 16,
            Problem::CountMismatch,
        ));
    }
    let needed = plan_object_len(nav.regions, waypoints.len()).ok_or(ObjectError::at(
        PLAN_HEADER_LEN + 16,
        Problem::CountMismatch,
    ))?;
    output(out, needed)?;
    let nav_len = PLAN_NAV_HEADER_LEN + regions.len() * 4;
    let at = PLAN_HEADER_LEN;
    for (k, v) in [nav.start[0], nav.start[1], nav.goal[0], nav.goal[1]]
        .iter()
        .enumerate()
    {
        put(out, at + 4 * k, &v.to_le_bytes());
    }
    put(out, at + 16, &nav.regions.to_le_bytes());
    put(out, at + 20, &nav.cost.to_le_bytes());
    for (i, id) in regions.enumerate() {
        put(out, at + PLAN_NAV_HEADER_LEN + 4 * i, &id.to_le_bytes());
    }
    finish_plan(out, meta, nav_len, waypoints)
}

/// A parsed Plan object.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PlanView<'a> {
    pub meta: PlanMeta,
    pub nav: NavPlan,
    bytes: &'a [u8],
    waypoints: u16,
}

impl<'a> PlanView<'a> {
    /// Checks `bytes` as a Plan object.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, ObjectError> {
        check_prefix(bytes, ObjectKind::Plan)?;
        let flags = u8_at(bytes, 2)?;
        if flags & !PLAN_SMOOTHED != 0 {
            return Err(ObjectError::at(2, Problem::ReservedNotZero));
        }
        if u8_at(bytes, 3)? != 0 {
            return Err(ObjectError::at(3, Problem::ReservedNotZero));
        }
        let meta = PlanMeta {
            smoothed: flags & PLAN_SMOOTHED != 0,
            map_id: u32_at(bytes, 4)?,
        };
        let nav = nav_at(bytes, PLAN_HEADER_LEN)?;
        // The region count is untrusted: bound it by the bytes before computing offsets.
        let tail = plan_object_len(nav.regions, 0)
            .filter(|&t| t <= bytes.len())
            .map(|t| t - 4)
            .ok_or(ObjectError::at(
                PLAN_HEADER_LEN + 16,
                Problem::Truncated {
                    needed: plan_object_len(nav.regions, 0).unwrap_or(usize::MAX),
                },
            ))?;
        let waypoints = u16_at(bytes, tail)?;
        if u16_at(bytes, tail + 2)? != 0 {
            return Err(ObjectError::at(tail + 2, Problem::ReservedNotZero));
        }
        if waypoints == 0 {
            return Err(ObjectError::at(tail, Problem::NoWaypoints));
        }
        let needed = tail + 4 + usize::from(waypoints) * WAYPOINT_LEN;
        check_len(bytes.len(), needed)?;
        Ok(PlanView {
            meta,
            nav,
            bytes,
            waypoints,
        })
    }

    /// The navigation block exactly as `nav::Plan::encode` wrote it.
    pub fn nav_block(&self) -> &'a [u8] {
        let end = PLAN_HEADER_LEN + PLAN_NAV_HEADER_LEN + self.nav.regions as usize * 4;
        self.bytes.get(PLAN_HEADER_LEN..end).unwrap_or(&[])
    }

    /// Region `i` of the plan (an index into the Regions object of the same map).
    pub fn region(&self, i: u32) -> Option<u32> {
        if i >= self.nav.regions {
            return None;
        }
        u32_at(
            self.bytes,
            PLAN_HEADER_LEN + PLAN_NAV_HEADER_LEN + 4 * i as usize,
        )
        .ok()
    }

    /// Number of waypoints (at least 1).
    pub fn waypoint_count(&self) -> u16 {
        self.waypoints
    }

    /// Waypoint `i` in map-frame millimetres.
    pub fn waypoint(&self, i: u16) -> Option<PointMm> {
        if i >= self.waypoints {
            return None;
        }
        let tail = PLAN_HEADER_LEN + PLAN_NAV_HEADER_LEN + self.nav.regions as usize * 4;
        point_at(self.bytes, tail + 4 + usize::from(i) * WAYPOINT_LEN).ok()
    }

    /// The waypoints in order.
    pub fn waypoints(&self) -> impl Iterator<Item = PointMm> + 'a {
        let view = *self;
        (0..self.waypoints).filter_map(move |i| view.waypoint(i))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plan_count_that_overflows_is_an_error_not_a_panic() {
        let mut b = [0u8; 40];
        b[0] = OBJECT_VERSION;
        b[1] = 1;
        b[24..28].copy_from_slice(&u32::MAX.to_le_bytes());
        let e = PlanView::parse(&b).expect_err("absurd count");
        assert_eq!(e.offset, 24);
        assert!(matches!(e.problem, Problem::Truncated { .. }));
    }
}
