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
//! Region side as the station runs it: `Vec` storage, the adjacency stored once per map
//! (`Adjacency`, built after segmentation and timed with it), the h cache on.
//!
//! `cargo bench -p robot-firmware --bench nav` prints a summary table once (stderr), then runs
//! the criterion groups with 10 samples and short measurement times (CI machines have 2 cores).
//! Without `--bench` (e.g. `cargo test --all-targets`) it runs a quick smoke version only.

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{Criterion, SamplingMode};
use pathfinding::directed::astar::astar;
use robot_firmware::nav::{
    find_path, grid_bytes, segment, smooth, Adjacency, Cell, Edge, Geometry, Grid, GridPoint, Plan,
    RegionGraph, Regions, SearchScratch, Smoothed, Square, UNITS_PER_CELL,
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

/// Openings of an `n` x `n` lattice of maze cells, `[right, down]` per cell: a depth-first
/// spanning tree, then `loops` of the remaining inner walls knocked out.
fn maze_openings(n: usize, loops: f64, rng: &mut Rng) -> Vec<[bool; 2]> {
    let mut opened = vec![[false; 2]; n * n];
    let mut seen = vec![false; n * n];
    let mut stack = vec![(0usize, 0usize)];
    seen[0] = true;
    while let Some(&(cx, cy)) = stack.last() {
        let mut next = Vec::with_capacity(4);
        for (dx, dy) in [(1i64, 0i64), (-1, 0), (0, 1), (0, -1)] {
            let (nx, ny) = (cx as i64 + dx, cy as i64 + dy);
            let inside = nx >= 0 && ny >= 0 && (nx as usize) < n && (ny as usize) < n;
            if inside && !seen[ny as usize * n + nx as usize] {
                next.push((nx as usize, ny as usize));
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
        opened[ay * n + ax][dir] = true;
        seen[ny * n + nx] = true;
        stack.push((nx, ny));
    }
    for cy in 0..n {
        for cx in 0..n {
            for (dir, inner) in [(0, cx + 1 < n), (1, cy + 1 < n)] {
                let roll = rng.below(1000) < (loops * 1000.0) as usize;
                if inner && roll {
                    opened[cy * n + cx][dir] = true;
                }
            }
        }
    }
    opened
}

/// A maze of `corridor`-wide passages between `wall`-thick walls (see [`maze_openings`]).
fn maze(side: usize, corridor: usize, wall: usize, loops: f64, seed: u64) -> VecGrid {
    let mut g = empty(side, Cell::Obstacle);
    let pitch = corridor + wall;
    let n = (side - wall) / pitch;
    let opened = maze_openings(n, loops, &mut Rng(seed));
    let mut carve = |x0: usize, y0: usize, w: usize, h: usize| {
        for y in y0..y0 + h {
            for x in x0..x0 + w {
                g.set(x, y, Cell::Free).expect("inside");
            }
        }
    };
    let origin = |i: usize| wall + i * pitch;
    for cy in 0..n {
        for cx in 0..n {
            let (x, y) = (origin(cx), origin(cy));
            carve(x, y, corridor, corridor);
            let [right, down] = opened[cy * n + cx];
            if right {
                carve(x + corridor, y, wall, corridor);
            }
            if down {
                carve(x, y + corridor, corridor, wall);
            }
        }
    }
    g
}

/// Station-style storage for one segmented grid: everything in `Vec`s.
struct Station {
    map: Vec<u32>,
    squares: Vec<Square>,
    offsets: Vec<u32>,
    edges: Vec<Edge>,
    count: usize,
}

impl Station {
    /// Segments `g` and stores its adjacency: what the station does once per map.
    fn new(g: &VecGrid) -> Station {
        let mut map = vec![0u32; g.len()];
        let mut squares = vec![Square::EMPTY; g.len()];
        let regions = segment(g, &mut map[..], &mut squares[..]).expect("Vec holds every region");
        let count = regions.len();
        let mut offsets = vec![0u32; count + 1];
        let mut edges = vec![Edge::default(); Adjacency::edge_count(&regions)];
        Adjacency::build(regions, &mut offsets, &mut edges).expect("sized by edge_count");
        squares.truncate(count);
        Station {
            map,
            squares,
            offsets,
            edges,
            count,
        }
    }

    fn regions<'a>(&'a self, g: &VecGrid) -> Regions<'a, [u32]> {
        Regions::from_segmented(g, &self.map[..], &self.squares[..]).expect("sizes match")
    }

    fn graph<'a>(&'a self, g: &VecGrid) -> Adjacency<'a, [u32]> {
        Adjacency::from_built(self.regions(g), &self.offsets, &self.edges).expect("sizes match")
    }
}

