//! The emulator's world limit (issue 13 item 6): mazes beyond 64 x 64 cells and grid maps
//! whose obstacle cells make more than 200,000 walls are refused by
//! `LoadOptions::for_simulation()` before their walls are built, naming the file and the sizes;
//! what fits loads as before, and other callers (the station's planner) keep their own limits.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};

use emulator::arena::{ascii, load, micromouse, LoadOptions, WorldLimit};

fn folder(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("arena-world-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// An `n` x `n` maze with every wall up.
fn maze(n: usize) -> String {
    let mut text = format!("o{}\n", "---o".repeat(n));
    for _ in 0..n {
        text.push_str(&format!("|{}\n", "   |".repeat(n)));
        text.push_str(&format!("o{}\n", "---o".repeat(n)));
    }
    text
}

/// An `n` x `n` checkerboard PGM map (every obstacle pixel its own wall) and its YAML.
fn checkerboard_map(dir: &Path, n: usize) -> PathBuf {
    let mut pgm = format!("P5 {n} {n} 255\n").into_bytes();
    pgm.extend((0..n * n).map(|i| if (i / n + i % n) % 2 == 0 { 0u8 } else { 255 }));
    std::fs::write(dir.join("checker.pgm"), pgm).unwrap();
    let yaml = dir.join("checker.yaml");
    std::fs::write(
        &yaml,
        "image: checker.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\n\
         occupied_thresh: 0.65\nfree_thresh: 0.196\n",
    )
    .unwrap();
    yaml
}

#[test]
fn the_largest_maze_the_world_takes_loads_and_one_cell_more_is_refused() {
    let sim = LoadOptions::for_simulation();
    let side = WorldLimit::EMULATOR.max_maze_side as usize;
    let a = micromouse::parse(Path::new("m.txt"), &maze(side), &sim).unwrap();
    assert!(!a.walls.is_empty());
    let e = micromouse::parse(Path::new("m.txt"), &maze(side + 1), &sim)
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "m.txt: a 65 x 65 maze: the emulator's world takes at most 64 x 64 maze cells (refused \
         before building its walls)"
    );
    // The planner (no world limit) still takes it.
    assert!(
        micromouse::parse(Path::new("m.txt"), &maze(side + 1), &LoadOptions::default()).is_ok()
    );
}

#[test]
fn a_maze_beyond_the_world_is_refused_from_its_size_before_its_walls_are_read() {
    // Only the first post row and the number of lines are real: every wall line is garbage,
    // which reading the walls would report instead.
    let n = 2000;
    let mut text = format!("o{}\n", "---o".repeat(n));
    text.push_str(&"x\n".repeat(2 * n));
    let e = micromouse::parse(Path::new("big.txt"), &text, &LoadOptions::for_simulation())
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("big.txt: a 2000 x 2000 maze: the emulator's world takes at most 64 x 64"),
        "{e}"
    );
}

#[test]
fn a_grid_map_making_too_many_walls_is_refused_naming_the_sizes() {
    let dir = folder("checker");
    // 640 x 640 alternating pixels: 204,800 one-pixel walls, past the 200,000 the world takes.
    let yaml = checkerboard_map(&dir, 640);
    let e = match load(&yaml, &LoadOptions::for_simulation()) {
        Ok(a) => panic!("loaded with {} walls", a.walls.len()),
        Err(e) => e.to_string(),
    };
    assert_eq!(
        e,
        format!(
            "{}: a 640 x 640 grid map's obstacle cells, merged into rectangles, make more than \
             200000 walls: the emulator's world takes at most 200000 walls (refused before \
             building them); use a coarser or cleaner map",
            yaml.display()
        )
    );
    // Within a larger budget the same map loads, one wall per obstacle pixel.
    let roomy = LoadOptions {
        world_limit: Some(WorldLimit {
            max_walls: 204_800,
            ..WorldLimit::EMULATOR
        }),
        ..LoadOptions::default()
    };
    assert_eq!(load(&yaml, &roomy).unwrap().walls.len(), 204_800);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_ascii_grid_making_too_many_walls_is_refused() {
    let limit = LoadOptions {
        world_limit: Some(WorldLimit {
            max_walls: 3,
            ..WorldLimit::EMULATOR
        }),
        ..LoadOptions::default()
    };
    // Four separate obstacles, and a solid block that merges into one wall.
    let scattered = "#.#\n...\n#.#\n";
    let e = ascii::parse(Path::new("g.txt"), scattered, &limit)
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("g.txt: a 3 x 3 grid map's obstacle cells, merged into rectangles, make more than 3 walls"),
        "{e}"
    );
    let block = "###\n###\n###\n";
    assert_eq!(
        ascii::parse(Path::new("g.txt"), block, &limit)
            .unwrap()
            .walls
            .len(),
        1
    );
}

#[test]
fn the_sample_arenas_and_a_32_by_32_maze_fit_the_world() {
    let sim = LoadOptions::for_simulation();
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    for p in [
        "ascii/corridor.txt",
        "ascii/tiny.grid",
        "ros/room.yaml",
        "ros/room_plain.yaml",
    ] {
        load(&data.join(p), &sim).unwrap_or_else(|e| panic!("{p}: {e}"));
    }
    assert!(micromouse::parse(Path::new("m.txt"), &maze(32), &sim).is_ok());
}
