//! The grid planner (`wave.rs`) and the robot's instance on 64 x 64 maps whose squares do not
//! fit its `NAV64_REGIONS` (255): the worst case of `max_regions` (3072 squares) and random maps.

extern crate std;

use std::collections::VecDeque;
use std::vec;
use std::vec::Vec;

use super::util::{lattice, parse, Rng, Seg};
use crate::nav::fixed::NAV64_REGIONS;
use crate::nav::smooth::line_of_sight_by;
use crate::nav::{
    max_regions, wave_bytes, wave_first_waypoint, wave_plan, Cell, Geometry, Grid, GridPoint,
    Nav64, Passable, PlanError, Route, SegmentError, WavePlan, WaveRoute, NAV64_BYTES,
    UNITS_PER_CELL,
};

/// Waypoints a Plan object of the robot holds with no regions: (3124 - 36) / 8.
const OBJECT_WAYPOINTS: usize = 386;

/// Shortest 4-connected path between two free cells, in steps (a plain BFS over `Vec`s).
fn bfs_steps<S: AsRef<[u8]>>(g: &Grid<S>, from: (usize, usize), to: (usize, usize)) -> Option<u32> {
    let (w, h) = (usize::from(g.width()), usize::from(g.height()));
    let mut dist = vec![u32::MAX; w * h];
    let mut q = VecDeque::new();
    dist[from.1 * w + from.0] = 0;
    q.push_back(from);
    while let Some((x, y)) = q.pop_front() {
        let d = dist[y * w + x];
        if (x, y) == to {
            return Some(d);
        }
        let n = [
            (x + 1, y),
            (x.wrapping_sub(1), y),
            (x, y + 1),
            (x, y.wrapping_sub(1)),
        ];
        for (nx, ny) in n {
            if nx < w && ny < h && g.get(nx, ny) == Cell::Free && dist[ny * w + nx] == u32::MAX {
                dist[ny * w + nx] = d + 1;
                q.push_back((nx, ny));
            }
        }
    }
    None
}

/// Every consecutive pair of waypoints is either in line of sight (every cell its closed
/// segment meets is free) or one step between neighbouring free cells' centres, or inside
/// one free cell: the polyline never crosses an obstacle or an unknown cell.
fn assert_feasible<S: AsRef<[u8]>>(g: &Grid<S>, pts: &[GridPoint], what: &str) {
    let free = |x: i32, y: i32| g.contains(x, y) && g.get(x as usize, y as usize) == Cell::Free;
    for pair in pts.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let (ca, cb) = (a.cell(), b.cell());
        let manhattan = (ca.0 - cb.0).abs() + (ca.1 - cb.1).abs();
        let ok = line_of_sight_by(g.width(), g.height(), free, a, b)
            || (manhattan <= 1 && free(ca.0, ca.1) && free(cb.0, cb.1));
        assert!(ok, "{what}: segment {a:?} -> {b:?} crosses a blocked cell");
    }
}

/// Plans with the robot's instance and checks the plan against the reference BFS.
fn plan_on_nav64(nav: &mut Nav64, from: (u16, u16), to: (u16, u16), what: &str) -> Vec<GridPoint> {
    let (s, g) = (
        GridPoint::cell_centre(from.0, from.1),
        GridPoint::cell_centre(to.0, to.1),
    );
    let route = nav.route(s, g).unwrap_or_else(|e| panic!("{what}: {e}"));
    let Route::Grid(plan) = route else {
        panic!("{what}: expected the grid planner, got {route:?}");
    };
    let want = bfs_steps(
        nav.grid(),
        (usize::from(from.0), usize::from(from.1)),
        (usize::from(to.0), usize::from(to.1)),
    );
    assert_eq!(Some(plan.steps), want, "{what}: a shortest cell path");
    let pts: Vec<GridPoint> = nav
        .wave_route(plan)
        .expect("labels kept")
        .waypoints()
        .collect();
    assert_eq!(pts.len(), plan.waypoint_count(), "{what}");
    assert_eq!((pts[0], pts[pts.len() - 1]), (s, g), "{what}");
    assert!(
        pts.len() <= OBJECT_WAYPOINTS,
        "{what}: {} waypoints",
        pts.len()
    );
    assert_feasible(nav.grid(), &pts, what);
    // Never longer than the cell path itself (the waypoints only cut its corners).
    assert!(
        plan.cost <= (plan.steps + 1) * UNITS_PER_CELL as u32,
        "{what}"
    );
    pts
}

fn load(nav: &mut Nav64, src: &Grid<Vec<u8>>) {
    let g = nav.grid_mut();
    g.reshape(src.width(), src.height()).expect("fits");
    for y in 0..usize::from(src.height()) {
        for x in 0..usize::from(src.width()) {
            g.set(x, y, src.get(x, y)).expect("inside");
        }
    }
}

