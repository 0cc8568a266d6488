//! Micromouse maze text: posts `o` (or `+`), horizontal walls `---` between posts, vertical
//! walls `|`, cells `S` (start) and `G` (goal) marked inside, top text row = north (max y).
//!
//! ```text
//! o---o---o
//! | G     |
//! o   o---o
//! | S |   |
//! o---o---o
//! ```
//!
//! Layer: arena importer. The post spacing (4 characters in the usual files) is read from the
//! first line, so N x M is inferred from the text. Geometry (classic rules): 0.18 m cell pitch
//! for mazes up to 16 x 16, 0.09 m for larger (half-size 32 x 32), overridable by
//! [`LoadOptions::maze_pitch_m`]; walls [`LoadOptions::maze_wall_m`] (0.012 m) thick, centred on
//! the grid lines, so `bounds` are the grid lines (0..N·pitch) and the outer walls' outer half
//! lies just outside them. Each straight run of wall becomes one rectangle; a post no wall
//! touches becomes a small square (posts are physical).
//!
//! Start: the cells marked `S`, else the conventional bottom-left cell; heading towards the
//! cell's first open side in the order north, east, south, west. Goal: the centre of the `G`
//! cells, else the classic centre (of the middle 2 x 2) for 16 x 16 and 32 x 32 mazes.
//!
//! What can fail (each at file:line:column): no post row first, irregular post spacing, a
//! missing post, a wall that is neither `---` nor blank, an unknown character in a cell, text
//! past the right edge, tabs, an even number of lines, sizes beyond [`MAX_GRID_SIDE`].

use std::f64::consts::{FRAC_PI_2, PI};
use std::path::Path;

use super::error::{excerpt, to_u32, ArenaError};
use super::{Arena, ArenaFormat, GridLimit, LoadOptions, Pose, Wall, WorldLimit, MAX_GRID_SIDE};
use crate::geometry::{Aabb, Point};

/// A maze's wall layout, independent of its physical size. Row 0 is the south row.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Maze {
    /// Cells west to east.
    pub cols: u32,
    /// Cells south to north.
    pub rows: u32,
    /// Walls on horizontal grid lines: `(rows + 1) x cols`, line 0 the south edge,
    /// index `line * cols + col`.
    pub horizontal: Vec<bool>,
    /// Walls on vertical grid lines: `rows x (cols + 1)`, line 0 the west edge,
    /// index `row * (cols + 1) + line`.
    pub vertical: Vec<bool>,
    /// Cells marked `S`, as (col, row), in reading order.
    pub starts: Vec<(u32, u32)>,
    /// Cells marked `G`, as (col, row), in reading order.
    pub goals: Vec<(u32, u32)>,
}

/// A side of a cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// +y.
    North,
    /// +x.
    East,
    /// -y.
    South,
    /// -x.
    West,
}

impl Maze {
    /// True when the given side of cell (col, row) has a wall (cells outside count as walled).
    pub fn wall(&self, col: u32, row: u32, side: Side) -> bool {
        if col >= self.cols || row >= self.rows {
            return true;
        }
        let (c, r, n) = (col as usize, row as usize, self.cols as usize);
        let at = |v: &Vec<bool>, i: usize| v.get(i).copied().unwrap_or(true);
        match side {
            Side::North => at(&self.horizontal, (r + 1) * n + c),
            Side::South => at(&self.horizontal, r * n + c),
            Side::East => at(&self.vertical, r * (n + 1) + c + 1),
            Side::West => at(&self.vertical, r * (n + 1) + c),
        }
    }

    /// Number of unit wall pieces (one cell side each), outer walls included.
    pub fn wall_count(&self) -> usize {
        self.horizontal
            .iter()
            .chain(&self.vertical)
            .filter(|w| **w)
            .count()
    }
}

/// The pitch for a maze of this size: 0.18 m up to 16 x 16 cells, 0.09 m beyond.
pub fn default_pitch(cols: u32, rows: u32) -> f64 {
    if cols.max(rows) <= 16 {
        0.18
    } else {
        0.09
    }
}

/// True when the first non-blank line is a row of posts (`o---o`, `+---+`).
pub fn looks_like_maze(text: &str) -> bool {
    let first = text
        .lines()
        .map(str::trim_end)
        .find(|l| !l.is_empty())
        .unwrap_or("");
    (first.starts_with('o') || first.starts_with('+')) && first.chars().all(|c| "o+- ".contains(c))
}

