//! The workloads, the same on the Cortex-M4 and the host: seed 004 §6 on the paper's arena and
//! the robot's planner on 64 x 64 maps (the square segmentation's worst case among them), all
//! through the firmware's own instance (`Nav64`), as `Objects::plan_route` calls it.

use robot_firmware::nav::{
    wave_bytes, wave_plan, Cell, GridPoint, Nav64, Passable, PlanError, Route, WaveRoute,
};

/// Cells of the largest map, for the grid planner's scratch outside `Nav64`.
const CELLS_17: usize = 17 * 17;

/// One measured step: `setup` builds the map (not measured), `run` is what is measured; it
/// returns a checksum of its result, so the two targets can be seen to compute the same plan,
/// and the method that made it.
pub struct Case {
    pub name: &'static str,
    pub setup: fn(&mut Nav64),
    pub run: fn(&mut Nav64) -> (u32, Method),
}

/// Which planner a case ran.
#[derive(Clone, Copy)]
pub enum Method {
    /// Segmentation or A* alone.
    Part,
    /// Seed 004 §6: squares + A*.
    Squares,
    /// The grid planner (the fallback, or run directly).
    Grid,
    Failed,
}

impl Method {
    pub fn name(self) -> &'static str {
        match self {
            Method::Part => "part",
            Method::Squares => "squares+A*",
            Method::Grid => "grid",
            Method::Failed => "failed",
        }
    }
}

pub const CASES: [Case; 13] = [
    Case {
        name: "micro-rato-99 17x17: segmentation (Fig. 6)",
        setup: micro_rato_99,
        run: |nav| {
            nav.forget_segmentation();
            (nav.segment().map_or(u32::MAX, |n| n as u32), Method::Part)
        },
    },
    Case {
        name: "micro-rato-99 17x17: A* over the squares",
        setup: |nav| {
            micro_rato_99(nav);
            let _ = nav.segment();
        },
        run: |nav| {
            let plan = nav.plan(c(1, 1), c(9, 8));
            (check(plan.map(|p| p.cost ^ p.len << 24)), Method::Part)
        },
    },
    Case {
        name: "micro-rato-99 17x17: segmentation + A* (seed 004 §6)",
        setup: micro_rato_99,
        run: |nav| {
            nav.forget_segmentation();
            route(nav, c(1, 1), c(9, 8))
        },
    },
    Case {
        name: "micro-rato-99 17x17: grid planner (for comparison)",
        setup: micro_rato_99,
        run: |nav| {
            let mut scratch = [0u8; wave_bytes(CELLS_17)];
            let (s, g) = (c(1, 1), c(9, 8));
            let plan = wave_plan(nav.grid(), Passable::Free, s, g, &mut scratch);
            let sum = check(plan.map(|p| {
                let r = WaveRoute::new(nav.grid(), Passable::Free, &scratch, p);
                r.waypoints().fold(p.cost, mix)
            }));
            (sum, Method::Grid)
        },
    },
    Case {
        name: "64x64 0.5 % obstacles (squares fit): segmentation + A*",
        setup: |nav| random(nav, 5, 1),
        run: |nav| {
            nav.forget_segmentation();
            route(nav, c(0, 0), c(62, 62))
        },
    },
    Case {
        name: "64x64 1 % obstacles (just past 255 squares): segmentation try + grid planner",
        setup: |nav| random(nav, 10, 1),
        run: |nav| {
            nav.forget_segmentation();
            route(nav, c(0, 0), c(62, 62))
        },
    },
    Case {
        name: "64x64 worst case, 3072 squares: segmentation try + grid planner",
        setup: |nav| {
            fill(nav, |x, y| x % 2 == 1 && y % 2 == 1);
        },
        run: |nav| {
            nav.forget_segmentation();
            route(nav, c(0, 0), c(62, 62))
        },
    },
    Case {
        name: "64x64 3.5 % obstacles (538 squares): segmentation try + grid planner",
        setup: |nav| random(nav, 35, 2),
        run: |nav| {
            nav.forget_segmentation();
            route(nav, c(0, 0), c(62, 62))
        },
    },
    Case {
        name: "64x64 serpentine, 2,047-cell path: segmentation + grid planner",
        setup: |nav| {
            // Corridors on even rows, walls on odd rows open at alternate ends.
            fill(nav, |x, y| match y % 4 {
                1 => x != 63,
                3 => x != 0,
                _ => false,
            });
        },
        run: |nav| {
            nav.forget_segmentation();
            route(nav, c(0, 0), c(0, 62))
        },
    },
    // The planned search's replan (issue 32): the grid planner over free and unknown cells
    // and the route's first waypoint, as `ExploreMap::route_towards` calls it.
    Case {
        name: "search replan, 56x29 (a 28 x 14-unit lab at 0.15 m), nothing known yet",
        setup: |nav| search_map(nav, 56, 29, |_, _| false),
        run: |nav| first_waypoint(nav, c(2, 2), c(53, 26)),
    },
    Case {
        name: "search replan, 56x29, a comb of three walls known (route 2.4x the line)",
        setup: |nav| {
            search_map(nav, 56, 29, |x, y| match x {
                14 | 42 => y >= 3,
                28 => y <= 25,
                _ => false,
            })
        },
        run: |nav| first_waypoint(nav, c(2, 14), c(53, 14)),
    },
    Case {
        name: "search replan, 64x64 serpentine known (the longest route the grid holds)",
        setup: |nav| {
            search_map(nav, 64, 64, |x, y| match y % 4 {
                1 => x != 63,
                3 => x != 0,
                _ => false,
            })
        },
        run: |nav| first_waypoint(nav, c(0, 0), c(0, 62)),
    },
    Case {
        name: "search, no way on its map: reopening (two waves + scan), 64x64 cut in two",
        setup: |nav| search_map(nav, 64, 64, |_, _| false),
        run: |nav| {
            // The wall marked again first (64 cells, a few thousand instructions), so each
            // run has the same way to reopen.
            for y in 0..64 {
                let _ = nav.grid_mut().set(32, y, Cell::Obstacle);
            }
            let n = nav.open_between(Passable::FreeOrUnknown, c(2, 2), c(60, 60));
            (n as u32, Method::Grid)
        },
    },
];

