//! Where the benchmark's arenas come from (files, folders, generated kinds) and each run's
//! seed, drawn from the base seed so that a run can be repeated alone.

use std::path::{Path, PathBuf};

use crate::arena::{Arena, LoadOptions};
use crate::arena_gen;
use crate::arena_gen::Kind;
use crate::rng::SimRng;

/// Where one benchmark arena comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum ArenaSource {
    /// `arena_gen::generate(kind, seed)`.
    Generated(Kind, u64),
    /// A file or a built-in arena name, loaded as `--arena` would.
    Named(String),
}

impl ArenaSource {
    /// The arena's label in reports.
    pub fn label(&self) -> String {
        match self {
            ArenaSource::Generated(k, s) => arena_gen::arena_name(*k, *s),
            ArenaSource::Named(n) => n.clone(),
        }
    }

    /// The arena: generated, or loaded as `--arena` would.
    pub fn load(&self) -> Result<Arena, String> {
        self.load_with_features().map(|(a, _)| a)
    }

    /// The arena and the features its generator drew it with (none for a file).
    pub fn load_with_features(&self) -> Result<(Arena, Vec<&'static str>), String> {
        match self {
            ArenaSource::Generated(k, s) => arena_gen::generate(*k, *s)
                .map(|g| (g.arena, g.features))
                .map_err(|e| e.to_string()),
            ArenaSource::Named(n) => crate::builtin::load(n, &LoadOptions::for_simulation())
                .map(|a| (a, Vec::new()))
                .map_err(|e| e.to_string()),
        }
    }
}

/// Stream of the benchmark's base seed from which each run's emulator seed is drawn (beyond
/// the per-component streams of `rng::stream` and the fleet's).
const BENCH_SEED_STREAM: u64 = 0x0042_656e_6368; // "Bench"

/// The emulator seed of draw `draw` (1-based, `--seeds K` runs 1..=K) on the arena at
/// `arena_index` (0-based, the order of `--arenas` after expansion: `generated:N` is
/// arenas 1..N at indices 0..N-1) of a benchmark with base seed `base` (`--seed`): the
/// `draw`-th value of the generator seeded with `base` on stream "Bench" + `arena_index`.
/// Different arenas and draws get independent noise; the same triple always the same seed.
pub fn run_seed(base: u64, arena_index: usize, draw: u64) -> u64 {
    run_seeds(base, arena_index, draw)
        .last()
        .copied()
        .unwrap_or_default()
}

/// Draws 1..=`draws` of [`run_seed`] for one arena.
fn run_seeds(base: u64, arena_index: usize, draws: u64) -> Vec<u64> {
    let mut rng = SimRng::new(base, BENCH_SEED_STREAM.wrapping_add(arena_index as u64));
    (0..draws).map(|_| rng.next_u64()).collect()
}

/// Every (arena index, draw, emulator seed) of a benchmark, in report order.
pub(crate) fn run_list(arenas: usize, base: u64, draws: u64) -> Vec<(usize, u64, u64)> {
    (0..arenas)
        .flat_map(|a| {
            run_seeds(base, a, draws)
                .into_iter()
                .zip(1..)
                .map(move |(seed, draw)| (a, draw, seed))
        })
        .collect()
}

/// Most arenas `generated:N` may ask for.
pub const MAX_GENERATED: u64 = 100_000;

/// Resolves `--arenas` values: `generated:N` (N arenas of `kind`, seeds 1..=N), a directory
/// (every arena file in it, sorted by name; grid files are not arenas), or a file or
/// built-in name.
pub fn resolve_arenas(specs: &[String], kind: Kind) -> Result<Vec<ArenaSource>, String> {
    let mut out = Vec::new();
    for spec in specs {
        if let Some(n) = spec.strip_prefix("generated:") {
            let n: u64 = n
                .parse()
                .ok()
                .filter(|n| (1..=MAX_GENERATED).contains(n))
                .ok_or_else(|| {
                    format!(
                        "--arenas {spec}: expected generated:N with N a whole number in \
                         1..={MAX_GENERATED}"
                    )
                })?;
            out.extend((1..=n).map(|s| ArenaSource::Generated(kind, s)));
        } else if Path::new(spec).is_dir() {
            let files = arena_files(Path::new(spec))?;
            if files.is_empty() {
                return Err(format!(
                    "--arenas {spec}: the directory holds no arena files (.xml labs, .txt \
                     mazes or grids, .yaml maps)"
                ));
            }
            out.extend(
                files
                    .into_iter()
                    .map(|p| ArenaSource::Named(p.to_string_lossy().into_owned())),
            );
        } else {
            out.push(ArenaSource::Named(spec.clone()));
        }
    }
    Ok(out)
}

/// The arena files in a directory, sorted: labs (not their grid files), mazes/grids, maps.
fn arena_files(dir: &Path) -> Result<Vec<PathBuf>, String> {
    let entries = std::fs::read_dir(dir).map_err(|e| format!("--arenas {}: {e}", dir.display()))?;
    let mut files: Vec<PathBuf> = entries
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_file())
        .filter(|p| {
            let ext = p
                .extension()
                .and_then(|e| e.to_str())
                .map(str::to_ascii_lowercase);
            let stem = p
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("")
                .to_ascii_lowercase();
            match ext.as_deref() {
                // A grid (start poses) or parameter file beside the labs is none.
                Some("xml") => {
                    !stem.ends_with("grid")
                        && !matches!(
                            crate::arena::ciberrato::root_element(p).as_deref(),
                            Some("Grid" | "Parameters")
                        )
                }
                Some("txt" | "yaml" | "yml") => true,
                _ => false,
            }
        })
        .collect();
    files.sort();
    Ok(files)
}
