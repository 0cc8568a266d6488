//! Arenas from files: CiberRato lab XML, micromouse maze text, ROS map_server PGM+YAML, and a
//! plain ASCII grid, all turned into one [`Arena`] in metres; and [`rasterise`], which turns any
//! arena into an occupancy grid for the planner (seed 004 §5: 0.3 m cells, 17 x 17 for the
//! 5 x 5 m Micro-Rato'99 arena).
//!
//! Layer: std, in the emulator crate; the emulator simulates a robot in an [`Arena`] and the
//! station reuses these importers for planning, so they exist once, here.
//!
//! Map frame: x right, y up, metres; the origin is the arena's lower-left corner (for ROS maps,
//! the map's own `origin`). Headings are radians anticlockwise from +x.
//!
//! Invariants of an [`Arena`] from [`load`]: every number is finite; `bounds` has positive width
//! and height; every wall polygon has at least 3 corners, non-zero area and does not cross
//! itself; raster cells are row-major with row 0 at the bottom (min y).
//!
//! What can fail: reading the file, and any malformed content — each reported as an
//! [`ArenaError`] naming the file and the line/column (text, XML, YAML) or byte offset (PGM).
//! Nothing here panics on input. Recoverable oddities (an unknown XML attribute, a ROS map yaw
//! that map_server ignores too) are kept in [`Arena::warnings`].
//!
//! Formats:
//! - [`ciberrato`]: `<Lab>` XML in CiberRato units, scaled by [`LoadOptions::ciberrato_unit_m`]
//!   (default 5/17.5 m: Micro-Rato'99's 17.5-unit lab is the real 5 m arena). The lab's outer
//!   rectangle is a wall ([`Arena::enclosed`]). Start poses come from the grid file.
//! - [`micromouse`]: `o---o` / `|` ASCII mazes; 0.18 m pitch up to 16 x 16, 0.09 m above
//!   (half-size 32 x 32), 0.012 m walls centred on the grid lines.
//! - [`rosmap`]: map_server YAML + P5/P2 PGM, cells classified exactly as map_server does.
//! - [`ascii`]: `#` obstacle, `.`/space free, `?` unknown, `S` start, `G` goal, with optional
//!   `# cell 0.3`-style header lines (see that module).

pub mod ascii;
pub mod ciberrato;
mod error;
pub mod free_path;
pub mod micromouse;
mod pgm;
pub mod raster;
pub mod reach;
pub mod rosmap;

use std::path::{Path, PathBuf};

pub use error::{ArenaError, Location, Position, EXCERPT_CHARS, MAX_FILE_BYTES};
pub use raster::{rasterise, RasterError, RasterMap};
pub use robot_firmware::nav::grid::Cell;

use crate::geometry::{point_in_polygon, polygon_edges, Aabb, Point, Segment, SegmentSet};

/// Largest grid side (cells, maze cells or pixels) any importer or [`rasterise`] accepts.
pub const MAX_GRID_SIDE: u32 = 8192;

/// Metres per CiberRato unit by default: Micro-Rato'99's lab is 17.5 units for a 5 m arena
/// (seed 004 §2), and CiberRato's robot is 1 unit across.
pub const CIBERRATO_UNIT_M: f64 = 5.0 / 17.5;

/// Which importer made an arena.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ArenaFormat {
    /// CiberRato lab XML (+ grid XML).
    CiberRato,
    /// Micromouse maze text.
    Micromouse,
    /// ROS map_server YAML + PGM.
    RosMap,
    /// Plain ASCII grid.
    AsciiGrid,
}

/// A wall: a solid polygon (its inside is obstacle), corners in metres, implicitly closed.
#[derive(Clone, Debug, PartialEq)]
pub struct Wall {
    /// At least 3 corners; the last joins the first.
    pub corners: Vec<Point>,
    /// Height in metres when the format gives one (beacon line of sight over low walls).
    pub height_m: Option<f64>,
}

