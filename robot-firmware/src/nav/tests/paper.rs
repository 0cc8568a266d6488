//! The paper's own scale (seed 004 §5-6): the Micro-Rato'99 arena as a 17 x 17 grid of 0.3 m
//! cells, segmented and planned on from the start corner to the goal light, in `Vec` storage
//! and in the firmware's fixed instance.

extern crate std;

use std::vec::Vec;

use super::reference;
use super::util::{centre, encode, encode_smoothed, parse, tuples, with_adjacency, Seg, VecSearch};
use crate::nav::{Cell, Geometry, GridPoint, Nav64};

use crate::nav::paper_map::MICRO_RATO_99;

fn arena() -> crate::nav::Grid<Vec<u8>> {
    let rows: Vec<std::string::String> =
        MICRO_RATO_99.iter().map(|r| r.replace('B', "#")).collect();
    let refs: Vec<&str> = rows.iter().map(|r| r.as_str()).collect();
    parse(&refs)
}

/// Start: cell (1, 1), in the corner left of the first wall; goal: the free cell beside the
/// light, (9, 8).
fn query() -> (GridPoint, GridPoint) {
    (centre(1, 1), centre(9, 8))
}

#[test]
fn micro_rato_99_segments_by_fig6_and_plans_optimally_over_its_regions() {
    let g = arena();
    let seg = Seg::new(&g).expect("fits");
    assert_eq!(seg.squares, reference::fig6(&g));
    // Pinned: 35 squares, the largest of side 4 along the open rows (cf. seed 004 Fig. 7a).
    assert_eq!(seg.squares.len(), 35);
    assert_eq!(
        tuples(&seg.squares[..4]),
        [(0, 0, 3), (4, 0, 4), (8, 0, 4), (12, 0, 4)]
    );
    let regions = seg.regions(&g);
    let mut s = VecSearch::new(regions.len());
    let (start, goal) = query();
    let plan = s
        .plan(&regions, start, goal)
        .expect("the goal is reachable");
    let ids: Vec<u32> = s.path[..plan.len as usize].to_vec();
    // Pinned: up the left side, along the far rows, into the C-shaped wall through its mouth.
    assert_eq!(ids, [0, 7, 14, 20, 23, 28, 29, 30, 26, 21, 18]);
    assert_eq!(plan.cost, 8551);
    let (from, to) = (ids[0], ids[ids.len() - 1]);
    assert_eq!(
        Some(u64::from(plan.cost)),
        reference::dijkstra(&seg.squares, from, to, start, goal)
    );
    for step in ids.windows(2) {
        let (a, b) = (seg.squares[step[0] as usize], seg.squares[step[1] as usize]);
        assert!(reference::touch(&a, &b), "{a:?} -> {b:?}");
    }
    let smooth = s.smooth(&regions, &plan, 0).expect("fits");
    assert!(smooth.cost <= plan.cost);
    let geo = g.geometry();
    let m = |p: GridPoint| geo.grid_to_metres(p);
    let raw: Vec<(f32, f32)> = plan.waypoints(&regions, &s.path[..]).map(m).collect();
    let smoothed: Vec<(f32, f32)> = smooth.waypoints(&s.points).map(m).collect();
    std::eprintln!("plan {ids:?}\nraw {raw:?}\nsmoothed {smoothed:?}");
    std::eprintln!("raw {} units, smoothed {} units", plan.cost, smooth.cost);
}

#[test]
fn micro_rato_99_gives_the_same_bytes_in_the_firmware_instance() {
    let g = arena();
    let seg = Seg::new(&g).expect("fits");
    let regions = seg.regions(&g);
    let mut s = VecSearch::new(regions.len());
    let (start, goal) = query();
    // The station's way: stored adjacency, h cache, u32 ids.
    let plan = with_adjacency(regions, |adj| s.plan(adj, start, goal)).expect("reachable");
    let smooth = s.smooth(&regions, &plan, 64).expect("fits");

    let mut nav = Nav64::new(Geometry::SEED_004);
    let grid = nav.grid_mut();
    grid.reshape(17, 17).expect("fits 64 x 64");
    for y in 0..17 {
        for x in 0..17 {
            grid.set(x, y, g.get(x, y)).expect("inside");
        }
    }
    assert_eq!(grid.as_bytes()[..g.as_bytes().len()], g.as_bytes()[..]);
    assert_eq!(nav.segment(), Ok(seg.squares.len()));
    let fixed_plan = nav.plan(start, goal).expect("reachable");
    let fixed_smooth = nav.smooth(&fixed_plan, 64).expect("fits");
    assert_eq!(encode(&fixed_plan, nav.path()), encode(&plan, &s.path[..]));
    assert_eq!(
        encode_smoothed(&fixed_smooth, nav.smoothed_points()),
        encode_smoothed(&smooth, &s.points)
    );
    // Changing the map forgets the segmentation until it is redone.
    nav.grid_mut().set(0, 0, Cell::Obstacle).expect("inside");
    assert_eq!(
        nav.plan(start, goal),
        Err(crate::nav::PlanError::NotSegmented)
    );
}
