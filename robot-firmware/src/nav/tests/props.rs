//! Property tests on random grids: segmentation invariants, plans over adjacent regions with
//! optimal cost, sound line of sight, and byte-identical plans from fixed and `Vec` storage.

extern crate std;

use std::collections::BTreeSet;
use std::vec;
use std::vec::Vec;

use proptest::collection::vec as pvec;
use proptest::prelude::*;

use super::reference;
use super::util::{encode, encode_smoothed, from_cells, with_adjacency, Seg, VecSearch};
use crate::nav::{
    line_of_sight, polyline_length, Cell, Geometry, Grid, GridPoint, Nav64, Plan, PlanError,
    Regions, SegmentError, Smoothed, UNITS_PER_CELL,
};

/// Width, height, cells (more or fewer obstacles per case, some unknown), and two selectors
/// (index, sub-cell offsets) for start and goal.
type Case = (
    usize,
    usize,
    Vec<Cell>,
    (usize, i32, i32),
    (usize, i32, i32),
);

fn case(max_side: usize) -> impl Strategy<Value = Case> {
    (1..=max_side, 1..=max_side, 0u32..=8).prop_flat_map(|(w, h, d)| {
        let cell = prop_oneof![
            10 - d => Just(Cell::Free),
            d + 1 => Just(Cell::Obstacle),
            1 => Just(Cell::Unknown),
        ];
        let sel = || (any::<usize>(), 0..UNITS_PER_CELL, 0..UNITS_PER_CELL);
        (Just(w), Just(h), pvec(cell, w * h), sel(), sel())
    })
}

/// A point in a free cell chosen by `sel`, if there is a free cell.
fn free_point(g: &Grid<Vec<u8>>, sel: (usize, i32, i32)) -> Option<GridPoint> {
    let free: Vec<usize> = (0..g.len())
        .filter(|&i| g.cell_at(i) == Cell::Free)
        .collect();
    let i = *free.get(sel.0 % free.len().max(1))?;
    let w = usize::from(g.width());
    Some(GridPoint {
        x: (i % w) as i32 * UNITS_PER_CELL + sel.1,
        y: (i / w) as i32 * UNITS_PER_CELL + sel.2,
    })
}

fn check_regions(g: &Grid<Vec<u8>>, seg: &Seg) -> Result<(), TestCaseError> {
    // The rule itself: seed 004 §6, Fig. 6, by the letter.
    prop_assert_eq!(&seg.squares, &reference::fig6(g));
    let w = usize::from(g.width());
    let mut owner = vec![u32::MAX; g.len()];
    for (id, s) in seg.squares.iter().enumerate() {
        prop_assert!(s.size >= 1);
        prop_assert!(usize::from(s.x + s.size) <= w && s.y + s.size <= g.height());
        for y in usize::from(s.y)..usize::from(s.y + s.size) {
            for x in usize::from(s.x)..usize::from(s.x + s.size) {
                prop_assert_eq!(
                    g.get(x, y),
                    Cell::Free,
                    "square {} holds a non-free cell",
                    id
                );
                prop_assert_eq!(
                    owner[y * w + x],
                    u32::MAX,
                    "squares overlap at ({}, {})",
                    x,
                    y
                );
                owner[y * w + x] = id as u32;
            }
        }
    }
    for (i, &o) in owner.iter().enumerate() {
        // Disjoint squares covering exactly the free cells, and the map says which.
        prop_assert_eq!(o != u32::MAX, g.cell_at(i) == Cell::Free);
        prop_assert_eq!(seg.map[i], o);
    }
    let mut walked = BTreeSet::new();
    seg.regions(g).for_each_edge(|a, b| {
        walked.insert((a, b));
    });
    prop_assert_eq!(walked, reference::edges(&seg.squares));
    Ok(())
}

fn check_plan(
    regions: &Regions<'_, [u32]>,
    seg: &Seg,
    s: &VecSearch,
    plan: &Plan,
) -> Result<(), TestCaseError> {
    let ids = &s.path[..plan.len as usize];
    prop_assert_eq!(ids.first().copied(), regions.region_of(plan.start));
    prop_assert_eq!(ids.last().copied(), regions.region_of(plan.goal));
    for step in ids.windows(2) {
        let (a, b) = (seg.squares[step[0] as usize], seg.squares[step[1] as usize]);
        prop_assert!(reference::touch(&a, &b), "{:?} -> {:?} not adjacent", a, b);
    }
    let best = reference::dijkstra(
        &seg.squares,
        ids[0],
        ids[ids.len() - 1],
        plan.start,
        plan.goal,
    );
    prop_assert_eq!(Some(u64::from(plan.cost)), best);
    prop_assert_eq!(
        plan.cost,
        polyline_length(plan.waypoints(regions, &s.path[..]))
    );
    Ok(())
}