impl Wall {
    /// The polygon's edges.
    pub fn edges(&self) -> impl Iterator<Item = Segment> + '_ {
        polygon_edges(&self.corners)
    }

    /// An axis-aligned rectangle wall.
    pub fn rectangle(b: Aabb, height_m: Option<f64>) -> Wall {
        let corners = vec![
            b.min,
            Point::new(b.max.x, b.min.y),
            b.max,
            Point::new(b.min.x, b.max.y),
        ];
        Wall { corners, height_m }
    }
}

/// An infrared beacon (CiberRato): where it is and how high, for line of sight over walls.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Beacon {
    /// Position, metres.
    pub position: Point,
    /// Height above the floor, metres.
    pub height_m: f64,
}

/// A circular target (goal) area on the floor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Target {
    /// Centre, metres.
    pub centre: Point,
    /// Radius, metres.
    pub radius_m: f64,
}

/// A light source (Khepera light sensors); importers leave these empty, the emulator adds them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Position, metres.
    pub position: Point,
    /// Height above the floor, metres.
    pub height_m: f64,
    /// Relative intensity (1 = the emulator's reference lamp).
    pub intensity: f64,
}

/// A robot pose in the map frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
    /// Heading, radians anticlockwise from +x.
    pub heading: f64,
}

/// An arena in metres, whatever file it came from.
#[derive(Clone, Debug, PartialEq)]
pub struct Arena {
    /// Human name (the lab's `Name`, a header `name`, or the file stem).
    pub name: String,
    /// The file it was loaded from (the YAML for ROS maps).
    pub source: PathBuf,
    /// Which importer made it.
    pub format: ArenaFormat,
    /// The arena's extent in the map frame.
    pub bounds: Aabb,
    /// True when the `bounds` rectangle itself is a wall (CiberRato labs): outside is solid.
    pub enclosed: bool,
    /// Solid walls. Grid formats give one rectangle per maximal run of obstacle cells.
    pub walls: Vec<Wall>,
    /// The occupancy grid the file itself holds (ROS maps, ASCII grids), row 0 at the bottom.
    pub raster: Option<RasterMap>,
    /// Beacons (CiberRato labs have at most one in practice; later labs may list several).
    pub beacons: Vec<Beacon>,
    /// Target areas.
    pub targets: Vec<Target>,
    /// Light sources; empty from every importer.
    pub lights: Vec<Light>,
    /// Start poses, in the file's order.
    pub starts: Vec<Pose>,
    /// The goal point, when the format marks one: CiberRato's first target centre, the maze's
    /// `G` cells' centre (or the classic centre), the ASCII grid's `G` cells' centre.
    pub goal: Option<Point>,
    /// Metres per source unit: the CiberRato unit, the maze pitch, the ROS resolution or the
    /// ASCII cell size (so e.g. CiberRato's 1-unit robot is `unit_m` across).
    pub unit_m: f64,
    /// Non-fatal oddities found while loading, each with its file:line.
    pub warnings: Vec<String>,
}

impl Arena {
    /// The first beacon, if any.
    pub fn beacon(&self) -> Option<&Beacon> {
        self.beacons.first()
    }

    /// The first target area, if any.
    pub fn target(&self) -> Option<&Target> {
        self.targets.first()
    }

    /// Whether a beacon stands in target `t` (CiberRato marks each beacon's area with one).
    pub fn beacon_marks(&self, t: &Target) -> bool {
        self.beacons
            .iter()
            .any(|b| (b.position - t.centre).norm() <= t.radius_m)
    }

