//! [`NavMap`]: an arena file turned into the planner's occupancy grid, with its markers.
//!
//! Layer: reads arenas through the shared importers (`emulator::builtin::load`, which also
//! knows `builtin:micro-rato-99`), rasterises them with `emulator::arena::rasterise` (its exact
//! obstacle rule, inflated by the robot radius) and copies the cells into a `nav::Grid` over a
//! `Vec` (row 0 = smallest y on both sides, so no flip). Maps that arrive as a nav grid (a map
//! object from the robot, a synthetic grid) enter through [`NavMap::from_grid`] /
//! [`NavMap::from_packed`].
//!
//! Choices, each documented where it is made:
//! - Cell size: `--cell`, rounded to whole millimetres (nav's unit; a cell that is not whole mm
//!   would drift from the raster by a fraction of a mm per cell). Default 0.3 m (seed 004 §5),
//!   except micromouse mazes, whose default is half the pitch: the coarsest grid that keeps
//!   one-cell corridors open.
//! - Micromouse mazes: the grid starts half a cell before the maze, so wall lines run through
//!   cell centres (half a cell rounded down to whole mm); at half the pitch this is the
//!   classic (2N + 1) x (2N + 1) grid of posts, wall slots and cell centres. Aligned on the wall lines instead, a 12 mm wall would mark
//!   the cells on both sides of it and close every corridor.
//! - Beacons (CiberRato) are obstacles: their cell is marked (seed 004 §6, "the goal beacon is
//!   marked as an obstacle").
//! - The goal area is the target circle when the map has one (CiberRato), else a disc of one
//!   map unit (the maze pitch, the ASCII cell) around the goal marker. The default goal is the
//!   marker itself when its cell is free, otherwise the free point of the goal area nearest
//!   its centre, kept a quarter cell inside its free cell (so not on an obstacle's edge). With
//!   the beacon an obstacle this is the point just beside the beacon (Micro-Rato'99).
//! - Explicit `--from` / `--to` points are used as given: outside the map or in a cell that is
//!   not free is an error, never silently moved.
//!
//! What can fail: loading, rasterising, option ranges, a grid over nav's `MAX_SIDE`.

use robot_firmware::nav::{grid_bytes, Cell, Geometry, Grid, GridPoint, MAX_SIDE};

use emulator::arena::{rasterise, Arena, ArenaFormat, LoadOptions, RasterMap};
use protocol::units::mm_from_m;

use super::{End, NavError};

/// Seed 004 §5: "the resolution of the grid is also set to 0.3 m".
pub const DEFAULT_CELL_M: f64 = 0.3;
/// Smallest cell accepted, metres.
pub const MIN_CELL_M: f64 = 0.005;
/// Largest cell accepted, metres.
pub const MAX_CELL_M: f64 = 100.0;
/// Largest robot radius accepted, metres.
pub const MAX_RADIUS_M: f64 = 100.0;

/// How to turn an arena into a grid.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct MapOptions {
    /// Cell side, metres; `None`: 0.3 m, or half the pitch for micromouse mazes.
    pub cell_m: Option<f64>,
    /// Robot radius, metres: obstacles grow by it (0: the paper's grid).
    pub radius_m: f64,
}

/// What the goal area is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GoalKind {
    /// A target circle of the map (CiberRato).
    Target,
    /// A disc of one map unit around the map's goal marker.
    Marker,
}

/// Where the map says the goal is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GoalArea {
    /// The marker (target centre, maze goal), metres.
    pub centre: (f64, f64),
    /// Radius of the area, metres.
    pub radius_m: f64,
    pub kind: GoalKind,
}

/// A plan's end: the point in metres (whole mm) and in grid units.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Endpoint {
    /// Map-frame millimetres.
    pub mm: (i32, i32),
    pub grid: GridPoint,
}

impl Endpoint {
    /// Metres.
    pub fn metres(&self) -> (f64, f64) {
        (f64::from(self.mm.0) / 1000.0, f64::from(self.mm.1) / 1000.0)
    }
}

