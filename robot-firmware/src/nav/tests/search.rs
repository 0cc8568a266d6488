//! A* over regions (seed 004 §6) against brute-force Dijkstra, its errors, and smoothing.

extern crate std;

use std::vec;
use std::vec::Vec;

use super::reference;
use super::util::{centre, from_cells, parse, Rng, Seg, VecSearch};
use crate::nav::{
    find_path, line_of_sight, polyline_length, Cell, GridPoint, PlanError, SearchScratch,
};

#[test]
fn a_plan_runs_start_then_region_centres_then_goal() {
    // Square regions: A (0,0,3) on the left, a corridor of 1-cell squares on row 0, B on the
    // right. Start in A, goal in the last corridor square.
    let g = parse(&["......", "...###", "...###"]);
    let seg = Seg::new(&g).expect("fits");
    let regions = seg.regions(&g);
    let mut s = VecSearch::new(regions.len());
    let start = GridPoint { x: 10, y: 700 };
    let goal = centre(5, 0);
    let plan = s.plan(&regions, start, goal).expect("reachable");
    let ids: Vec<u32> = (0..plan.len as usize).map(|i| s.path[i]).collect();
    assert_eq!(ids, [0, 1, 2, 3]);
    let wps: Vec<GridPoint> = plan.waypoints(&regions, &s.path[..]).collect();
    assert_eq!(
        wps,
        [
            start,
            GridPoint { x: 384, y: 384 },
            centre(3, 0),
            centre(4, 0),
            centre(5, 0),
            goal
        ]
    );
    assert_eq!(plan.cost, polyline_length(wps.iter().copied()));
    let metres = g.geometry().grid_to_metres(wps[1]);
    assert_eq!(metres, (0.45, 0.45));
}

#[test]
fn astar_cost_equals_brute_force_dijkstra_over_the_same_graph() {
    let mut rng = Rng(6);
    let mut checked = 0;
    for _ in 0..300 {
        let (w, h) = (2 + rng.below(18) as usize, 2 + rng.below(18) as usize);
        let density = rng.below(45);
        let cells: Vec<Cell> = (0..w * h)
            .map(|_| {
                if rng.below(100) < density {
                    Cell::Obstacle
                } else {
                    Cell::Free
                }
            })
            .collect();
        let g = from_cells(w, h, &cells);
        let seg = Seg::new(&g).expect("fits");
        let regions = seg.regions(&g);
        let mut s = VecSearch::new(regions.len());
        let pick = |rng: &mut Rng| GridPoint {
            x: rng.below(w as u64 * 256) as i32,
            y: rng.below(h as u64 * 256) as i32,
        };
        let (start, goal) = (pick(&mut rng), pick(&mut rng));
        let (Some(from), Some(to)) = (regions.region_of(start), regions.region_of(goal)) else {
            continue;
        };
        let best = reference::dijkstra(&seg.squares, from, to, start, goal);
        match s.plan(&regions, start, goal) {
            Ok(plan) => {
                assert_eq!(Some(u64::from(plan.cost)), best);
                let wps: Vec<GridPoint> = plan.waypoints(&regions, &s.path[..]).collect();
                assert_eq!(plan.cost, polyline_length(wps));
                checked += 1;
            }
            Err(e) => {
                assert_eq!(e, PlanError::Unreachable);
                assert_eq!(best, None);
            }
        }
    }
    assert!(checked > 100, "only {checked} reachable cases");
}

#[test]
fn blocked_and_unreachable_queries_are_typed_errors() {
    let g = parse(&["..#..", "..#..", "..#.?"]);
    let seg = Seg::new(&g).expect("fits");
    let regions = seg.regions(&g);
    let mut s = VecSearch::new(regions.len());
    let (left, right) = (centre(0, 0), centre(4, 0));
    assert_eq!(s.plan(&regions, left, right), Err(PlanError::Unreachable));
    assert_eq!(
        s.plan(&regions, centre(2, 1), right),
        Err(PlanError::StartBlocked)
    );
    assert_eq!(
        s.plan(&regions, left, centre(4, 2)),
        Err(PlanError::GoalBlocked)
    );
    let off_map = GridPoint { x: -1, y: 10 };
    assert_eq!(
        s.plan(&regions, off_map, left),
        Err(PlanError::StartBlocked)
    );
    let past_edge = GridPoint { x: 5 * 256, y: 10 };
    assert_eq!(
        s.plan(&regions, left, past_edge),
        Err(PlanError::GoalBlocked)
    );
}

#[test]
fn storage_too_small_for_the_regions_or_the_plan_is_an_error() {
    let g = parse(&[".....", "#####", "....."]);
    let seg = Seg::new(&g).expect("fits");
    let regions = seg.regions(&g);
    let n = regions.len();
    let (mut f, mut p, mut h, mut q) = (vec![0; n], vec![0u32; n], vec![0u32; n - 1], vec![0; n]);
    let mut scratch = SearchScratch::new(&mut f, &mut p[..], &mut h[..], &mut q[..]);
    let mut path = vec![0u32; n];
    assert_eq!(
        find_path(
            &regions,
            centre(0, 0),
            centre(4, 0),
            &mut scratch,
            &mut path[..]
        ),
        Err(PlanError::ScratchTooSmall {
            regions: n,
            capacity: n - 1
        })
    );
    let mut s = VecSearch::new(n);
    s.path.truncate(2);
    assert_eq!(
        s.plan(&regions, centre(0, 0), centre(4, 0)),
        Err(PlanError::PathTooLong { capacity: 2 })
    );
    let mut s = VecSearch::new(n);
    let plan = s
        .plan(&regions, centre(0, 0), centre(4, 0))
        .expect("reachable");
    let mut small = [0u8; 10];
    assert_eq!(
        plan.encode(&s.path[..], &mut small),
        Err(PlanError::BufferTooSmall {
            needed: plan.encoded_len()
        })
    );
}