    /// The target areas a beacon search may end in: those with a beacon inside, or every
    /// target when none has one. A target without a beacon beside beaconed ones is a start or
    /// home area (CiberRato 2011: the robot starts in target 1 and must find target 0), not
    /// somewhere to arrive.
    pub fn goal_targets(&self) -> impl Iterator<Item = &Target> + '_ {
        let any_marked = self.targets.iter().any(|t| self.beacon_marks(t));
        self.targets
            .iter()
            .filter(move |t| !any_marked || self.beacon_marks(t))
    }

    /// The four edges of `bounds`, anticlockwise from the lower-left corner.
    pub fn boundary_edges(&self) -> [Segment; 4] {
        let (lo, hi) = (self.bounds.min, self.bounds.max);
        let (lr, ul) = (Point::new(hi.x, lo.y), Point::new(lo.x, hi.y));
        [
            Segment::new(lo, lr),
            Segment::new(lr, hi),
            Segment::new(hi, ul),
            Segment::new(ul, lo),
        ]
    }

    /// Every wall edge, plus the boundary when the arena is enclosed.
    pub fn segments(&self) -> Vec<Segment> {
        self.segments_where(|_| true)
    }

    /// The walls as a [`SegmentSet`] for ray casts and collisions.
    pub fn segment_set(&self) -> SegmentSet {
        SegmentSet::new(self.segments())
    }

    /// Walls at least `height_m` tall (walls of unknown height and the boundary count as tall):
    /// what hides a beacon at that height. CiberRato (`cbLab::wallDistanceAboveHeight`) skips
    /// only walls lower than the beacon, so a wall exactly as tall hides it.
    pub fn segment_set_hiding(&self, height_m: f64) -> SegmentSet {
        SegmentSet::new(self.segments_where(|w| w.height_m.is_none_or(|h| h >= height_m)))
    }

    fn segments_where(&self, keep: impl Fn(&Wall) -> bool) -> Vec<Segment> {
        let mut out: Vec<Segment> = self
            .walls
            .iter()
            .filter(|w| keep(w))
            .flat_map(Wall::edges)
            .collect();
        if self.enclosed {
            out.extend(self.boundary_edges());
        }
        out
    }

    /// True when `p` is inside a wall polygon, or outside an enclosed arena.
    pub fn is_solid(&self, p: Point) -> bool {
        (self.enclosed && !self.bounds.contains(p))
            || self.walls.iter().any(|w| point_in_polygon(p, &w.corners))
    }
}

/// Which CiberRato grid (start positions) file to read with a lab.
#[derive(Clone, Debug, PartialEq, Eq, Default)]
pub enum GridFile {
    /// `…Lab.xml` -> `…Grid.xml` beside it, when that file exists.
    #[default]
    Auto,
    /// No grid file: no start poses.
    None,
    /// This file.
    Path(PathBuf),
}

/// Settings for [`load`]; [`Default`] gives the documented defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadOptions {
    /// Metres per CiberRato unit (default [`CIBERRATO_UNIT_M`]).
    pub ciberrato_unit_m: f64,
    /// The CiberRato grid file (default: found automatically).
    pub ciberrato_grid: GridFile,
    /// Maze cell pitch; `None` picks 0.18 m up to 16 x 16 cells, else 0.09 m.
    pub maze_pitch_m: Option<f64>,
    /// Maze wall thickness (default 0.012 m).
    pub maze_wall_m: f64,
    /// Maze wall height (default 0.05 m, the classic contest rules).
    pub maze_wall_height_m: f64,
    /// ASCII grid cell size when the file has no `# cell` header (default 0.3 m, seed 004 §5).
    pub ascii_cell_m: f64,
    /// The grid the caller will build from the arena, if it has a limit (default none): a
    /// raster map beyond it is refused from its image header, before the pixels are read.
    pub grid_limit: Option<GridLimit>,
    /// What a simulated world takes, if the caller simulates the arena (default none; see
    /// [`LoadOptions::for_simulation`]): checked before any wall is built.
    pub world_limit: Option<WorldLimit>,
}

