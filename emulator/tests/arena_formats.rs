//! Every real arena in shared/data/arenas and the samples in tests/data load into the facts
//! their files state: sizes, wall counts, start poses, goals, and the seed 004 §5 raster
//! (Micro-Rato'99 at 0.3 m cells is 17 x 17).
#![allow(clippy::unwrap_used, clippy::panic)]

use std::f64::consts::FRAC_PI_2;
use std::path::{Path, PathBuf};

use emulator::arena::micromouse::{self, Side};
use emulator::arena::{
    load, rasterise, Arena, ArenaFormat, Cell, GridFile, LoadOptions, Pose, CIBERRATO_UNIT_M,
};
use emulator::geometry::{Point, Vector};

fn shared(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/data/arenas")
        .join(rel)
}

fn data(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(rel)
}

fn open(path: &Path) -> Arena {
    load(path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-9
}

fn assert_pose(p: &Pose, x: f64, y: f64, heading_deg: f64) {
    let ok = close(p.x, x) && close(p.y, y) && close(p.heading, heading_deg.to_radians());
    assert!(ok, "{p:?} should be ({x}, {y}, {heading_deg} deg)");
}

#[test]
fn every_shared_arena_file_loads_or_explains_itself() {
    let mut seen = 0;
    for sub in ["ciberrato", "micromouse"] {
        for entry in std::fs::read_dir(shared(sub)).unwrap() {
            let path = entry.unwrap().path();
            seen += 1;
            match load(&path, &LoadOptions::default()) {
                Ok(a) => {
                    assert!(
                        !a.walls.is_empty() && a.bounds.width() > 0.0 && a.bounds.height() > 0.0,
                        "{a:?}"
                    );
                    assert!(a.walls.iter().all(|w| w.corners.len() >= 3));
                    assert!(a
                        .walls
                        .iter()
                        .flat_map(|w| &w.corners)
                        .all(|c| c.x.is_finite() && c.y.is_finite()));
                    assert!(a.warnings.is_empty(), "{:?}", a.warnings);
                }
                // A grid file holds start poses for a lab; alone it is not an arena.
                Err(e) if path.ends_with("Ciber2005_FinalGrid.xml") => {
                    assert!(e.to_string().contains("grid file"), "{e}");
                }
                Err(e) => panic!("{e}"),
            }
        }
    }
    assert_eq!(seen, 7);
}

#[test]
fn micro_rato_99_is_a_5_m_square_with_four_walls_and_the_beacon_in_the_goal() {
    let a = open(&shared("ciberrato/wallsMicRato99.xml"));
    assert_eq!(a.format, ArenaFormat::CiberRato);
    assert_eq!(a.name, "Ciber-Rato 1999");
    assert!(close(a.bounds.min.x, 0.0) && close(a.bounds.max.x, 5.0) && close(a.bounds.max.y, 5.0));
    assert!(a.enclosed && close(a.unit_m, 5.0 / 17.5) && close(a.unit_m, CIBERRATO_UNIT_M));
    let corners: Vec<usize> = a.walls.iter().map(|w| w.corners.len()).collect();
    assert_eq!(corners, [4, 8, 4, 4]);
    assert_eq!(
        a.segments().len(),
        20 + 4,
        "wall edges plus the four boundary edges"
    );
    let b = a.beacon().unwrap();
    assert!(
        close(b.position.x, 10.5 * a.unit_m)
            && close(b.position.y, 9.0 * a.unit_m)
            && close(b.height_m, 2.0 * a.unit_m)
    );
    let t = a.target().unwrap();
    assert!(
        close(t.radius_m, 2.0 * a.unit_m) && t.centre == b.position && a.goal == Some(t.centre)
    );
    // No grid file exists for this lab, so no start poses.
    assert!(a.starts.is_empty());
    // Wall 1 runs from x 3.5 to 4.5 units (1.0 to 1.286 m), from the floor up to y 9 units.
    assert!(a.is_solid(Point::new(1.1, 2.0)) && !a.is_solid(Point::new(1.1, 2.7)));
    assert!(
        a.is_solid(Point::new(5.01, 1.0)),
        "outside the enclosure is solid"
    );
}

/// Seed 004 §5's grid for this arena, inflation 0: '#' is any cell a wall enters.
const MICRO_RATO_99_AT_0_3: &str = "\
#################
................#
................#
................#
......######.##.#
......######.##.#
......##.....##.#
......##.....##.#
...##.##..G.....#
...##.##.....##.#
...##.##.....##.#
...##.##.....##.#
...##.######.##.#
...##.######.##.#
...##...........#
...##...........#
...##...........#
";

#[test]
fn micro_rato_99_rasterises_to_the_papers_17_by_17_grid() {
    let a = open(&shared("ciberrato/wallsMicRato99.xml"));
    let r = rasterise(&a, 0.3, 0.0).unwrap();
    assert_eq!((r.width, r.height), (17, 17));
    assert_eq!(r.origin, [0.0, 0.0]);
    assert_eq!(r.to_ascii(), MICRO_RATO_99_AT_0_3);
    // Cells of wall 1 (cols 3-4, rows 0-8) and the goal cell under the beacon.
    assert!((0..=8)
        .all(|row| r.get(3, row) == Some(Cell::Obstacle) && r.get(4, row) == Some(Cell::Obstacle)));
    assert_eq!(r.get(3, 9), Some(Cell::Free));
    assert_eq!(r.cell_at(3.0, 9.0 * a.unit_m), Some((10, 8)));
    assert_eq!(r.count(Cell::Unknown), 0);
    // Inflating by Dom Dinis's radius (0.12 m, seed 004 §3) only grows the obstacles.
    let fat = rasterise(&a, 0.3, 0.12).unwrap();
    assert!(fat.count(Cell::Obstacle) > r.count(Cell::Obstacle));
    assert!(r
        .cells
        .iter()
        .zip(&fat.cells)
        .all(|(t, f)| *t != Cell::Obstacle || *f == Cell::Obstacle));
    assert_eq!(
        fat.get(0, 0),
        Some(Cell::Obstacle),
        "the boundary is now within reach"
    );
}

#[test]
fn ciber_2005_lab_takes_its_start_poses_from_the_grid_file_beside_it() {
    let lab = shared("ciberrato/Ciber2005_FinalLab.xml");
    let a = open(&lab);
    let u = 5.0 / 17.5;
    assert_eq!(a.name, "tos challenge");
    assert!(close(a.bounds.max.x, 28.0 * u) && close(a.bounds.max.y, 14.0 * u));
    assert_eq!(a.walls.len(), 32);
    assert_eq!(a.walls.iter().map(|w| w.corners.len()).sum::<usize>(), 158);
    assert_eq!(a.starts.len(), 3);
    assert_pose(&a.starts[0], 2.0 * u, 12.5 * u, -15.0);
    assert_pose(&a.starts[1], 1.75 * u, 1.5 * u, 15.0);
    assert_pose(&a.starts[2], 26.25 * u, 12.5 * u, -165.0);
    // The same grid given explicitly, and no grid at all.
    let grid = shared("ciberrato/Ciber2005_FinalGrid.xml");
    let explicit = load(
        &lab,
        &LoadOptions {
            ciberrato_grid: GridFile::Path(grid),
            ..LoadOptions::default()
        },
    )
    .unwrap();
    assert_eq!(explicit.starts, a.starts);
    let none = load(
        &lab,
        &LoadOptions {
            ciberrato_grid: GridFile::None,
            ..LoadOptions::default()
        },
    )
    .unwrap();
    assert!(none.starts.is_empty());
    // A beacon 2 units high is hidden only by the 14 walls 3 units high, not the 18 of 1 unit.
    let b = a.beacon().unwrap();
    let tall = a.segment_set_hiding(b.height_m);
    let tall_walls = a
        .walls
        .iter()
        .filter(|w| w.height_m.is_some_and(|h| h > b.height_m))
        .count();
    assert_eq!(tall_walls, 14);
    assert!(tall.len() < a.segment_set().len());
}

#[test]
fn lab_scale_is_configurable() {
    let opts = LoadOptions {
        ciberrato_unit_m: 0.3,
        ..LoadOptions::default()
    };
    let a = load(&shared("ciberrato/wallsMicRato99.xml"), &opts).unwrap();
    assert!(close(a.bounds.max.x, 5.25) && close(a.unit_m, 0.3));
}

/// Counts unit walls straight from the text: every `---` and every `|`.
fn text_wall_count(path: &Path) -> usize {
    let t = std::fs::read_to_string(path).unwrap();
    t.matches("---").count() + t.matches('|').count()
}

#[test]
fn classic_16x16_mazes_are_2_88_m_with_the_goal_in_the_centre() {
    for name in ["AAMC16Maze.txt", "alljapan-001-1980.txt"] {
        let path = shared(&format!("micromouse/{name}"));
        let text = std::fs::read_to_string(&path).unwrap();
        let maze = micromouse::parse_maze(&path, &text).unwrap();
        assert_eq!((maze.cols, maze.rows), (16, 16));
        assert_eq!(maze.wall_count(), text_wall_count(&path));
        let mut goals = maze.goals.clone();
        goals.sort();
        assert_eq!(
            goals,
            [(7, 7), (7, 8), (8, 7), (8, 8)],
            "{name}: G marks are the centre 2x2"
        );
        assert_eq!(maze.starts, [(0, 0)]);
        assert!(
            maze.wall(0, 0, Side::West)
                && maze.wall(0, 0, Side::East)
                && maze.wall(0, 0, Side::South)
        );
        assert!(!maze.wall(0, 0, Side::North));

        let a = open(&path);
        assert_eq!(a.format, ArenaFormat::Micromouse);
        assert!(
            close(a.bounds.max.x, 2.88) && close(a.bounds.max.y, 2.88) && close(a.unit_m, 0.18)
        );
        assert_pose(&a.starts[0], 0.09, 0.09, 90.0);
        let g = a.goal.unwrap();
        assert!(close(g.x, 1.44) && close(g.y, 1.44));
    }
}

#[test]
fn merged_maze_walls_cover_exactly_the_unit_walls() {
    // Each run rectangle is (pieces x pitch + thickness) long; lone posts are thickness square.
    for (name, pitch) in [
        ("AAMC16Maze.txt", 0.18),
        ("japan2016hef.txt", 0.09),
        ("maze-train-10x5-a.txt", 0.18),
    ] {
        let path = shared(&format!("micromouse/{name}"));
        let a = open(&path);
        let t = 0.012;
        let length: f64 = a
            .walls
            .iter()
            .map(|w| {
                let (dx, dy) = (
                    w.corners[2].x - w.corners[0].x,
                    w.corners[2].y - w.corners[0].y,
                );
                dx.max(dy) - t
            })
            .sum();
        let pieces = (length / pitch).round() as usize;
        assert_eq!(pieces, text_wall_count(&path), "{name}");
        assert!((length - pieces as f64 * pitch).abs() < 1e-6, "{name}");
    }
}

#[test]
fn half_size_32x32_maze_uses_the_0_09_m_pitch_and_its_3x3_goal() {
    let path = shared("micromouse/japan2016hef.txt");
    let text = std::fs::read_to_string(&path).unwrap();
    let maze = micromouse::parse_maze(&path, &text).unwrap();
    assert_eq!((maze.cols, maze.rows), (32, 32));
    assert_eq!(maze.wall_count(), 1018);
    assert_eq!(maze.goals.len(), 9);
    let a = open(&path);
    assert!(close(a.bounds.max.x, 2.88) && close(a.unit_m, 0.09));
    assert_pose(&a.starts[0], 0.045, 0.045, 90.0);
    let g = a.goal.unwrap();
    assert!(close(g.x, 2.5 * 0.09) && close(g.y, 3.5 * 0.09), "{g:?}");
    assert!(a.segment_set().is_indexed());
}

#[test]
fn maze_without_g_marks_gets_the_classic_centre_and_pitch_can_be_overridden() {
    let path = shared("micromouse/maze-train-10x5-a.txt");
    let a = open(&path);
    let g = a.goal.unwrap();
    assert!(close(g.x, 1.44) && close(g.y, 1.44));
    let opts = LoadOptions {
        maze_pitch_m: Some(0.1),
        ..LoadOptions::default()
    };
    let b = load(&path, &opts).unwrap();
    assert!(close(b.bounds.max.x, 1.6) && close(b.unit_m, 0.1));
}

#[test]
fn rays_from_the_maze_start_stop_at_the_wall_faces() {
    let path = shared("micromouse/AAMC16Maze.txt");
    let a = open(&path);
    let text = std::fs::read_to_string(&path).unwrap();
    let maze = micromouse::parse_maze(&path, &text).unwrap();
    let walls = a.segment_set();
    let start = Point::new(a.starts[0].x, a.starts[0].y);
    // East: the start cell's east wall, whose face is half a thickness before x = 0.18.
    let east = walls
        .ray_cast(start, Vector::new(1.0, 0.0), f64::INFINITY)
        .unwrap();
    assert!(close(east.distance, 0.18 - 0.006 - 0.09), "{east:?}");
    // North: up column 0 to the first cell with a north wall, by the parsed layout.
    let first_wall = (0..16).find(|&r| maze.wall(0, r, Side::North)).unwrap();
    let north = walls
        .ray_cast(start, Vector::new(0.0, 1.0), f64::INFINITY)
        .unwrap();
    assert!(
        close(
            north.distance,
            (first_wall + 1) as f64 * 0.18 - 0.006 - 0.09
        ),
        "{north:?}"
    );
    // The robot-sized disc at the start touches nothing; one 0.09 m across the west wall does.
    assert!(!walls.circle_collides(start, 0.05));
    assert!(walls.circle_collides(Point::new(0.09, 0.09), 0.085));
    assert!(!a.starts.is_empty() && close(a.starts[0].heading, FRAC_PI_2));
}

#[test]
fn ros_map_cells_follow_map_servers_thresholds() {
    let a = open(&data("ros/room.yaml"));
    assert_eq!(a.format, ArenaFormat::RosMap);
    assert_eq!(a.name, "room");
    let r = a.raster.as_ref().unwrap();
    assert_eq!(
        (r.width, r.height, r.cell_m, r.origin),
        (20, 12, 0.05, [-0.5, -0.3])
    );
    assert!(
        close(a.bounds.min.x, -0.5) && close(a.bounds.max.x, 0.5) && close(a.bounds.max.y, 0.3)
    );
    // Border (60) + a 4 x 3 block; a 5 x 3 patch of 205 grey is unknown.
    assert_eq!(
        (
            r.count(Cell::Obstacle),
            r.count(Cell::Unknown),
            r.count(Cell::Free)
        ),
        (72, 15, 153)
    );
    // The image's top rows are the map's max y: the grey patch is top right.
    assert_eq!(r.get(15, 9), Some(Cell::Unknown));
    assert_eq!(r.get(15, 2), Some(Cell::Free));
    assert_eq!(r.cell_at(-0.225, -0.025), Some((5, 5)));
    assert_eq!(r.get(5, 5), Some(Cell::Obstacle));
    // Merged walls: bottom row, top row, two side columns, the block.
    assert_eq!(a.walls.len(), 5);
    assert!(a.walls.iter().all(|w| w.height_m.is_none()));
}

#[test]
fn plain_negated_ros_map_gives_the_same_cells_as_the_binary_one() {
    let binary = open(&data("ros/room.yaml"));
    let plain = open(&data("ros/room_plain.yaml"));
    assert_eq!(
        plain.raster.as_ref().unwrap().cells,
        binary.raster.as_ref().unwrap().cells
    );
    assert_eq!(plain.walls, binary.walls);
}

#[test]
fn rasterising_a_grid_map_at_its_own_resolution_gives_it_back() {
    let a = open(&data("ros/room.yaml"));
    let own = a.raster.as_ref().unwrap();
    let r = rasterise(&a, own.cell_m, 0.0).unwrap();
    assert_eq!(
        (r.width, r.height, r.origin),
        (own.width, own.height, own.origin)
    );
    assert_eq!(r.cells, own.cells);
    // At double the cell size, a coarse cell is unknown if it overlaps the grey patch.
    let coarse = rasterise(&a, 0.1, 0.0).unwrap();
    assert_eq!((coarse.width, coarse.height), (10, 6));
    assert_eq!(coarse.get(7, 4), Some(Cell::Unknown));
    assert_eq!(coarse.get(0, 0), Some(Cell::Obstacle));
    assert_eq!(coarse.get(4, 1), Some(Cell::Free));
}

#[test]
fn ascii_grid_reads_its_header_marks_and_unknowns() {
    let a = open(&data("ascii/corridor.txt"));
    assert_eq!(a.format, ArenaFormat::AsciiGrid);
    assert_eq!(a.name, "corridor");
    let r = a.raster.as_ref().unwrap();
    assert_eq!(
        (r.width, r.height, r.cell_m, r.origin),
        (10, 6, 0.25, [1.0, -0.5])
    );
    assert!(close(a.bounds.max.x, 3.5) && close(a.bounds.max.y, 1.0));
    assert_eq!(a.starts.len(), 1);
    assert_pose(&a.starts[0], 1.625, 0.375, 90.0);
    let g = a.goal.unwrap();
    assert!(close(g.x, 3.125) && close(g.y, 0.375));
    assert_eq!(r.count(Cell::Unknown), 3);
    // The raster prints back as the file's grid rows.
    let text = std::fs::read_to_string(data("ascii/corridor.txt")).unwrap();
    let rows: String = text
        .lines()
        .filter(|l| !l.starts_with("# "))
        .map(|l| format!("{l}\n"))
        .collect();
    assert_eq!(r.to_ascii(), rows);
}

#[test]
fn ascii_grid_without_header_uses_the_default_cell_and_any_extension() {
    let a = open(&data("ascii/tiny.grid"));
    let r = a.raster.as_ref().unwrap();
    assert_eq!((r.width, r.height, r.cell_m), (5, 5, 0.3));
    assert_eq!(r.count(Cell::Obstacle), 17);
    assert_pose(&a.starts[0], 0.45, 1.05, 0.0);
}

#[test]
fn a_rasterised_lab_saved_as_ascii_loads_back_to_the_same_cells() {
    let a = open(&shared("ciberrato/wallsMicRato99.xml"));
    let r = rasterise(&a, 0.3, 0.0).unwrap();
    let path = std::env::temp_dir().join(format!("arena-roundtrip-{}.txt", std::process::id()));
    std::fs::write(
        &path,
        format!("# name micro-rato 99\n# cell 0.3\n{}", r.to_ascii()),
    )
    .unwrap();
    let back = load(&path, &LoadOptions::default());
    std::fs::remove_file(&path).unwrap();
    let back = back.unwrap();
    assert_eq!(back.raster.as_ref().unwrap().cells, r.cells);
    assert_eq!(
        back.goal.map(|g| r.cell_at(g.x, g.y)),
        Some(r.cell_at(3.0, 9.0 * a.unit_m))
    );
}
