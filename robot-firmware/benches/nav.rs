//! Navigation benchmarks: seed 004 segmentation + A* over regions against plain grid A*.
//!
//! Grids: the paper's 17 x 17 arena; 512 x 512 and 2048 x 2048 random grids (about 25 %
//! obstacles in round blobs) and mazes (6-cell corridors, 2-cell walls, 10 % of the remaining
//! walls knocked out so there are loops). Storage is `Vec`-backed, as in the station.
//!
//! Baseline: `pathfinding::directed::astar` on the 8-connected grid, octile costs (diagonals
//! only where both side cells are free, the same no-corner-cutting rule as the smoother's line
//! of sight), octile heuristic. Its cost is the grid optimum the length ratios refer to.
//!
//! `cargo bench -p robot-firmware --bench nav` prints a summary table once (stderr), then runs
//! the criterion groups with 10 samples and short measurement times (CI machines have 2 cores).
//! Without `--bench` (e.g. `cargo test --all-targets`) it runs a quick smoke version only.

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{Criterion, SamplingMode};
use pathfinding::directed::astar::astar;
use robot_firmware::nav::{
    find_path, grid_bytes, segment, smooth, Cell, Geometry, Grid, GridPoint, IdStore, Plan,
    Regions, SearchScratch, Square, UNITS_PER_CELL,
};

/// splitmix64: a fixed-seed generator, so every run benchmarks the same maps.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

type VecGrid = Grid<Vec<u8>>;

fn empty(side: usize, cell: Cell) -> VecGrid {
    let mut g = Grid::new(
        side as u16,
        side as u16,
        Geometry::SEED_004,
        vec![0; grid_bytes(side, side)],
    )
    .expect("side within MAX_SIDE");
    g.fill(cell);
    g
}

fn is_free(g: &VecGrid, x: i32, y: i32) -> bool {
    g.contains(x, y) && g.get(x as usize, y as usize) == Cell::Free
}

/// Round blobs of random radius until `fraction` of the cells are obstacles.
fn blobs(side: usize, fraction: f64, seed: u64) -> VecGrid {
    let mut g = empty(side, Cell::Free);
    let mut rng = Rng(seed);
    let (r_min, r_max) = (2 + side / 256, 4 + side / 40);
    let target = (fraction * (side * side) as f64) as usize;
    let mut blocked = 0;
    while blocked < target {
        let (cx, cy) = (rng.below(side) as i64, rng.below(side) as i64);
        let r = (r_min + rng.below(r_max - r_min + 1)) as i64;
        for y in (cy - r).max(0)..(cy + r + 1).min(side as i64) {
            for x in (cx - r).max(0)..(cx + r + 1).min(side as i64) {
                let inside = (x - cx).pow(2) + (y - cy).pow(2) <= r * r;
                if inside && g.get(x as usize, y as usize) == Cell::Free {
                    g.set(x as usize, y as usize, Cell::Obstacle)
                        .expect("inside");
                    blocked += 1;
                }
            }
        }
    }
    g
}

/// A maze: a depth-first spanning tree of `corridor`-wide passages between `wall`-thick walls,
/// then `loops` of the remaining inner walls knocked out.
fn maze(side: usize, corridor: usize, wall: usize, loops: f64, seed: u64) -> VecGrid {
    let mut g = empty(side, Cell::Obstacle);
    let pitch = corridor + wall;
    let n = (side - wall) / pitch;
    let mut rng = Rng(seed);
    let carve = |g: &mut VecGrid, x0: usize, y0: usize, w: usize, h: usize| {
        for y in y0..y0 + h {
            for x in x0..x0 + w {
                g.set(x, y, Cell::Free).expect("inside");
            }
        }
    };
    let origin = |i: usize| wall + i * pitch;
    for cy in 0..n {
        for cx in 0..n {
            carve(&mut g, origin(cx), origin(cy), corridor, corridor);
        }
    }
    // Openings: between (cx, cy) and its right (dir 0) or lower (dir 1) neighbour.
    let open = |g: &mut VecGrid, cx: usize, cy: usize, dir: usize| {
        if dir == 0 {
            carve(g, origin(cx) + corridor, origin(cy), wall, corridor);
        } else {
            carve(g, origin(cx), origin(cy) + corridor, corridor, wall);
        }
    };
    let mut seen = vec![false; n * n];
    let mut opened = vec![[false; 2]; n * n];
    let mut stack = vec![(0usize, 0usize)];
    seen[0] = true;
    while let Some(&(cx, cy)) = stack.last() {
        let mut next = Vec::with_capacity(4);
        for (dx, dy) in [(1i64, 0i64), (-1, 0), (0, 1), (0, -1)] {
            let (nx, ny) = (cx as i64 + dx, cy as i64 + dy);
            if nx >= 0 && ny >= 0 && (nx as usize) < n && (ny as usize) < n {
                if !seen[ny as usize * n + nx as usize] {
                    next.push((nx as usize, ny as usize));
                }
            }
        }
        if next.is_empty() {
            stack.pop();
            continue;
        }
        let (nx, ny) = next[rng.below(next.len())];
        let (ax, ay, dir) = if nx != cx {
            (cx.min(nx), cy, 0)
        } else {
            (cx, cy.min(ny), 1)
        };
        open(&mut g, ax, ay, dir);
        opened[ay * n + ax][dir] = true;
        seen[ny * n + nx] = true;
        stack.push((nx, ny));
    }
    for cy in 0..n {
        for cx in 0..n {
            for dir in 0..2 {
                let inner = if dir == 0 { cx + 1 < n } else { cy + 1 < n };
                let roll = rng.below(1000) < (loops * 1000.0) as usize;
                if inner && !opened[cy * n + cx][dir] && roll {
                    open(&mut g, cx, cy, dir);
                }
            }
        }
    }
    g
}

