//! Arena generator for the generalisation benchmark (issue 14): Micro-Rato labyrinths (seed 004
//! §2), micromouse mazes, and Khepera boxes with blocks, bars and dead ends (seed 000 §4,
//! Fig. 17), each deterministic per seed and checked solvable before it is handed out.
//!
//! Layer: std, beside the importers. The generator writes the same text a file would hold
//! (CiberRato lab + grid XML, or maze text) and the arena is always read back through the
//! existing importers ([`crate::arena::ciberrato`], [`crate::arena::micromouse`]), so what the
//! benchmark runs is exactly what `--out` writes and what `--arena FILE` loads.
//!
//! Solvability: the imported arena is rasterised at a quarter of the robot's diameter with
//! obstacles inflated by its radius (the raster's exact, conservative rule: a free cell is one
//! where the robot's centre fits anywhere in it), and a 4-connected flood from the start must
//! reach a free cell whose centre lies in the goal area. An attempt that fails (or that the
//! importer refuses) is replaced by the next sub-seed, up to [`MAX_ATTEMPTS`].
//!
//! Determinism: every draw comes from [`SimRng`] seeded with (seed, [`STREAM`] + attempt);
//! nothing depends on time, threads or hash order.
//!
//! What can fail: writing the files ([`GenError::Io`], nothing half-written: each file goes to
//! a temporary name beside it and is renamed into place), and, in principle, a seed for which
//! no attempt is solvable ([`GenError::Unsolvable`]).

mod khepera_box;
mod maze;
mod micro_rato;
pub mod real_like;
mod shapes;
mod traps;
mod xml;

use std::path::{Path, PathBuf};

use crate::arena::{self, Arena, ArenaError, LoadOptions};
use crate::geometry::Point;
use crate::rng::SimRng;

pub use maze::maze_text;

/// Random stream of the first attempt; attempt `k` uses `STREAM + k` (after `forage`'s 16/17).
pub const STREAM: u64 = 1000;
/// Attempts (sub-seeds) before a seed is given up as unsolvable.
pub const MAX_ATTEMPTS: u32 = 64;

/// Which kind of arena.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Kind {
    /// 5 x 5 m Micro-Rato labyrinth with a 1 m goal circle and beacon (CiberRato XML).
    MicroRato,
    /// Micromouse maze, 4-16 cells a side, goal at the farthest cell (maze text).
    Maze,
    /// Khepera box of 75 x 60 cm or larger with blocks, bars and dead ends (CiberRato XML).
    Box,
    /// CiberRato/Micro-Rato lab like the real ones: up to 28 x 14 units, long detours (U
    /// traps, long walls, spirals, combs, `<Row>` mazes), narrow gaps, small targets, several
    /// beacons, home areas, walls hiding the beacon, odd starts (CiberRato XML).
    RealLike,
}

impl Kind {
    /// The name used in arena names and file names.
    pub fn name(self) -> &'static str {
        match self {
            Kind::MicroRato => "micro-rato",
            Kind::Maze => "maze",
            Kind::Box => "box",
            Kind::RealLike => "real-like",
        }
    }

    /// The robot the arena is made for (its diameter decides solvability).
    pub fn profile(self) -> &'static robot_firmware::Profile {
        match self {
            Kind::MicroRato | Kind::RealLike => &robot_firmware::MICRO_RATO,
            Kind::Maze | Kind::Box => &robot_firmware::KHEPERA,
        }
    }
}

/// The text of a generated arena.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ArenaText {
    /// CiberRato lab XML and its grid file (start poses).
    CiberRato {
        /// `<Lab>` XML.
        lab: String,
        /// `<Grid>` XML.
        grid: String,
    },
    /// Micromouse maze text.
    Maze(String),
}

/// One generated arena: its text and the arena the importers read from it.
#[derive(Clone, Debug)]
pub struct Generated {
    /// Kind.
    pub kind: Kind,
    /// Seed asked for.
    pub seed: u64,
    /// Sub-seed that gave a solvable arena (0 = the first attempt).
    pub attempt: u32,
    /// What a file holds.
    pub text: ArenaText,
    /// The arena as the importer reads the text.
    pub arena: Arena,
    /// What the generator drew it with, for reports by feature (real-like arenas).
    pub features: Vec<&'static str>,
}

