//! CiberRato lab XML (`<Lab Name Width Height>` with any number of `<Beacon X Y Height>`,
//! `<Target X Y Radius>`, `<Wall Height><Corner X Y/>…</Wall>` and `<Row Pos Pattern>`) and its
//! grid file (`<Grid><Position X Y Dir/>…`, start poses with Dir in degrees), read as the
//! CiberRato simulator's own parser reads them (`simulator/cblabhandler.cpp`, `cbwall.cpp`,
//! `cbgridhandler.cpp` in nunolau/ciberRatoTools):
//! - `<Row>` rows describe a maze of 2-unit cells in ASCII (see [`row_walls`]);
//! - a wall without `Height` is 4 units high (`cbWall`'s default);
//! - a corner repeated consecutively (also the last repeating the first) is dropped, with a
//!   warning: the simulator keeps such walls;
//! - every beacon and target is kept, in file order.
//!
//! Warnings (unknown names, dropped repeats, clipped rows, how the grid file was found) are kept
//! in [`Arena::warnings`], at most [`MAX_WARNINGS`] of them plus a count of the rest, so a file
//! of 60,000 unknown elements costs 60,000 cheap counts, not 60,000 line:column scans.
//!
//! Layer: arena importer. Units: CiberRato units scaled by [`LoadOptions::ciberrato_unit_m`]
//! (default 5/17.5 m per unit, so Micro-Rato'99's 17.5-unit lab is the real 5 m arena); wall
//! and beacon heights are scaled the same way so height comparisons keep their meaning. The
//! lab's frame is already x right, y up, origin at the lower-left corner.
//!
//! Invariants of the result: the lab rectangle (0..Width, 0..Height) is a wall
//! (`enclosed`); every corner, beacon, target centre and start position lies inside it (row
//! walls are clipped to it); wall polygons have >= 3 distinct consecutive corners, non-zero
//! area and no self-crossing.
//!
//! What can fail: malformed XML (roxmltree's message, at its line:column), a wrong root element,
//! missing or non-finite attributes, non-positive sizes, absurd sizes (> [`MAX_LAB_UNITS`]),
//! too few corners, points outside the lab, a row `Pos` that is not a whole number, a misspelt
//! element or attribute name (a name that is merely unknown becomes a warning). Each error
//! names file:line:column. Time and memory are linear in the file.

use std::path::Path;

use roxmltree::{Document, Node, ParsingOptions};

use super::error::{read_text, unknown_name, ArenaError, Text};
use super::{Arena, ArenaFormat, Beacon, GridFile, LoadOptions, Pose, Target, Wall};
use crate::geometry::{polygon_self_crossing, polygon_signed_area, Aabb, Point};

mod grid_file;

pub use grid_file::{find_grid, grid_path_for, root_element, FoundGrid};

/// Largest lab side accepted, in CiberRato units (real labs are at most a few tens).
pub const MAX_LAB_UNITS: f64 = 1000.0;

/// Most corners one wall may have (the self-crossing check is quadratic in them).
pub const MAX_WALL_CORNERS: usize = 4096;

// Caps the DOM so a hostile file cannot make the parser allocate without bound.
const MAX_XML_NODES: u32 = 1_000_000;

/// Most warnings kept per file; the rest are counted in one closing line.
pub const MAX_WARNINGS: usize = 20;

/// A wall's height when the file gives none, in CiberRato units (`cbWall::cbWall`).
pub const DEFAULT_WALL_HEIGHT: f64 = 4.0;

/// Side of one `<Row>` maze cell, CiberRato units (`PATHCUBESIZE` in `cblabhandler.cpp`).
pub const ROW_CELL: f64 = 2.0;

/// Half a `<Row>` wall's thickness as a fraction of the cell (`PATHWALLWIDTH`): 0.1 units.
pub const ROW_WALL_HALF: f64 = 0.05;

/// Pattern characters per `<Row>` cell: two for the cell, one for the wall on its right.
const ROW_CHARS_PER_CELL: usize = 3;

/// Loads a lab file and, per [`LoadOptions::ciberrato_grid`], its grid file.
pub fn load(path: &Path, opts: &LoadOptions) -> Result<Arena, ArenaError> {
    let text = read_text(path)?;
    load_text(path, &text, opts)
}