/// Station-style storage for one segmented grid: everything in `Vec`s.
struct Station {
    map: Vec<u32>,
    squares: Vec<Square>,
    count: usize,
}

impl Station {
    fn new(g: &VecGrid) -> Station {
        let mut map = vec![0u32; g.len()];
        let mut squares = vec![Square::EMPTY; g.len()];
        let count = segment(g, &mut map[..], &mut squares[..])
            .expect("Vec storage holds every region")
            .len();
        squares.truncate(count);
        Station {
            map,
            squares,
            count,
        }
    }

    fn regions<'a>(&'a self, g: &VecGrid) -> Regions<'a, [u32]> {
        Regions::from_segmented(g, &self.map[..], &self.squares[..]).expect("sizes match")
    }
}

/// A* scratch plus raw and smoothed path stores.
struct Search {
    f: Vec<u32>,
    parent: Vec<u32>,
    heap: Vec<u32>,
    pos: Vec<u32>,
    path: Vec<u32>,
    smoothed: Vec<u32>,
}

impl Search {
    fn new(n: usize) -> Search {
        Search {
            f: vec![0; n],
            parent: vec![0; n],
            heap: vec![0; n],
            pos: vec![0; n],
            path: vec![0; n],
            smoothed: vec![0; n],
        }
    }

    fn plan(&mut self, r: &Regions<'_, [u32]>, q: (GridPoint, GridPoint)) -> Option<Plan> {
        let mut scratch = SearchScratch::new(
            &mut self.f,
            &mut self.parent[..],
            &mut self.heap[..],
            &mut self.pos[..],
        );
        find_path(r, q.0, q.1, &mut scratch, &mut self.path[..]).ok()
    }

    fn smooth(&mut self, r: &Regions<'_, [u32]>, plan: &Plan) -> Plan {
        smooth(r, plan, &self.path[..], &mut self.smoothed[..]).expect("store holds the plan")
    }
}

const STRAIGHT: u64 = 1_000_000;
const DIAGONAL: u64 = 1_414_214;

/// Plain 8-connected grid A* (no corner cutting); returns the cost in 1e-6 cells.
fn grid_astar(g: &VecGrid, from: (i32, i32), to: (i32, i32)) -> Option<u64> {
    const DIRS: [(i32, i32); 8] = [
        (1, 0),
        (-1, 0),
        (0, 1),
        (0, -1),
        (1, 1),
        (1, -1),
        (-1, 1),
        (-1, -1),
    ];
    let successors = |&(x, y): &(i32, i32)| {
        DIRS.iter().filter_map(move |&(dx, dy)| {
            let (nx, ny) = (x + dx, y + dy);
            let diagonal = dx != 0 && dy != 0;
            let ok = is_free(g, nx, ny)
                && (!diagonal || (is_free(g, x + dx, y) && is_free(g, x, y + dy)));
            ok.then_some(((nx, ny), if diagonal { DIAGONAL } else { STRAIGHT }))
        })
    };
    let heuristic = |&(x, y): &(i32, i32)| {
        let (dx, dy) = (
            (x - to.0).unsigned_abs() as u64,
            (y - to.1).unsigned_abs() as u64,
        );
        STRAIGHT * dx.max(dy) + (DIAGONAL - STRAIGHT) * dx.min(dy)
    };
    astar(&from, successors, heuristic, |&p| p == to).map(|(_, c)| c)
}