/// Parses a maze text into an [`Arena`].
pub fn parse(path: &Path, text: &str, opts: &LoadOptions) -> Result<Arena, ArenaError> {
    let maze = parse_maze_within(path, text, opts.world_limit)?;
    let pitch = opts
        .maze_pitch_m
        .unwrap_or_else(|| default_pitch(maze.cols, maze.rows));
    if opts.maze_wall_m >= pitch {
        return Err(ArenaError::Option {
            name: "maze_wall_m",
            message: format!(
                "{} m walls do not fit the {pitch} m pitch",
                opts.maze_wall_m
            ),
        });
    }
    if let Some(l) = opts.grid_limit {
        check_limit(path, &maze, pitch, l)?;
    }
    Ok(to_arena(&maze, path, pitch, opts))
}

/// Refuses a maze the caller's grid cannot hold, before its walls are built: at
/// `cols * pitch / cell` cells a side it is refused whatever margin the caller adds.
fn check_limit(path: &Path, maze: &Maze, pitch: f64, l: GridLimit) -> Result<(), ArenaError> {
    let cell = l.maze_cell_m.unwrap_or(pitch / 2.0);
    let side = |n: u32| f64::from(n) * pitch / cell - 1e-9;
    let max = f64::from(l.max_side);
    if side(maze.cols) <= max && side(maze.rows) <= max {
        return Ok(());
    }
    let coarser = (f64::from(maze.cols.max(maze.rows)) * pitch / max * 1000.0).ceil() / 1000.0;
    Err(ArenaError::at_file(
        path,
        format!(
            "a {} x {} maze at {pitch} m pitch needs more than {max} cells of {cell} m a side, \
             beyond what {} takes (refused before building its walls); cells of at least \
             {coarser} m would fit",
            maze.cols, maze.rows, l.who
        ),
    ))
}

/// Reads the maze layout from the text.
pub fn parse_maze(path: &Path, text: &str) -> Result<Maze, ArenaError> {
    parse_maze_within(path, text, None)
}

