//! Malformed arena files (tests/data/bad/): each must fail with an error that names the file
//! and the line:column (text, XML, YAML, plain PGM) or byte offset (binary PGM) of the fault,
//! and says what is wrong. None may panic.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};

use emulator::arena::{load, ArenaError, GridFile, LoadOptions};

fn data(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(rel)
}

fn shared(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/data/arenas")
        .join(rel)
}

/// Loads `file` and checks the message starts with `<where>: ` and mentions `what`.
/// `where_` is the offending file (relative to tests/data) plus `:line:col`, `:line` or
/// `: byte N`, or nothing for a whole-file error.
fn fails_at(
    file: &Path,
    opts: &LoadOptions,
    where_file: &str,
    where_: &str,
    what: &str,
) -> ArenaError {
    let err = match load(file, opts) {
        Ok(a) => panic!("{} loaded but should fail: {a:?}", file.display()),
        Err(e) => e,
    };
    let msg = err.to_string();
    let prefix = format!("{}{where_}: ", data(where_file).display());
    assert!(
        msg.starts_with(&prefix),
        "message {msg:?}\n  should start with {prefix:?}"
    );
    assert!(
        msg.contains(what),
        "message {msg:?}\n  should mention {what:?}"
    );
    err
}

fn bad(file: &str, where_: &str, what: &str) -> ArenaError {
    let f = format!("bad/{file}");
    fails_at(&data(&f), &LoadOptions::default(), &f, where_, what)
}

#[test]
fn xml_that_does_not_parse_is_reported_at_roxmltrees_position() {
    bad("lab_unclosed.xml", ":4:3", "expected 'Wall' tag, not 'Wal'");
}

#[test]
fn non_finite_lab_width_is_reported_at_the_attribute_value() {
    bad(
        "lab_nan_width.xml",
        ":2:13",
        "Width=\"NaN\" is not a finite number",
    );
}

#[test]
fn negative_lab_height_is_refused() {
    bad("lab_negative_height.xml", ":1:34", "Height -14 must be > 0");
}

#[test]
fn absurd_lab_size_is_refused() {
    bad("lab_absurd_size.xml", ":1:22", "absurd");
}

#[test]
fn wall_with_two_corners_is_refused_at_the_wall() {
    bad(
        "lab_two_corners.xml",
        ":3:3",
        "at least 3 <Corner>s, this one has 2",
    );
}

#[test]
fn corner_outside_the_lab_is_refused_at_the_corner() {
    bad("lab_corner_outside.xml", ":4:5", "outside the lab");
}

#[test]
fn self_crossing_wall_is_refused() {
    bad("lab_self_crossing.xml", ":3:3", "crosses itself");
}

#[test]
fn misspelt_attribute_is_an_error_naming_the_right_one() {
    bad("lab_misspelt_attr.xml", ":2:23", "did you mean 'Radius'");
}

#[test]
fn dtd_entities_are_refused() {
    bad("lab_dtd_entity.xml", ":2:1", "DTD");
}

#[test]
fn grid_file_with_a_word_for_a_direction_is_reported_in_the_grid_file() {
    let opts = LoadOptions {
        ciberrato_grid: GridFile::Path(data("bad/grid_bad_dir.xml")),
        ..LoadOptions::default()
    };
    let lab = shared("ciberrato/wallsMicRato99.xml");
    fails_at(
        &lab,
        &opts,
        "bad/grid_bad_dir.xml",
        ":3:35",
        "Dir=\"east\" is not a finite number",
    );
}

#[test]
fn start_position_outside_the_lab_is_refused() {
    let opts = LoadOptions {
        ciberrato_grid: GridFile::Path(data("bad/grid_outside.xml")),
        ..LoadOptions::default()
    };
    let lab = shared("ciberrato/wallsMicRato99.xml");
    fails_at(
        &lab,
        &opts,
        "bad/grid_outside.xml",
        ":2:3",
        "outside the lab",
    );
}

#[test]
fn grid_file_loaded_as_a_lab_says_what_it_is() {
    let e = load(
        &shared("ciberrato/Ciber2005_FinalGrid.xml"),
        &LoadOptions::default(),
    )
    .unwrap_err();
    assert!(
        e.to_string()
            .contains("Ciber2005_FinalGrid.xml:1:1: this is a CiberRato grid file"),
        "{e}"
    );
}

#[test]
fn maze_cell_with_an_unknown_mark_is_reported_at_the_character() {
    bad("maze_bad_char.txt", ":2:7", "unexpected 'X' in a cell");
}

#[test]
fn maze_with_irregular_posts_is_reported_at_the_stray_post() {
    bad("maze_irregular_posts.txt", ":1:8", "irregular post spacing");
}

#[test]
fn maze_with_a_missing_post_is_reported_where_it_should_be() {
    bad("maze_missing_post.txt", ":3:9", "expected a post 'o'");
}

#[test]
fn maze_without_its_bottom_post_row_is_refused() {
    bad("maze_no_bottom.txt", ":4:1", "missing the last post row");
}