/// The bytes of `spec` if it is a file that opens as a Map object (version 1, kind 0): its
/// first two bytes say so, then it is read whole as an object file (`input_file`'s rule).
fn map_object_file(spec: &str) -> Result<Option<Vec<u8>>, NavError> {
    let path = std::path::Path::new(spec);
    if !path.is_file() {
        return Ok(None);
    }
    let kind = &crate::transfer::objects::OBJECT_FILE;
    let refused = |e: crate::input_file::InputError| NavError::Load(e.into());
    let head = crate::input_file::read_head(path, kind, 2).map_err(refused)?;
    if head != [protocol::object::OBJECT_VERSION, 0] {
        return Ok(None);
    }
    crate::input_file::read(path, kind)
        .map(Some)
        .map_err(refused)
}

/// The planner's map: a nav grid in `Vec` storage, its markers and where it came from.
#[derive(Clone, Debug, PartialEq)]
pub struct NavMap {
    /// Human name (the lab's name, the file stem).
    pub name: String,
    /// The file or built-in name it was loaded from.
    pub source: String,
    pub grid: Grid<Vec<u8>>,
    /// Start marker, metres.
    pub start: Option<(f64, f64)>,
    pub goal: Option<GoalArea>,
    /// Robot radius the obstacles were grown by, metres.
    pub radius_m: f64,
    /// Cells marked because a beacon stands there (seed 004 §6).
    pub beacon_cells: Vec<(u16, u16)>,
    /// What was decided while building it, for the summary.
    pub notes: Vec<String>,
    /// Micromouse pitch, when the map is a maze (for hints).
    pub maze_pitch_m: Option<f64>,
}

impl NavMap {
    /// Loads `spec` (an arena file, a Map object file such as `station download-map --out`
    /// writes, or `builtin:micro-rato-99`) and builds its grid.
    pub fn load(spec: &str, opts: &MapOptions) -> Result<NavMap, NavError> {
        if let Some(bytes) = map_object_file(spec)? {
            let name = std::path::Path::new(spec)
                .file_stem()
                .map_or_else(|| spec.to_string(), |s| s.to_string_lossy().into_owned());
            let mut map = NavMap::from_map_object(&name, &bytes)
                .map_err(|e| NavError::BadOption(format!("{spec}: {e}")))?;
            map.source = spec.to_string();
            map.notes.push(
                "a Map object: its cells are used as they are (--cell and --radius apply to \
                 arena files)"
                    .into(),
            );
            return Ok(map);
        }
        // A raster map too large for the grid at this cell size is refused from its image's
        // header, before its pixels are read (an 8192 x 8192 map took 4.7 GB to refuse), and
        // a maze before its walls are built.
        // A maze's cell is half its pitch unless --cell says otherwise.
        let mm = |c: f64| cell_mm(c).ok().map(|mm| f64::from(mm) / 1000.0);
        let load = LoadOptions {
            grid_limit: mm(opts.cell_m.unwrap_or(DEFAULT_CELL_M)).map(|cell_m| {
                emulator::arena::GridLimit {
                    cell_m,
                    maze_cell_m: opts.cell_m.and_then(mm),
                    max_side: u32::from(MAX_SIDE),
                    who: "the station's planner",
                }
            }),
            ..LoadOptions::default()
        };
        let arena = emulator::builtin::load(spec, &load)?;
        NavMap::from_arena(&arena, spec, opts)
    }

