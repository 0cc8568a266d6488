//! The paper's own case (seed 004 §5-6) through the station's planner: the Micro-Rato'99
//! arena, from the shared data file and from the copy built into the emulator, at 0.3 m cells
//! is the 17 x 17 grid; it is segmented and planned on from the start to the target area, and
//! the raw path is checked cell by cell.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};

use emulator::arena::{Arena, LoadOptions};
use robot_firmware::nav::{Cell, Square};
use station::plan::{MapOptions, NavMap, PlanResult, Planner};

fn shared_file() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/data/arenas/ciberrato/wallsMicRato99.xml")
}

fn builtin_arena() -> Arena {
    emulator::builtin::micro_rato_99(&LoadOptions::default()).unwrap()
}

/// The built-in arena's start pose (the shared lab has no grid file, so no start of its own).
fn builtin_start() -> (f64, f64) {
    let s = builtin_arena().starts[0];
    (s.x, s.y)
}

fn planner_for(spec: &str) -> Planner {
    Planner::new(NavMap::load(spec, &MapOptions::default()).unwrap()).unwrap()
}

/// Whether two squares share an edge segment of positive length.
fn share_an_edge(a: Square, b: Square) -> bool {
    let (ax0, ay0, ax1, ay1) = (a.x, a.y, a.x + a.size, a.y + a.size);
    let (bx0, by0, bx1, by1) = (b.x, b.y, b.x + b.size, b.y + b.size);
    let overlap = |l0: u16, h0: u16, l1: u16, h1: u16| l0.max(l1) < h0.min(h1);
    ((ax1 == bx0 || bx1 == ax0) && overlap(ay0, ay1, by0, by1))
        || ((ay1 == by0 || by1 == ay0) && overlap(ax0, ax1, bx0, bx1))
}

/// Every raw segment, sampled every 1/64 cell, stays in free cells of its two squares, and
/// consecutive squares of the plan are adjacent.
fn assert_feasible(p: &Planner, r: &PlanResult) {
    let map = p.map();
    let n = r.path.len();
    assert!(n >= 1);
    for pair in r.path.windows(2) {
        let (a, b) = (p.squares()[pair[0] as usize], p.squares()[pair[1] as usize]);
        assert!(
            share_an_edge(a, b),
            "regions {pair:?} are not adjacent: {a:?} {b:?}"
        );
    }
    for (k, w) in r.waypoints.windows(2).enumerate() {
        // Segment k joins waypoint k and k + 1: regions path[k - 1] and path[k] (clamped).
        let allowed = [r.path[k.saturating_sub(1)], r.path[k.min(n - 1)]];
        let steps = 64 * 20;
        for i in 0..=steps {
            let t = f64::from(i) / f64::from(steps);
            let pt = (
                w[0].0 + (w[1].0 - w[0].0) * t,
                w[0].1 + (w[1].1 - w[0].1) * t,
            );
            let (cx, cy) = map
                .cell_of(pt)
                .unwrap_or_else(|| panic!("{pt:?} off the map"));
            assert_eq!(
                map.grid.get(cx.into(), cy.into()),
                Cell::Free,
                "{pt:?} in segment {k}"
            );
            let region = p.region_at(cx.into(), cy.into()).unwrap();
            assert!(
                allowed.contains(&region),
                "{pt:?} of segment {k} is in region {region}, not {allowed:?}"
            );
        }
    }
}

fn assert_in_target(arena: &Arena, (x, y): (f64, f64)) {
    let t = arena.target().unwrap();
    let d = (x - t.centre.x).hypot(y - t.centre.y);
    assert!(
        d <= t.radius_m,
        "({x}, {y}) is {d} m from the target centre (radius {})",
        t.radius_m
    );
}

#[test]
fn the_shared_micro_rato_99_file_at_0_3_m_is_the_papers_17_by_17_grid() {
    let p = planner_for(shared_file().to_str().unwrap());
    let m = p.map();
    assert_eq!((m.grid.width(), m.grid.height()), (17, 17));
    assert_eq!(m.cell_m(), 0.3);
    assert_eq!(m.origin(), (0.0, 0.0));
    // The beacon's cell is an obstacle (seed 004 §6); the squares cover exactly the free cells.
    assert_eq!(m.beacon_cells, vec![(10, 8)]);
    let covered: usize = p.squares().iter().map(|s| usize::from(s.size).pow(2)).sum();
    assert_eq!(covered, m.counts().0);
}

#[test]
fn the_shared_file_plans_from_the_start_into_the_target_through_adjacent_free_squares() {
    let p = planner_for(shared_file().to_str().unwrap());
    let r = p.plan(Some(builtin_start()), None, true).unwrap();
    assert_eq!(r.start(), (0.5, 0.5));
    let arena = emulator::arena::load(&shared_file(), &LoadOptions::default()).unwrap();
    assert_in_target(&arena, r.goal());
    assert_in_target(
        &arena,
        *r.smoothed.as_ref().unwrap().waypoints.last().unwrap(),
    );
    assert_feasible(&p, &r);
}

#[test]
fn the_built_in_copy_gives_the_same_grid_and_the_same_plan_from_its_own_start() {
    let built_in = planner_for(emulator::builtin::MICRO_RATO_99);
    let file = planner_for(shared_file().to_str().unwrap());
    assert_eq!(built_in.map().grid, file.map().grid);
    assert_eq!(built_in.squares(), file.squares());
    let a = built_in.plan(None, None, false).unwrap();
    let b = file.plan(Some(builtin_start()), None, false).unwrap();
    assert_eq!((a.path.clone(), a.waypoints.clone()), (b.path, b.waypoints));
    assert_in_target(&builtin_arena(), a.goal());
    assert_feasible(&built_in, &a);
}

#[test]
fn plans_to_any_free_point_stay_in_free_cells_of_adjacent_squares() {
    let p = planner_for(emulator::builtin::MICRO_RATO_99);
    let m = p.map().clone();
    let mut planned = 0;
    for cy in 0..m.grid.height() {
        for cx in 0..m.grid.width() {
            if m.grid.get(cx.into(), cy.into()) != Cell::Free {
                continue;
            }
            let goal = (0.15 + 0.3 * f64::from(cx), 0.15 + 0.3 * f64::from(cy));
            let r = p.plan(None, Some(goal), true).unwrap();
            assert_feasible(&p, &r);
            let s = r.smoothed.unwrap();
            assert!(s.length_m <= r.length_m + 1e-9);
            planned += 1;
        }
    }
    assert_eq!(planned, m.counts().0);
}
