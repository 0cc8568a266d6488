//! Hostile arena files (issue 13 items 5, 6, 12): deep nesting, tens of thousands of unknown
//! keys or marks, huge values and names, maps larger than the caller's grid. Each must be
//! refused (or accepted) with a short, positioned message, in time linear in its size: these
//! files took minutes, or gigabytes, before. Timings are not asserted (see the benchmarks and
//! docs/reliability.md's figures); a quadratic importer makes these tests take minutes instead.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};

use emulator::arena::{load, micromouse, GridLimit, LoadOptions, EXCERPT_CHARS};

const ROS_KEYS: &str =
    "resolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";

/// A fresh folder with a 4 x 4 free PGM `small.pgm` in it.
fn folder(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("arena-hostile-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let mut pgm = b"P5 4 4 255\n".to_vec();
    pgm.extend([254u8; 16]);
    std::fs::write(dir.join("small.pgm"), pgm).unwrap();
    dir
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn err(path: &Path, opts: &LoadOptions) -> String {
    match load(path, opts) {
        Ok(_) => panic!("{} loaded", path.display()),
        Err(e) => e.to_string(),
    }
}

#[test]
fn deep_yaml_nesting_is_refused_at_the_first_level_too_deep() {
    let dir = folder("nested");
    let text = format!(
        "image: small.pgm\n{ROS_KEYS}extra: {}\n",
        "[ ".repeat(100_000)
    );
    let p = write(&dir, "m.yaml", &text);
    let e = err(&p, &LoadOptions::default());
    // `extra: ` is 7 characters; the 33rd `[` is at column 8 + 2 * 32.
    let at = format!("{}:7:72: YAML nested deeper than 32 levels", p.display());
    assert!(e.starts_with(&at), "{e}");
    // Block sequences opened on one line nest too.
    let p = write(&dir, "b.yaml", &format!("{}x\n", "- ".repeat(50_000)));
    let e = err(&p, &LoadOptions::default());
    assert!(
        e.contains(":1:65: YAML nested deeper than 32 levels"),
        "{e}"
    );
}

#[test]
fn nesting_inside_quotes_and_comments_is_not_nesting() {
    let dir = folder("quoted");
    let deep = "[".repeat(100);
    let text =
        format!("image: small.pgm\n{ROS_KEYS}comment: '{deep}'\nother: \"{deep}\" # {deep}\n");
    let p = write(&dir, "m.yaml", &text);
    let a = load(&p, &LoadOptions::default()).unwrap();
    assert_eq!(a.raster.unwrap().width, 4);
}

#[test]
fn sixty_thousand_unknown_keys_load_with_a_bounded_list_of_warnings() {
    let dir = folder("keys");
    let keys: String = (0..60_000).map(|i| format!("k{i:06}: 1\n")).collect();
    let p = write(
        &dir,
        "m.yaml",
        &format!("image: small.pgm\n{ROS_KEYS}{keys}"),
    );
    let a = load(&p, &LoadOptions::default()).unwrap();
    assert!(a.warnings.len() <= 10, "{} warnings", a.warnings.len());
    assert!(
        a.warnings[0].contains(":7: unknown key 'k000000' ignored"),
        "{:?}",
        a.warnings
    );
    let last = a.warnings.last().unwrap();
    assert!(last.ends_with("59992 more unknown keys ignored"), "{last}");
    // A misspelt key after them is still found, at its own line.
    let p = write(
        &dir,
        "n.yaml",
        &format!("image: small.pgm\n{ROS_KEYS}{keys}resolutin: 1\n"),
    );
    let e = err(&p, &LoadOptions::default());
    assert!(
        e.contains(":60007:1: unknown key 'resolutin'; did you mean 'resolution'?"),
        "{e}"
    );
}

#[test]
fn a_huge_value_or_name_is_quoted_as_a_short_excerpt() {
    let dir = folder("long");
    let origin = vec!["0"; 1_000_000].join(", ");
    let text = format!(
        "image: small.pgm\nresolution: 0.05\norigin: [{origin}]\nnegate: 0\n\
         occupied_thresh: 0.65\nfree_thresh: 0.196\n"
    );
    let p = write(&dir, "o.yaml", &text);
    let e = err(&p, &LoadOptions::default());
    assert!(
        e.ends_with(":3:1: origin must be [x, y, yaw], found a list of 1000000 items"),
        "{e}"
    );
    let name = "x".repeat(100_000);
    let p = write(&dir, "i.yaml", &format!("image: {name}.pgm\n{ROS_KEYS}"));
    let e = err(&p, &LoadOptions::default());
    assert!(e.len() < 400, "{} bytes: {}", e.len(), &e[..400]);
    let quoted = format!(
        "image '{}… (99956 more bytes)' not found",
        &name[..EXCERPT_CHARS]
    );
    assert!(e.contains(&quoted), "{e}");
    // A value with control characters reaches the message escaped.
    let p = write(&dir, "c.yaml", &format!("image: \"a\\e[2Jb\"\n{ROS_KEYS}"));
    let e = err(&p, &LoadOptions::default());
    assert!(e.contains("image 'a\\x1b[2Jb' not found"), "{e}");
    assert!(!e.contains('\u{1b}'), "{e}");
}

#[test]
fn a_yaml_past_its_size_limit_is_refused_before_parsing() {
    let dir = folder("size");
    let origin = vec!["0"; 2_000_000].join(", ");
    let p = write(
        &dir,
        "o.yaml",
        &format!("image: small.pgm\norigin: [{origin}]\n"),
    );
    let e = err(&p, &LoadOptions::default());
    assert!(
        e.contains(": map YAML is 6000026 bytes; map_server YAMLs are a few hundred"),
        "{e}"
    );
}

fn station_limit(cell_m: f64) -> LoadOptions {
    LoadOptions {
        grid_limit: Some(GridLimit {
            cell_m,
            maze_cell_m: None,
            max_side: 2048,
            who: "the test's planner",
        }),
        ..LoadOptions::default()
    }
}

#[test]
fn a_raster_map_beyond_the_callers_grid_is_refused_from_its_header() {
    let dir = folder("huge");
    // No pixel data at all: a refusal must not need (or read) it.
    std::fs::write(dir.join("huge.pgm"), b"P5 8192 8192 255\n").unwrap();
    let yaml = ROS_KEYS.replace("0.05", "0.5");
    let p = write(&dir, "h.yaml", &format!("image: huge.pgm\n{yaml}"));
    let e = err(&p, &station_limit(0.3));
    let at = format!(
        "{}: a 8192 x 8192 image at 0.5 m/pixel is 4096.0 x 4096.0 m: 13654 x 13654 cells of \
         0.3 m, beyond the 2048 cells a side the test's planner takes",
        dir.join("huge.pgm").display()
    );
    assert!(e.starts_with(&at), "{e}");
    // Within the limit, the header is not the problem: the missing pixels are.
    let e = err(&p, &station_limit(2.0));
    assert!(
        e.contains(": byte 17: truncated: pixel data needs 67108864 bytes"),
        "{e}"
    );
    // Without a limit, the importer's own limits apply.
    let e = err(&p, &LoadOptions::default());
    assert!(e.contains(": byte 17: truncated"), "{e}");
}

#[test]
fn a_maze_beyond_the_callers_grid_is_refused_before_its_walls_are_built() {
    let m = 128;
    let mut text = format!("o{}\n", "---o".repeat(m));
    for _ in 0..m {
        text.push_str(&format!("|{}\n", "   |".repeat(m)));
        text.push_str(&format!("o{}\n", "---o".repeat(m)));
    }
    let opts = LoadOptions {
        grid_limit: Some(GridLimit {
            cell_m: 0.3,
            maze_cell_m: Some(0.005),
            max_side: 2048,
            who: "the test's planner",
        }),
        ..LoadOptions::default()
    };
    let e = micromouse::parse(Path::new("m.txt"), &text, &opts)
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with(
            "m.txt: a 128 x 128 maze at 0.09 m pitch needs more than 2048 cells of 0.005 m"
        ),
        "{e}"
    );
    // Half the pitch (the default) fits: 256 cells a side.
    let opts = station_limit(0.3);
    assert!(micromouse::parse(Path::new("m.txt"), &text, &opts).is_ok());
}

#[test]
fn a_maze_with_every_cell_marked_loads_in_linear_time() {
    // 512 x 512 cells, each marked S and G twice: the duplicate check was a search of every
    // mark so far (quadratic in marked cells).
    let m = 512;
    let mut text = format!("o{}\n", "---o".repeat(m));
    for _ in 0..m {
        text.push_str(&format!("|{}\n", "SGS|".repeat(m)));
        text.push_str(&format!("o{}\n", "---o".repeat(m)));
    }
    let maze = micromouse::parse_maze(Path::new("m.txt"), &text).unwrap();
    assert_eq!(maze.starts.len(), m * m);
    assert_eq!(maze.goals.len(), m * m);
}