    /// Builds the grid of an arena loaded from `source`.
    pub fn from_arena(arena: &Arena, source: &str, opts: &MapOptions) -> Result<NavMap, NavError> {
        let maze = arena.format == ArenaFormat::Micromouse;
        let cell_mm = cell_mm(opts.cell_m.unwrap_or(if maze {
            arena.unit_m / 2.0
        } else {
            DEFAULT_CELL_M
        }))?;
        let radius = opts.radius_m;
        if !(radius.is_finite() && (0.0..=MAX_RADIUS_M).contains(&radius)) {
            return Err(NavError::BadOption(format!(
                "radius {radius} m must be between 0 and {MAX_RADIUS_M} m"
            )));
        }
        let cell_m = f64::from(cell_mm) / 1000.0;
        let mut notes = Vec::new();
        let padded;
        let arena = if maze {
            // See the module notes: wall lines through cell centres (half a cell in whole mm,
            // so the raster's origin is the nav grid's exactly).
            let mut a = arena.clone();
            let pad = f64::from(cell_mm / 2) / 1000.0;
            a.bounds = a.bounds.expanded(pad);
            notes.push(format!(
                "maze grid starts {pad} m (half a cell) before the maze: wall lines run through \
                 cell centres"
            ));
            padded = a;
            &padded
        } else {
            arena
        };
        check_size(arena.bounds.width(), arena.bounds.height(), cell_m)?;
        let raster = rasterise(arena, cell_m, radius)?;
        let mut grid = nav_grid(&raster, cell_mm)?;
        // Seed 004 §6: "the goal beacon is marked as an obstacle".
        let mut beacon_cells = Vec::new();
        for b in &arena.beacons {
            if let Some((c, r)) = raster.cell_at(b.position.x, b.position.y) {
                let (c, r) = (c as u16, r as u16);
                grid.set(usize::from(c), usize::from(r), Cell::Obstacle)?;
                beacon_cells.push((c, r));
                notes.push(format!(
                    "beacon at ({:.3}, {:.3}) marks cell ({c}, {r}) as an obstacle (as Dom Dinis plans)",
                    b.position.x, b.position.y
                ));
            }
        }
        Ok(NavMap {
            name: arena.name.clone(),
            source: source.to_string(),
            grid,
            start: raster.start.map(|[x, y]| (x, y)),
            goal: goal_area(arena),
            radius_m: radius,
            beacon_cells,
            notes,
            maze_pitch_m: maze.then_some(arena.unit_m),
        })
    }

    /// A map over an existing nav grid (a synthetic grid, a map received from the robot).
    pub fn from_grid(
        name: &str,
        grid: Grid<Vec<u8>>,
        start: Option<(f64, f64)>,
        goal: Option<(f64, f64)>,
    ) -> NavMap {
        let cell = grid.geometry().cell_size_m().into();
        NavMap {
            name: name.to_string(),
            source: name.to_string(),
            grid,
            start,
            goal: goal.map(|centre| GoalArea {
                centre,
                radius_m: cell,
                kind: GoalKind::Marker,
            }),
            radius_m: 0.0,
            beacon_cells: Vec::new(),
            notes: Vec::new(),
            maze_pitch_m: None,
        }
    }

    /// The seam for maps from the robot: the fields of a Map object (PROTOCOL.md §12: size,
    /// cell mm, origin mm, optional start and goal mm, then the packed cells in nav's layout).
    #[allow(clippy::too_many_arguments)]
    pub fn from_packed(
        name: &str,
        width: u16,
        height: u16,
        cell_mm: u32,
        origin_mm: (i32, i32),
        start_mm: Option<(i32, i32)>,
        goal_mm: Option<(i32, i32)>,
        cells: &[u8],
    ) -> Result<NavMap, NavError> {
        let geometry = Geometry::new(cell_mm, origin_mm.0, origin_mm.1)?;
        check_extent(&geometry, width, height)?;
        let n = grid_bytes(width.into(), height.into());
        let bytes = cells.get(..n).unwrap_or(cells).to_vec();
        let grid = Grid::new(width, height, geometry, bytes)?;
        let m = |(x, y): (i32, i32)| (f64::from(x) / 1000.0, f64::from(y) / 1000.0);
        Ok(NavMap::from_grid(
            name,
            grid,
            start_mm.map(m),
            goal_mm.map(m),
        ))
    }

    /// A Map object's bytes (PROTOCOL.md §12, e.g. downloaded from the robot), checked by
    /// `protocol::object::MapView::parse`.
    pub fn from_map_object(name: &str, bytes: &[u8]) -> Result<NavMap, NavError> {
        let v = protocol::object::MapView::parse(bytes)
            .map_err(|e| NavError::BadOption(format!("not a usable map object: {e}")))?;
        let h = v.header;
        let mm = |p: protocol::PointMm| (p.x_mm, p.y_mm);
        NavMap::from_packed(
            name,
            h.width,
            h.height,
            h.cell_mm,
            mm(h.origin),
            h.start.map(mm),
            h.goal.map(mm),
            v.cells(),
        )
    }