/// Whether `p` lies in the closed square of one of the plan's regions.
fn in_plan_squares(squares: &[crate::nav::Square], p: (i64, i64, i64)) -> bool {
    let (xn, yn, den) = p;
    let u = i64::from(UNITS_PER_CELL);
    squares.iter().any(|s| {
        let lo = |v: u16| i64::from(v) * u * den;
        let hi = |v: u16| (i64::from(v) + i64::from(s.size)) * u * den;
        (lo(s.x)..=hi(s.x)).contains(&xn) && (lo(s.y)..=hi(s.y)).contains(&yn)
    })
}

fn check_smoothed(
    regions: &Regions<'_, [u32]>,
    s: &VecSearch,
    plan: &Plan,
    smooth: &Smoothed,
) -> Result<(), TestCaseError> {
    prop_assert!(smooth.cost <= plan.cost);
    prop_assert_eq!(smooth.cost, polyline_length(smooth.waypoints(&s.points)));
    // Each segment passes the line-of-sight test, or (a funnel segment) stays inside the
    // closed squares of the plan: checked exactly at 65 points along it.
    let squares: Vec<_> = s.path[..plan.len as usize]
        .iter()
        .map(|&id| regions.square(id).expect("valid id"))
        .collect();
    let wps: Vec<GridPoint> = smooth.waypoints(&s.points).collect();
    for pair in wps.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        if line_of_sight(regions, a, b) {
            continue;
        }
        for k in 0..=64i64 {
            let at = |p: i32, q: i32| i64::from(p) * (64 - k) + i64::from(q) * k;
            let point = (at(a.x, b.x), at(a.y, b.y), 64);
            prop_assert!(
                in_plan_squares(&squares, point),
                "{:?} -> {:?} leaves the plan",
                a,
                b
            );
        }
    }
    Ok(())
}

/// The same query through the firmware's fixed instance: packed 9-bit map, u16 scratch,
/// implicit graph, no h cache - against the station's `Vec`s, stored adjacency and h cache.
fn check_fixed(
    g: &Grid<Vec<u8>>,
    seg: &Seg,
    s: &VecSearch,
    query: Option<(GridPoint, GridPoint)>,
    plans: Option<(Plan, Smoothed, u32)>,
) -> Result<(), TestCaseError> {
    let mut nav = Nav64::new(Geometry::SEED_004);
    let grid = nav.grid_mut();
    grid.reshape(g.width(), g.height()).expect("fits 64 x 64");
    let w = usize::from(g.width());
    for i in 0..g.len() {
        grid.set(i % w, i / w, g.cell_at(i)).expect("inside");
    }
    match nav.segment() {
        Err(SegmentError::TooManyRegions { capacity }) => {
            prop_assert!(seg.squares.len() > capacity);
            return Ok(());
        }
        other => prop_assert_eq!(other, Ok(seg.squares.len())),
    }
    let Some((start, goal)) = query else {
        return Ok(());
    };
    match (nav.plan(start, goal), plans) {
        (Ok(fixed), Some((plan, smooth, margin))) => {
            prop_assert_eq!(encode(&fixed, nav.path()), encode(&plan, &s.path[..]));
            let fixed_smooth = nav.smooth(&fixed, margin).expect("fits");
            prop_assert_eq!(
                encode_smoothed(&fixed_smooth, nav.smoothed_points()),
                encode_smoothed(&smooth, &s.points)
            );
            // And the waypoints in metres, bit for bit.
            let regions = nav.regions().expect("segmented");
            let geo = g.geometry();
            let bits = |p: GridPoint| {
                let (x, y) = geo.grid_to_metres(p);
                (x.to_bits(), y.to_bits())
            };
            let a: Vec<_> = fixed.waypoints(&regions, nav.path()).map(bits).collect();
            let vr = seg.regions(g);
            let b: Vec<_> = plan.waypoints(&vr, &s.path[..]).map(bits).collect();
            prop_assert_eq!(a, b);
        }
        (Err(PlanError::PathTooLong { .. }), Some((plan, _, _))) => prop_assert!(plan.len > 256),
        (Err(e), None) => prop_assert_eq!(e, PlanError::Unreachable),
        (fixed, vec_side) => prop_assert!(false, "fixed {:?} vs vec {:?}", fixed, vec_side),
    }
    Ok(())
}