/// [`parse_maze`], refusing a maze larger than `limit` takes from its size (the first line's
/// posts and the number of lines), before its walls are read or built.
pub fn parse_maze_within(
    path: &Path,
    text: &str,
    limit: Option<WorldLimit>,
) -> Result<Maze, ArenaError> {
    let err = |line: usize, col: usize, msg: String| {
        ArenaError::at_line(path, to_u32(line + 1), Some(to_u32(col + 1)), msg)
    };
    // Lines stay slices of the text; each is split into characters only while it is read
    // (a character array of the whole file took 4 bytes a character).
    let all: Vec<&str> = text
        .split('\n')
        .map(|l| l.trim_end_matches(['\r', ' ']))
        .collect();
    let first = all
        .iter()
        .position(|l| !l.is_empty())
        .ok_or_else(|| ArenaError::at_file(path, "empty maze file"))?;
    let last = all.iter().rposition(|l| !l.is_empty()).unwrap_or(first);
    let lines = &all[first..=last];
    for (i, l) in lines.iter().enumerate() {
        if let Some(c) = l.chars().position(|c| c == '\t') {
            return Err(err(
                first + i,
                c,
                "tab character; maze text must use spaces".into(),
            ));
        }
    }
    let first_line: Vec<char> = lines[0].chars().collect();
    let post = first_line[0];
    if post != 'o' && post != '+' {
        return Err(err(
            first,
            0,
            format!(
                "expected a row of posts ('o' or '+'), found '{}'",
                quote(post)
            ),
        ));
    }
    // Post spacing from the first line: posts at 0, k, 2k, ...
    let posts: Vec<usize> = first_line
        .iter()
        .enumerate()
        .filter(|(_, &c)| c == post)
        .map(|(i, _)| i)
        .collect();
    let k = posts.get(1).copied().unwrap_or(0);
    if k < 2 {
        return Err(err(
            first,
            k,
            "a maze needs at least one cell: posts at least 2 characters apart".into(),
        ));
    }
    if let Some((j, &p)) = posts.iter().enumerate().find(|(j, &p)| p != j * k) {
        return Err(err(
            first,
            p,
            format!(
                "irregular post spacing: expected a post every {k} characters (post {})",
                j + 1
            ),
        ));
    }
    let cols = posts.len() - 1;
    if lines.len() % 2 == 0 {
        return Err(err(
            first + lines.len() - 1,
            0,
            "a maze ends with a row of posts: missing the last post row".into(),
        ));
    }
    let rows = lines.len() / 2;
    if cols > MAX_GRID_SIDE as usize || rows > MAX_GRID_SIDE as usize {
        return Err(ArenaError::at_file(
            path,
            format!("maze {cols} x {rows} exceeds {MAX_GRID_SIDE} cells a side"),
        ));
    }
    if let Some(l) = limit {
        let max = l.max_maze_side as usize;
        if cols > max || rows > max {
            return Err(ArenaError::at_file(
                path,
                format!(
                    "a {cols} x {rows} maze: the emulator's world takes at most {max} x {max} \
                     maze cells (refused before building its walls)"
                ),
            ));
        }
    }
    let mut maze = Maze {
        cols: to_u32(cols),
        rows: to_u32(rows),
        horizontal: vec![false; (rows + 1) * cols],
        vertical: vec![false; rows * (cols + 1)],
        starts: Vec::new(),
        goals: Vec::new(),
    };
    let width = cols * k + 1;
    for (i, text_line) in lines.iter().enumerate() {
        let ln = first + i;
        let line: Vec<char> = text_line.chars().collect();
        if line.len() > width {
            return Err(err(
                ln,
                width,
                format!("text beyond the maze's right edge (it is {width} characters wide)"),
            ));
        }
        let ch = |c: usize| line.get(c).copied().unwrap_or(' ');
        if i % 2 == 0 {
            let hline = rows - i / 2;
            for j in 0..=cols {
                if ch(j * k) != post {
                    return Err(err(
                        ln,
                        j * k,
                        format!("expected a post '{post}', found '{}'", quote(ch(j * k))),
                    ));
                }
                if j == cols {
                    break;
                }
                let span: Vec<char> = (j * k + 1..(j + 1) * k).map(ch).collect();
                if span.iter().all(|&c| c == '-') {
                    maze.horizontal[hline * cols + j] = true;
                } else if let Some(o) = span.iter().position(|&c| c != ' ') {
                    // Point at a stray character, or else where dashes and blanks first mix.
                    let (o, what) = match span.iter().position(|&c| c != ' ' && c != '-') {
                        Some(x) => (x, format!("unexpected '{}'", quote(span[x]))),
                        None => (
                            span.iter().position(|&c| c != span[0]).unwrap_or(o),
                            "broken wall".to_string(),
                        ),
                    };
                    let msg = format!("{what}: a wall between posts is all '-' or all blank");
                    return Err(err(ln, j * k + 1 + o, msg));
                }
            }
        } else {
            let row = rows - 1 - i / 2;
            for j in 0..=cols {
                match ch(j * k) {
                    '|' => maze.vertical[row * (cols + 1) + j] = true,
                    ' ' => {}
                    c => {
                        return Err(err(
                            ln,
                            j * k,
                            format!("expected '|' or blank for a wall, found '{}'", quote(c)),
                        ))
                    }
                }
                if j == cols {
                    break;
                }
                let cell = (to_u32(j), to_u32(row));
                for c in j * k + 1..(j + 1) * k {
                    match ch(c) {
                        ' ' => {}
                        // A cell's marks are read together, so a repeat is the last one
                        // pushed (searching the whole list was quadratic in marked cells).
                        'S' if maze.starts.last() != Some(&cell) => maze.starts.push(cell),
                        'G' if maze.goals.last() != Some(&cell) => maze.goals.push(cell),
                        'S' | 'G' => {}
                        x => {
                            return Err(err(
                                ln,
                                c,
                                format!(
                                    "unexpected '{}' in a cell (only S and G marks are understood)",
                                    quote(x)
                                ),
                            ))
                        }
                    }
                }
            }
        }
    }
    Ok(maze)
}

/// A character of the file for a message (a control character escaped).
fn quote(c: char) -> String {
    excerpt(c.encode_utf8(&mut [0; 4]))
}