    /// Cell side, metres.
    pub fn cell_m(&self) -> f64 {
        f64::from(self.grid.geometry().cell_mm()) / 1000.0
    }

    /// Map-frame corner of cell (0, 0), metres.
    pub fn origin(&self) -> (f64, f64) {
        let (x, y) = self.grid.geometry().origin_mm();
        (f64::from(x) / 1000.0, f64::from(y) / 1000.0)
    }

    /// The grid's extent: min x, min y, max x, max y, metres.
    pub fn bounds(&self) -> [f64; 4] {
        let (x0, y0) = self.origin();
        let c = self.cell_m();
        [
            x0,
            y0,
            x0 + c * f64::from(self.grid.width()),
            y0 + c * f64::from(self.grid.height()),
        ]
    }

    /// A map-frame point in whole millimetres and grid units, as the robot converts it;
    /// `None` beyond the wire's millimetres (outside any map, whose extent fits them).
    pub fn endpoint(&self, (x, y): (f64, f64)) -> Option<Endpoint> {
        let mm = (mm_from_m("x", x).ok()?, mm_from_m("y", y).ok()?);
        Some(Endpoint {
            mm,
            grid: self.grid.geometry().to_grid(mm.0, mm.1),
        })
    }

    /// A map-frame point in grid units (through whole millimetres).
    pub fn to_grid(&self, p: (f64, f64)) -> Option<GridPoint> {
        self.endpoint(p).map(|e| e.grid)
    }

    /// Grid units to metres (whole millimetres).
    pub fn to_metres(&self, p: GridPoint) -> (f64, f64) {
        let (x, y) = self.grid.geometry().to_mm(p);
        (f64::from(x) / 1000.0, f64::from(y) / 1000.0)
    }

    /// The cell holding a map-frame point, if inside the grid.
    pub fn cell_of(&self, p: (f64, f64)) -> Option<(u16, u16)> {
        let (cx, cy) = self.to_grid(p)?.cell();
        self.grid.contains(cx, cy).then_some((cx as u16, cy as u16))
    }

    /// A given point, checked: inside the grid and in a free cell.
    pub fn check_point(&self, end: End, p: (f64, f64)) -> Result<Endpoint, NavError> {
        // One conversion decides both: a point is inside exactly when its whole millimetres
        // fall in a cell (the bounds reported are those cells' edges).
        let (Some(g), Some((col, row))) = (self.endpoint(p), self.cell_of(p)) else {
            let [x0, y0, x1, y1] = self.bounds();
            return Err(NavError::Outside {
                end,
                x: p.0,
                y: p.1,
                x0,
                y0,
                x1,
                y1,
            });
        };
        match self.grid.get(col.into(), row.into()) {
            Cell::Free => Ok(g),
            cell => Err(NavError::Blocked {
                end,
                x: p.0,
                y: p.1,
                col,
                row,
                cell,
                hint: self.hint(),
            }),
        }
    }

    /// The start: `from`, else the map's start marker.
    pub fn resolve_start(&self, from: Option<(f64, f64)>) -> Result<Endpoint, NavError> {
        let p = from.or(self.start).ok_or(NavError::NoMarker(End::Start))?;
        self.check_point(End::Start, p)
    }

    /// The goal: `to`, else the map's goal (see the module notes).
    pub fn resolve_goal(&self, to: Option<(f64, f64)>) -> Result<Endpoint, NavError> {
        if let Some(p) = to {
            return self.check_point(End::Goal, p);
        }
        let area = self.goal.ok_or(NavError::NoMarker(End::Goal))?;
        if let Ok(g) = self.check_point(End::Goal, area.centre) {
            return Ok(g);
        }
        self.nearest_free(&area)
            .ok_or_else(|| NavError::NoFreeGoal {
                x: area.centre.0,
                y: area.centre.1,
                radius_m: area.radius_m,
                hint: self.hint(),
            })
    }

