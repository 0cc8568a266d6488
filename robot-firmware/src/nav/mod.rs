//! Navigation: occupancy grid, square segmentation and A* over regions (seed 004 §5-6).
//! Heap-free: every algorithm works in storage the caller provides, so the firmware runs it in
//! fixed arrays and the station in vectors, with the same results.
//!
//! Pipeline: [`Grid`] -> [`segment`] (squares + region-id map = [`Regions`], whose
//! [`Regions::neighbours`] is the connectivity graph; [`Adjacency`] stores it for many
//! queries) -> [`find_path`] (A*, a raw [`Plan`] through region centres) -> optionally
//! [`smooth`] (a shorter [`Smoothed`] path, reported beside the raw one).
//! Positions inside the planner are integer [`GridPoint`]s (1/256 cell); [`Geometry`] converts
//! to and from the map frame. [`Nav64`] is the firmware's fixed instance; its
//! [`FixedNav::route`] falls back to the grid planner ([`wave_plan`], a wavefront over cells)
//! when a map's squares do not fit its storage, so every map it holds can be planned.
//!
//! Panic contract: no function here panics on any input, and none allocates.
//!
//! ```
//! use robot_firmware::nav::*;
//!
//! // The firmware: fixed arrays, 15 KB, implicit graph (a `static` works too: `new` is const).
//! let mut nav = Nav64::new(Geometry::SEED_004);
//! let grid = nav.grid_mut();
//! grid.reshape(17, 17)?;
//! grid.fill(Cell::Free);
//! grid.set(8, 8, Cell::Obstacle)?; // the goal light is an obstacle (seed 004 §6)
//! nav.segment()?;
//! let (start, goal) = (GridPoint::cell_centre(1, 1), GridPoint::cell_centre(9, 8));
//! let plan = nav.plan(start, goal)?;
//! let smooth = nav.smooth(&plan, 64)?; // keep a quarter cell from square corners
//! assert!(smooth.cost <= plan.cost);
//!
//! // The station: the same functions over Vecs, a stored adjacency and the h cache.
//! let g = nav.grid();
//! let mut map = vec![0u32; g.len()];
//! let mut squares = vec![Square::EMPTY; g.len()];
//! let regions = segment(g, &mut map[..], &mut squares[..])?;
//! let n = regions.len();
//! let mut offsets = vec![0u32; n + 1];
//! let mut edges = vec![Edge::default(); Adjacency::edge_count(&regions)];
//! let graph = Adjacency::build(regions, &mut offsets, &mut edges)?;
//! let (mut f, mut h) = (vec![0u32; n], vec![0u32; n]);
//! let (mut parent, mut heap, mut pos) = (vec![0u32; n], vec![0u32; n], vec![0u32; n]);
//! let mut scratch = SearchScratch::new(&mut f, &mut parent[..], &mut heap[..], &mut pos[..])
//!     .with_h_cache(&mut h);
//! let mut path = vec![0u32; n];
//! let station_plan = find_path(&graph, start, goal, &mut scratch, &mut path[..])?;
//!
//! // Byte-identical plans on both sides of the link.
//! let (mut a, mut b) = ([0u8; 256], [0u8; 256]);
//! let la = plan.encode(nav.path(), &mut a)?;
//! let lb = station_plan.encode(&path[..], &mut b)?;
//! assert_eq!(a[..la], b[..lb]);
//! // Waypoints in metres, map frame: start, region centres, goal.
//! let first = plan.waypoints(&regions, &path[..]).next().map(|p| g.geometry().grid_to_metres(p));
//! assert_eq!(first, Some((0.45, 0.45)));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod astar;
mod dist;
pub mod fixed;
pub mod graph;
pub mod grid;
mod heap;
pub mod ids;
pub mod opening;
pub mod paper_map;
pub mod segment;
pub mod smooth;
pub mod wave;

pub use astar::{find_path, Plan, PlanError, SearchScratch};
pub use fixed::{FixedNav, Nav64, Route, NAV64_BYTES};
pub use graph::{Adjacency, Edge, GraphError, RegionGraph};
pub use grid::{grid_bytes, Cell, Geometry, Grid, GridError, GridPoint, MAX_SIDE, UNITS_PER_CELL};
pub use ids::{packed_bytes, IdStore, PackedIds};
pub use opening::{open_between, opening_bytes};
pub use segment::{
    max_regions, segment, segment_with, Neighbours, Passable, Regions, SegmentError, Square,
};
pub use smooth::{line_of_sight, polyline_length, smooth, Smoothed};
pub use wave::{wave_bytes, wave_first_waypoint, wave_plan, WavePlan, WaveRoute};

#[cfg(test)]
mod tests;