/// Like [`load`] with the lab's text already read.
pub fn load_text(path: &Path, text: &str, opts: &LoadOptions) -> Result<Arena, ArenaError> {
    let mut arena = parse_lab(path, text, opts.ciberrato_unit_m)?;
    let grid = match &opts.ciberrato_grid {
        GridFile::Auto => {
            let found = find_grid(path);
            arena.warnings.extend(found.note);
            found.path
        }
        GridFile::None => None,
        GridFile::Path(p) => Some(p.clone()),
    };
    if let Some(grid) = grid {
        let grid_text = read_text(&grid)?;
        let mut warnings = Vec::new();
        arena.starts = parse_grid(&grid, &grid_text, &arena, &mut warnings)?;
        arena.warnings.extend(warnings);
    }
    Ok(arena)
}

/// Parses a lab's XML text; `unit_m` is metres per CiberRato unit.
pub fn parse_lab(path: &Path, text: &str, unit_m: f64) -> Result<Arena, ArenaError> {
    let t = Text { path, text };
    let doc = parse_xml(t)?;
    let lab = doc.root_element();
    match lab.tag_name().name() {
        "Lab" => {}
        "Grid" => {
            return Err(err_node(t, lab, "this is a CiberRato grid file (start positions), not a lab; load the lab and give this file as its grid"))
        }
        other => return Err(err_node(t, lab, format!("expected a <Lab> root element, found <{other}>"))),
    }
    let mut warnings = Warnings::new(t);
    check_attrs(t, lab, &["Name", "Width", "Height"], &mut warnings)?;
    let width = positive_attr(t, lab, "Width")?;
    let height = positive_attr(t, lab, "Height")?;
    let name = match lab.attribute("Name") {
        Some(n) => n.to_string(),
        None => path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
    };
    let lab_box = Aabb {
        min: Point::new(0.0, 0.0),
        max: Point::new(width, height),
    };
    let scale = |p: Point| Point::new(p.x * unit_m, p.y * unit_m);
    let mut arena = Arena {
        name,
        source: path.to_path_buf(),
        format: ArenaFormat::CiberRato,
        bounds: Aabb {
            min: Point::origin(),
            max: scale(lab_box.max),
        },
        enclosed: true,
        walls: Vec::new(),
        raster: None,
        beacons: Vec::new(),
        targets: Vec::new(),
        lights: Vec::new(),
        starts: Vec::new(),
        goal: None,
        unit_m,
        warnings: Vec::new(),
    };
    let mut push_wall = |w: Wall| {
        arena.walls.push(Wall {
            corners: w.corners.iter().map(|&c| scale(c)).collect(),
            height_m: w.height_m.map(|h| h * unit_m),
        });
    };
    let mut beacons = Vec::new();
    let mut targets = Vec::new();
    for node in lab.children().filter(Node::is_element) {
        match node.tag_name().name() {
            "Beacon" => {
                check_attrs(t, node, &["X", "Y", "Height"], &mut warnings)?;
                let p = point_in(t, node, &lab_box)?;
                let h = non_negative_attr(t, node, "Height")?;
                beacons.push(Beacon {
                    position: scale(p),
                    height_m: h * unit_m,
                });
            }
            "Target" => {
                check_attrs(t, node, &["X", "Y", "Radius"], &mut warnings)?;
                let p = point_in(t, node, &lab_box)?;
                let r = positive_attr(t, node, "Radius")?;
                targets.push(Target {
                    centre: scale(p),
                    radius_m: r * unit_m,
                });
            }
            "Wall" => push_wall(parse_wall(t, node, &lab_box, &mut warnings)?),
            "Row" => {
                for w in parse_row(t, node, &lab_box, &mut warnings)? {
                    push_wall(w);
                }
            }
            other => note_unknown(
                t,
                node,
                "element",
                other,
                &["Beacon", "Target", "Wall", "Row"],
                &mut warnings,
            )?,
        }
    }
    // The first target's centre is where a CiberRato robot is sent: the goal point.
    arena.goal = targets.first().map(|t| t.centre);
    arena.beacons = beacons;
    arena.targets = targets;
    arena.warnings = warnings.finish();
    Ok(arena)
}