#[test]
fn maze_wall_half_drawn_is_reported_where_dashes_stop() {
    bad("maze_broken_wall.txt", ":3:4", "broken wall");
}

#[test]
fn invalid_utf8_is_reported_at_its_line_and_column() {
    bad("maze_bad_utf8.txt", ":2:5", "invalid UTF-8");
}

#[test]
fn yaml_syntax_error_is_reported_at_the_parsers_position() {
    let e = load(&data("bad/ros_syntax.yaml"), &LoadOptions::default()).unwrap_err();
    let loc = e.location().unwrap();
    assert!(
        matches!(
            loc.position,
            emulator::arena::Position::Line {
                column: Some(_),
                ..
            }
        ),
        "{e}"
    );
    assert!(
        e.to_string().contains("ros_syntax.yaml:") && e.to_string().contains("YAML:"),
        "{e}"
    );
}

#[test]
fn missing_yaml_key_is_named() {
    bad(
        "ros_missing_resolution.yaml",
        "",
        "missing key 'resolution'",
    );
}

#[test]
fn yaml_image_that_does_not_exist_is_reported_at_the_image_key() {
    bad(
        "ros_image_missing.yaml",
        ":2:1",
        "image 'nowhere.pgm' not found",
    );
}

#[test]
fn free_threshold_above_occupied_is_refused() {
    bad(
        "ros_thresholds.yaml",
        ":6:1",
        "free_thresh 0.65 must be below occupied_thresh 0.25",
    );
}

#[test]
fn misspelt_yaml_key_is_an_error_naming_the_right_one() {
    bad("ros_misspelt_key.yaml", ":4:1", "did you mean 'negate'");
}

#[test]
fn negative_resolution_is_refused() {
    bad(
        "ros_bad_resolution.yaml",
        ":2:1",
        "resolution -0.05 m/pixel must be > 0",
    );
}

#[test]
fn nan_in_the_origin_is_refused() {
    bad("ros_origin_nan.yaml", ":4:1", "not a finite number");
}

#[test]
fn truncated_binary_pgm_is_reported_at_the_byte_where_it_ends() {
    let opts = LoadOptions::default();
    fails_at(
        &data("bad/ros_truncated.yaml"),
        &opts,
        "bad/truncated.pgm",
        ": byte 53",
        "needs 100 bytes from byte 13",
    );
}

#[test]
fn plain_pgm_value_above_maxval_is_reported_at_its_line_and_column() {
    let opts = LoadOptions::default();
    fails_at(
        &data("bad/ros_p2_value.yaml"),
        &opts,
        "bad/p2_value.pgm",
        ":5:3",
        "pixel value 300 exceeds maxval 255",
    );
}

#[test]
fn absurd_pgm_width_is_refused_before_reading_pixels() {
    let opts = LoadOptions::default();
    fails_at(
        &data("bad/ros_huge.yaml"),
        &opts,
        "bad/huge.pgm",
        ": byte 3",
        "width 100000 must be 1..=8192",
    );
}

#[test]
fn png_named_by_a_map_yaml_is_recognised() {
    let opts = LoadOptions::default();
    fails_at(
        &data("bad/ros_png.yaml"),
        &opts,
        "bad/not_pgm.png",
        ": byte 0",
        "a PNG image",
    );
}

#[test]
fn a_pgm_alone_points_to_its_yaml() {
    let opts = LoadOptions::default();
    fails_at(
        &data("ros/room.pgm"),
        &opts,
        "ros/room.pgm",
        "",
        "load its map YAML instead",
    );
    let e = load(&data("ros/room.pgm"), &opts).unwrap_err().to_string();
    assert!(e.contains("room.yaml"), "{e}");
}

#[test]
fn ascii_grid_with_an_unknown_character_is_reported_at_it() {
    bad("ascii_bad_char.txt", ":3:4", "unexpected 'x' in a grid row");
}

#[test]
fn ascii_header_typo_is_an_error_naming_the_right_key() {
    bad("ascii_unknown_header.txt", ":1:3", "did you mean 'cell'");
}

#[test]
fn ascii_negative_cell_size_is_refused_at_the_value() {
    bad("ascii_bad_cell.txt", ":2:8", "cell size -1 m must be > 0");
}

#[test]
fn ascii_tab_is_refused() {
    bad("ascii_tab.txt", ":2:3", "tab character");
}

#[test]
fn ascii_header_after_the_grid_gets_a_hint() {
    bad(
        "ascii_header_after_grid.txt",
        ":2:3",
        "header lines must come before the grid",
    );
}

#[test]
fn bad_load_options_are_refused_before_reading() {
    let opts = LoadOptions {
        ciberrato_unit_m: f64::NAN,
        ..LoadOptions::default()
    };
    let e = load(&shared("ciberrato/wallsMicRato99.xml"), &opts).unwrap_err();
    assert!(
        e.to_string().starts_with("load option ciberrato_unit_m"),
        "{e}"
    );
}

