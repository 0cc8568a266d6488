//! The firmware's fixed-size navigation storage: grid, segmentation and search in arrays.
//!
//! Layer: a convenience owner over the generic functions of `segment.rs`, `astar.rs` and
//! `smooth.rs`; the station calls the same functions with `Vec`-backed slices and gets the
//! same bytes (see `tests/props.rs`). Sizes are const parameters, checked at compile time, so
//! the memory is known before the robot runs (architecture: "every piece of state has a size
//! fixed at compile time").
//!
//! [`Nav64`], the robot's instance, is 64 x 64 cells, up to 255 regions, 256-region plans and
//! 128-point smoothed plans: [`NAV64_BYTES`] = 10 776 bytes on a 64-bit host (asserted
//! below; a 32-bit MCU saves the upper half of a `usize`), within the seed 004 §3 robot's 32 KB.
//! Where the bytes go: grid 1 040 (2 bits/cell + size and geometry), region map 4 107
//! (8 bits/cell, ids 0 ..= 254), squares 1 530 (6 B each), search scratch 2 550 (`f` u32,
//! parent/heap/pos u16; no h cache and no stored adjacency: the implicit graph costs nothing),
//! raw plan 512 (u16 ids), smoothed plan 1 024 (8 B points), what the region map holds
//! (`Held`) and padding. On `thumbv7em-none-eabihf` it is 10 764 bytes
//! (`robot-firmware/size-report.sh`; 15 372 with the 511 regions it held before).
//!
//! Every map the grid holds is planned. [`FixedNav::route`] uses the squares + A* (seed 004
//! §6) whenever the segmentation fits, and otherwise the grid planner of `wave.rs`, whose 2 048
//! bytes of labels and frontiers (64 x 64) live in the region map's bytes, which a failed
//! segmentation leaves unused: the fallback costs no state. The worst 64 x 64 map has
//! [`max_regions`](super::segment::max_regions)`(64, 64)` = 3072 squares, and A* storage for
//! them alone would be 12 KB; so the square storage is sized for the maps the robot meets
//! instead: 255 regions hold the Micro-Rato'99 arena (35 squares), a 27 x 14-cell CiberRato
//! final (125) and random 64 x 64 maps up to about 1.5 % obstacles; 64 x 64 maps past that
//! take the grid planner (they took a `CapacityExceeded` past 511 squares before, at 4.6 KB
//! more state). [`FixedNav::segment`] alone still fails with `TooManyRegions` on such maps
//! (there are no squares to report).
//!
//! What can fail: segmentation (too many regions) and planning errors, as in those modules;
//! planning on a map changed since the last [`FixedNav::segment`] returns `NotSegmented`.

use super::astar::{find_path, Plan, PlanError, SearchScratch};
use super::grid::{grid_bytes, Geometry, Grid, GridPoint, MAX_SIDE};
use super::ids::{packed_bytes, PackedIds};
use super::segment::{segment_with, Passable, Regions, SegmentError, Square};
use super::smooth::{smooth, Smoothed};
use super::wave::{wave_bytes, wave_first_waypoint, wave_plan, WavePlan, WaveRoute};

/// Fixed-capacity navigation storage: a `W` x `H` grid (`GB` bytes), a `BITS`-bit region map
/// (`MB` bytes), up to `R` regions, plans of up to `P` regions, smoothed plans of `S` points.
pub struct FixedNav<
    const W: u16,
    const H: u16,
    const GB: usize,
    const BITS: u32,
    const MB: usize,
    const R: usize,
    const P: usize,
    const S: usize,
> {
    grid: Grid<[u8; GB]>,
    map: PackedIds<BITS, [u8; MB]>,
    squares: [Square; R],
    /// What the region map holds for the grid as it is (nothing once the grid changed).
    held: Held,
    f: [u32; R],
    parent: [u16; R],
    heap: [u16; R],
    pos: [u16; R],
    path: [u16; P],
    smoothed: [GridPoint; S],
}

/// What the region map's bytes hold: a segmentation's region ids (and the number of regions),
/// the grid planner's labels (made over these passable cells), or nothing valid. One field, so
/// the fallback costs no state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Held {
    Nothing,
    Squares(u16, Passable),
    Labels(Passable),
}

impl Held {
    const fn squares(self) -> Option<u16> {
        match self {
            Held::Squares(n, _) => Some(n),
            _ => None,
        }
    }
}

/// What [`FixedNav::route`] planned with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Route {
    /// Seed 004 §6: squares and A*; the regions are in [`FixedNav::path`].
    Squares(Plan),
    /// The squares did not fit: the grid planner's plan (no regions; waypoints from
    /// [`FixedNav::wave_route`]).
    Grid(WavePlan),
}

/// Cells of the robot's map side.
pub const NAV64_SIDE: u16 = 64;
/// Bits per region id in the robot's map: ids 0 ..= 254, 255 means "no region".
pub const NAV64_MAP_BITS: u32 = 8;
/// Regions the robot's instance holds.
pub const NAV64_REGIONS: usize = 255;
/// Regions a robot plan holds.
pub const NAV64_PATH: usize = 256;
/// Points a robot's smoothed plan holds (corners only, so far fewer than regions).
pub const NAV64_SMOOTHED: usize = 128;