/// Parses a grid file's start positions against an already parsed lab (positions must lie
/// inside it). Positions are CiberRato units, `Dir` degrees anticlockwise from +x.
pub fn parse_grid(
    path: &Path,
    text: &str,
    lab: &Arena,
    warnings: &mut Vec<String>,
) -> Result<Vec<Pose>, ArenaError> {
    let t = Text { path, text };
    let doc = parse_xml(t)?;
    let grid = doc.root_element();
    match grid.tag_name().name() {
        "Grid" => {}
        "Lab" => return Err(err_node(
            t,
            grid,
            "this is a lab file; a grid file has a <Grid> root with <Position X Y Dir/> elements",
        )),
        other => {
            return Err(err_node(
                t,
                grid,
                format!("expected a <Grid> root element, found <{other}>"),
            ))
        }
    }
    let mut w = Warnings::new(t);
    check_attrs(t, grid, &[], &mut w)?;
    let u = lab.unit_m;
    let lab_box = Aabb {
        min: Point::origin(),
        max: Point::new(lab.bounds.max.x / u, lab.bounds.max.y / u),
    };
    let mut starts = Vec::new();
    for node in grid.children().filter(Node::is_element) {
        if node.tag_name().name() != "Position" {
            note_unknown(
                t,
                node,
                "element",
                node.tag_name().name(),
                &["Position"],
                &mut w,
            )?;
            continue;
        }
        check_attrs(t, node, &["X", "Y", "Dir"], &mut w)?;
        let p = point_in(t, node, &lab_box)?;
        let dir = num_attr(t, node, "Dir")?.unwrap_or(0.0);
        starts.push(Pose {
            x: p.x * u,
            y: p.y * u,
            heading: dir.to_radians(),
        });
    }
    if starts.is_empty() {
        w.push(grid.range().start, "grid file has no <Position> elements");
    }
    warnings.extend(w.finish());
    Ok(starts)
}

/// A file's warnings, each `file:line:col: message`: the first [`MAX_WARNINGS`] are kept and
/// located, the rest only counted (locating one scans the text before it, so locating all of
/// 60,000 would be quadratic).
struct Warnings<'a> {
    t: Text<'a>,
    kept: Vec<String>,
    more: usize,
}

impl<'a> Warnings<'a> {
    fn new(t: Text<'a>) -> Self {
        Warnings {
            t,
            kept: Vec::new(),
            more: 0,
        }
    }

    /// A warning about the text at byte `offset`.
    fn push(&mut self, offset: usize, message: impl std::fmt::Display) {
        if self.kept.len() < MAX_WARNINGS {
            let (line, col) = self.t.line_col(offset);
            let path = self.t.path.display();
            let text = format!("{path}:{line}:{col}: {message}");
            // Warnings reach terminals; attribute values may hold control characters (&#7;).
            self.kept
                .push(crate::terminal_text::printable(&text).into_owned());
        } else {
            self.more += 1;
        }
    }

    fn finish(mut self) -> Vec<String> {
        if self.more > 0 {
            self.kept.push(format!(
                "{}: {} more warnings not shown",
                self.t.path.display(),
                self.more
            ));
        }
        self.kept
    }
}

fn parse_xml<'a>(t: Text<'a>) -> Result<Document<'a>, ArenaError> {
    let opt = ParsingOptions {
        allow_dtd: false,
        nodes_limit: MAX_XML_NODES,
        ..ParsingOptions::default()
    };
    Document::parse_with_options(t.text, opt).map_err(|e| {
        if matches!(e, roxmltree::Error::DtdDetected) {
            // roxmltree places this at 1:1; point at the DOCTYPE itself.
            let at = t.text.find("<!DOCTYPE").unwrap_or(0);
            return t.err_at(
                at,
                "malformed XML: DTDs (<!DOCTYPE>) are not allowed in arena files",
            );
        }
        let pos = e.pos();
        // roxmltree ends its messages with " at row:col"; the location already leads ours.
        let msg = e.to_string().replace(&format!(" at {pos}"), "");
        ArenaError::at_line(
            t.path,
            pos.row,
            Some(pos.col),
            format!("malformed XML: {msg}"),
        )
    })
}

