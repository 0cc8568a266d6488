//! Arenas compiled into the binary, so `robot-emulator` and `station` run with no files.
//!
//! The Micro-Rato'99 labyrinth of seed 004 (Dom Dinis) is CiberRato's `wallsMicRato99.xml`;
//! the lab file has no grid file, so the start pose beside it is the emulator's own choice
//! (documented in the XML comment). ALICE's scenes (seed 001) are `alice`.

use std::path::Path;

use crate::arena::{ciberrato, Arena, ArenaError, LoadOptions};
use crate::geometry::Point;

pub mod alice;

/// Name of the built-in floor-grid arena (seed 003): an empty walled square over a floor grid.
pub const FLOOR_GRID: &str = "builtin:floor-grid";
/// Side of the floor-grid arena, metres: room for the survey's 0.8 m disc around the centre
/// start, with a robot's turning margin before the walls.
pub const FLOOR_GRID_SIDE_M: f64 = 2.4;

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

/// The floor-grid arena: walls around a square with its lower-left corner at the origin (so
/// the grid's lines are at whole multiples of the pitch, where the firmware assumes them),
/// the start near the centre, off every line, heading 23 degrees.
pub fn floor_grid() -> Arena {
    let side = FLOOR_GRID_SIDE_M;
    Arena {
        starts: vec![crate::arena::Pose {
            x: side / 2.0 + 0.03,
            y: side / 2.0 + 0.04,
            heading: 0.4,
        }],
        ..crate::arena::walled_box("Floor grid (line correction)", FLOOR_GRID, side, side)
    }
}

/// The floor grid pitch a built-in arena comes with (seed 003 §2.6.4: 10 cm squares).
pub fn floor_grid_pitch(name: &str) -> Option<f64> {
    (name == FLOOR_GRID).then_some(crate::world::GRID_PITCH_M)
}

/// The foraging arena of seed 000 §7 (`builtin:forage`, see `crate::forage`): a 1.0 x 0.8 m
/// box (the paper's arenas are 75 x 60 and 80 x 80 cm) with one block in the middle, the home
/// base (the target circle, 10 cm radius) in the lower-left corner where the robot starts,
/// and three lamps, each with an object under it. The landmarks are outside the walls
/// (`ForageSite::for_arena`).
pub fn forage() -> Result<Arena, ArenaError> {
    let mut arena = crate::arena::ascii::parse(
        Path::new(crate::forage::BUILTIN_FORAGE),
        FORAGE_GRID,
        &LoadOptions::default(),
    )?;
    arena.source = Path::new(crate::forage::BUILTIN_FORAGE).to_path_buf();
    let home = arena
        .starts
        .first()
        .map_or(Point::new(0.125, 0.125), |s| Point::new(s.x, s.y));
    arena.targets = vec![crate::arena::Target {
        centre: home,
        radius_m: crate::forage::HOME_RADIUS_M,
    }];
    arena.goal = Some(home);
    arena.lights = [(0.82, 0.64), (0.22, 0.62), (0.80, 0.18)]
        .into_iter()
        .map(|(x, y)| crate::arena::Light {
            position: Point::new(x, y),
            height_m: 0.05,
            intensity: 1.0,
        })
        .collect();
    Ok(arena)
}

/// 5 cm cells, the border outside the 1.0 x 0.8 m floor; `S` is the home base's centre.
const FORAGE_GRID: &str = "\
# name Foraging (Löffler et al.)
# cell 0.05
# origin -0.05 -0.05
# heading 45
######################
#....................#
#....................#
#....................#
#....................#
#....................#
#....................#
#....................#
#........####........#
#........####........#
#....................#
#....................#
#....................#
#....................#
#..S.................#
#....................#
#....................#
######################
";

/// Loads `name`: a built-in arena name or a file path.
pub fn load(name: &str, opts: &LoadOptions) -> Result<Arena, ArenaError> {
    if name == MICRO_RATO_99 {
        micro_rato_99(opts)
    } else if name == FLOOR_GRID {
        Ok(floor_grid())
    } else if name == crate::forage::BUILTIN_FORAGE {
        forage()
    } else if let Some(a) = alice::builtin(name) {
        Ok(a)
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