/// Why generation failed.
#[derive(Debug, thiserror::Error)]
pub enum GenError {
    /// No attempt was solvable (never seen; kept so a bug cannot loop forever).
    #[error("no solvable {kind} arena for seed {seed} in every attempt: {last}")]
    Unsolvable {
        /// Kind.
        kind: &'static str,
        /// Seed.
        seed: u64,
        /// Why the last attempt was rejected.
        last: String,
    },
    /// Writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The error.
        source: std::io::Error,
    },
    /// The output helper refused or failed (an existing file without `--force`, a special
    /// file, the directory).
    #[error("{0}")]
    Output(crate::output_file::OutputError),
    /// `--out` cannot name the grid file that goes with the lab.
    #[error("{0}")]
    OutPath(String),
}

/// A layout in metres, before it becomes text (CiberRato kinds).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Layout {
    pub name: String,
    pub width_m: f64,
    pub height_m: f64,
    /// Wall polygons, corners in metres.
    pub walls: Vec<Vec<Point>>,
    /// Each wall's height in CiberRato units (beside `walls`); empty: every wall
    /// [`xml::LOW_WALL`], below the beacon.
    pub wall_heights: Vec<f64>,
    /// `<Row Pos Pattern>` maze rows (CiberRato's own maze notation), after the walls.
    pub rows: Vec<(u32, String)>,
    /// The goal beacon (the first in the file, the one the robot is told of).
    pub beacon: Point,
    /// The goal beacon's target area.
    pub target: (Point, f64),
    /// Further beacons, each with its own target area of this radius (CiberRato labs with
    /// several beacons).
    pub more_beacons: Vec<(Point, f64)>,
    /// Target areas without a beacon: home or start areas (CiberRato 2011).
    pub homes: Vec<(Point, f64)>,
    /// Start poses (x, y, heading radians).
    pub starts: Vec<[f64; 3]>,
}

impl Layout {
    /// One beacon over its target, plain walls below it.
    pub fn plain(
        name: &str,
        (width_m, height_m): (f64, f64),
        walls: Vec<Vec<Point>>,
        target: (Point, f64),
        starts: Vec<[f64; 3]>,
    ) -> Layout {
        Layout {
            name: name.to_string(),
            width_m,
            height_m,
            walls,
            wall_heights: Vec::new(),
            rows: Vec::new(),
            beacon: target.0,
            target,
            more_beacons: Vec::new(),
            homes: Vec::new(),
            starts,
        }
    }
}

/// The arena name for a kind and seed: `micro-rato-0007`.
pub fn arena_name(kind: Kind, seed: u64) -> String {
    format!("{}-{seed:04}", kind.name())
}

/// Attempts of a real-like arena that must fall in the detour class drawn for its seed; the
/// rest of [`REAL_LIKE_ATTEMPTS`] take any solvable draw, so a seed never fails for its class.
const IN_CLASS_ATTEMPTS: u32 = 150;
/// Attempts of a real-like arena (its classes need more than [`MAX_ATTEMPTS`]).
const REAL_LIKE_ATTEMPTS: u32 = 200;