#[test]
fn missing_file_is_an_io_error_naming_it() {
    let e = load(&data("bad/does_not_exist.xml"), &LoadOptions::default()).unwrap_err();
    assert!(
        matches!(e, ArenaError::Io { .. }) && e.to_string().contains("does_not_exist.xml"),
        "{e}"
    );
}

#[test]
fn oversized_file_is_refused_without_reading_it() {
    // A sparse file: its length is past the limit but it takes no disk space.
    let path = std::env::temp_dir().join(format!("arena-huge-{}.txt", std::process::id()));
    let f = std::fs::File::create(&path).unwrap();
    f.set_len(emulator::arena::MAX_FILE_BYTES + 1).unwrap();
    drop(f);
    let e = load(&path, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    std::fs::remove_file(&path).unwrap();
    assert!(e.contains("arena files are limited to"), "{e}");
}

const ALPHABET: &[u8] = b"0123456789.-+eE<>\"/= #|oG S?\n\t:[],NaInf";

/// A small deterministic generator, so failures reproduce.
struct Lcg(u64);

impl Lcg {
    fn below(&mut self, n: usize) -> usize {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 33) as usize) % n.max(1)
    }

    fn byte(&mut self) -> u8 {
        ALPHABET[self.below(ALPHABET.len())]
    }

    /// One to three ASCII edits: replace, delete or insert a character.
    fn mutate(&mut self, text: &str) -> String {
        let mut b = text.as_bytes().to_vec();
        for _ in 0..1 + self.below(3) {
            let at = self.below(b.len());
            let c = self.byte();
            match self.below(3) {
                0 if !b.is_empty() => b[at] = c,
                1 if !b.is_empty() => {
                    b.remove(at);
                }
                _ => b.insert(at, c),
            }
        }
        String::from_utf8(b).unwrap()
    }
}

/// Loaded arenas must rasterise too.
fn rasterises(r: Result<emulator::arena::Arena, ArenaError>) {
    if let Ok(a) = r {
        let cell = (a.bounds.width().max(a.bounds.height()) / 64.0).max(0.01);
        emulator::arena::rasterise(&a, cell, cell / 2.0).unwrap();
    }
}

/// Deterministic mutations of every sample (digits, signs, markup, separators replaced,
/// inserted or deleted): each must load or fail with an error, never panic, and whatever loads
/// must rasterise.
#[test]
fn mutated_text_samples_never_panic() {
    use emulator::arena::{ascii, ciberrato, micromouse, rosmap};
    let mut rng = Lcg(0x5eed);
    let opts = LoadOptions {
        ciberrato_grid: GridFile::None,
        ..LoadOptions::default()
    };
    let samples = [
        (shared("ciberrato/wallsMicRato99.xml"), 'x'),
        (shared("ciberrato/Ciber2005_FinalLab.xml"), 'x'),
        (shared("micromouse/AAMC16Maze.txt"), 'm'),
        (data("ascii/corridor.txt"), 'a'),
        (data("ros/room.yaml"), 'y'),
    ];
    for (path, kind) in samples {
        let text = std::fs::read_to_string(&path).unwrap();
        for _ in 0..400 {
            let m = rng.mutate(&text);
            match kind {
                'x' => rasterises(ciberrato::load_text(&path, &m, &opts)),
                'm' => rasterises(micromouse::parse(&path, &m, &opts)),
                'a' => rasterises(ascii::parse(&path, &m, &opts)),
                _ => rasterises(rosmap::parse(&path, &m)),
            }
        }
    }
    // The grid file against its lab.
    let lab_path = shared("ciberrato/Ciber2005_FinalLab.xml");
    let lab =
        ciberrato::parse_lab(&lab_path, &std::fs::read_to_string(&lab_path).unwrap(), 0.3).unwrap();
    let grid = std::fs::read_to_string(shared("ciberrato/Ciber2005_FinalGrid.xml")).unwrap();
    for _ in 0..400 {
        let _ = ciberrato::parse_grid(
            Path::new("g.xml"),
            &rng.mutate(&grid),
            &lab,
            &mut Vec::new(),
        );
    }
}

/// Mutated PGM images, plain and binary (also cut short), behind a fixed YAML.
#[test]
fn mutated_pgm_images_never_panic() {
    let mut rng = Lcg(0xb17e);
    let dir = std::env::temp_dir().join(format!("arena-mutants-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let yaml = "image: m.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
    std::fs::write(dir.join("m.yaml"), yaml).unwrap();
    let plain = std::fs::read_to_string(data("ros/room_plain.pgm")).unwrap();
    let binary = std::fs::read(data("ros/room.pgm")).unwrap();
    for i in 0..400 {
        if i % 2 == 0 {
            std::fs::write(dir.join("m.pgm"), rng.mutate(&plain)).unwrap();
        } else {
            let mut b = binary.clone();
            let at = rng.below(b.len());
            b[at] = rng.byte();
            b.truncate(b.len() - rng.below(8));
            std::fs::write(dir.join("m.pgm"), b).unwrap();
        }
        rasterises(load(&dir.join("m.yaml"), &LoadOptions::default()));
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
