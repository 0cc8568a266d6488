//! Navigation: occupancy grid, square segmentation and A* over regions (seed 004 §5-6).
//! Heap-free: every algorithm works in storage the caller provides, so the firmware runs it in
//! fixed arrays and the station in vectors, with the same results.
//!
//! Pipeline: [`Grid`] -> [`segment`] (squares + region-id map = [`Regions`], whose
//! [`Regions::neighbours`] is the connectivity graph; [`Adjacency`] stores it for many
//! queries) -> [`find_path`] (A*, a raw [`Plan`] through region centres) -> optionally
//! [`smooth`] (a shorter [`Smoothed`] path, reported beside the raw one).
//! Positions inside the planner are integer [`GridPoint`]s (1/256 cell); [`Geometry`] converts
//! to and from the map frame. [`Nav64`] is the firmware's fixed instance.
//!
//! Panic contract: no function here panics on any input, and none allocates.

pub mod astar;
pub mod fixed;
pub mod graph;
pub mod grid;
mod heap;
pub mod ids;
pub mod segment;
pub mod smooth;

pub use astar::{find_path, Plan, PlanError, SearchScratch};
pub use fixed::{FixedNav, Nav64, NAV64_BYTES};
pub use graph::{Adjacency, Edge, GraphError, RegionGraph};
pub use grid::{grid_bytes, Cell, Geometry, Grid, GridError, GridPoint, MAX_SIDE, UNITS_PER_CELL};
pub use ids::{packed_bytes, IdStore, PackedIds};
pub use segment::{segment, Neighbours, Regions, SegmentError, Square};
pub use smooth::{line_of_sight, polyline_length, smooth, Smoothed};

#[cfg(test)]
mod tests;