/// Generates the arena of `kind` for `seed`.
pub fn generate(kind: Kind, seed: u64) -> Result<Generated, GenError> {
    let name = arena_name(kind, seed);
    let mut last = String::new();
    let radius = f64::from(kind.profile().body_diameter_m) / 2.0;
    // The real-like family's detour class, on a stream of its own (attempts do not move it).
    let class = real_like::wanted_bucket(&mut SimRng::new(seed, STREAM - 1));
    let attempts = if kind == Kind::RealLike {
        REAL_LIKE_ATTEMPTS
    } else {
        MAX_ATTEMPTS
    };
    for attempt in 0..attempts {
        let mut rng = SimRng::new(seed, STREAM + u64::from(attempt));
        let mut features = Vec::new();
        let text = match kind {
            Kind::MicroRato => xml::ciberrato(&micro_rato::layout(&name, &mut rng)),
            Kind::Box => xml::ciberrato(&khepera_box::layout(&name, &mut rng)),
            Kind::Maze => ArenaText::Maze(maze::generate(&mut rng)),
            Kind::RealLike => match real_like::layout(&name, &mut rng, class) {
                Some(d) => {
                    features = d.features;
                    xml::ciberrato(&d.layout)
                }
                None => {
                    last = "a structure broke the spacing rules".to_string();
                    continue;
                }
            },
        };
        let arena = match import(&name, &text) {
            Ok(a) => a,
            Err(e) => {
                last = format!("importer refused it: {e}");
                continue;
            }
        };
        if let Err(why) = solvable(&arena, radius) {
            last = why;
            continue;
        }
        if kind == Kind::RealLike && attempt < IN_CLASS_ATTEMPTS {
            let want = real_like::DETOUR_BUCKETS[class].0;
            match detour_of(&arena, radius) {
                Some(r) if real_like::detour_bucket(r) == want => {}
                other => {
                    last = format!("detour {other:?} is not in class {want}");
                    continue;
                }
            }
        }
        return Ok(Generated {
            kind,
            seed,
            attempt,
            text,
            arena,
            features,
        });
    }
    Err(GenError::Unsolvable {
        kind: kind.name(),
        seed,
        last,
    })
}

/// The detour ratio from the arena's first start to its goal area for a robot of `radius`.
pub fn detour_of(arena: &Arena, radius: f64) -> Option<f64> {
    let start = arena.starts.first()?;
    let (goal, r) = goal_area(arena)?;
    arena::free_path::free_path(arena, Point::new(start.x, start.y), goal, r, radius)
        .map(|f| f.detour_ratio)
}

/// Reads generated text back through the importers, as a file of that name would be.
pub fn import(name: &str, text: &ArenaText) -> Result<Arena, ArenaError> {
    let opts = LoadOptions::default();
    match text {
        ArenaText::CiberRato { lab, grid } => {
            let lab_path = PathBuf::from(format!("generated:{name}Lab.xml"));
            let grid_path = PathBuf::from(format!("generated:{name}Grid.xml"));
            let mut a = arena::ciberrato::parse_lab(&lab_path, lab, opts.ciberrato_unit_m)?;
            let mut warnings = Vec::new();
            a.starts = arena::ciberrato::parse_grid(&grid_path, grid, &a, &mut warnings)?;
            a.warnings.extend(warnings);
            Ok(a)
        }
        ArenaText::Maze(t) => {
            arena::micromouse::parse(&PathBuf::from(format!("generated:{name}.txt")), t, &opts)
        }
    }
}

/// The goal a go-to or search heads for: the first target's centre and radius, else the
/// marked goal point with no area.
pub fn goal_area(arena: &Arena) -> Option<(Point, f64)> {
    arena
        .target()
        .map(|t| (t.centre, t.radius_m))
        .or_else(|| arena.goal.map(|g| (g, 0.0)))
}

/// `Ok` when a robot of `radius` can drive from the arena's first start to its goal area
/// ([`crate::arena::reach::Reach`]: the robot may start against a wall, so the free cells whose
/// centres are within a radius of the start are its seeds; a goal cell is a free one whose
/// centre lies in the goal area, or within a cell of a point goal).
pub fn solvable(arena: &Arena, radius: f64) -> Result<(), String> {
    let start = arena.starts.first().ok_or("no start pose")?;
    let (goal, goal_r) = goal_area(arena).ok_or("no goal")?;
    let s = Point::new(start.x, start.y);
    let reach = crate::arena::reach::Reach::from(arena, radius, |c| (c - s).norm() <= radius)
        .map_err(|e| e.to_string())?;
    if reach.is_empty() {
        return Err(format!(
            "no free cell around the start ({:.2}, {:.2})",
            s.x, s.y
        ));
    }
    let within = goal_r.max(radius / 2.0);
    if reach.any(|c| (c - goal).norm() <= within) {
        return Ok(());
    }
    Err(format!(
        "the goal ({:.2}, {:.2}) cannot be reached from the start ({:.2}, {:.2}) by a {:.3} m robot",
        goal.x,
        goal.y,
        s.x,
        s.y,
        2.0 * radius
    ))
}

