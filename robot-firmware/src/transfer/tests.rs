extern crate std;

use std::borrow::ToOwned;

use super::*;
use crate::nav::fixed::NAV64_REGIONS;
use crate::nav::{Cell, NAV64_BYTES};

#[test]
fn the_object_capacity_holds_the_longest_nav64_plan() {
    assert_eq!(
        plan_object_len(256, 258),
        Some(OBJECT_CAPACITY),
        "nav::fixed::NAV64_PATH regions and their waypoints"
    );
    const {
        assert!(
            12 + 6 * NAV64_REGIONS <= OBJECT_CAPACITY,
            "NAV64_REGIONS squares"
        )
    };
    const { assert!(NAV64_BYTES + 3 * OBJECT_CAPACITY < 25_000) };
}

#[test]
fn a_map_changed_in_place_gets_the_id_of_its_new_content() {
    let mut o = Objects::new();
    assert!(o.grid_mut().is_none(), "no map, nothing to change");
    let mut g = Grid::new(4, 4, Geometry::SEED_004, [0u8; 4]).expect("fits");
    let first = o.set_map(&g, None, None).expect("fits");
    if let Some(grid) = o.grid_mut() {
        grid.set(1, 2, Cell::Free).expect("inside");
    }
    g.set(1, 2, Cell::Free).expect("inside");
    let id = o.map().map(|m| m.id);
    assert_eq!(id, map_object_crc(&g, None, None).ok());
    assert_ne!(id, Some(first));
}

#[test]
fn a_new_goal_is_where_a_plan_with_no_goal_ends_and_changes_the_maps_id() {
    let mut o = Objects::new();
    let mut g = Grid::new(5, 1, Geometry::SEED_004, [0u8; 2]).expect("fits");
    g.fill(Cell::Free);
    g.set(4, 0, Cell::Unknown).expect("inside");
    let pt = |x_mm| PointMm { x_mm, y_mm: 150 };
    let first = o.set_map(&g, None, Some(pt(1350))).expect("fits");
    // The goal given with the map lies in a cell nobody has seen.
    assert_eq!(o.plan_route(pt(150), None), Err(NackReason::BadPoint));
    o.set_goal(pt(1050));
    let id = o.map().map(|m| m.id);
    assert_eq!(id, map_object_crc(&g, None, Some(pt(1050))).ok());
    assert_ne!(id, Some(first));
    o.plan_route(pt(150), None).expect("plans");
    let (_, view) = o.plan().expect("installed");
    assert_eq!(view.waypoint(view.waypoint_count() - 1), Some(pt(1050)));
}

#[test]
fn a_plan_object_embeds_plan_encode_verbatim_and_a_refusal_writes_nothing() {
    let mut o = Objects::new();
    let mut g = Grid::new(5, 1, Geometry::SEED_004, [0u8; 2]).expect("fits");
    g.fill(Cell::Free);
    o.set_map(&g, None, None).expect("fits");
    let from = PointMm {
        x_mm: 150,
        y_mm: 150,
    };
    let to = PointMm {
        x_mm: 1350,
        y_mm: 150,
    };
    let id = o.plan_route(from, Some(to)).expect("plans");
    let mut nav = [0u8; 64];
    let plan = o
        .nav
        .plan(GridPoint::cell_centre(0, 0), GridPoint::cell_centre(4, 0));
    let n = plan
        .expect("plans")
        .encode(o.nav.path(), &mut nav)
        .expect("fits");
    let (got, view) = o.plan().expect("installed");
    assert_eq!(got, id);
    assert_eq!(view.nav_block(), &nav[..n]);
    assert_eq!(view.waypoint(0), Some(from));
    assert_eq!(view.waypoint(view.waypoint_count() - 1), Some(to));
    let before = o.plan_bytes().to_owned();
    let outside = PointMm {
        x_mm: 9000,
        y_mm: 150,
    };
    assert_eq!(o.plan_route(from, Some(outside)), Err(NackReason::BadPoint));
    assert_eq!(o.plan_bytes(), &before[..]);
}