#[test]
fn the_worst_case_64_by_64_map_plans_in_the_robot_instance_without_more_memory() {
    let board = lattice(64, 64);
    assert_eq!(
        Seg::new(&board).expect("fits").squares.len(),
        max_regions(64, 64)
    );
    let mut nav = Nav64::new(Geometry::SEED_004);
    load(&mut nav, &board);
    assert_eq!(
        nav.segment(),
        Err(SegmentError::TooManyRegions {
            capacity: NAV64_REGIONS
        })
    );
    for (from, to) in [
        ((0, 0), (62, 62)),
        ((0, 62), (62, 0)),
        ((63, 0), (0, 63)),
        ((32, 32), (0, 1)),
        ((10, 0), (10, 0)),
    ] {
        let pts = plan_on_nav64(
            &mut nav,
            from,
            to,
            &std::format!("lattice {from:?}->{to:?}"),
        );
        // Free rows and columns are even: the path is a few straight runs, not a staircase.
        assert!(pts.len() <= 5, "{from:?}->{to:?}: {pts:?}");
    }
    // No state of its own: the grid planner runs in the region map's bytes.
    #[cfg(target_pointer_width = "64")]
    assert_eq!(NAV64_BYTES, 10_776);
}

#[test]
fn random_64_by_64_maps_plan_whatever_their_square_count() {
    let mut rng = Rng(64);
    let (mut grid_plans, mut square_plans) = (0, 0);
    for k in 0..30 {
        // Obstacle densities from 0.1 to 30 %: square counts from far below to far above the robot's 255.
        let density = [1, 3, 5, 10, 20, 35, 50, 100, 200, 300][k % 10];
        let mut g = lattice(64, 64);
        for y in 0..64 {
            for x in 0..64 {
                let c = if rng.below(1000) < density {
                    Cell::Obstacle
                } else {
                    Cell::Free
                };
                g.set(x, y, c).expect("inside");
            }
        }
        let squares = Seg::new(&g).expect("fits").squares.len();
        let free: Vec<(u16, u16)> = (0..64 * 64)
            .map(|i| ((i % 64) as u16, (i / 64) as u16))
            .filter(|&(x, y)| g.get(usize::from(x), usize::from(y)) == Cell::Free)
            .collect();
        let mut nav = Nav64::new(Geometry::SEED_004);
        load(&mut nav, &g);
        for _ in 0..4 {
            let from = free[rng.below(free.len() as u64) as usize];
            let to = free[rng.below(free.len() as u64) as usize];
            let (s, t) = (
                GridPoint::cell_centre(from.0, from.1),
                GridPoint::cell_centre(to.0, to.1),
            );
            let reachable = bfs_steps(
                &g,
                (usize::from(from.0), usize::from(from.1)),
                (usize::from(to.0), usize::from(to.1)),
            );
            let what = std::format!("map {k} ({squares} squares) {from:?}->{to:?}");
            match (nav.route(s, t), reachable) {
                (Ok(Route::Squares(_)), Some(_)) => {
                    assert!(squares <= NAV64_REGIONS, "{what}");
                    square_plans += 1;
                }
                (Ok(Route::Grid(_)), Some(_)) => {
                    assert!(
                        squares > NAV64_REGIONS,
                        "{what}: squares fit, yet the grid planner ran"
                    );
                    plan_on_nav64(&mut nav, from, to, &what);
                    grid_plans += 1;
                }
                (Err(PlanError::Unreachable), None) => {}
                (got, want) => panic!("{what}: {got:?}, reference {want:?}"),
            }
        }
    }
    // Both methods ran, so the test sees the switch from one to the other.
    assert!(
        grid_plans >= 20 && square_plans >= 20,
        "{grid_plans} / {square_plans}"
    );
}

#[test]
fn squares_and_a_star_stay_the_method_where_they_fit() {
    let g = parse(&[
        ".....", //
        ".###.", //
        ".....",
    ]);
    let mut nav = Nav64::new(Geometry::SEED_004);
    load(&mut nav, &g);
    let (s, t) = (GridPoint::cell_centre(0, 1), GridPoint::cell_centre(4, 1));
    let Ok(Route::Squares(plan)) = nav.route(s, t) else {
        panic!("seed 004's method on a map whose squares fit");
    };
    assert_eq!(nav.plan(s, t), Ok(plan));
    assert!(nav
        .wave_route(WavePlan {
            start: s,
            goal: t,
            points: 0,
            steps: 0,
            cost: 0
        })
        .is_none());
}