fn parse_wall(
    t: Text<'_>,
    node: Node<'_, '_>,
    lab: &Aabb,
    warnings: &mut Warnings<'_>,
) -> Result<Wall, ArenaError> {
    check_attrs(t, node, &["Height"], warnings)?;
    let height = match num_attr(t, node, "Height")? {
        Some(h) if h <= 0.0 => {
            return Err(err_attr(
                t,
                node,
                "Height",
                format!("wall Height {h} must be > 0"),
            ))
        }
        Some(h) => h,
        None => DEFAULT_WALL_HEIGHT,
    };
    let mut corners: Vec<Point> = Vec::new();
    let mut repeats = 0usize;
    for c in node.children().filter(Node::is_element) {
        if c.tag_name().name() != "Corner" {
            note_unknown(t, c, "element", c.tag_name().name(), &["Corner"], warnings)?;
            continue;
        }
        check_attrs(t, c, &["X", "Y"], warnings)?;
        let p = point_in(t, c, lab)?;
        // CiberRato keeps a wall whose corner repeats (a zero-length side); so do we, without
        // the repeat, which would otherwise look like the polygon touching itself.
        if corners.last() == Some(&p) {
            repeats += 1;
            warnings.push(
                c.range().start,
                format!(
                    "corner ({}, {}) repeats the one before it; the repeat is dropped",
                    p.x, p.y
                ),
            );
            continue;
        }
        if corners.len() >= MAX_WALL_CORNERS {
            let msg = format!("a wall with more than {MAX_WALL_CORNERS} corners is absurd");
            return Err(err_node(t, node, msg));
        }
        corners.push(p);
    }
    if corners.len() > 1 && corners.first() == corners.last() {
        if let Some(p) = corners.pop() {
            repeats += 1;
            warnings.push(
                node.range().start,
                format!(
                    "the last corner ({}, {}) repeats the first (walls are closed anyway); dropped",
                    p.x, p.y
                ),
            );
        }
    }
    if corners.len() < 3 {
        return Err(err_node(
            t,
            node,
            format!(
                "a wall needs at least 3 <Corner>s, this one has {}{}",
                corners.len(),
                if repeats > 0 { " besides repeats" } else { "" }
            ),
        ));
    }
    if let Some((i, j)) = polygon_self_crossing(&corners) {
        let n = corners.len();
        return Err(err_node(
            t,
            node,
            format!(
                "wall polygon crosses itself: edge corner {}->{} meets edge corner {}->{}",
                i + 1,
                (i + 1) % n + 1,
                j + 1,
                (j + 1) % n + 1
            ),
        ));
    }
    // After the crossing test: a symmetric bow-tie has zero signed area too.
    if polygon_signed_area(&corners) == 0.0 {
        return Err(err_node(
            t,
            node,
            "wall polygon has zero area (its corners are collinear)",
        ));
    }
    Ok(Wall {
        corners,
        height_m: Some(height),
    })
}

/// The walls of one `<Row Pos Pattern>`, in CiberRato units, clipped to the lab.
fn parse_row(
    t: Text<'_>,
    node: Node<'_, '_>,
    lab: &Aabb,
    warnings: &mut Warnings<'_>,
) -> Result<Vec<Wall>, ArenaError> {
    check_attrs(t, node, &["Pos", "Pattern"], warnings)?;
    let pos = match node.attribute("Pos") {
        Some(v) => match v.trim().parse::<u32>() {
            Ok(p) => p,
            Err(_) => {
                let msg =
                    format!("Pos=\"{v}\" must be a whole number >= 0 (the row, 0 at the bottom)");
                return Err(err_attr(t, node, "Pos", msg));
            }
        },
        None => {
            warnings.push(
                node.range().start,
                "<Row> without Pos is row 0, as in CiberRato",
            );
            0
        }
    };
    let Some(pattern) = node.attribute("Pattern") else {
        warnings.push(node.range().start, "<Row> without Pattern has no walls");
        return Ok(Vec::new());
    };
    let (walls, run_to_end) = row_walls(pos, pattern, lab.max.x);
    if run_to_end {
        warnings.push(
            node.range().start,
            "a horizontal wall runs to the end of the pattern, past the lab's last cell; kept",
        );
    }
    let mut out = Vec::with_capacity(walls.len());
    let mut outside = 0usize;
    for r in walls {
        let clipped = Aabb {
            min: Point::new(r.min.x.max(lab.min.x), r.min.y.max(lab.min.y)),
            max: Point::new(r.max.x.min(lab.max.x), r.max.y.min(lab.max.y)),
        };
        if clipped.width() <= 0.0 || clipped.height() <= 0.0 {
            outside += 1;
            continue;
        }
        if clipped != r {
            outside += 1;
        }
        out.push(Wall::rectangle(clipped, Some(DEFAULT_WALL_HEIGHT)));
    }
    if outside > 0 {
        warnings.push(
            node.range().start,
            format!("{outside} wall(s) of this row reach outside the lab and were cut at its edge"),
        );
    }
    Ok(out)
}

