//! Arenas compiled into the binary, so `robot-emulator` and `station` run with no files.
//!
//! The Micro-Rato'99 labyrinth of seed 004 (Dom Dinis) is CiberRato's `wallsMicRato99.xml`;
//! the lab file has no grid file, so the start pose beside it is the emulator's own choice
//! (documented in the XML comment).

use std::path::Path;

use crate::arena::{ciberrato, Arena, ArenaError, LoadOptions};

/// Name the command line uses for the built-in Micro-Rato'99 arena.
pub const MICRO_RATO_99: &str = "builtin:micro-rato-99";

const LAB: &str = include_str!("../arenas/wallsMicRato99.xml");
const GRID: &str = include_str!("../arenas/wallsMicRato99Grid.xml");

/// The Micro-Rato'99 arena with its start pose.
pub fn micro_rato_99(opts: &LoadOptions) -> Result<Arena, ArenaError> {
    let mut arena = ciberrato::parse_lab(
        Path::new("builtin:wallsMicRato99.xml"),
        LAB,
        opts.ciberrato_unit_m,
    )?;
    let mut warnings = Vec::new();
    arena.starts = ciberrato::parse_grid(
        Path::new("builtin:wallsMicRato99Grid.xml"),
        GRID,
        &arena,
        &mut warnings,
    )?;
    arena.warnings.extend(warnings);
    Ok(arena)
}

/// Loads `name`: a built-in arena name or a file path.
pub fn load(name: &str, opts: &LoadOptions) -> Result<Arena, ArenaError> {
    if name == MICRO_RATO_99 {
        micro_rato_99(opts)
    } else {
        crate::arena::load(Path::new(name), opts)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_built_in_micro_rato_arena_has_its_start_and_beacon() {
        let a = micro_rato_99(&LoadOptions::default()).expect("built in");
        assert_eq!(a.starts.len(), 1);
        assert!(a.beacon().is_some());
        assert!((a.bounds.max.x - 5.0).abs() < 1e-9);
    }
}
