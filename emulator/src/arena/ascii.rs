//! The plain ASCII grid: one text row per grid row, the top text row being the max-y row.
//!
//! ```text
//! # name corridor
//! # cell 0.25
//! # origin 0 0
//! # heading 90
//! ##########
//! #S....?..#
//! #.....#.G#
//! ##########
//! ```
//!
//! Cells: `#` obstacle, `.` or space free, `?` unknown, `S` a start (free), `G` a goal (free).
//! Header lines, only before the first grid row, are `#`, optional spaces, then a lowercase
//! key (grid rows hold no lowercase letters, so `# S` is a row and `# cell` a header):
//! - `cell <metres>`: cell side (default [`LoadOptions::ascii_cell_m`], 0.3 m);
//! - `origin <x> <y>`: map position of the grid's lower-left corner (default 0 0);
//! - `heading <degrees>`: heading of every `S` start, anticlockwise from +x (default 0);
//! - `name <text>`: the arena's name (default the file stem);
//! - `note <text>`: a comment, ignored.
//!
//! Blank lines before the grid are skipped; trailing blank lines are dropped. Rows shorter than
//! the longest are padded with free cells, since editors strip trailing spaces. Every `S` is a
//! start pose (at its cell centre); the goal is the centre of the `G` cells.
//! The grid's rectangle is not a wall by itself: draw the border with `#`.
//!
//! Layer: arena importer. What can fail (at file:line:column): an unknown or repeated header
//! key, a bad header value (non-finite, cell <= 0), an unexpected character or a tab in a row,
//! no rows at all, more than [`MAX_GRID_SIDE`] rows or columns.

use std::path::Path;

use super::error::{did_you_mean, excerpt, parse_finite, to_u32, ArenaError};
use super::raster::{obstacle_walls_within, RasterMap};
use super::{Arena, ArenaFormat, Cell, LoadOptions, Pose, MAX_GRID_SIDE};
use crate::geometry::{Aabb, Point};

const KEYS: [&str; 5] = ["cell", "origin", "heading", "name", "note"];

#[derive(Default)]
struct Header {
    cell: Option<f64>,
    origin: Option<[f64; 2]>,
    heading_deg: Option<f64>,
    name: Option<String>,
}

/// Parses an ASCII grid's text.
pub fn parse(path: &Path, text: &str, opts: &LoadOptions) -> Result<Arena, ArenaError> {
    let err = |line: usize, col: usize, msg: String| {
        ArenaError::at_line(path, to_u32(line + 1), Some(to_u32(col + 1)), msg)
    };
    let lines: Vec<&str> = text
        .split('\n')
        .map(|l| l.strip_suffix('\r').unwrap_or(l))
        .collect();
    let mut header = Header::default();
    let mut seen: Vec<&str> = Vec::new();
    let mut first_row = None;
    for (i, line) in lines.iter().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let Some((key, key_col)) = header_key(line) else {
            first_row = Some(i);
            break;
        };
        if !KEYS.contains(&key) {
            // A header key nobody knows cannot be taken for a row; say what was meant.
            let hint = match did_you_mean(key, &KEYS) {
                Some(k) => format!("; did you mean '{k}'?"),
                None => format!(
                    " (known: {}; free text goes after '# note')",
                    KEYS.join(", ")
                ),
            };
            return Err(err(
                i,
                key_col,
                format!("unknown header key '{}'{hint}", excerpt(key)),
            ));
        }
        if key != "note" && seen.contains(&key) {
            return Err(err(i, key_col, format!("header key '{key}' given twice")));
        }
        seen.push(key);
        parse_header_value(&mut header, key, line, key_col + key.len())
            .map_err(|(c, m)| err(i, c, m))?;
    }
    let first = first_row.ok_or_else(|| ArenaError::at_file(path, "no grid rows"))?;
    let last = lines
        .iter()
        .rposition(|l| !l.trim().is_empty())
        .unwrap_or(first);
    let rows = &lines[first..=last];
    let height = rows.len();
    let width = rows.iter().map(|r| r.chars().count()).max().unwrap_or(0);
    if width == 0 || width > MAX_GRID_SIDE as usize || height > MAX_GRID_SIDE as usize {
        return Err(ArenaError::at_file(
            path,
            format!("a {width} x {height} grid must be 1..={MAX_GRID_SIDE} cells a side"),
        ));
    }
    let cell_m = header.cell.unwrap_or(opts.ascii_cell_m);
    let origin = header.origin.unwrap_or([0.0, 0.0]);
    let heading = header.heading_deg.unwrap_or(0.0).to_radians();
    let mut raster = RasterMap {
        width: to_u32(width),
        height: to_u32(height),
        cell_m,
        origin,
        cells: vec![Cell::Free; width * height],
        start: None,
        goal: None,
    };
    let mut starts = Vec::new();
    let mut goals = Vec::new();
    for (t, line) in rows.iter().enumerate() {
        let row = height - 1 - t;
        for (col, ch) in line.chars().enumerate() {
            let cell = match ch {
                '#' => Cell::Obstacle,
                '.' | ' ' => Cell::Free,
                '?' => Cell::Unknown,
                'S' | 'G' => {
                    let [x, y] = raster.cell_centre(to_u32(col), to_u32(row));
                    if ch == 'S' { &mut starts } else { &mut goals }.push(Point::new(x, y));
                    Cell::Free
                }
                '\t' => {
                    return Err(err(
                        first + t,
                        col,
                        "tab character; use spaces or '.' for free cells".into(),
                    ))
                }
                c => {
                    let hint = if header_key(line).is_some() {
                        " (header lines must come before the grid)"
                    } else {
                        ""
                    };
                    return Err(err(
                        first + t,
                        col,
                        format!(
                            "unexpected {c:?} in a grid row; expected one of # . space ? S G{hint}"
                        ),
                    ));
                }
            };
            raster.cells[row * width + col] = cell;
        }
    }
    let goal = (!goals.is_empty()).then(|| {
        Point::from(
            goals
                .iter()
                .fold(nalgebra::Vector2::zeros(), |a, g| a + g.coords)
                / goals.len() as f64,
        )
    });
    raster.start = starts.first().map(|p| [p.x, p.y]);
    raster.goal = goal.map(|g| [g.x, g.y]);
    let bounds = Aabb {
        min: Point::new(origin[0], origin[1]),
        max: Point::new(raster.line_x(raster.width), raster.line_y(raster.height)),
    };
    Ok(Arena {
        name: header.name.unwrap_or_else(|| {
            path.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        }),
        source: path.to_path_buf(),
        format: ArenaFormat::AsciiGrid,
        bounds,
        enclosed: false,
        walls: obstacle_walls_within(path, &raster, opts.world_limit)?,
        raster: Some(raster),
        beacons: Vec::new(),
        targets: Vec::new(),
        lights: Vec::new(),
        starts: starts
            .iter()
            .map(|p| Pose {
                x: p.x,
                y: p.y,
                heading,
            })
            .collect(),
        goal,
        unit_m: cell_m,
        warnings: Vec::new(),
    })
}