    /// The free point of `area` nearest its centre, a quarter cell inside its free cell, in
    /// whole millimetres; ties go to the lower row, then the lower column.
    pub fn nearest_free(&self, area: &GoalArea) -> Option<Endpoint> {
        let (cx, cy) = area.centre;
        let c = self.cell_m();
        let (ox, oy) = self.origin();
        let margin = c / 4.0;
        let reach = (area.radius_m / c).ceil() as i64 + 1;
        let (ccx, ccy) = self.to_grid(area.centre)?.cell();
        let mut best: Option<(f64, Endpoint)> = None;
        for row in (i64::from(ccy) - reach)..=(i64::from(ccy) + reach) {
            for col in (i64::from(ccx) - reach)..=(i64::from(ccx) + reach) {
                let inside = col >= 0
                    && row >= 0
                    && col < i64::from(self.grid.width())
                    && row < i64::from(self.grid.height());
                if !inside || self.grid.get(col as usize, row as usize) != Cell::Free {
                    continue;
                }
                let (x0, y0) = (ox + col as f64 * c, oy + row as f64 * c);
                let px = cx.clamp(x0 + margin, x0 + c - margin);
                let py = cy.clamp(y0 + margin, y0 + c - margin);
                let Some(e) = self.endpoint((px, py)) else {
                    continue;
                };
                let (mx, my) = e.metres();
                let d = (mx - cx).hypot(my - cy);
                if d > area.radius_m || best.is_some_and(|(b, _)| b <= d) {
                    continue;
                }
                best = Some((d, e));
            }
        }
        best.map(|(_, e)| e)
    }

    /// A hint for blocked or unreachable points: mazes at a coarse cell, inflation.
    pub fn hint(&self) -> String {
        let cell = self.cell_m();
        if let Some(pitch) = self.maze_pitch_m {
            if cell > pitch / 2.0 + 1e-9 {
                return format!(
                    " (at {cell} m cells this maze's {pitch} m corridors are closed; try --cell {})",
                    pitch / 2.0
                );
            }
        }
        if self.radius_m > 0.0 {
            return format!(
                " (obstacles are grown by --radius {} m; a smaller radius opens more cells)",
                self.radius_m
            );
        }
        // A cell that touches any wall is an obstacle: in a small arena coarse cells leave few
        // free ones (`builtin:forage` at 0.3 m: none).
        let (free, obstacle, _) = self.counts();
        if free * 4 < free + obstacle && cell > 0.1 + 1e-9 {
            return format!(
                " (at {cell} m cells only {free} of {} cells are free; try a smaller --cell, e.g. \
                 {})",
                free + obstacle,
                (cell / 3.0 * 100.0).round().max(1.0) / 100.0
            );
        }
        String::new()
    }

    /// Cells in each state: free, obstacle, unknown.
    pub fn counts(&self) -> (usize, usize, usize) {
        (0..self.grid.len()).fold((0, 0, 0), |(f, o, u), i| match self.grid.cell_at(i) {
            Cell::Free => (f + 1, o, u),
            Cell::Obstacle => (f, o + 1, u),
            Cell::Unknown => (f, o, u + 1),
        })
    }
}

/// The raster's cells in a nav grid (both row-major with row 0 at the smallest y: no flip).
fn nav_grid(raster: &RasterMap, cell_mm: u32) -> Result<Grid<Vec<u8>>, NavError> {
    let cell_m = raster.cell_m;
    let (w, h) = (side(raster.width, cell_m)?, side(raster.height, cell_m)?);
    let geometry = Geometry::new(
        cell_mm,
        mm_from_m("map origin x", raster.origin[0])?,
        mm_from_m("map origin y", raster.origin[1])?,
    )?;
    check_extent(&geometry, w, h)?;
    let mut grid = Grid::new(w, h, geometry, vec![0u8; grid_bytes(w.into(), h.into())])?;
    for (i, c) in raster.cells.iter().enumerate() {
        let (x, y) = (i % usize::from(w), i / usize::from(w));
        grid.set(x, y, *c)?;
    }
    Ok(grid)
}

/// Refuses a grid whose far edges lie beyond the wire's millimetres: every point inside a map
/// must have a position the robot can be sent (and `cell_of` and `bounds` must agree).
fn check_extent(g: &Geometry, width: u16, height: u16) -> Result<(), NavError> {
    let (ox, oy) = g.origin_mm();
    let far = |o: i32, n: u16| (i64::from(o) + i64::from(n) * i64::from(g.cell_mm())) as f64 / 1e3;
    mm_from_m("map's far edge x", far(ox, width))?;
    mm_from_m("map's far edge y", far(oy, height))?;
    Ok(())
}