/// The wall rectangles of a `<Row>` (CiberRato units), as `cbLabHandler` builds them: the
/// pattern has 3 characters per 2-unit cell (column `c` is cell `c / 3`). An even row `pos`
/// holds cells `pos .. pos + 2` units high, where `|` at column `c` is a vertical wall at
/// `x = 2 (c + 1) / 3`; an odd row holds the horizontal walls at `y = pos + 1`, where a run of
/// `-` on the cells' first columns (`c % 3 == 0`) is one wall, ended by a space there. Other
/// characters (`+`, decorations) do nothing. Walls are 0.1 units thick either side of their
/// line. CiberRato ends a run at the last cell of its 28-unit-wide labs (column 39); here at
/// the last cell of this lab's width, and at the end of the pattern (the flag says so; the
/// simulator drops such a run).
pub fn row_walls(pos: u32, pattern: &str, lab_width: f64) -> (Vec<Aabb>, bool) {
    let half = ROW_WALL_HALF * ROW_CELL;
    let row = f64::from(pos);
    let cells = (lab_width / ROW_CELL).ceil().max(1.0);
    let last_cell_col = (cells as usize - 1).saturating_mul(ROW_CHARS_PER_CELL);
    let x_of = |col: usize| col as f64 / ROW_CHARS_PER_CELL as f64 * ROW_CELL;
    let mut walls = Vec::new();
    if pos % 2 == 0 {
        for (col, ch) in pattern.chars().enumerate() {
            if ch == '|' {
                let x = x_of(col + 1);
                walls.push(Aabb {
                    min: Point::new(x - half, row),
                    max: Point::new(x + half, row + ROW_CELL),
                });
            }
        }
        return (walls, false);
    }
    let y = row + 1.0;
    let horizontal = |start: usize, end: usize| Aabb {
        min: Point::new(x_of(start), y - half),
        max: Point::new(x_of(end) + ROW_CELL, y + half),
    };
    let mut start: Option<usize> = None;
    let mut last_col = 0;
    for (col, ch) in pattern.chars().enumerate() {
        last_col = col;
        if col % ROW_CHARS_PER_CELL != 0 {
            continue;
        }
        match (ch, start) {
            ('-', None) if col == last_cell_col => walls.push(horizontal(col, col)),
            ('-', None) => start = Some(col),
            ('-', Some(s)) if col == last_cell_col => {
                walls.push(horizontal(s, col));
                start = None;
            }
            (' ', Some(s)) => {
                walls.push(horizontal(s, col - ROW_CHARS_PER_CELL));
                start = None;
            }
            _ => {}
        }
    }
    let run_to_end = start.is_some();
    if let Some(s) = start {
        let end = last_col - last_col % ROW_CHARS_PER_CELL;
        walls.push(horizontal(s, end));
    }
    (walls, run_to_end)
}

/// Reads X and Y and checks the point lies in the lab (a small tolerance absorbs decimals).
fn point_in(t: Text<'_>, node: Node<'_, '_>, lab: &Aabb) -> Result<Point, ArenaError> {
    let x = req_attr(t, node, "X")?;
    let y = req_attr(t, node, "Y")?;
    let tol = 1e-9 * lab.width().max(lab.height());
    if !lab.expanded(tol).contains(Point::new(x, y)) {
        return Err(err_node(
            t,
            node,
            format!(
                "point ({x}, {y}) lies outside the lab (0..{} x 0..{})",
                lab.max.x, lab.max.y
            ),
        ));
    }
    Ok(Point::new(x, y))
}

fn num_attr(t: Text<'_>, node: Node<'_, '_>, name: &str) -> Result<Option<f64>, ArenaError> {
    let Some(v) = node.attribute(name) else {
        return Ok(None);
    };
    match super::error::parse_finite(v) {
        Some(x) => Ok(Some(x)),
        None => Err(err_attr(
            t,
            node,
            name,
            format!("{name}=\"{v}\" is not a finite number"),
        )),
    }
}

fn req_attr(t: Text<'_>, node: Node<'_, '_>, name: &str) -> Result<f64, ArenaError> {
    num_attr(t, node, name)?.ok_or_else(|| {
        err_node(
            t,
            node,
            format!("<{}> is missing attribute {name}", node.tag_name().name()),
        )
    })
}