/// A* scratch (with the h cache) plus raw plan and smoothed point stores.
struct Search {
    f: Vec<u32>,
    h: Vec<u32>,
    parent: Vec<u32>,
    heap: Vec<u32>,
    pos: Vec<u32>,
    path: Vec<u32>,
    points: Vec<GridPoint>,
}

impl Search {
    fn new(n: usize) -> Search {
        Search {
            f: vec![0; n],
            h: vec![0; n],
            parent: vec![0; n],
            heap: vec![0; n],
            pos: vec![0; n],
            path: vec![0; n],
            points: vec![GridPoint::default(); n],
        }
    }

    fn plan<G: RegionGraph>(&mut self, graph: &G, q: (GridPoint, GridPoint)) -> Option<Plan> {
        let mut scratch = SearchScratch::new(
            &mut self.f,
            &mut self.parent[..],
            &mut self.heap[..],
            &mut self.pos[..],
        )
        .with_h_cache(&mut self.h);
        find_path(graph, q.0, q.1, &mut scratch, &mut self.path[..]).ok()
    }

    fn smooth(&mut self, r: &Regions<'_, [u32]>, plan: &Plan, margin: u32) -> Smoothed {
        smooth(r, plan, &self.path[..], margin, &mut self.points).expect("store holds the plan")
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

/// Euclidean length of a polyline, in cells.
fn length_cells(points: impl IntoIterator<Item = GridPoint>) -> f64 {
    let pts: Vec<GridPoint> = points.into_iter().collect();
    let u = f64::from(UNITS_PER_CELL);
    pts.windows(2)
        .map(|w| f64::from(w[1].x - w[0].x).hypot(f64::from(w[1].y - w[0].y)) / u)
        .sum()
}

/// `count` reachable queries between random free cell centres at least half a side apart.
fn queries(g: &VecGrid, st: &Station, count: usize, seed: u64) -> Vec<(GridPoint, GridPoint)> {
    let side = usize::from(g.width());
    let graph = st.graph(g);
    let mut s = Search::new(st.count);
    let mut rng = Rng(seed);
    let mut out = Vec::new();
    let free_cell = |rng: &mut Rng| loop {
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
        if far && s.plan(&graph, q).is_some() {
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
        case("random-512", blobs(512, 0.25, 1), 16),
        case("maze-512", maze(512, 6, 2, 0.1, 2), 16),
        case("random-2048", blobs(2048, 0.25, 3), 6),
        case("maze-2048", maze(2048, 6, 2, 0.1, 4), 6),
    ]
}

/// Fastest of `runs` timings of `f`, in seconds: the least-disturbed run on a shared machine.
fn time<T>(runs: usize, mut f: impl FnMut() -> T) -> f64 {
    (0..runs.max(1))
        .map(|_| {
            let t = Instant::now();
            black_box(f());
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Smoothing margin of the last ratio column: a quarter cell, in grid units.
const MARGIN: u32 = 64;

/// Measurements of one grid: times are means over its queries of each query's fastest run.
struct Row {
    t_seg: f64,
    t_astar: f64,
    t_smooth: f64,
    t_grid: f64,
    /// Per-query speed-ups, sorted.
    speedups: Vec<f64>,
    raw: f64,
    tight: f64,
    margin: f64,
}

fn measure(c: &Case) -> Row {
    let big = c.grid.len() > 1 << 20;
    let t_seg = time(3, || Station::new(&c.grid).count);
    let (regions, graph) = (c.station.regions(&c.grid), c.station.graph(&c.grid));
    let mut s = Search::new(c.station.count);
    let n = c.queries.len() as f64;
    let mut row = Row {
        t_seg,
        t_astar: 0.0,
        t_smooth: 0.0,
        t_grid: 0.0,
        speedups: Vec::new(),
        raw: 0.0,
        tight: 0.0,
        margin: 0.0,
    };
    for &q in &c.queries {
        let t_a = time(10, || s.plan(&graph, q));
        let plan = s.plan(&graph, q).expect("reachable");
        row.t_smooth += time(10, || s.smooth(&regions, &plan, 0)) / n;
        let (a, b) = (q.0.cell(), q.1.cell());
        let mut opt = None;
        let t_g = time(if big { 1 } else { 3 }, || opt = grid_astar(&c.grid, a, b));
        let opt = opt.expect("the grid search agrees the goal is reachable") as f64 / 1e6;
        row.t_astar += t_a / n;
        row.t_grid += t_g / n;
        row.speedups.push(t_g / t_a);
        row.raw += length_cells(plan.waypoints(&regions, &s.path[..])) / opt / n;
        let tight = s.smooth(&regions, &plan, 0);
        row.tight += length_cells(tight.waypoints(&s.points)) / opt / n;
        let loose = s.smooth(&regions, &plan, MARGIN);
        row.margin += length_cells(loose.waypoints(&s.points)) / opt / n;
    }
    row.speedups.sort_by(f64::total_cmp);
    row
}

/// The summary: one row per grid.
fn summary(cases: &[Case]) {
    eprintln!(
        "\n{:<11} {:>7} {:>9} {:>9} {:>8} {:>9} {:>7} {:>12} {:>6} {:>6} {:>6}",
        "grid",
        "regions",
        "seg+graph",
        "A*/query",
        "smooth",
        "grid A*",
        "speedup",
        "per-query",
        "raw",
        "smooth",
        "margin"
    );
    let ms = |secs: f64| format!("{:.3}ms", secs * 1e3);
    for c in cases {
        let r = measure(c);
        let (lo, hi) = (r.speedups[0], r.speedups[r.speedups.len() - 1]);
        eprintln!(
            "{:<11} {:>7} {:>9} {:>9} {:>8} {:>9} {:>6.1}x {:>12} {:>6.3} {:>6.3} {:>6.3}",
            c.name,
            c.station.count,
            ms(r.t_seg),
            ms(r.t_astar),
            ms(r.t_smooth),
            ms(r.t_grid),
            r.t_grid / r.t_astar,
            format!("{lo:.1}-{hi:.0}x"),
            r.raw,
            r.tight,
            r.margin
        );
    }
    eprintln!("Times: mean over the queries of each query's fastest run. seg+graph: segmentation");
    eprintln!("and stored adjacency, once per map. A*/query: region A* alone; smooth: the");
    eprintln!("smoothing pass alone. speedup: grid A* time / region A* time (per-query range");
    eprintln!("beside it). raw / smooth / margin: path length over the 8-connected grid optimum");
    eprintln!("(raw centres; smoothed; smoothed with a 1/4-cell margin), mean over the queries.\n");
}

/// The paper's arena: Micro-Rato'99 at 17 x 17 (as in the crate's tests), B = goal light.
fn micro_rato_99() -> VecGrid {
    const ROWS: [&str; 17] = robot_firmware::nav::paper_map::MICRO_RATO_99;
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
    let mut group = c.benchmark_group("paper-17x17");
    group.sample_size(10);
    group.warm_up_time(Duration::from_millis(300));
    group.measurement_time(Duration::from_secs(1));
    // As the firmware does it: segmentation, then A* over the implicit graph.
    group.bench_function("segment+astar", |b| {
        b.iter(|| {
            let r = segment(&g, &mut map[..], &mut squares[..]).expect("fits");
            black_box(s.plan(&r, (start, goal)))
        })
    });
    group.finish();
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
    group.bench_function("segment+graph", |b| {
        b.iter(|| black_box(Station::new(&case.grid).count))
    });
    let (regions, graph) = (
        case.station.regions(&case.grid),
        case.station.graph(&case.grid),
    );
    let mut s = Search::new(case.station.count);
    let qs = &case.queries;
    let mut k = 0;
    group.bench_function("region-astar/query", |b| {
        b.iter(|| {
            k += 1;
            black_box(s.plan(&graph, qs[k % qs.len()]))
        })
    });
    group.bench_function("region-astar+smooth/query", |b| {
        b.iter(|| {
            k += 1;
            let plan = s.plan(&graph, qs[k % qs.len()]).expect("reachable");
            black_box(s.smooth(&regions, &plan, 0))
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