#[test]
fn blocked_points_unreachable_goals_and_small_scratch_are_errors() {
    let g = parse(&[
        "..#..", //
        "..#..", //
        "..#.#",
    ]);
    let c = GridPoint::cell_centre;
    let mut scratch = vec![0u8; wave_bytes(g.len())];
    let plan = |a, b, s: &mut [u8]| wave_plan(&g, Passable::Free, a, b, s);
    assert_eq!(
        plan(c(0, 0), c(4, 0), &mut scratch),
        Err(PlanError::Unreachable)
    );
    assert_eq!(
        plan(c(2, 0), c(0, 0), &mut scratch),
        Err(PlanError::StartBlocked)
    );
    assert_eq!(
        plan(c(0, 0), c(4, 2), &mut scratch),
        Err(PlanError::GoalBlocked)
    );
    let off = GridPoint { x: -1, y: 0 };
    assert_eq!(
        plan(off, c(0, 0), &mut scratch),
        Err(PlanError::StartBlocked)
    );
    assert!(matches!(
        plan(c(0, 0), c(1, 2), &mut scratch[..3]),
        Err(PlanError::ScratchTooSmall { .. })
    ));
    let ok = plan(c(0, 0), c(1, 2), &mut scratch).expect("plans");
    assert_eq!(ok.steps, 3);
    // Unknown cells are passable only when asked for.
    let u = parse(&["..?.."]);
    let mut s2 = vec![0u8; wave_bytes(u.len())];
    let (a, b) = (c(0, 0), c(4, 0));
    assert_eq!(
        wave_plan(&u, Passable::Free, a, b, &mut s2),
        Err(PlanError::Unreachable)
    );
    let p = wave_plan(&u, Passable::FreeOrUnknown, a, b, &mut s2).expect("plans");
    let pts: Vec<_> = WaveRoute::new(&u, Passable::FreeOrUnknown, &s2, p)
        .waypoints()
        .collect();
    assert_eq!(pts, vec![a, b], "one straight segment");
}

#[test]
fn a_serpentine_gives_one_waypoint_per_bend() {
    // 1-cell corridors joined at alternate ends: the longest path on its map.
    let rows: Vec<std::string::String> = (0..15)
        .map(|y| match y % 4 {
            1 => "##############.".into(),
            3 => ".##############".into(),
            _ => "...............".into(),
        })
        .collect();
    let rows: Vec<&str> = rows.iter().map(|r| r.as_str()).collect();
    let g = parse(&rows);
    let mut scratch = vec![0u8; wave_bytes(g.len())];
    let (a, b) = (GridPoint::cell_centre(0, 0), GridPoint::cell_centre(14, 14));
    let p = wave_plan(&g, Passable::Free, a, b, &mut scratch).expect("plans");
    assert_eq!(Some(p.steps), bfs_steps(&g, (0, 0), (14, 14)));
    let pts: Vec<_> = WaveRoute::new(&g, Passable::Free, &scratch, p)
        .waypoints()
        .collect();
    assert_feasible(&g, &pts, "serpentine");
    // Start, two bends at each of the 7 corridor changes but the last (its drop ends at the
    // goal), goal.
    assert_eq!(pts.len(), 1 + 7 * 2 - 1 + 1, "{pts:?}");
    assert!(
        pts.iter().all(|p| p.x == 128 || p.x == 14 * 256 + 128),
        "{pts:?}"
    );
}

#[test]
fn the_first_waypoint_alone_is_the_full_plans_and_so_is_its_length() {
    // The search's replan (issue 32) takes only the route's first point and length: the same
    // as the whole plan's, on maps with a straight way, one bend and a serpentine.
    let serpentine: Vec<std::string::String> = (0..15)
        .map(|y| match y % 4 {
            1 => "?????????????#.".into(),
            3 => ".#????????????#".into(),
            _ => "...............".into(),
        })
        .collect();
    let maps: [Vec<&str>; 3] = [
        vec!["?????????", "?????????", "?????????"],
        vec!["....#....", "....#....", "........."],
        serpentine.iter().map(|r| r.as_str()).collect(),
    ];
    for rows in &maps {
        let g = parse(rows);
        let (w, h) = (g.width() - 1, g.height() - 1);
        let (a, b) = (GridPoint::cell_centre(0, 0), GridPoint::cell_centre(w, h));
        let mut scratch = vec![0u8; wave_bytes(g.len())];
        let p = wave_plan(&g, Passable::FreeOrUnknown, a, b, &mut scratch).expect("plans");
        let second = WaveRoute::new(&g, Passable::FreeOrUnknown, &scratch, p)
            .waypoints()
            .nth(1);
        let (first, steps) =
            wave_first_waypoint(&g, Passable::FreeOrUnknown, a, b, &mut scratch).expect("plans");
        assert_eq!((Some(first), steps), (second, p.steps), "{rows:?}");
    }
}