/// The target circle (CiberRato), else a disc of one map unit around the goal marker.
fn goal_area(arena: &Arena) -> Option<GoalArea> {
    match (arena.target(), arena.goal) {
        (Some(t), _) => Some(GoalArea {
            centre: (t.centre.x, t.centre.y),
            radius_m: t.radius_m,
            kind: GoalKind::Target,
        }),
        (None, Some(g)) => Some(GoalArea {
            centre: (g.x, g.y),
            radius_m: arena.unit_m,
            kind: GoalKind::Marker,
        }),
        (None, None) => None,
    }
}

/// A cell size in whole millimetres, checked.
fn cell_mm(cell_m: f64) -> Result<u32, NavError> {
    if !(cell_m.is_finite() && (MIN_CELL_M..=MAX_CELL_M).contains(&cell_m)) {
        return Err(NavError::BadOption(format!(
            "cell size {cell_m} m must be between {MIN_CELL_M} and {MAX_CELL_M} m"
        )));
    }
    Ok((cell_m * 1000.0).round() as u32)
}

/// Refuses extents whose grid would exceed `MAX_SIDE`, naming a cell that would fit.
fn check_size(width_m: f64, height_m: f64, cell_m: f64) -> Result<(), NavError> {
    let n = |e: f64| (e / cell_m - 1e-9).ceil().max(1.0);
    let (w, h) = (n(width_m), n(height_m));
    let max = f64::from(MAX_SIDE);
    if w <= max && h <= max {
        return Ok(());
    }
    let suggest = (width_m.max(height_m) / max * 1000.0).ceil() / 1000.0;
    Err(NavError::TooLarge {
        width: w as u64,
        height: h as u64,
        cell_m,
        max: MAX_SIDE,
        suggest_m: suggest.max(cell_m),
    })
}

