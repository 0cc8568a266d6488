//! Station planning benchmarks: the `station plan` path on Micro-Rato'99 and the map view's
//! render time with the planning layers on a 128 x 128 grid.
//!
//! - `plan_cli/*`: what `station plan --map wallsMicRato99.xml --from 0.5,0.5` does before it
//!   prints: read and parse the lab, rasterise at 0.3 m (17 x 17), copy into the nav grid,
//!   segment, build the region graph, resolve the goal, A* (and, separately, the parts alone).
//! - `render/map_128x128_at_200x60`: one whole frame of the Map view (grid, squares, raw and
//!   smoothed plan, start/goal, plan panel) into a 200 x 60 `TestBackend`; the grid is random
//!   blobs at about 25 % obstacles with a fixed seed, planned corner to corner.
//!
//! `cargo bench -p station --bench plan` prints a one-shot summary (stderr), then runs the
//! criterion groups with 10 samples and short measurement times (2-core machines). Without
//! `--bench` (`cargo test --all-targets`) it runs each routine once as a smoke test.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use criterion::Criterion;
use ratatui::backend::TestBackend;
use ratatui::Terminal;
use robot_firmware::nav::{grid_bytes, Cell, Geometry, Grid};
use station::action::Action;
use station::app::{App, AppOptions, View};
use station::plan::{MapOptions, NavMap, PlanState, Planner};

fn lab() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/data/arenas/ciberrato/wallsMicRato99.xml")
}

/// The built-in start (the shared lab has no grid file).
const START: (f64, f64) = (0.5, 0.5);

/// `station plan` minus printing.
fn plan_cli(path: &str) -> usize {
    let map = NavMap::load(path, &MapOptions::default()).unwrap();
    let planner = Planner::new(map).unwrap();
    planner.plan(Some(START), None, false).unwrap().path.len()
}

/// splitmix64: fixed seed, the same grid every run.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

/// A `side` x `side` grid of 0.1 m cells with round obstacle blobs covering about 25 %,
/// the two corner cells (and their neighbours) kept free.
fn blob_grid(side: u16, seed: u64) -> Grid<Vec<u8>> {
    let n = usize::from(side);
    let geo = Geometry::new(100, 0, 0).unwrap();
    let mut g = Grid::new(side, side, geo, vec![0u8; grid_bytes(n, n)]).unwrap();
    g.fill(Cell::Free);
    let mut rng = Rng(seed);
    let target = n * n / 4;
    let mut marked = 0;
    while marked < target {
        let (cx, cy) = (rng.below(side.into()) as i64, rng.below(side.into()) as i64);
        let r = 1 + rng.below(4) as i64;
        for y in (cy - r).max(0)..=(cy + r).min(n as i64 - 1) {
            for x in (cx - r).max(0)..=(cx + r).min(n as i64 - 1) {
                let corner = (x < 3 && y < 3) || (x >= n as i64 - 3 && y >= n as i64 - 3);
                let inside = (x - cx).pow(2) + (y - cy).pow(2) <= r * r;
                if inside && !corner && g.get(x as usize, y as usize) == Cell::Free {
                    g.set(x as usize, y as usize, Cell::Obstacle).unwrap();
                    marked += 1;
                }
            }
        }
    }
    g
}

/// An app showing the Map view of a blob grid, planned corner to corner (seed chosen so the
/// corners are connected; falls through the seeds until one is).
fn render_app() -> App {
    for seed in 1..100 {
        let g = blob_grid(128, seed);
        let map = NavMap::from_grid("blobs 128", g, Some((0.05, 0.05)), Some((12.75, 12.75)));
        let mut app = App::new(AppOptions::default());
        app.map.plan = PlanState::from_map(map).unwrap();
        app.update(Action::ShowView(View::Map));
        app.update(Action::PlanLocal);
        if app.map.plan.result.is_some() {
            return app;
        }
    }
    panic!("no connected blob grid in 100 seeds");
}

fn draw(term: &mut Terminal<TestBackend>, app: &App) {
    term.draw(|f| station::ui::render(app, f)).unwrap();
}

fn summary(app: &App) {
    let path = lab();
    let path = path.to_str().unwrap();
    let t = Instant::now();
    let steps = plan_cli(path);
    let cold = t.elapsed();
    let p = Planner::new(NavMap::load(path, &MapOptions::default()).unwrap()).unwrap();
    let r = p.plan(Some(START), None, true).unwrap();
    eprintln!(
        "Micro-Rato'99 17x17: {} squares, plan {} regions / {:.2} m (smoothed {:.2} m); \
         segment+graph {} µs, A* {} µs; whole CLI path once {:?} ({steps} regions)",
        p.squares().len(),
        r.path.len(),
        r.length_m,
        r.smoothed.as_ref().map_or(0.0, |s| s.length_m),
        p.segment_us(),
        r.search_us,
        cold,
    );
    let planner = app.map.plan.planner().unwrap();
    let plan = app.map.plan.result.as_ref().unwrap();
    let mut term = Terminal::new(TestBackend::new(200, 60)).unwrap();
    let t = Instant::now();
    draw(&mut term, app);
    eprintln!(
        "render 128x128 ({} squares, plan {} regions) at 200x60: first frame {:?}",
        planner.squares().len(),
        plan.path.len(),
        t.elapsed()
    );
}

fn main() {
    let full = std::env::args().any(|a| a == "--bench");
    let app = render_app();
    summary(&app);
    if !full {
        return;
    }
    let mut c = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2))
        .configure_from_args();
    let path = lab();
    let path = path.to_str().unwrap().to_string();
    let mut g = c.benchmark_group("plan_cli");
    g.bench_function("micro_rato_99_file", |b| {
        b.iter(|| black_box(plan_cli(&path)))
    });
    g.bench_function("micro_rato_99_builtin", |b| {
        b.iter(|| black_box(plan_cli(emulator::builtin::MICRO_RATO_99)))
    });
    let arena = emulator::arena::load(Path::new(&path), &Default::default()).unwrap();
    g.bench_function("rasterise_only", |b| {
        b.iter(|| black_box(NavMap::from_arena(&arena, &path, &MapOptions::default()).unwrap()))
    });
    let map = NavMap::from_arena(&arena, &path, &MapOptions::default()).unwrap();
    g.bench_function("segment_and_graph_only", |b| {
        b.iter(|| black_box(Planner::new(map.clone()).unwrap().squares().len()))
    });
    let planner = Planner::new(map).unwrap();
    g.bench_function("astar_only", |b| {
        b.iter(|| black_box(planner.plan(Some(START), None, false).unwrap().path.len()))
    });
    g.finish();
    let mut g = c.benchmark_group("render");
    let mut term = Terminal::new(TestBackend::new(200, 60)).unwrap();
    g.bench_function("map_128x128_at_200x60", |b| {
        b.iter(|| draw(&mut term, &app))
    });
    g.finish();
    c.final_summary();
}
