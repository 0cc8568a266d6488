//! CiberRato lab XML (`<Lab Name Width Height>` with `<Beacon X Y Height>`, `<Target X Y
//! Radius>`, `<Wall Height><Corner X Y/>…</Wall>`) and its grid file (`<Grid><Position X Y
//! Dir/>…`, start poses with Dir in degrees).
//!
//! Layer: arena importer. Units: CiberRato units scaled by [`LoadOptions::ciberrato_unit_m`]
//! (default 5/17.5 m per unit, so Micro-Rato'99's 17.5-unit lab is the real 5 m arena); wall
//! and beacon heights are scaled the same way so height comparisons keep their meaning. The
//! lab's frame is already x right, y up, origin at the lower-left corner.
//!
//! Invariants of the result: the lab rectangle (0..Width, 0..Height) is a wall
//! (`enclosed`); every corner, beacon, target centre and start position lies inside it; wall
//! polygons have >= 3 corners, non-zero area and no self-crossing.
//!
//! What can fail: malformed XML (roxmltree's message, at its line:column), a wrong root element,
//! missing or non-finite attributes, non-positive sizes, absurd sizes (> [`MAX_LAB_UNITS`]),
//! too few corners, points outside the lab, a misspelt element or attribute name (a name that
//! is merely unknown becomes a warning). Each error names file:line:column.

use std::path::{Path, PathBuf};

use roxmltree::{Document, Node, ParsingOptions};

use super::error::{read_text, unknown_name, ArenaError, Text};
use super::{Arena, ArenaFormat, Beacon, GridFile, LoadOptions, Pose, Target, Wall};
use crate::geometry::{polygon_self_crossing, polygon_signed_area, Aabb, Point};

/// Largest lab side accepted, in CiberRato units (real labs are at most a few tens).
pub const MAX_LAB_UNITS: f64 = 1000.0;

/// Most corners one wall may have (the self-crossing check is quadratic in them).
pub const MAX_WALL_CORNERS: usize = 4096;

// Caps the DOM so a hostile file cannot make the parser allocate without bound.
const MAX_XML_NODES: u32 = 1_000_000;

/// Loads a lab file and, per [`LoadOptions::ciberrato_grid`], its grid file.
pub fn load(path: &Path, opts: &LoadOptions) -> Result<Arena, ArenaError> {
    let text = read_text(path)?;
    load_text(path, &text, opts)
}

/// Like [`load`] with the lab's text already read.
pub fn load_text(path: &Path, text: &str, opts: &LoadOptions) -> Result<Arena, ArenaError> {
    let mut arena = parse_lab(path, text, opts.ciberrato_unit_m)?;
    let grid = match &opts.ciberrato_grid {
        GridFile::Auto => grid_path_for(path).filter(|p| p.is_file()),
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

/// The grid file that obviously goes with a lab file: `…Lab.xml` -> `…Grid.xml` (also `lab`
/// -> `grid`, `LAB` -> `GRID`), in the same folder. `None` when the name does not say.
pub fn grid_path_for(lab: &Path) -> Option<PathBuf> {
    let stem = lab.file_stem()?.to_str()?;
    let ext = lab.extension().and_then(|e| e.to_str()).unwrap_or("xml");
    let (base, grid) = [("Lab", "Grid"), ("lab", "grid"), ("LAB", "GRID")]
        .iter()
        .find_map(|(l, g)| stem.strip_suffix(l).map(|b| (b, *g)))?;
    Some(lab.with_file_name(format!("{base}{grid}.{ext}")))
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
    let mut warnings = Vec::new();
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
    for node in lab.children().filter(Node::is_element) {
        match node.tag_name().name() {
            "Beacon" => {
                check_attrs(t, node, &["X", "Y", "Height"], &mut warnings)?;
                let p = point_in(t, node, &lab_box)?;
                let h = non_negative_attr(t, node, "Height")?;
                arena.beacons.push(Beacon {
                    position: scale(p),
                    height_m: h * unit_m,
                });
            }
            "Target" => {
                check_attrs(t, node, &["X", "Y", "Radius"], &mut warnings)?;
                let p = point_in(t, node, &lab_box)?;
                let r = positive_attr(t, node, "Radius")?;
                arena.targets.push(Target {
                    centre: scale(p),
                    radius_m: r * unit_m,
                });
                // The target's centre is where a CiberRato robot is sent: the goal point.
                arena.goal = arena.goal.or(Some(scale(p)));
            }
            "Wall" => {
                let wall = parse_wall(t, node, &lab_box, &mut warnings)?;
                let corners = wall.corners.iter().map(|&c| scale(c)).collect();
                arena.walls.push(Wall {
                    corners,
                    height_m: wall.height_m.map(|h| h * unit_m),
                });
            }
            other => note_unknown(
                t,
                node,
                "element",
                other,
                &["Beacon", "Target", "Wall"],
                &mut warnings,
            )?,
        }
    }
    arena.warnings = warnings;
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
    check_attrs(t, grid, &[], warnings)?;
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
                warnings,
            )?;
            continue;
        }
        check_attrs(t, node, &["X", "Y", "Dir"], warnings)?;
        let p = point_in(t, node, &lab_box)?;
        let dir = num_attr(t, node, "Dir")?.unwrap_or(0.0);
        starts.push(Pose {
            x: p.x * u,
            y: p.y * u,
            heading: dir.to_radians(),
        });
    }
    if starts.is_empty() {
        warnings.push(format!(
            "{}:{}: grid file has no <Position> elements",
            path.display(),
            line_of(t, grid)
        ));
    }
    Ok(starts)
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
    warnings: &mut Vec<String>,
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
        h => h,
    };
    let mut corners = Vec::new();
    for c in node.children().filter(Node::is_element) {
        if c.tag_name().name() != "Corner" {
            note_unknown(t, c, "element", c.tag_name().name(), &["Corner"], warnings)?;
            continue;
        }
        check_attrs(t, c, &["X", "Y"], warnings)?;
        corners.push(point_in(t, c, lab)?);
    }
    if corners.len() > MAX_WALL_CORNERS {
        let msg = format!(
            "a wall with {} corners is absurd (limit {MAX_WALL_CORNERS})",
            corners.len()
        );
        return Err(err_node(t, node, msg));
    }
    if corners.len() < 3 {
        return Err(err_node(
            t,
            node,
            format!(
                "a wall needs at least 3 <Corner>s, this one has {}",
                corners.len()
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
        height_m: height,
    })
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
    warnings: &mut Vec<String>,
) -> Result<(), ArenaError> {
    for a in node.attributes() {
        if !known.contains(&a.name()) {
            let what = format!("attribute of <{}>", node.tag_name().name());
            let (line, col) = t.line_col(a.range_qname().start);
            match unknown_name(&what, a.name(), known) {
                Ok(w) => warnings.push(format!("{}:{line}:{col}: {w}", t.path.display())),
                Err(e) => return Err(ArenaError::at_line(t.path, line, Some(col), e)),
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
    warnings: &mut Vec<String>,
) -> Result<(), ArenaError> {
    match unknown_name(what, name, known) {
        Ok(w) => {
            let (line, col) = t.line_col(node.range().start);
            warnings.push(format!("{}:{line}:{col}: {w}", t.path.display()));
            Ok(())
        }
        Err(e) => Err(err_node(t, node, e)),
    }
}

fn line_of(t: Text<'_>, node: Node<'_, '_>) -> u32 {
    t.line_col(node.range().start).0
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