/// Euclidean length of a plan's waypoints, in cells.
fn length_cells<P: IdStore + ?Sized>(r: &Regions<'_, [u32]>, plan: &Plan, path: &P) -> f64 {
    let pts: Vec<GridPoint> = plan.waypoints(r, path).collect();
    let u = f64::from(UNITS_PER_CELL);
    pts.windows(2)
        .map(|w| f64::from(w[1].x - w[0].x).hypot(f64::from(w[1].y - w[0].y)) / u)
        .sum()
}

/// `count` reachable queries between random free cell centres at least half a side apart.
fn queries(g: &VecGrid, st: &Station, count: usize, seed: u64) -> Vec<(GridPoint, GridPoint)> {
    let side = usize::from(g.width());
    let regions = st.regions(g);
    let mut s = Search::new(st.count);
    let mut rng = Rng(seed);
    let mut out = Vec::new();
    let mut free_cell = |rng: &mut Rng| loop {
        let (x, y) = (rng.below(side), rng.below(side));
        if g.get(x, y) == Cell::Free {
            return (x as u16, y as u16);
        }
    };
    while out.len() < count {
        let (a, b) = (free_cell(&mut rng), free_cell(&mut rng));
        let far = usize::from(a.0.abs_diff(b.0)) + usize::from(a.1.abs_diff(b.1)) >= side / 2;
        let q = (
            GridPoint::cell_centre(a.0, a.1),
            GridPoint::cell_centre(b.0, b.1),
        );
        if far && s.plan(&regions, q).is_some() {
            out.push(q);
        }
    }
    out
}

struct Case {
    name: String,
    grid: VecGrid,
    station: Station,
    queries: Vec<(GridPoint, GridPoint)>,
}

fn case(name: &str, grid: VecGrid, n_queries: usize) -> Case {
    let station = Station::new(&grid);
    let queries = queries(&grid, &station, n_queries, 99);
    Case {
        name: name.to_string(),
        grid,
        station,
        queries,
    }
}

fn cases(full: bool) -> Vec<Case> {
    if !full {
        return vec![
            case("random-128", blobs(128, 0.25, 1), 2),
            case("maze-128", maze(128, 6, 2, 0.1, 2), 2),
        ];
    }
    vec![
        case("random-512", blobs(512, 0.25, 1), 8),
        case("maze-512", maze(512, 6, 2, 0.1, 2), 8),
        case("random-2048", blobs(2048, 0.25, 3), 4),
        case("maze-2048", maze(2048, 6, 2, 0.1, 4), 4),
    ]
}

/// Median of `runs` timings of `f`.
fn time<T>(runs: usize, mut f: impl FnMut() -> T) -> Duration {
    let mut v: Vec<Duration> = (0..runs)
        .map(|_| {
            let t = Instant::now();
            black_box(f());
            t.elapsed()
        })
        .collect();
    v.sort();
    v[v.len() / 2]
}

/// The table of the summary: one row per grid, averaged over its queries.
fn summary(cases: &[Case]) {
    eprintln!(
        "\n{:<12} {:>8} {:>9} {:>10} {:>10} {:>10} {:>8} {:>8} {:>9} {:>9}",
        "grid",
        "regions",
        "segment",
        "A*/query",
        "+smooth",
        "grid A*",
        "speedup",
        "+smooth",
        "raw/opt",
        "smth/opt"
    );
    for c in cases {
        let t_seg = time(3, || Station::new(&c.grid).count);
        let regions = c.station.regions(&c.grid);
        let mut s = Search::new(c.station.count);
        let (mut t_a, mut t_s, mut t_g) = (Duration::ZERO, Duration::ZERO, Duration::ZERO);
        let (mut raw_ratio, mut smooth_ratio) = (0.0, 0.0);
        for &q in &c.queries {
            t_a += time(5, || s.plan(&regions, q));
            let plan = s.plan(&regions, q).expect("reachable");
            t_s += time(5, || s.smooth(&regions, &plan));
            let smoothed = s.smooth(&regions, &plan);
            let (a, b) = (q.0.cell(), q.1.cell());
            let mut opt = None;
            t_g += time(1, || opt = grid_astar(&c.grid, a, b));
            let opt = opt.expect("the grid search agrees the goal is reachable") as f64 / 1e6;
            raw_ratio += length_cells(&regions, &plan, &s.path[..]) / opt;
            smooth_ratio += length_cells(&regions, &smoothed, &s.smoothed[..]) / opt;
        }
        let n = c.queries.len() as f64;
        let per = |d: Duration| d.as_secs_f64() / n;
        let ms = |secs: f64| format!("{:.3} ms", secs * 1e3);
        eprintln!(
            "{:<12} {:>8} {:>9} {:>10} {:>10} {:>10} {:>7.0}x {:>7.0}x {:>9.3} {:>9.3}",
            c.name,
            c.station.count,
            ms(t_seg.as_secs_f64()),
            ms(per(t_a)),
            ms(per(t_s)),
            ms(per(t_g)),
            per(t_g) / per(t_a),
            per(t_g) / (per(t_a) + per(t_s)),
            raw_ratio / n,
            smooth_ratio / n
        );
    }
    eprintln!("(A*/query excludes segmentation; +smooth is the smoothing pass alone; ratios are");
    eprintln!(" path length over the 8-connected grid optimum, averaged over the queries)\n");
}