fn side(n: u32, cell_m: f64) -> Result<u16, NavError> {
    u16::try_from(n)
        .ok()
        .filter(|&s| s <= MAX_SIDE)
        .ok_or(NavError::TooLarge {
            width: n.into(),
            height: n.into(),
            cell_m,
            max: MAX_SIDE,
            suggest_m: cell_m * f64::from(n) / f64::from(MAX_SIDE),
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn micro_rato() -> NavMap {
        NavMap::load(emulator::builtin::MICRO_RATO_99, &MapOptions::default()).expect("built in")
    }

    #[test]
    fn a_map_object_file_loads_as_the_map_it_encodes() {
        let arena = micro_rato();
        let object = crate::transfer::objects::map_object(&arena).expect("encodes");
        let path = std::env::temp_dir().join(format!("robot-map-{}.obj", std::process::id()));
        std::fs::write(&path, &object.bytes).expect("writes");
        let spec = path.display().to_string();
        let loaded = NavMap::load(&spec, &MapOptions::default()).expect("a Map object loads");
        assert_eq!(loaded.grid, arena.grid);
        assert_eq!(loaded.start, arena.start);
        assert_eq!(loaded.source, spec);
        // A damaged one says what and where, naming the file.
        std::fs::write(&path, &object.bytes[..20]).expect("writes");
        let e = NavMap::load(&path.display().to_string(), &MapOptions::default())
            .expect_err("truncated")
            .to_string();
        assert!(e.contains("robot-map-") && e.contains("byte "), "{e}");
        let _ = std::fs::remove_file(&path);
    }

    #[test]
    fn micro_rato_99_at_the_default_cell_is_the_papers_17_by_17_grid() {
        let m = micro_rato();
        assert_eq!((m.grid.width(), m.grid.height()), (17, 17));
        assert_eq!(m.grid.geometry().cell_mm(), 300);
        assert_eq!(m.beacon_cells, vec![(10, 8)]);
        assert_eq!(m.grid.get(10, 8), Cell::Obstacle);
    }

    #[test]
    fn raster_row_zero_is_nav_row_zero_at_the_bottom() {
        // The first inner wall spans x 1.0 .. 1.29 m, y 0 .. 2.57 m: low rows, not high ones.
        let m = micro_rato();
        assert_eq!(m.grid.get(3, 0), Cell::Obstacle);
        assert_eq!(m.grid.get(3, 15), Cell::Free);
        // The top row straddles the 5 m boundary (17 x 0.3 = 5.1 m): solid.
        assert!((0..17).all(|x| m.grid.get(x, 16) == Cell::Obstacle));
    }

    #[test]
    fn the_default_goal_is_the_free_point_of_the_target_nearest_the_beacon() {
        let m = micro_rato();
        let g = m.resolve_goal(None).expect("a free point");
        let (x, y) = g.metres();
        let area = m.goal.expect("target");
        let d = (x - area.centre.0).hypot(y - area.centre.1);
        assert!(d <= area.radius_m && d < 0.1, "({x}, {y}) is {d} m away");
        assert_eq!((x, y), (2.925, 2.571));
        let (cx, cy) = g.grid.cell();
        assert_eq!(m.grid.get(cx as usize, cy as usize), Cell::Free);
    }

    /// A 7 x 4 ASCII map of 0.3 m cells at `origin` ("X Y"), start at cell (1, 2).
    fn ascii_at(name: &str, origin: &str) -> Result<NavMap, NavError> {
        let path =
            std::env::temp_dir().join(format!("robot-map-{}-{name}.txt", std::process::id()));
        let text = format!("# cell 0.3\n# origin {origin}\n#######\n#S    #\n#    G#\n#######\n");
        std::fs::write(&path, text).expect("writes");
        let m = NavMap::load(&path.display().to_string(), &MapOptions::default());
        let _ = std::fs::remove_file(&path);
        m
    }

    #[test]
    fn a_map_beyond_the_links_millimetres_is_refused_by_field() {
        for (origin, field) in [
            ("5000000 0", "map origin x 5000000 m does not fit"),
            ("0 -2147483.9", "map origin y -2147483.9 m does not fit"),
            // The origin fits, the far edge (2.1 m on) does not: points inside could not be sent.
            ("2147483.5 0", "map's far edge x 2147485.6 m does not fit"),
        ] {
            let e = ascii_at("far", origin).expect_err(origin).to_string();
            assert!(e.contains(field), "{origin}: {e}");
        }
    }

    #[test]
    fn near_the_limit_the_check_agrees_with_the_bounds_it_reports() {
        // Far edge at 2147483.6 m, 47 mm inside the link's range.
        let m = ascii_at("near", "2147481.5 0").expect("fits");
        let s = m
            .resolve_start(None)
            .expect("the start marker is in a free cell");
        assert_eq!(s.grid.cell(), (1, 2));
        assert_eq!(s.mm, (2_147_481_950, 750));
        let [x0, _, x1, _] = m.bounds();
        for x in [x0 + 0.01, x1 - 0.01] {
            let e = m
                .check_point(End::Start, (x, 0.75))
                .expect_err("a border wall");
            assert!(matches!(e, NavError::Blocked { .. }), "{x}: {e}");
        }
        for x in [x0 - 0.01, x1 + 0.01, 3e6] {
            let e = m.check_point(End::Start, (x, 0.75)).expect_err("outside");
            assert!(matches!(e, NavError::Outside { .. }), "{x}: {e}");
        }
    }

    #[test]
    fn points_outside_or_in_walls_are_refused_not_moved() {
        let m = micro_rato();
        let e = m.resolve_goal(Some((7.0, 1.0))).expect_err("outside");
        assert!(e.to_string().contains("outside the map"), "{e}");
        let e = m.resolve_goal(Some((1.15, 1.0))).expect_err("wall");
        assert!(e.to_string().contains("obstacle cell (3, 3)"), "{e}");
    }

    #[test]
    fn cell_sizes_are_whole_millimetres_and_bounded() {
        assert_eq!(cell_mm(0.0904).ok(), Some(90));
        assert!(cell_mm(0.0).is_err());
        assert!(cell_mm(f64::NAN).is_err());
        let e = check_size(5.0, 5.0, 0.001).expect_err("too large");
        assert!(e.to_string().contains("--cell 0.003"), "{e}");
    }
}