fn positive_attr(t: Text<'_>, node: Node<'_, '_>, name: &str) -> Result<f64, ArenaError> {
    let v = req_attr(t, node, name)?;
    if v <= 0.0 {
        return Err(err_attr(t, node, name, format!("{name} {v} must be > 0")));
    }
    if v > MAX_LAB_UNITS {
        return Err(err_attr(
            t,
            node,
            name,
            format!("{name} {v} is absurd (limit {MAX_LAB_UNITS} units)"),
        ));
    }
    Ok(v)
}

fn non_negative_attr(t: Text<'_>, node: Node<'_, '_>, name: &str) -> Result<f64, ArenaError> {
    let v = req_attr(t, node, name)?;
    if !(0.0..=MAX_LAB_UNITS).contains(&v) {
        return Err(err_attr(
            t,
            node,
            name,
            format!("{name} {v} must be in 0..{MAX_LAB_UNITS}"),
        ));
    }
    Ok(v)
}

/// Applies the unknown-name policy to every attribute not in `known`.
fn check_attrs(
    t: Text<'_>,
    node: Node<'_, '_>,
    known: &[&str],
    warnings: &mut Warnings<'_>,
) -> Result<(), ArenaError> {
    for a in node.attributes() {
        if !known.contains(&a.name()) {
            let what = format!("attribute of <{}>", node.tag_name().name());
            match unknown_name(&what, a.name(), known) {
                Ok(w) => warnings.push(a.range_qname().start, w),
                Err(e) => return Err(t.err_at(a.range_qname().start, e)),
            }
        }
    }
    Ok(())
}

fn note_unknown(
    t: Text<'_>,
    node: Node<'_, '_>,
    what: &str,
    name: &str,
    known: &[&str],
    warnings: &mut Warnings<'_>,
) -> Result<(), ArenaError> {
    match unknown_name(what, name, known) {
        Ok(w) => {
            warnings.push(node.range().start, w);
            Ok(())
        }
        Err(e) => Err(err_node(t, node, e)),
    }
}

fn err_node(t: Text<'_>, node: Node<'_, '_>, msg: impl Into<String>) -> ArenaError {
    t.err_at(node.range().start, msg)
}

fn err_attr(t: Text<'_>, node: Node<'_, '_>, name: &str, msg: impl Into<String>) -> ArenaError {
    match node.attribute_node(name) {
        Some(a) => t.err_at(a.range_value().start, msg),
        None => err_node(t, node, msg),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    #[test]
    fn grid_file_is_found_from_a_lab_name_ending_in_lab() {
        let g = grid_path_for(Path::new("d/Ciber2005_FinalLab.xml"));
        assert_eq!(g, Some(PathBuf::from("d/Ciber2005_FinalGrid.xml")));
        assert_eq!(grid_path_for(Path::new("d/wallsMicRato99.xml")), None);
    }

    #[test]
    fn lab_units_scale_to_metres() {
        let xml = r#"<Lab Name="t" Width="3.5" Height="7"><Beacon X="1" Y="2" Height="2"/>
            <Wall Height="1"><Corner X="0" Y="0"/><Corner X="1" Y="0"/><Corner X="1" Y="1"/></Wall></Lab>"#;
        let a = parse_lab(Path::new("t.xml"), xml, 0.5).unwrap();
        assert_eq!(a.bounds.max, Point::new(1.75, 3.5));
        assert_eq!(a.beacons[0].position, Point::new(0.5, 1.0));
        assert_eq!(a.beacons[0].height_m, 1.0);
        assert_eq!(a.walls[0].height_m, Some(0.5));
    }

    #[test]
    fn unknown_attribute_is_a_warning_but_a_misspelt_one_an_error() {
        let ok = r#"<Lab Width="3" Height="3" Colour="red"/>"#;
        let a = parse_lab(Path::new("t.xml"), ok, 1.0).unwrap();
        assert!(
            a.warnings[0].starts_with("t.xml:1:27: unknown attribute"),
            "{:?}",
            a.warnings
        );
        let bad = r#"<Lab Width="3" Heigth="3"/>"#;
        let e = parse_lab(Path::new("t.xml"), bad, 1.0)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("t.xml:1:16: unknown attribute of <Lab> 'Heigth'; did you mean 'Height'"),
            "{e}"
        );
    }
}
