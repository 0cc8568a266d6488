//! Planning on the station with the robot's own navigation code (seed 004 §5-6).
//!
//! Layer: std glue between the shared arena importers (`emulator::arena`: CiberRato XML,
//! micromouse mazes, ROS maps, ASCII grids, rasterised by `emulator::arena::rasterise`) and the
//! firmware's heap-free `robot_firmware::nav` (grid, square segmentation, A* over regions,
//! smoothing), run here over `Vec` storage so a plan made on the station is the plan the robot
//! would make from the same grid. Pipeline:
//! [`NavMap`] (file -> raster -> `nav::Grid`, markers, goal area) -> [`Planner`] (segmentation
//! and stored adjacency, timed) -> [`Planner::plan`] (start/goal resolved, A*, optional
//! smoothing) -> [`PlanResult`] in metres, map frame. The station crate's `commands::plan` is
//! the `station plan` / `station segment` edge; `report` turns results into JSON and text,
//! `state` is what the TUI keeps.
//!
//! Invariants: nav row 0 is the smallest y, exactly as the raster's row 0 (raster.rs), so cells
//! copy across unchanged; the cell size is whole millimetres (nav's unit), so the raster and
//! the nav grid agree cell for cell. Grids are unbounded here except by nav's
//! [`MAX_SIDE`](robot_firmware::nav::MAX_SIDE) (2048) a side, refused with the coarsest cell
//! that would fit.
//!
//! What can fail: every problem is a [`NavError`] that says what is wrong in words (a bad
//! file, a cell size, a grid too large, a start or goal outside the map or not in a free
//! cell, an unreachable goal, a map with no start or goal marker when none is given). Nothing
//! here panics.

pub mod map;
pub mod report;
pub mod solve;
pub mod state;

use robot_firmware::nav::{Cell, GraphError, GridError, PlanError, SegmentError};

pub use map::{Endpoint, GoalArea, GoalKind, MapOptions, NavMap};
pub use solve::{PlanResult, Planner, SmoothedPath};
pub use state::PlanState;

/// Which end of a plan a point is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum End {
    Start,
    Goal,
}

impl std::fmt::Display for End {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            End::Start => "start",
            End::Goal => "goal",
        })
    }
}

/// Why a map could not be built or a plan made.
#[derive(Debug, thiserror::Error)]
pub enum NavError {
    /// The file could not be read or parsed (the importer's error names the file and line).
    #[error("cannot load map: {0}")]
    Load(#[from] emulator::arena::ArenaError),
    /// The arena could not be rasterised.
    #[error("cannot make a grid: {0}")]
    Raster(#[from] emulator::arena::RasterError),
    /// `--cell` or `--radius` out of range.
    #[error("{0}")]
    BadOption(String),
    /// A position the link's whole millimetres cannot carry.
    #[error("{0}")]
    Range(#[from] protocol::units::OutOfRange),
    /// The grid exceeds nav's limit.
    #[error(
        "a {width} x {height} grid of {cell_m} m cells exceeds the planner's {max} cells a \
         side; use --cell {suggest_m} or larger"
    )]
    TooLarge {
        width: u64,
        height: u64,
        cell_m: f64,
        max: u16,
        suggest_m: f64,
    },
    /// The nav grid refused the size or geometry.
    #[error("grid: {0}")]
    Grid(#[from] GridError),
    /// Segmentation failed.
    #[error("segmentation: {0}")]
    Segment(#[from] SegmentError),
    /// The adjacency could not be stored.
    #[error("region graph: {0}")]
    Graph(#[from] GraphError),
    /// No point given and the map marks none.
    #[error("the map marks no {0}; give --{flag} X,Y", flag = if *.0 == End::Start { "from" } else { "to" })]
    NoMarker(End),
    /// The point lies outside the grid.
    #[error(
        "{end} ({x:.3}, {y:.3}) is outside the map, which spans x {x0:.3} .. {x1:.3}, \
         y {y0:.3} .. {y1:.3} m"
    )]
    Outside {
        end: End,
        x: f64,
        y: f64,
        x0: f64,
        y0: f64,
        x1: f64,
        y1: f64,
    },
    /// The point's cell is an obstacle or unknown.
    #[error("{end} ({x:.3}, {y:.3}) is in {what} cell ({col}, {row}){hint}",
            what = cell_words(*cell))]
    Blocked {
        end: End,
        x: f64,
        y: f64,
        col: u16,
        row: u16,
        cell: Cell,
        hint: String,
    },
    /// The goal area holds no free cell.
    #[error(
        "no free cell in the goal area (centre ({x:.3}, {y:.3}), radius {radius_m:.3} m){hint}"
    )]
    NoFreeGoal {
        x: f64,
        y: f64,
        radius_m: f64,
        hint: String,
    },
    /// Start and goal are in regions the graph does not connect.
    #[error(
        "goal ({gx:.3}, {gy:.3}) is unreachable from start ({sx:.3}, {sy:.3}): no chain of \
         adjacent free squares joins them{hint}"
    )]
    Unreachable {
        sx: f64,
        sy: f64,
        gx: f64,
        gy: f64,
        hint: String,
    },
    /// Any other planner error (storage sizes are computed, so these are not expected).
    #[error("planner: {0}")]
    Plan(#[from] PlanError),
}

/// "an obstacle", "an unknown", "a free".
fn cell_words(c: Cell) -> &'static str {
    match c {
        Cell::Obstacle => "an obstacle",
        Cell::Unknown => "an unknown (unexplored, treated as obstacle)",
        Cell::Free => "a free",
    }
}

/// Whole microseconds of a duration (saturating).
pub(crate) fn micros(d: std::time::Duration) -> u64 {
    u64::try_from(d.as_micros()).unwrap_or(u64::MAX)
}
