//! `station plan` and `station segment` as a user runs them: the real binary, its JSON and its
//! exit codes, on the shared arenas (Micro-Rato'99 and the micromouse mazes) and on bad input.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::Value;

fn data(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/data/arenas")
        .join(rel)
}

fn station(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_station"))
        .args(args)
        .output()
        .unwrap()
}

fn ok_json(args: &[&str]) -> Value {
    let out = station(args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// Exit status 1 and the stderr text.
fn fails(args: &[&str]) -> String {
    let out = station(args);
    assert_eq!(out.status.code(), Some(1), "{args:?} should fail");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn xy(v: &Value) -> (f64, f64) {
    (v[0].as_f64().unwrap(), v[1].as_f64().unwrap())
}

fn polyline(v: &Value) -> Vec<(f64, f64)> {
    v.as_array().unwrap().iter().map(xy).collect()
}

fn length(p: &[(f64, f64)]) -> f64 {
    p.windows(2)
        .map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1))
        .sum()
}

#[test]
fn plan_json_has_the_required_keys_and_sane_values() {
    let v = ok_json(&["plan", "--map", "builtin:micro-rato-99", "--json"]);
    for key in [
        "regions",
        "waypoints",
        "length_m",
        "segment_us",
        "search_us",
    ] {
        assert!(v.get(key).is_some(), "missing {key}: {v}");
    }
    assert!(v.get("smoothed").is_none(), "smoothed only when asked: {v}");
    assert!(v["regions"].as_u64().unwrap() > 10);
    assert!(v["segment_us"].is_u64() && v["search_us"].is_u64());
    let w = polyline(&v["waypoints"]);
    assert!(w.len() >= 3);
    assert!(w
        .iter()
        .all(|&(x, y)| (0.0..=5.1).contains(&x) && (0.0..=5.1).contains(&y)));
    assert_eq!(w[0], (0.5, 0.5));
    let l = v["length_m"].as_f64().unwrap();
    assert!((l - length(&w)).abs() < 0.005, "{l} vs {}", length(&w));
    let (a, b) = (w[0], *w.last().unwrap());
    assert!(l >= (b.0 - a.0).hypot(b.1 - a.1));
}

#[test]
fn smoothing_is_reported_beside_the_raw_plan_and_is_never_longer() {
    let v = ok_json(&[
        "plan",
        "--map",
        "builtin:micro-rato-99",
        "--smooth",
        "--json",
    ]);
    let s = &v["smoothed"];
    let (raw, smooth) = (polyline(&v["waypoints"]), polyline(&s["waypoints"]));
    assert!(smooth.len() < raw.len());
    assert_eq!((smooth[0], smooth.last()), (raw[0], raw.last()));
    assert!(s["length_m"].as_f64().unwrap() <= v["length_m"].as_f64().unwrap());
}

#[test]
fn the_shared_file_plans_like_the_built_in_copy_from_the_same_start() {
    let file = data("ciberrato/wallsMicRato99.xml");
    let a = ok_json(&["plan", "--map", "builtin:micro-rato-99", "--json"]);
    let b = ok_json(&[
        "plan",
        "--map",
        file.to_str().unwrap(),
        "--from",
        "0.5,0.5",
        "--json",
    ]);
    assert_eq!(a["waypoints"], b["waypoints"]);
    assert_eq!(a["regions"], b["regions"]);
}

/// A maze's `S` cell centre and `G` cell rectangles, metres, read with the shared importer.
fn maze_marks(path: &Path) -> ((f64, f64), Vec<[f64; 4]>, f64) {
    use emulator::arena::micromouse::{default_pitch, parse_maze};
    let text = std::fs::read_to_string(path).unwrap();
    let maze = parse_maze(path, &text).unwrap();
    let pitch = default_pitch(maze.cols, maze.rows);
    let (sc, sr) = maze.starts[0];
    let start = ((f64::from(sc) + 0.5) * pitch, (f64::from(sr) + 0.5) * pitch);
    let goals = maze
        .goals
        .iter()
        .map(|&(c, r)| {
            let (x, y) = (f64::from(c) * pitch, f64::from(r) * pitch);
            [x, y, x + pitch, y + pitch]
        })
        .collect();
    (start, goals, pitch)
}

#[test]
fn micromouse_mazes_plan_from_s_to_g_at_half_the_pitch() {
    for name in [
        "AAMC16Maze.txt",
        "alljapan-001-1980.txt",
        "japan2016hef.txt",
    ] {
        let path = data(&format!("micromouse/{name}"));
        let (start, goals, pitch) = maze_marks(&path);
        let cell = format!("{}", pitch / 2.0);
        let v = ok_json(&[
            "plan",
            "--map",
            path.to_str().unwrap(),
            "--cell",
            &cell,
            "--smooth",
            "--json",
        ]);
        let w = polyline(&v["waypoints"]);
        let d = (w[0].0 - start.0).hypot(w[0].1 - start.1);
        assert!(d < 0.002, "{name}: starts at {:?}, S is {start:?}", w[0]);
        let (gx, gy) = *w.last().unwrap();
        assert!(
            goals
                .iter()
                .any(|g| gx >= g[0] && gx <= g[2] && gy >= g[1] && gy <= g[3]),
            "{name}: ends at ({gx}, {gy}), outside the G cells {goals:?}"
        );
        // A maze path is long: at least the Manhattan distance between the cells.
        let l = v["length_m"].as_f64().unwrap();
        assert!(
            l >= (gx - w[0].0).abs() + (gy - w[0].1).abs() - 1e-6,
            "{name}: {l}"
        );
        assert!(v["smoothed"]["length_m"].as_f64().unwrap() <= l);
    }
}

#[test]
fn the_default_cell_of_a_maze_is_half_its_pitch() {
    let path = data("micromouse/AAMC16Maze.txt");
    let v = ok_json(&["segment", "--map", path.to_str().unwrap(), "--json"]);
    assert_eq!(v["cell_m"].as_f64(), Some(0.09));
    // 16 cells -> 33: posts and wall slots between the cell centres.
    assert_eq!(
        (v["width"].as_u64(), v["height"].as_u64()),
        (Some(33), Some(33))
    );
}

#[test]
fn a_walled_in_maze_reports_the_goal_unreachable_and_plans_inside() {
    // maze-train-10x5-a: a closed 10 x 5 maze in the corner of a 16 x 16 frame; no S or G,
    // so the start is the corner cell and the goal the classic centre, outside the small maze.
    let path = data("micromouse/maze-train-10x5-a.txt");
    let p = path.to_str().unwrap();
    let err = fails(&["plan", "--map", p]);
    assert!(err.contains(p) && err.contains("unreachable"), "{err}");
    // Its far corner cell (9, 4) is reachable.
    let v = ok_json(&["plan", "--map", p, "--to", "1.71,0.81", "--json"]);
    assert_eq!(
        xy(v["waypoints"].as_array().unwrap().last().unwrap()),
        (1.71, 0.81)
    );
}

#[test]
fn a_goal_in_a_wall_or_off_the_map_is_an_error_naming_the_map() {
    let err = fails(&["plan", "--map", "builtin:micro-rato-99", "--to", "1.1,1.0"]);
    assert!(err.contains("builtin:micro-rato-99"), "{err}");
    assert!(
        err.contains("goal (1.100, 1.000) is in an obstacle cell (3, 3)"),
        "{err}"
    );
    let err = fails(&["plan", "--map", "builtin:micro-rato-99", "--from", "-1,0.5"]);
    assert!(
        err.contains("start (-1.000, 0.500) is outside the map"),
        "{err}"
    );
    let maze = data("micromouse/AAMC16Maze.txt");
    let err = fails(&["plan", "--map", maze.to_str().unwrap(), "--cell", "0.18"]);
    assert!(err.contains("try --cell 0.09"), "{err}");
}

#[test]
fn a_map_without_a_start_asks_for_one() {
    let file = data("ciberrato/wallsMicRato99.xml");
    let err = fails(&["plan", "--map", file.to_str().unwrap()]);
    assert!(
        err.contains("wallsMicRato99.xml") && err.contains("--from X,Y"),
        "{err}"
    );
}

#[test]
fn bad_files_are_refused_with_the_file_and_the_problem() {
    let err = fails(&["plan", "--map", "/nonexistent/lab.xml"]);
    assert!(err.contains("/nonexistent/lab.xml: cannot read"), "{err}");
    let dir = std::env::temp_dir().join(format!("station-plan-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("broken.xml");
    std::fs::write(&bad, "<Lab Name=\"x\" Width=\"5\" Height=\"5\">\n<Wall>\n").unwrap();
    let err = fails(&["segment", "--map", bad.to_str().unwrap()]);
    assert!(err.contains("broken.xml:"), "{err}");
    let empty = dir.join("empty.txt");
    std::fs::write(&empty, "").unwrap();
    let err = fails(&["plan", "--map", empty.to_str().unwrap()]);
    assert!(err.contains("empty.txt"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn usage_errors_exit_2() {
    for args in [
        &["plan", "--map", "builtin:micro-rato-99", "--cell", "0"][..],
        &["plan", "--map", "builtin:micro-rato-99", "--to", "1.5"],
        &["plan", "--map", "builtin:micro-rato-99", "--radius", "-1"],
        &["plan"],
    ] {
        assert_eq!(station(args).status.code(), Some(2), "{args:?}");
    }
}

#[test]
fn segment_json_lists_squares_in_cells_that_tile_the_free_space() {
    let v = ok_json(&["segment", "--map", "builtin:micro-rato-99", "--json"]);
    assert_eq!(
        (v["width"].as_u64(), v["height"].as_u64()),
        (Some(17), Some(17))
    );
    assert_eq!(v["cell_m"].as_f64(), Some(0.3));
    assert_eq!(xy(&v["origin"]), (0.0, 0.0));
    let squares = v["squares"].as_array().unwrap();
    assert_eq!(squares.len() as u64, v["regions"].as_u64().unwrap());
    let mut seen = vec![false; 17 * 17];
    for s in squares {
        let (x, y, n) = (
            s["x"].as_u64().unwrap() as usize,
            s["y"].as_u64().unwrap() as usize,
            s["size"].as_u64().unwrap() as usize,
        );
        assert!(n >= 1 && x + n <= 17 && y + n <= 17, "{s}");
        for cy in y..y + n {
            for cx in x..x + n {
                assert!(!seen[cy * 17 + cx], "overlap at ({cx}, {cy})");
                seen[cy * 17 + cx] = true;
            }
        }
    }
    // The beacon cell (10, 8) and the top row (past the 5 m wall) are in no square.
    assert!(!seen[8 * 17 + 10]);
    assert!((0..17).all(|x| !seen[16 * 17 + x]));
}

#[test]
fn text_output_is_a_summary_and_a_picture() {
    let out = station(&["plan", "--map", "builtin:micro-rato-99", "--smooth"]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    for needle in [
        "17 x 17 cells of 0.3 m",
        "regions",
        "smoothed",
        "legend:",
        "S",
        "G",
    ] {
        assert!(text.contains(needle), "{needle}: {text}");
    }
}

#[test]
fn ascii_grids_plan_from_their_s_to_their_g() {
    let dir = std::env::temp_dir().join(format!("station-plan-ascii-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("room.txt");
    std::fs::write(
        &file,
        "# cell 0.3\n#########\n#S..#...#\n#...#.G.#\n#.......#\n#########\n",
    )
    .unwrap();
    let v = ok_json(&["plan", "--map", file.to_str().unwrap(), "--json"]);
    let w = polyline(&v["waypoints"]);
    assert_eq!(w.first(), Some(&(0.45, 1.05)));
    assert_eq!(w.last(), Some(&(1.95, 0.75)));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_small_arena_at_coarse_cells_suggests_a_finer_cell_which_then_plans() {
    let e = fails(&["plan", "--map", "builtin:forage"]);
    assert!(e.contains("try a smaller --cell, e.g. 0.1"), "{e}");
    let v = ok_json(&["plan", "--map", "builtin:forage", "--cell", "0.1", "--json"]);
    assert!(
        v["waypoints"].as_array().is_some_and(|w| !w.is_empty()),
        "{v}"
    );
}