/// The robot's instance: 64 x 64 cells, 255 regions, 256-region plans, 128-point smoothing.
pub type Nav64 = FixedNav<
    NAV64_SIDE,
    NAV64_SIDE,
    { grid_bytes(NAV64_SIDE as usize, NAV64_SIDE as usize) },
    NAV64_MAP_BITS,
    { packed_bytes(NAV64_MAP_BITS, NAV64_SIDE as usize * NAV64_SIDE as usize) },
    NAV64_REGIONS,
    NAV64_PATH,
    NAV64_SMOOTHED,
>;

/// Size of [`Nav64`] in bytes.
pub const NAV64_BYTES: usize = core::mem::size_of::<Nav64>();

impl<
        const W: u16,
        const H: u16,
        const GB: usize,
        const BITS: u32,
        const MB: usize,
        const R: usize,
        const P: usize,
        const S: usize,
    > FixedNav<W, H, GB, BITS, MB, R, P, S>
{
    /// Compile-time check of the const parameters (evaluated by `new`).
    const SIZES_OK: () = {
        assert!(W >= 1 && H >= 1 && W <= MAX_SIDE && H <= MAX_SIDE);
        assert!(GB >= grid_bytes(W as usize, H as usize));
        assert!(BITS >= 1 && BITS <= 16);
        assert!(MB >= packed_bytes(BITS, W as usize * H as usize));
        // Ids 0 ..= R - 1 must stay below the map's and the u16 scratch's markers.
        assert!(R < (1usize << BITS) && R < u16::MAX as usize - 1);
        // The grid planner runs in the region map's bytes, and so does reopening a way.
        assert!(MB >= wave_bytes(W as usize * H as usize));
        assert!(MB >= super::opening::opening_bytes(W as usize * H as usize));
    };

    /// Empty storage: a `W` x `H` grid of unknown cells, not yet segmented.
    pub const fn new(geometry: Geometry) -> Self {
        let () = Self::SIZES_OK;
        FixedNav {
            grid: Grid::from_raw(W, H, geometry, [0; GB]),
            map: PackedIds::from_raw(W as usize * H as usize, [0; MB]),
            squares: [Square::EMPTY; R],
            held: Held::Nothing,
            f: [0; R],
            parent: [0; R],
            heap: [0; R],
            pos: [0; R],
            path: [0; P],
            smoothed: [GridPoint { x: 0, y: 0 }; S],
        }
    }

    /// The occupancy grid.
    pub const fn grid(&self) -> &Grid<[u8; GB]> {
        &self.grid
    }

    /// The occupancy grid for writing (e.g. `reshape` to a smaller map); forgets the
    /// segmentation, which must be redone before planning.
    pub fn grid_mut(&mut self) -> &mut Grid<[u8; GB]> {
        self.held = Held::Nothing;
        &mut self.grid
    }

    /// Segments the grid (seed 004 §6, Fig. 6); returns the number of regions.
    pub fn segment(&mut self) -> Result<usize, SegmentError> {
        self.segment_with(Passable::Free)
    }

    /// Segments the grid with `passable` cells; returns the number of regions.
    pub fn segment_with(&mut self, passable: Passable) -> Result<usize, SegmentError> {
        self.held = Held::Nothing;
        if !self.map.resize(self.grid.len()) {
            return Err(SegmentError::MapSizeMismatch {
                expected: self.grid.len(),
                got: self.map.capacity(),
            });
        }
        let n = segment_with(&self.grid, &mut self.map, &mut self.squares, passable)?.len();
        // n <= R < u16::MAX (SIZES_OK), so this never saturates.
        self.held = Held::Squares(u16::try_from(n).unwrap_or(u16::MAX), passable);
        Ok(n)
    }

    /// The last segmentation, if the grid has not changed since.
    pub fn regions(&self) -> Option<Regions<'_, PackedIds<BITS, [u8; MB]>>> {
        let n = usize::from(self.held.squares()?);
        let squares = self.squares.get(..n)?;
        Some(Regions::from_parts(&self.grid, &self.map, squares))
    }

    /// Plans from `start` to `goal` (seed 004 §6); the regions are in [`path`](Self::path).
    pub fn plan(&mut self, start: GridPoint, goal: GridPoint) -> Result<Plan, PlanError> {
        let n = usize::from(self.held.squares().ok_or(PlanError::NotSegmented)?);
        let squares = self.squares.get(..n).ok_or(PlanError::NotSegmented)?;
        let regions = Regions::from_parts(&self.grid, &self.map, squares);
        let mut scratch = SearchScratch::new(
            &mut self.f,
            &mut self.parent[..],
            &mut self.heap[..],
            &mut self.pos[..],
        );
        find_path(&regions, start, goal, &mut scratch, &mut self.path[..])
    }

    /// Smooths a plan made by [`plan`](Self::plan), `margin` grid units from square corners;
    /// the points are in [`smoothed_points`](Self::smoothed_points), the raw plan stays in
    /// [`path`](Self::path).
    pub fn smooth(&mut self, plan: &Plan, margin: u32) -> Result<Smoothed, PlanError> {
        let n = usize::from(self.held.squares().ok_or(PlanError::NotSegmented)?);
        let squares = self.squares.get(..n).ok_or(PlanError::NotSegmented)?;
        let regions = Regions::from_parts(&self.grid, &self.map, squares);
        smooth(&regions, plan, &self.path[..], margin, &mut self.smoothed)
    }

    /// Forgets the segmentation (one made for a purpose of its own, which a later `Plan`
    /// command must not reuse).
    pub fn forget_segmentation(&mut self) {
        self.held = Held::Nothing;
    }

    /// Plans on every map the grid can hold: seed 004 §6's squares + A* when the segmentation
    /// fits (segmenting first unless the last one is still valid and of the same passable
    /// cells), else the grid planner of
    /// `wave.rs` in the region map's bytes (the segmentation is then gone). A grid plan's
    /// waypoints come from [`wave_route`](Self::wave_route).
    pub fn route(&mut self, start: GridPoint, goal: GridPoint) -> Result<Route, PlanError> {
        self.route_with(Passable::Free, start, goal)
    }

    /// [`route`](Self::route) over `passable` cells.
    pub fn route_with(
        &mut self,
        passable: Passable,
        start: GridPoint,
        goal: GridPoint,
    ) -> Result<Route, PlanError> {
        let fits = match self.held {
            Held::Squares(_, made) if made == passable => true,
            _ => match self.segment_with(passable) {
                Ok(_) => true,
                Err(SegmentError::TooManyRegions { .. }) => false,
                Err(SegmentError::MapSizeMismatch { .. }) => return Err(PlanError::NotSegmented),
            },
        };
        if fits {
            return self.plan(start, goal).map(Route::Squares);
        }
        self.grid_route(passable, start, goal).map(Route::Grid)
    }

    /// The grid planner alone, over `passable` cells, in the region map's bytes (any
    /// segmentation is gone); its waypoints come from [`wave_route`](Self::wave_route). What
    /// a search that replans as its map fills in uses: its cost depends on the cells the wave
    /// covers, not on how the free space cuts into squares.
    pub fn grid_route(
        &mut self,
        passable: Passable,
        start: GridPoint,
        goal: GridPoint,
    ) -> Result<WavePlan, PlanError> {
        self.held = Held::Nothing;
        let plan = wave_plan(&self.grid, passable, start, goal, self.map.bytes_mut())?;
        self.held = Held::Labels(passable);
        Ok(plan)
    }

    /// The grid planner's route from `start` to `goal` over `passable` cells, reduced to what
    /// a search that replans as it drives needs: its first waypoint (the farthest route
    /// point in line of sight) and its length in steps between cells.
    pub fn first_waypoint(
        &mut self,
        passable: Passable,
        start: GridPoint,
        goal: GridPoint,
    ) -> Result<(GridPoint, u32), PlanError> {
        // The labels are left, but no plan to replay them for.
        self.held = Held::Nothing;
        wave_first_waypoint(&self.grid, passable, start, goal, self.map.bytes_mut())
    }

    /// Makes unknown the wall cells that alone part `a`'s region from `b`'s
    /// ([`open_between`](super::opening::open_between)), in the region map's bytes (any
    /// segmentation or grid plan is gone); returns how many.
    pub fn open_between(&mut self, passable: Passable, a: GridPoint, b: GridPoint) -> usize {
        self.held = Held::Nothing;
        super::opening::open_between(&mut self.grid, passable, a, b, self.map.bytes_mut())
    }

    /// The waypoints of a grid plan the last [`route`](Self::route) made; `None` if the grid
    /// or the region map changed since (the labels it replays from are gone).
    pub fn wave_route(&self, plan: WavePlan) -> Option<WaveRoute<'_, [u8; GB]>> {
        let Held::Labels(passable) = self.held else {
            return None;
        };
        Some(WaveRoute::new(
            &self.grid,
            passable,
            self.map.as_bytes(),
            plan,
        ))
    }

    /// Region store of the last raw plan.
    pub fn path(&self) -> &[u16] {
        &self.path
    }

    /// Point store of the last smoothed plan.
    pub fn smoothed_points(&self) -> &[GridPoint] {
        &self.smoothed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_robot_instance_is_10_kb_and_the_grid_planner_fits_its_region_map() {
        #[cfg(target_pointer_width = "64")]
        assert_eq!(NAV64_BYTES, 10_776);
        // 15 384 with 511 regions and no fallback; the fallback must not bring it back.
        const { assert!(NAV64_BYTES <= 10_776) };
        const { assert!(wave_bytes(64 * 64) <= packed_bytes(NAV64_MAP_BITS, 64 * 64)) };
    }
}