/// The files `write` creates for `out`: the lab (or maze) itself, and for CiberRato kinds the
/// grid file the importer finds beside it (`…Lab.xml` -> `…Grid.xml`).
pub fn out_paths(kind: Kind, out: &Path) -> Result<Vec<PathBuf>, GenError> {
    if kind == Kind::Maze {
        return Ok(vec![out.to_path_buf()]);
    }
    let grid = arena::ciberrato::grid_path_for(out).ok_or_else(|| {
        GenError::OutPath(format!(
            "--out {}: a CiberRato lab file must be named ...Lab.xml, so that its start \
             positions (...Grid.xml, written beside it) are found when it is loaded",
            out.display()
        ))
    })?;
    Ok(vec![out.to_path_buf(), grid])
}

/// Writes a generated arena to `out` (and its grid file beside it); returns the files written.
/// Every file goes through [`crate::output_file`] (an O_EXCL temporary with an unpredictable
/// name, renamed into place; an existing file only with `force`, a special file never), so a
/// failure leaves no half-written file.
pub fn write(g: &Generated, out: &Path, force: bool) -> Result<Vec<PathBuf>, GenError> {
    use std::io::Write as _;
    let paths = out_paths(g.kind, out)?;
    let texts: Vec<&str> = match &g.text {
        ArenaText::CiberRato { lab, grid } => vec![lab, grid],
        ArenaText::Maze(t) => vec![t],
    };
    let mut staged = Vec::new();
    for (path, text) in paths.iter().zip(texts) {
        let mut file =
            crate::output_file::OutputFile::create(path, force).map_err(GenError::Output)?;
        file.writer()
            .write_all(text.as_bytes())
            .map_err(|source| GenError::Io {
                path: path.clone(),
                source,
            })?;
        staged.push(file);
    }
    // The grid first: a lab never appears without its start positions beside it. Dropping the
    // files not yet committed removes their temporaries.
    for file in staged.into_iter().rev() {
        file.commit().map_err(GenError::Output)?;
    }
    Ok(paths)
}

/// A perfect maze of `cols` x `rows` cells, carved by a randomised depth-first search from
/// `from`: the walls east of and north of each cell (row-major, `r * cols + c`), true where
/// standing; every cell joined to every other by exactly one way.
pub(crate) fn carve(
    cols: usize,
    rows: usize,
    from: (usize, usize),
    rng: &mut SimRng,
) -> (Vec<bool>, Vec<bool>) {
    let (n, m) = (cols, rows);
    let mut east = vec![true; n * m];
    let mut north = vec![true; n * m];
    let mut seen = vec![false; n * m];
    let mut stack = vec![from];
    if let Some(s) = seen.get_mut(from.1 * n + from.0) {
        *s = true;
    }
    while let Some(&(c, r)) = stack.last() {
        let mut next = Vec::new();
        if c > 0 && !seen[r * n + c - 1] {
            next.push((c - 1, r));
        }
        if c + 1 < n && !seen[r * n + c + 1] {
            next.push((c + 1, r));
        }
        if r > 0 && !seen[(r - 1) * n + c] {
            next.push((c, r - 1));
        }
        if r + 1 < m && !seen[(r + 1) * n + c] {
            next.push((c, r + 1));
        }
        if next.is_empty() {
            stack.pop();
            continue;
        }
        let (nc, nr) = next[(rng.next_u64() % next.len() as u64) as usize];
        if nr == r {
            east[r * n + c.min(nc)] = false;
        } else {
            north[r.min(nr) * n + c] = false;
        }
        seen[nr * n + nc] = true;
        stack.push((nc, nr));
    }
    (east, north)
}

/// Uniform in `[lo, hi)`.
pub(crate) fn uniform(rng: &mut SimRng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.uniform()
}