/// The planned search's step: the first waypoint and the route's length.
fn first_waypoint(nav: &mut Nav64, s: GridPoint, g: GridPoint) -> (u32, Method) {
    match nav.first_waypoint(Passable::FreeOrUnknown, s, g) {
        Ok((p, steps)) => (mix(steps, p), Method::Grid),
        Err(_) => (u32::MAX, Method::Failed),
    }
}

/// A `w` x `h` search map: `wall(x, y)` cells walls, the rest unknown (the search plans
/// through them as free).
fn search_map(nav: &mut Nav64, w: u16, h: u16, wall: impl Fn(usize, usize) -> bool) {
    let g = nav.grid_mut();
    let _ = g.reshape(w, h);
    for y in 0..usize::from(h) {
        for x in 0..usize::from(w) {
            let cell = if wall(x, y) {
                Cell::Obstacle
            } else {
                Cell::Unknown
            };
            let _ = g.set(x, y, cell);
        }
    }
}

fn c(x: u16, y: u16) -> GridPoint {
    GridPoint::cell_centre(x, y)
}

fn mix(h: u32, p: GridPoint) -> u32 {
    (h.rotate_left(5) ^ p.x as u32).wrapping_mul(0x9E37_79B1) ^ p.y as u32
}

fn check(r: Result<u32, PlanError>) -> u32 {
    r.unwrap_or(u32::MAX)
}

/// The robot's planner as `Objects::plan_route` runs it, waypoints included.
fn route(nav: &mut Nav64, s: GridPoint, g: GridPoint) -> (u32, Method) {
    match nav.route(s, g) {
        Ok(Route::Squares(p)) => (p.cost ^ p.len << 24, Method::Squares),
        Ok(Route::Grid(p)) => match nav.wave_route(p) {
            Some(r) => (r.waypoints().fold(p.cost, mix), Method::Grid),
            None => (u32::MAX, Method::Failed),
        },
        Err(_) => (u32::MAX, Method::Failed),
    }
}

/// Seed 004's Micro-Rato'99 arena at 17 x 17 (as in the crate's tests), B the goal light.
fn micro_rato_99(nav: &mut Nav64) {
    const ROWS: [&str; 17] = robot_firmware::nav::paper_map::MICRO_RATO_99;
    let g = nav.grid_mut();
    let _ = g.reshape(17, 17);
    for (y, row) in ROWS.iter().enumerate() {
        for (x, ch) in row.bytes().enumerate() {
            let cell = if ch == b'.' {
                Cell::Free
            } else {
                Cell::Obstacle
            };
            let _ = g.set(x, y, cell);
        }
    }
}

/// A 64 x 64 map, `blocked(x, y)` cells obstacles, the rest free.
fn fill(nav: &mut Nav64, blocked: impl Fn(usize, usize) -> bool) {
    let g = nav.grid_mut();
    let _ = g.reshape(64, 64);
    for y in 0..64 {
        for x in 0..64 {
            let cell = if blocked(x, y) {
                Cell::Obstacle
            } else {
                Cell::Free
            };
            let _ = g.set(x, y, cell);
        }
    }
}

/// A 64 x 64 map with `per_mille` of its cells obstacles at random (splitmix64, `seed`); the
/// corners (0, 0) and (62, 62) free.
fn random(nav: &mut Nav64, per_mille: u64, seed: u64) {
    let mut s = seed;
    let mut next = move || {
        s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    };
    let mut cells = [false; 64 * 64];
    for c in cells.iter_mut() {
        *c = next() % 1000 < per_mille;
    }
    fill(nav, |x, y| {
        cells[y * 64 + x] && (x, y) != (0, 0) && (x, y) != (62, 62)
    });
}