/// Builds the arena for a maze at the given pitch.
pub fn to_arena(maze: &Maze, path: &Path, pitch: f64, opts: &LoadOptions) -> Arena {
    let (n, m) = (maze.cols as usize, maze.rows as usize);
    let half = opts.maze_wall_m / 2.0;
    let height = Some(opts.maze_wall_height_m);
    let rect = |x0: f64, y0: f64, x1: f64, y1: f64| {
        Wall::rectangle(
            Aabb::from_corners(Point::new(x0, y0), Point::new(x1, y1)),
            height,
        )
    };
    let mut walls = Vec::new();
    // Horizontal runs along each grid line y = line * pitch.
    for line in 0..=m {
        let y = line as f64 * pitch;
        for (c0, c1) in runs((0..n).map(|c| maze.horizontal[line * n + c])) {
            walls.push(rect(
                c0 as f64 * pitch - half,
                y - half,
                c1 as f64 * pitch + half,
                y + half,
            ));
        }
    }
    // Vertical runs along each grid line x = line * pitch.
    for line in 0..=n {
        let x = line as f64 * pitch;
        for (r0, r1) in runs((0..m).map(|r| maze.vertical[r * (n + 1) + line])) {
            walls.push(rect(
                x - half,
                r0 as f64 * pitch - half,
                x + half,
                r1 as f64 * pitch + half,
            ));
        }
    }
    // Posts that no wall touches.
    for line in 0..=m {
        for v in 0..=n {
            let h = |c: usize| c < n && maze.horizontal[line * n + c];
            let vert = |r: usize| r < m && maze.vertical[r * (n + 1) + v];
            let touched = h(v) || (v > 0 && h(v - 1)) || vert(line) || (line > 0 && vert(line - 1));
            if !touched {
                let (x, y) = (v as f64 * pitch, line as f64 * pitch);
                walls.push(rect(x - half, y - half, x + half, y + half));
            }
        }
    }
    let centre =
        |(c, r): (u32, u32)| Point::new((c as f64 + 0.5) * pitch, (r as f64 + 0.5) * pitch);
    let start_cells = if maze.starts.is_empty() {
        vec![(0, 0)]
    } else {
        maze.starts.clone()
    };
    let starts = start_cells
        .iter()
        .map(|&cell| {
            let p = centre(cell);
            let open = [
                (Side::North, FRAC_PI_2),
                (Side::East, 0.0),
                (Side::South, -FRAC_PI_2),
                (Side::West, PI),
            ]
            .into_iter()
            .find(|(s, _)| !maze.wall(cell.0, cell.1, *s));
            Pose {
                x: p.x,
                y: p.y,
                heading: open.map_or(FRAC_PI_2, |(_, h)| h),
            }
        })
        .collect();
    let goal = if !maze.goals.is_empty() {
        let sum = maze
            .goals
            .iter()
            .fold(Point::origin(), |acc, &g| acc + centre(g).coords);
        Some(sum / maze.goals.len() as f64)
    } else if (n, m) == (16, 16) || (n, m) == (32, 32) {
        Some(Point::new(n as f64 / 2.0 * pitch, m as f64 / 2.0 * pitch))
    } else {
        None
    };
    Arena {
        name: path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        source: path.to_path_buf(),
        format: ArenaFormat::Micromouse,
        bounds: Aabb {
            min: Point::origin(),
            max: Point::new(n as f64 * pitch, m as f64 * pitch),
        },
        enclosed: false,
        walls,
        raster: None,
        beacons: Vec::new(),
        targets: Vec::new(),
        lights: Vec::new(),
        starts,
        goal,
        unit_m: pitch,
        warnings: Vec::new(),
    }
}

/// Maximal runs of `true` as inclusive-start, exclusive-end index pairs.
fn runs(flags: impl Iterator<Item = bool>) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start = None;
    let mut len = 0;
    for (i, f) in flags.enumerate() {
        len = i + 1;
        match (f, start) {
            (true, None) => start = Some(i),
            (false, Some(s)) => {
                out.push((s, i));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        out.push((s, len));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const TINY: &str = "o---o---o\n| G     |\no   o---o\n| S |   |\no---o---o\n";

    #[test]
    fn tiny_maze_walls_marks_and_geometry() {
        let maze = parse_maze(Path::new("m.txt"), TINY).unwrap();
        assert_eq!((maze.cols, maze.rows), (2, 2));
        assert_eq!(maze.starts, vec![(0, 0)]);
        assert_eq!(maze.goals, vec![(0, 1)]);
        assert!(maze.wall(0, 0, Side::East) && !maze.wall(0, 0, Side::North));
        assert!(maze.wall(1, 0, Side::North) && !maze.wall(0, 1, Side::East));
        assert_eq!(maze.wall_count(), 10);
        let a = to_arena(&maze, Path::new("m.txt"), 0.18, &LoadOptions::default());
        assert_eq!(
            a.starts[0],
            Pose {
                x: 0.09,
                y: 0.09,
                heading: FRAC_PI_2
            }
        );
        assert_eq!(a.goal, Some(Point::new(0.09, 0.27)));
        // Runs: 2 horizontal lines of 2 + the middle line's one piece; 3 vertical runs.
        assert_eq!(a.walls.len(), 6);
    }

    #[test]
    fn runs_are_maximal() {
        assert_eq!(
            runs([true, true, false, true].into_iter()),
            vec![(0, 2), (3, 4)]
        );
        assert_eq!(runs([false, false].into_iter()), vec![]);
    }
}