/// The limit of the emulator's simulated world. Its robots live in worlds metres across:
/// Khepera boxes and Micro-Rato labs, micromouse mazes of at most 32 x 32 cells, ROS maps of
/// a lab. Every wall costs the simulation memory (its polygon, four segments with their boxes
/// in the spatial index: a few hundred bytes) and its sensors' ray casts time, so a world far
/// beyond these is refused before its walls are built, rather than simulated at gigabytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WorldLimit {
    /// Most maze cells a side: twice the half-size contest's 32.
    pub max_maze_side: u32,
    /// Most walls a grid map (ROS map, ASCII grid) may become, its obstacle cells merged into
    /// rectangles: a lab's map at 5 cm needs a few thousand, a noisy one tens of thousands.
    pub max_walls: usize,
}

impl WorldLimit {
    /// The emulator's: 64 x 64 maze cells, 200,000 walls (a 58 MB world at most).
    pub const EMULATOR: WorldLimit = WorldLimit {
        max_maze_side: 64,
        max_walls: 200_000,
    };

    /// The words every refusal ends with.
    pub fn describe(&self) -> String {
        format!(
            "the emulator's world takes at most {} x {} maze cells and {} walls from a grid map",
            self.max_maze_side, self.max_maze_side, self.max_walls
        )
    }
}

/// A caller's limit on the grid it builds from an arena: it rasterises at `cell_m` (mazes at
/// `maze_cell_m`) and takes at most `max_side` cells a side (the station's planner: 2048).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridLimit {
    /// Cell side the caller rasterises raster maps at, metres.
    pub cell_m: f64,
    /// Cell side for mazes; `None`: half the maze's pitch.
    pub maze_cell_m: Option<f64>,
    /// Most cells a side it takes.
    pub max_side: u32,
    /// Who sets the limit, for the message ("the station's planner").
    pub who: &'static str,
}

impl Default for LoadOptions {
    fn default() -> Self {
        LoadOptions {
            ciberrato_unit_m: CIBERRATO_UNIT_M,
            ciberrato_grid: GridFile::Auto,
            maze_pitch_m: None,
            maze_wall_m: 0.012,
            maze_wall_height_m: 0.05,
            ascii_cell_m: 0.3,
            grid_limit: None,
            world_limit: None,
        }
    }
}

impl LoadOptions {
    /// The options of everything that simulates the arena (`robot-emulator run` and `serve`,
    /// its benchmarks, the station's built-in emulator): the defaults plus
    /// [`WorldLimit::EMULATOR`].
    pub fn for_simulation() -> LoadOptions {
        LoadOptions {
            world_limit: Some(WorldLimit::EMULATOR),
            ..LoadOptions::default()
        }
    }

    /// Checks every length is finite and positive (wall thickness: and below the pitch).
    pub fn validate(&self) -> Result<(), ArenaError> {
        let positive = |name: &'static str, v: f64| {
            if v.is_finite() && v > 0.0 && v <= 1e6 {
                Ok(())
            } else {
                Err(ArenaError::Option {
                    name,
                    message: format!("{v} must be a finite length > 0 and <= 1e6 m"),
                })
            }
        };
        positive("ciberrato_unit_m", self.ciberrato_unit_m)?;
        positive("maze_wall_m", self.maze_wall_m)?;
        positive("maze_wall_height_m", self.maze_wall_height_m)?;
        positive("ascii_cell_m", self.ascii_cell_m)?;
        if let Some(l) = self.grid_limit {
            positive("grid_limit.cell_m", l.cell_m)?;
            if let Some(c) = l.maze_cell_m {
                positive("grid_limit.maze_cell_m", c)?;
            }
        }
        if let Some(p) = self.maze_pitch_m {
            positive("maze_pitch_m", p)?;
            if self.maze_wall_m >= p {
                return Err(ArenaError::Option {
                    name: "maze_wall_m",
                    message: format!("{} m walls do not fit a {p} m pitch", self.maze_wall_m),
                });
            }
        }
        Ok(())
    }
}