/// The paper's arena: Micro-Rato'99 at 17 x 17 (as in the crate's tests), B = goal light.
fn micro_rato_99() -> VecGrid {
    const ROWS: [&str; 17] = [
        "...#.............",
        "...#.............",
        "...#.............",
        "...#.............",
        "...#...#####.#...",
        "...#...#.....#...",
        "...#...#.....#...",
        "...#...#.....#...",
        "...#...#..B......",
        ".......#.........",
        ".......#.....#...",
        ".......#.....#...",
        ".......#####.#...",
        ".................",
        ".................",
        ".................",
        ".................",
    ];
    let mut g = empty(17, Cell::Free);
    for (y, row) in ROWS.iter().enumerate() {
        for (x, ch) in row.bytes().enumerate() {
            if ch != b'.' {
                g.set(x, y, Cell::Obstacle).expect("inside");
            }
        }
    }
    g
}

fn bench_paper(c: &mut Criterion) {
    let g = micro_rato_99();
    let (start, goal) = (GridPoint::cell_centre(1, 1), GridPoint::cell_centre(9, 8));
    let mut map = vec![0u32; g.len()];
    let mut squares = vec![Square::EMPTY; g.len()];
    let mut s = Search::new(g.len());
    c.bench_function("paper-17x17/segment+astar", |b| {
        b.iter(|| {
            let r = segment(&g, &mut map[..], &mut squares[..]).expect("fits");
            black_box(s.plan(&r, (start, goal)))
        })
    });
}

fn bench_case(c: &mut Criterion, case: &Case) {
    let mut group = c.benchmark_group(case.name.as_str());
    group.sample_size(10);
    group.warm_up_time(Duration::from_millis(300));
    group.measurement_time(Duration::from_secs(2));
    let mut map = vec![0u32; case.grid.len()];
    let mut squares = vec![Square::EMPTY; case.grid.len()];
    group.bench_function("segment", |b| {
        b.iter(|| black_box(segment(&case.grid, &mut map[..], &mut squares[..]).is_ok()))
    });
    let regions = case.station.regions(&case.grid);
    let mut s = Search::new(case.station.count);
    let qs = &case.queries;
    let mut k = 0;
    group.bench_function("region-astar/query", |b| {
        b.iter(|| {
            k += 1;
            black_box(s.plan(&regions, qs[k % qs.len()]))
        })
    });
    group.bench_function("region-astar+smooth/query", |b| {
        b.iter(|| {
            k += 1;
            let plan = s.plan(&regions, qs[k % qs.len()]).expect("reachable");
            black_box(s.smooth(&regions, &plan))
        })
    });
    // One grid A* query can take a second at 2048: flat sampling keeps it to 10 runs.
    group.sampling_mode(SamplingMode::Flat);
    group.bench_function("grid-astar/query", |b| {
        b.iter(|| {
            k += 1;
            let (a, z) = qs[k % qs.len()];
            black_box(grid_astar(&case.grid, a.cell(), z.cell()))
        })
    });
    group.finish();
}

fn main() {
    // `cargo bench` passes --bench; `cargo test --all-targets` does not: keep that run short.
    let full = std::env::args().any(|a| a == "--bench");
    let cases = cases(full);
    summary(&cases);
    let mut c = Criterion::default().configure_from_args();
    bench_paper(&mut c);
    for case in &cases {
        bench_case(&mut c, case);
    }
    c.final_summary();
}