#[test]
fn the_robot_plans_on_the_worst_case_64_by_64_map_and_the_plan_says_it_has_no_squares() {
    // Cell (odd, odd) of every 2 x 2 block blocked: every free cell is a square of its own,
    // 3072 squares (`nav::max_regions(64, 64)`), six times what `Nav64` holds.
    let mut g = Grid::new(64, 64, Geometry::SEED_004, [0u8; GRID_BYTES]).expect("fits");
    for y in 0..64 {
        for x in 0..64 {
            let c = if x % 2 == 1 && y % 2 == 1 {
                Cell::Obstacle
            } else {
                Cell::Free
            };
            g.set(x, y, c).expect("inside");
        }
    }
    let mut o = Objects::new();
    o.set_map(&g, None, None).expect("fits");
    // The Regions object cannot be held, and Segment says so.
    assert_eq!(o.segment(), Err(NackReason::CapacityExceeded));
    let mm = |c: i32| c * 300 + 150;
    let from = PointMm {
        x_mm: mm(0),
        y_mm: mm(0),
    };
    let to = PointMm {
        x_mm: mm(62),
        y_mm: mm(61),
    };
    let id = o.plan_route(from, Some(to)).expect("plans");
    let (got, view) = o.plan().expect("installed");
    assert_eq!(got, id);
    // No regions and flagged as not region centres: the grid planner made it.
    assert_eq!((view.nav.regions, view.meta.smoothed), (0, true));
    let pts: std::vec::Vec<PointMm> = view.waypoints().collect();
    assert_eq!((pts[0], pts[pts.len() - 1]), (from, to));
    // Along free row 0 or column 62, then down or across: one bend.
    assert_eq!(pts.len(), 3, "{pts:?}");
    let cost = view.nav.cost as usize;
    assert_eq!(
        cost,
        (62 + 61) * 256,
        "a shortest path along the free rows and columns"
    );
}

#[test]
fn a_grid_plan_with_more_waypoints_than_the_plan_object_holds_is_refused_and_changes_nothing() {
    // Diagonal 1-cell staircase corridors (x - y = 3k, 3k + 1) joined at alternate ends:
    // every cell of a staircase is a bend (corner contact is no passage), so the path
    // from one corner to the other needs about 2,700 waypoints, more than the 386 a Plan
    // object of OBJECT_CAPACITY bytes holds (the search itself succeeds).
    let mut g = Grid::new(64, 64, Geometry::SEED_004, [0u8; GRID_BYTES]).expect("fits");
    for y in 0..64i32 {
        for x in 0..64i32 {
            let d = x - y;
            let mut free = d.rem_euclid(3) != 2;
            if !free {
                let k = (d - 2).div_euclid(3);
                let (top, bottom) = (d.max(0), (63 + d).min(63));
                free = x == if k % 2 == 0 { top } else { bottom };
            }
            let c = if free { Cell::Free } else { Cell::Obstacle };
            g.set(x as usize, y as usize, c).expect("inside");
        }
    }
    let mut o = Objects::new();
    o.set_map(&g, None, None).expect("fits");
    let mm = |c: i32| c * 300 + 150;
    let near = PointMm {
        x_mm: mm(1),
        y_mm: mm(0),
    };
    let from = PointMm {
        x_mm: mm(0),
        y_mm: mm(0),
    };
    o.plan_route(from, Some(near)).expect("a short plan fits");
    let before = o.plan_bytes().to_owned();
    let (far_from, far_to) = (
        PointMm {
            x_mm: mm(0),
            y_mm: mm(63),
        },
        PointMm {
            x_mm: mm(63),
            y_mm: mm(0),
        },
    );
    assert_eq!(
        o.plan_route(far_from, Some(far_to)),
        Err(NackReason::CapacityExceeded)
    );
    assert_eq!(o.plan_bytes(), &before[..], "the old plan stays");
}