/// `Some((key, column))` when the line is a header line (`#`, spaces, a lowercase word).
fn header_key(line: &str) -> Option<(&str, usize)> {
    let rest = line.strip_prefix('#')?;
    let body = rest.trim_start_matches(' ');
    let col = 1 + rest.len() - body.len();
    let end = body
        .find(|c: char| !c.is_ascii_lowercase())
        .unwrap_or(body.len());
    (end > 0).then(|| (&body[..end], col))
}

/// Fills one header value; errors carry the 0-based column of the offending text.
fn parse_header_value(
    h: &mut Header,
    key: &str,
    line: &str,
    value_col: usize,
) -> Result<(), (usize, String)> {
    let raw = line.get(value_col..).unwrap_or("");
    let col = value_col + raw.len() - raw.trim_start().len();
    let value = raw.trim();
    let numbers = |n: usize| -> Result<Vec<f64>, (usize, String)> {
        let parts: Vec<&str> = value.split_whitespace().collect();
        if parts.len() != n {
            return Err((
                col,
                format!("'{key}' takes {n} number(s), found '{}'", excerpt(value)),
            ));
        }
        parts
            .iter()
            .map(|p| {
                parse_finite(p).ok_or((
                    col,
                    format!("'{key}': '{}' is not a finite number", excerpt(p)),
                ))
            })
            .collect()
    };
    match key {
        "cell" => {
            let c = numbers(1)?[0];
            if !(c > 0.0 && c <= 1000.0) {
                return Err((col, format!("cell size {c} m must be > 0 and <= 1000")));
            }
            h.cell = Some(c);
        }
        "origin" => {
            let o = numbers(2)?;
            if o.iter().any(|v| v.abs() > 1e7) {
                return Err((col, format!("origin {o:?} is absurd (beyond 1e7 m)")));
            }
            h.origin = Some([o[0], o[1]]);
        }
        "heading" => h.heading_deg = Some(numbers(1)?[0]),
        "name" => h.name = Some(value.to_string()),
        _ => {}
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_lines_are_told_from_rows_by_the_lowercase_key() {
        assert_eq!(header_key("# cell 0.3"), Some(("cell", 2)));
        assert_eq!(header_key("#cell 0.3"), Some(("cell", 1)));
        assert_eq!(header_key("# S ."), None);
        assert_eq!(header_key("####"), None);
    }

    #[test]
    fn grid_rows_run_top_down_and_marks_become_poses() {
        let text = "# cell 0.5\n# heading 90\n###\n#G \n#S?\n";
        let a = parse(Path::new("g.txt"), text, &LoadOptions::default()).unwrap();
        let r = a.raster.as_ref().unwrap();
        assert_eq!((r.width, r.height, r.cell_m), (3, 3, 0.5));
        assert_eq!(r.get(0, 2), Some(Cell::Obstacle));
        assert_eq!(r.get(2, 0), Some(Cell::Unknown));
        assert_eq!(r.get(2, 1), Some(Cell::Free));
        assert_eq!(
            a.starts,
            vec![Pose {
                x: 0.75,
                y: 0.25,
                heading: 90f64.to_radians()
            }]
        );
        assert_eq!(a.goal, Some(Point::new(0.75, 0.75)));
        assert_eq!(r.to_ascii(), "###\n#G.\n#S?\n");
    }
}