#[test]
fn start_and_goal_in_one_region_still_pass_through_its_centre() {
    let g = parse(&["....", "....", "....", "...."]);
    let seg = Seg::new(&g).expect("fits");
    let regions = seg.regions(&g);
    let mut s = VecSearch::new(regions.len());
    let (a, b) = (GridPoint { x: 10, y: 10 }, GridPoint { x: 1000, y: 1000 });
    let plan = s.plan(&regions, a, b).expect("same region");
    assert_eq!(plan.len, 1);
    let wps: Vec<GridPoint> = plan.waypoints(&regions, &s.path[..]).collect();
    assert_eq!(wps, [a, GridPoint { x: 512, y: 512 }, b]);
    // Smoothing drops the centre: the square is convex.
    let smooth = s.smooth(&regions, &plan, 0).expect("fits");
    assert_eq!(smooth.len, 0);
    assert_eq!(smooth.cost, polyline_length([a, b]));
}

#[test]
fn smoothing_pulls_the_path_tight_around_an_inner_corner() {
    // An L-shaped corridor: the obstacle block's corner is at vertex (2, 2) = (512, 512).
    let g = parse(&[".......", ".......", "..#####", "..#####", "..#####"]);
    let seg = Seg::new(&g).expect("fits");
    let regions = seg.regions(&g);
    let mut s = VecSearch::new(regions.len());
    let (start, goal) = (centre(6, 0), centre(0, 4));
    let plan = s.plan(&regions, start, goal).expect("reachable");
    assert!(!line_of_sight(&regions, start, goal));
    let tight = s.smooth(&regions, &plan, 0).expect("fits");
    let corner = GridPoint { x: 512, y: 512 };
    assert_eq!(&s.points[..tight.len as usize], [corner]);
    assert_eq!(tight.cost, polyline_length([start, corner, goal]));
    assert!(tight.cost < plan.cost);
    // With a margin the bend moves off the corner, and every segment keeps clear of the
    // obstacle by the conservative line-of-sight test.
    let loose = s.smooth(&regions, &plan, 64).expect("fits");
    assert!(tight.cost <= loose.cost && loose.cost <= plan.cost);
    let wps: Vec<GridPoint> = loose.waypoints(&s.points).collect();
    assert!(!wps.contains(&corner));
    for pair in wps.windows(2) {
        assert!(line_of_sight(&regions, pair[0], pair[1]), "{pair:?}");
    }
}

#[test]
fn smoothing_bends_the_right_way_through_left_and_right_turns() {
    // A corridor that turns right, then left (an S): a wrong left/right convention in the
    // funnel would cut through the walls.
    let g = parse(&[
        "....####", "....####", "##..####", "##......", "##......", "######..", "######..",
    ]);
    let seg = Seg::new(&g).expect("fits");
    let regions = seg.regions(&g);
    let mut s = VecSearch::new(regions.len());
    for (a, b) in [(centre(0, 0), centre(7, 6)), (centre(7, 6), centre(0, 0))] {
        let plan = s.plan(&regions, a, b).expect("reachable");
        let smooth = s.smooth(&regions, &plan, 32).expect("fits");
        assert!(smooth.cost < plan.cost);
        let wps: Vec<GridPoint> = smooth.waypoints(&s.points).collect();
        for pair in wps.windows(2) {
            assert!(
                line_of_sight(&regions, pair[0], pair[1]),
                "{pair:?} in {wps:?}"
            );
        }
    }
}

#[test]
fn a_smoothed_plan_too_long_for_its_store_is_an_error() {
    let g = parse(&[
        "....####", "....####", "##..####", "##......", "##......", "######..",
    ]);
    let seg = Seg::new(&g).expect("fits");
    let regions = seg.regions(&g);
    let mut s = VecSearch::new(regions.len());
    let plan = s
        .plan(&regions, centre(0, 0), centre(6, 5))
        .expect("reachable");
    let smooth = s.smooth(&regions, &plan, 0).expect("fits");
    assert!(smooth.len >= 1, "the corridor needs a bend");
    let mut none: [GridPoint; 0] = [];
    assert_eq!(
        crate::nav::smooth(&regions, &plan, &s.path[..], 0, &mut none),
        Err(PlanError::PathTooLong { capacity: 0 })
    );
}

#[test]
fn line_of_sight_refuses_edges_and_corners_of_obstacles() {
    let g = parse(&["...", ".#.", "..."]);
    let seg = Seg::new(&g).expect("fits");
    let r = seg.regions(&g);
    let p = |x: i32, y: i32| GridPoint { x, y };
    // Row 0 entirely: clear.
    assert!(line_of_sight(&r, p(10, 100), p(700, 100)));
    // Along the obstacle's top edge (y = 256): touches the obstacle, refused.
    assert!(!line_of_sight(&r, p(10, 256), p(700, 256)));
    // Through the obstacle's corner (256, 256) diagonally from cell (0,0): refused.
    assert!(!line_of_sight(&r, p(128, 128), p(256, 256)));
    // Down column 0: clear; down column 1: blocked.
    assert!(line_of_sight(&r, p(100, 10), p(100, 700)));
    assert!(!line_of_sight(&r, p(300, 10), p(300, 700)));
    // Off the map: refused.
    assert!(!line_of_sight(&r, p(-1, 10), p(100, 10)));
    assert!(!line_of_sight(&r, p(10, 10), p(768, 10)));
}
