//! The ROS map importer's two readers on arbitrary bytes, without the file system: the map
//! YAML (`rosmap::parse_meta`: YAML syntax, nesting, keys, values) and the PGM decoder with the
//! cell classification (`rosmap::raster_from_pgm`: P5/P2 headers, pixel data, limits).
//! Invariants: no panic; an accepted image's grid has one cell per pixel; every error message
//! is short (issue 13 item 12: messages quote excerpts) and holds no raw control character.
#![no_main]

use std::path::{Path, PathBuf};

use emulator::arena::rosmap::{parse_meta, raster_from_pgm, MapMeta, MapMode};
use emulator::arena::{ArenaError, GridLimit};
use libfuzzer_sys::fuzz_target;

fn check(e: &ArenaError) {
    let msg = e.to_string();
    assert!(msg.len() <= 1300, "{} byte message", msg.len());
    assert!(!msg.chars().any(char::is_control), "control character in {msg:?}");
}

fuzz_target!(|data: &[u8]| {
    let Some((&which, bytes)) = data.split_first() else { return };
    if which & 1 == 0 {
        let text = String::from_utf8_lossy(bytes);
        let mut warnings = Vec::new();
        // `image` is looked up on disk: a missing one is an error like any other.
        if let Err(e) = parse_meta(Path::new("fuzz.yaml"), &text, &mut warnings) {
            check(&e);
        }
        return;
    }
    let meta = MapMeta {
        image: PathBuf::from("fuzz.pgm"),
        resolution: 0.05,
        origin: [0.0; 3],
        negate: which & 2 != 0,
        occupied_thresh: 0.65,
        free_thresh: 0.196,
        mode: match (which >> 2) % 3 {
            0 => MapMode::Trinary,
            1 => MapMode::Scale,
            _ => MapMode::Raw,
        },
    };
    // Half the inputs under a planner's limit (refused from the header when too large).
    let limit = (which & 32 != 0).then_some(GridLimit {
        cell_m: 0.3,
        maze_cell_m: None,
        max_side: 2048,
        who: "the fuzzer",
    });
    match raster_from_pgm(&meta, bytes, limit) {
        Ok((r, _)) => assert_eq!(r.cells.len(), r.width as usize * r.height as usize),
        Err(e) => check(&e),
    }
});