/// An empty walled box `width_m` x `height_m` with its lower-left corner at the origin: no
/// obstacles, lights, targets or starts.
pub fn walled_box(name: &str, source: &str, width_m: f64, height_m: f64) -> Arena {
    Arena {
        name: name.to_string(),
        source: Path::new(source).to_path_buf(),
        format: ArenaFormat::AsciiGrid,
        bounds: Aabb::from_corners(Point::new(0.0, 0.0), Point::new(width_m, height_m)),
        enclosed: true,
        walls: Vec::new(),
        raster: None,
        beacons: Vec::new(),
        targets: Vec::new(),
        lights: Vec::new(),
        starts: Vec::new(),
        goal: None,
        unit_m: 0.01,
        warnings: Vec::new(),
    }
}

/// Loads an arena, choosing the importer by extension and content: `.xml` CiberRato lab,
/// `.yaml`/`.yml` ROS map, `.txt` micromouse maze when its first line starts with a post (`o`),
/// else an ASCII grid; `.pgm` alone is refused with a pointer to its YAML. Other extensions are
/// sniffed the same way.
pub fn load(path: &Path, opts: &LoadOptions) -> Result<Arena, ArenaError> {
    let arena = load_unchecked(path, opts)?;
    // Grid maps and mazes are refused before their walls are built; a lab XML lists its walls
    // one by one (its cost is the file's), so it is only counted here, before a world is
    // built from it.
    if let Some(l) = opts.world_limit {
        if arena.walls.len() > l.max_walls {
            return Err(ArenaError::at_file(
                path,
                format!(
                    "{} walls: the emulator's world takes at most {} walls",
                    arena.walls.len(),
                    l.max_walls
                ),
            ));
        }
    }
    Ok(arena)
}

fn load_unchecked(path: &Path, opts: &LoadOptions) -> Result<Arena, ArenaError> {
    opts.validate()?;
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("xml") => ciberrato::load(path, opts),
        Some("yaml" | "yml") => rosmap::load_with(path, opts),
        Some("pgm") => Err(pgm_without_yaml(path)),
        _ => {
            let bytes = error::read_bytes(path)?;
            if bytes.starts_with(b"P2") || bytes.starts_with(b"P5") {
                return Err(pgm_without_yaml(path));
            }
            if bytes.starts_with(b"\x89PNG") || bytes.contains(&0) {
                return Err(ArenaError::at(
                    path,
                    Position::Byte(0),
                    "a binary file, not an arena: expected lab XML, a map YAML (with its PGM), a maze or an ASCII grid",
                ));
            }
            let text = error::read_text(path)?;
            let head = text.trim_start_matches('\u{feff}').trim_start();
            if head.starts_with('<') {
                ciberrato::load_text(path, &text, opts)
            } else if micromouse::looks_like_maze(&text) {
                micromouse::parse(path, &text, opts)
            } else if ext.as_deref() != Some("txt") && text.lines().any(|l| l.starts_with("image:"))
            {
                rosmap::parse_with(path, &text, opts)
            } else {
                ascii::parse(path, &text, opts)
            }
        }
    }
}

/// The error for a bare PGM: names a YAML beside it that refers to it, if there is one.
fn pgm_without_yaml(path: &Path) -> ArenaError {
    let file_name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let found = std::fs::read_dir(dir).ok().and_then(|entries| {
        entries.flatten().map(|e| e.path()).find(|p| {
            let yaml = matches!(p.extension().and_then(|e| e.to_str()), Some("yaml" | "yml"));
            yaml && error::read_bytes(p).is_ok_and(|t| {
                !file_name.is_empty()
                    && t.windows(file_name.len())
                        .any(|w| w == file_name.as_bytes())
            })
        })
    });
    let hint = match found {
        Some(y) => format!("load its map YAML instead: {}", y.display()),
        None => "write a map_server YAML beside it (image, resolution, origin, negate, occupied_thresh, \
                 free_thresh) and load that"
            .to_string(),
    };
    ArenaError::at_file(
        path,
        format!("a PGM holds only pixels, not the map's scale or origin; {hint}"),
    )
}