/// Uniform integer in `lo..=hi`.
pub(crate) fn pick(rng: &mut SimRng, lo: u32, hi: u32) -> u32 {
    let n = u64::from(hi.saturating_sub(lo)) + 1;
    lo + (rng.next_u64() % n) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kind_is_deterministic_and_solvable_for_fixed_seeds() {
        for kind in [Kind::MicroRato, Kind::Maze, Kind::Box, Kind::RealLike] {
            for seed in 1..=12 {
                let a = generate(kind, seed).expect("generates");
                let b = generate(kind, seed).expect("generates");
                assert_eq!(a.text, b.text, "{kind:?} seed {seed} differs between calls");
                let r = f64::from(kind.profile().body_diameter_m) / 2.0;
                assert!(solvable(&a.arena, r).is_ok(), "{kind:?} {seed}");
                assert!(a.arena.warnings.is_empty(), "{:?}", a.arena.warnings);
            }
            let texts: Vec<_> = (1..=5)
                .map(|s| generate(kind, s).expect("generates").text)
                .collect();
            assert!(
                texts.windows(2).all(|w| w[0] != w[1]),
                "{kind:?}: seeds give different arenas"
            );
        }
    }

    #[test]
    fn a_walled_off_goal_is_unsolvable() {
        let mut g = generate(Kind::MicroRato, 3).expect("generates");
        let t = *g.arena.target().expect("target");
        // A closed square ring of wall around the goal circle.
        let (c, r) = (t.centre, t.radius_m + 0.1);
        let ring = |x0: f64, y0: f64, x1: f64, y1: f64| crate::arena::Wall {
            corners: vec![
                Point::new(x0, y0),
                Point::new(x1, y0),
                Point::new(x1, y1),
                Point::new(x0, y1),
            ],
            height_m: None,
        };
        let th = 0.05;
        g.arena.walls.extend([
            ring(c.x - r, c.y - r, c.x + r, c.y - r + th),
            ring(c.x - r, c.y + r - th, c.x + r, c.y + r),
            ring(c.x - r, c.y - r, c.x - r + th, c.y + r),
            ring(c.x + r - th, c.y - r, c.x + r, c.y + r),
        ]);
        let e = solvable(&g.arena, 0.12).unwrap_err();
        assert!(e.contains("cannot be reached"), "{e}");
    }

    #[test]
    fn micro_rato_follows_the_rules_of_seed_004() {
        for seed in 1..=20 {
            let g = generate(Kind::MicroRato, seed).expect("generates");
            let a = &g.arena;
            assert!((a.bounds.width() - 5.0).abs() < 1e-6, "5 x 5 m");
            assert!((a.bounds.height() - 5.0).abs() < 1e-6);
            let t = a.target().expect("goal circle");
            assert!((t.radius_m - 0.5).abs() < 1e-3, "1 m goal circle");
            let b = a.beacon().expect("beacon");
            assert!(
                (b.position - t.centre).norm() < 1e-3,
                "beacon at its centre"
            );
            assert!(!a.starts.is_empty());
            for s in &a.starts {
                assert!((Point::new(s.x, s.y) - t.centre).norm() > t.radius_m);
            }
            assert!(a.walls.len() >= 4, "a labyrinth, not an empty box");
        }
    }

    #[test]
    fn writing_a_lab_needs_a_lab_name_and_writes_its_grid_beside_it() {
        let dir = std::env::temp_dir().join(format!("arena-gen-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let g = generate(Kind::Box, 2).expect("generates");
        assert!(write(&g, &dir.join("box.xml"), false).is_err());
        let written = write(&g, &dir.join("boxLab.xml"), false).expect("writes");
        assert_eq!(written[1], dir.join("boxGrid.xml"));
        let a = crate::arena::load(&written[0], &LoadOptions::default()).expect("loads");
        assert_eq!(a.walls, g.arena.walls);
        assert_eq!(a.starts, g.arena.starts);
        let leftovers = std::fs::read_dir(&dir)
            .expect("list")
            .filter(|e| {
                e.as_ref()
                    .is_ok_and(|e| e.file_name().to_string_lossy().contains(".tmp-"))
            })
            .count();
        assert_eq!(leftovers, 0);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