// 256 cases each by default; PROPTEST_CASES=N runs more.
proptest! {
    #[test]
    fn segmentation_plans_and_storage_agree_on_random_grids(c in case(32), margin in 0u32..160) {
        let (w, h, cells, ssel, gsel) = c;
        let g = from_cells(w, h, &cells);
        let seg = Seg::new(&g).expect("Vec storage holds every region");
        check_regions(&g, &seg)?;
        let regions = seg.regions(&g);
        let mut s = VecSearch::new(regions.len());
        let query = free_point(&g, ssel).zip(free_point(&g, gsel));
        let mut plans = None;
        if let Some((start, goal)) = query {
            let implicit = s.plan(&regions, start, goal);
            let path = s.path.clone();
            let stored = with_adjacency(regions, |adj| s.plan(adj, start, goal));
            // Implicit and stored graphs give the same plan.
            prop_assert_eq!(&implicit, &stored);
            prop_assert_eq!(&path, &s.path);
            match stored {
                Ok(plan) => {
                    check_plan(&regions, &seg, &s, &plan)?;
                    let smooth = s.smooth(&regions, &plan, margin).expect("fits");
                    check_smoothed(&regions, &s, &plan, &smooth)?;
                    plans = Some((plan, smooth, margin));
                }
                Err(e) => {
                    prop_assert_eq!(e, PlanError::Unreachable);
                    let (from, to) = (regions.region_of(start), regions.region_of(goal));
                    let (from, to) = (from.unwrap(), to.unwrap());
                    let best = reference::dijkstra(&seg.squares, from, to, start, goal);
                    prop_assert_eq!(best, None);
                }
            }
        }
        check_fixed(&g, &seg, &s, query, plans)?;
    }

    #[test]
    fn a_start_or_goal_outside_free_space_is_refused(
        c in case(16),
        sx in -300i32..5000,
        sy in -300i32..5000,
    ) {
        let (w, h, cells, _, gsel) = c;
        let g = from_cells(w, h, &cells);
        let seg = Seg::new(&g).expect("fits");
        let regions = seg.regions(&g);
        let mut s = VecSearch::new(regions.len());
        let p = GridPoint { x: sx, y: sy };
        let (cx, cy) = p.cell();
        let free = g.contains(cx, cy) && g.get(cx as usize, cy as usize) == Cell::Free;
        if let (false, Some(goal)) = (free, free_point(&g, gsel)) {
            prop_assert_eq!(s.plan(&regions, p, goal), Err(PlanError::StartBlocked));
            prop_assert_eq!(s.plan(&regions, goal, p), Err(PlanError::GoalBlocked));
        }
    }

    #[test]
    fn line_of_sight_only_passes_segments_over_free_cells(
        c in case(24),
        (ax, ay) in (0i32..6144, 0i32..6144),
        (bx, by) in (0i32..6144, 0i32..6144),
    ) {
        let (w, h, cells, _, _) = c;
        let g = from_cells(w, h, &cells);
        let seg = Seg::new(&g).expect("fits");
        let regions = seg.regions(&g);
        let (a, b) = (GridPoint { x: ax, y: ay }, GridPoint { x: bx, y: by });
        if line_of_sight(&regions, a, b) {
            for k in 0..=256i64 {
                let at = |p: i32, q: i32| {
                    (i64::from(p) * (256 - k) + i64::from(q) * k).div_euclid(256)
                };
                let (x, y) = (at(a.x, b.x), at(a.y, b.y));
                let (cx, cy) = (x.div_euclid(256), y.div_euclid(256));
                prop_assert!(g.contains(cx as i32, cy as i32));
                let cell = g.get(cx as usize, cy as usize);
                prop_assert_eq!(cell, Cell::Free, "({}, {}) at k = {}", x, y, k);
            }
        }
    }
}
