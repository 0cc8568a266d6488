//! The occupancy grid (seed 004 §5): cells of three states, a cell size and an origin.
//!
//! Layer: data at the bottom of `nav`; segmentation, search and smoothing read it. Cells are
//! packed four to a byte (2 bits each, cell `i = y * width + x` at bits `2 * (i % 4)` of byte
//! `i / 4`), which is also the layout the station uploads verbatim. The 2-bit value 3 is
//! reserved and reads as [`Cell::Unknown`], so any byte string is a valid grid.
//!
//! Frames: row `y` and column `x` grow with the map frame's y and x. The paper's "top-left
//! vertex" (seed 004 §6, Fig. 6) is the corner with the smallest row and column, and its scan
//! order is row 0 first. Whether row 0 is drawn at the top is the display's choice.
//!
//! Geometry is kept in integer millimetres and positions inside the grid in 1/256 of a cell
//! ([`GridPoint`]), so every conversion the planner depends on is integer arithmetic and gives
//! the same bits on every platform; metres (`f32`) are only an input/output convenience.
//!
//! What can fail (typed [`GridError`], never a panic): a width or height of 0 or above
//! [`MAX_SIDE`], storage too small for the stated size, a cell size that is not positive, a
//! write outside the grid.

use core::fmt;

/// Largest width or height. Bounds every planner cost below `u32::MAX` (see `astar.rs`).
pub const MAX_SIDE: u16 = 2048;
/// Fixed-point resolution of [`GridPoint`]: units per cell side.
pub const UNITS_PER_CELL: i32 = 256;
/// Seed 004 §5: "the resolution of the grid is also set to 0.3 m".
pub const SEED_004_CELL_MM: u32 = 300;

/// One grid cell's state. Unknown counts as an obstacle for segmentation (seed 004 §6).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
#[repr(u8)]
pub enum Cell {
    #[default]
    Unknown = 0,
    Free = 1,
    Obstacle = 2,
}

impl Cell {
    /// The cell for a 2-bit code; the reserved code 3 (and higher bits) read as `Unknown`.
    pub const fn from_bits(v: u8) -> Cell {
        match v & 3 {
            1 => Cell::Free,
            2 => Cell::Obstacle,
            _ => Cell::Unknown,
        }
    }
}

/// Why a grid could not be built or changed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridError {
    /// Width or height is 0.
    Empty,
    /// Width or height is above [`MAX_SIDE`].
    GridTooLarge { width: u32, height: u32 },
    /// The storage holds fewer bytes than the size needs.
    StorageTooSmall { needed: usize, got: usize },
    /// The cell size is not a positive whole number of millimetres (or not finite).
    BadCellSize,
    /// A coordinate outside the grid.
    OutOfBounds { x: u32, y: u32 },
}

impl fmt::Display for GridError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            GridError::Empty => write!(f, "grid width and height must be at least 1"),
            GridError::GridTooLarge { width, height } => {
                write!(f, "grid {width} x {height} exceeds {MAX_SIDE} x {MAX_SIDE}")
            }
            GridError::StorageTooSmall { needed, got } => {
                write!(f, "grid storage holds {got} bytes, needs {needed}")
            }
            GridError::BadCellSize => write!(f, "cell size must be a positive number of mm"),
            GridError::OutOfBounds { x, y } => write!(f, "cell ({x}, {y}) is outside the grid"),
        }
    }
}

impl core::error::Error for GridError {}

/// Bytes of packed storage for a `width` x `height` grid (usable in array lengths).
pub const fn grid_bytes(width: usize, height: usize) -> usize {
    width.saturating_mul(height).div_ceil(4)
}

/// A position inside the grid in 1/256 of a cell, relative to the grid's origin corner.
///
/// The planner's unit: integer, so plans are bit-identical on every platform.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct GridPoint {
    pub x: i32,
    pub y: i32,
}

impl GridPoint {
    /// The centre of cell (`cx`, `cy`).
    pub const fn cell_centre(cx: u16, cy: u16) -> GridPoint {
        let half = UNITS_PER_CELL / 2;
        GridPoint {
            x: cx as i32 * UNITS_PER_CELL + half,
            y: cy as i32 * UNITS_PER_CELL + half,
        }
    }

    /// The cell holding this point (floor; may be negative or past the grid).
    pub const fn cell(self) -> (i32, i32) {
        (
            self.x.div_euclid(UNITS_PER_CELL),
            self.y.div_euclid(UNITS_PER_CELL),
        )
    }
}

/// Cell size and origin of a grid in the map frame, in integer millimetres.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Geometry {
    cell_mm: u32,
    origin_x_mm: i32,
    origin_y_mm: i32,
}

impl Geometry {
    /// Seed 004 §5: 0.3 m cells, origin at the map frame's origin.
    pub const SEED_004: Geometry = Geometry {
        cell_mm: SEED_004_CELL_MM,
        origin_x_mm: 0,
        origin_y_mm: 0,
    };

    /// A geometry of `cell_mm` millimetre cells whose cell (0, 0) has its corner at the origin.
    pub const fn new(cell_mm: u32, origin_x_mm: i32, origin_y_mm: i32) -> Result<Self, GridError> {
        if cell_mm == 0 || cell_mm > i32::MAX as u32 {
            return Err(GridError::BadCellSize);
        }
        Ok(Geometry {
            cell_mm,
            origin_x_mm,
            origin_y_mm,
        })
    }

    /// The same from metres, rounded to whole millimetres (e.g. 0.3 m -> 300 mm).
    pub fn from_metres(cell_m: f32, origin_x_m: f32, origin_y_m: f32) -> Result<Self, GridError> {
        let mm = |m: f32| {
            let v = libm::roundf(m * 1000.0);
            // NaN and values beyond i32 are refused rather than saturated.
            (v.is_finite() && v.abs() < 2.0e9).then_some(v as i32)
        };
        let cell = mm(cell_m).ok_or(GridError::BadCellSize)?;
        let ox = mm(origin_x_m).ok_or(GridError::BadCellSize)?;
        let oy = mm(origin_y_m).ok_or(GridError::BadCellSize)?;
        let cell = u32::try_from(cell).map_err(|_| GridError::BadCellSize)?;
        Geometry::new(cell, ox, oy)
    }

    /// Cell side in millimetres.
    pub const fn cell_mm(&self) -> u32 {
        self.cell_mm
    }

    /// Cell side in metres.
    pub fn cell_size_m(&self) -> f32 {
        self.cell_mm as f32 / 1000.0
    }

    /// Map-frame position (mm) of cell (0, 0)'s origin corner.
    pub const fn origin_mm(&self) -> (i32, i32) {
        (self.origin_x_mm, self.origin_y_mm)
    }

    /// Map-frame millimetres to grid units (floor), saturating far outside the grid.
    pub fn to_grid(&self, x_mm: i32, y_mm: i32) -> GridPoint {
        let conv = |v: i32, o: i32| {
            let num = (i64::from(v) - i64::from(o)) * i64::from(UNITS_PER_CELL);
            let u = num.div_euclid(i64::from(self.cell_mm));
            i32::try_from(u).unwrap_or(if u < 0 { i32::MIN } else { i32::MAX })
        };
        GridPoint {
            x: conv(x_mm, self.origin_x_mm),
            y: conv(y_mm, self.origin_y_mm),
        }
    }

    /// Grid units to map-frame millimetres (rounded to nearest, saturating).
    pub fn to_mm(&self, p: GridPoint) -> (i32, i32) {
        let conv = |u: i32, o: i32| {
            let scaled = i64::from(u) * i64::from(self.cell_mm);
            let half = i64::from(UNITS_PER_CELL / 2);
            let mm = (scaled + half).div_euclid(i64::from(UNITS_PER_CELL)) + i64::from(o);
            i32::try_from(mm).unwrap_or(if mm < 0 { i32::MIN } else { i32::MAX })
        };
        (conv(p.x, self.origin_x_mm), conv(p.y, self.origin_y_mm))
    }

    /// Map-frame metres to grid units (through whole millimetres, so it is deterministic).
    pub fn metres_to_grid(&self, x_m: f32, y_m: f32) -> GridPoint {
        let mm = |m: f32| {
            let v = libm::roundf(m * 1000.0);
            // `as` saturates and maps NaN to 0, which is a defined (if meaningless) position.
            v as i32
        };
        self.to_grid(mm(x_m), mm(y_m))
    }

    /// Grid units to map-frame metres.
    pub fn grid_to_metres(&self, p: GridPoint) -> (f32, f32) {
        let (x, y) = self.to_mm(p);
        (x as f32 / 1000.0, y as f32 / 1000.0)
    }

    /// Map-frame millimetres of cell (`cx`, `cy`)'s centre.
    pub fn cell_centre_mm(&self, cx: u16, cy: u16) -> (i32, i32) {
        self.to_mm(GridPoint::cell_centre(cx, cy))
    }
}

/// An occupancy grid over caller storage `S` (`[u8; N]` in the firmware, `Vec<u8>` in the station).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Grid<S> {
    width: u16,
    height: u16,
    geometry: Geometry,
    cells: S,
}

fn check_size(width: u16, height: u16, bytes: usize) -> Result<(), GridError> {
    if width == 0 || height == 0 {
        return Err(GridError::Empty);
    }
    if width > MAX_SIDE || height > MAX_SIDE {
        return Err(GridError::GridTooLarge {
            width: u32::from(width),
            height: u32::from(height),
        });
    }
    let needed = grid_bytes(usize::from(width), usize::from(height));
    if bytes < needed {
        return Err(GridError::StorageTooSmall { needed, got: bytes });
    }
    Ok(())
}

impl<S> Grid<S> {
    /// Used by the fixed firmware instance, whose sizes are checked at compile time.
    pub(crate) const fn from_raw(width: u16, height: u16, geometry: Geometry, cells: S) -> Self {
        Grid {
            width,
            height,
            geometry,
            cells,
        }
    }

    /// Columns.
    pub const fn width(&self) -> u16 {
        self.width
    }

    /// Rows.
    pub const fn height(&self) -> u16 {
        self.height
    }

    /// Number of cells.
    pub const fn len(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Always false: a grid has at least one cell.
    pub const fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Cell size and origin.
    pub const fn geometry(&self) -> Geometry {
        self.geometry
    }

    /// Whether (`x`, `y`) is a cell of this grid.
    pub const fn contains(&self, x: i32, y: i32) -> bool {
        x >= 0 && y >= 0 && x < self.width as i32 && y < self.height as i32
    }

    /// Gives the storage back.
    pub fn into_storage(self) -> S {
        self.cells
    }
}

impl<S: AsRef<[u8]>> Grid<S> {
    /// A `width` x `height` grid over `storage` (existing bytes are kept, see the layout above).
    pub fn new(width: u16, height: u16, geometry: Geometry, storage: S) -> Result<Self, GridError> {
        check_size(width, height, storage.as_ref().len())?;
        Ok(Grid::from_raw(width, height, geometry, storage))
    }

    /// The packed cell bytes.
    pub fn as_bytes(&self) -> &[u8] {
        self.cells.as_ref()
    }

    /// Cell number `i` (row-major); `Unknown` past the end.
    #[inline]
    pub fn cell_at(&self, i: usize) -> Cell {
        let byte = self.cells.as_ref().get(i / 4).copied().unwrap_or(0);
        Cell::from_bits(byte >> (2 * (i % 4)))
    }

    /// Cell (`x`, `y`); outside the grid reads as `Unknown` (the map edge is unexplored).
    #[inline]
    pub fn get(&self, x: usize, y: usize) -> Cell {
        if x >= usize::from(self.width) || y >= usize::from(self.height) {
            return Cell::Unknown;
        }
        self.cell_at(y * usize::from(self.width) + x)
    }
}

impl<S: AsRef<[u8]> + AsMut<[u8]>> Grid<S> {
    /// Sets cell (`x`, `y`).
    pub fn set(&mut self, x: usize, y: usize, cell: Cell) -> Result<(), GridError> {
        let out = GridError::OutOfBounds {
            x: u32::try_from(x).unwrap_or(u32::MAX),
            y: u32::try_from(y).unwrap_or(u32::MAX),
        };
        if x >= usize::from(self.width) || y >= usize::from(self.height) {
            return Err(out);
        }
        let i = y * usize::from(self.width) + x;
        let slot = self.cells.as_mut().get_mut(i / 4).ok_or(out)?;
        let shift = 2 * (i % 4);
        *slot = (*slot & !(3 << shift)) | ((cell as u8) << shift);
        Ok(())
    }

    /// Sets every cell to `cell`.
    pub fn fill(&mut self, cell: Cell) {
        let c = cell as u8;
        let byte = c | c << 2 | c << 4 | c << 6;
        self.cells.as_mut().fill(byte);
    }

    /// Takes `other`'s size, geometry and cells, in place (the robot's map install: no second
    /// grid's storage on the stack); bytes past `other`'s cells become 0. On an error (`other`
    /// larger than this storage) nothing changes.
    pub fn copy_from<T: AsRef<[u8]>>(&mut self, other: &Grid<T>) -> Result<(), GridError> {
        let needed = grid_bytes(usize::from(other.width), usize::from(other.height));
        let src = other
            .as_bytes()
            .get(..needed)
            .ok_or(GridError::StorageTooSmall {
                needed,
                got: other.as_bytes().len(),
            })?;
        check_size(other.width, other.height, self.cells.as_ref().len())?;
        let (dst, rest) = self.cells.as_mut().split_at_mut(needed);
        dst.copy_from_slice(src);
        rest.fill(0);
        (self.width, self.height, self.geometry) = (other.width, other.height, other.geometry);
        Ok(())
    }

    /// Changes the size (for storage sized for a larger map) and marks every cell `Unknown`.
    pub fn reshape(&mut self, width: u16, height: u16) -> Result<(), GridError> {
        check_size(width, height, self.cells.as_ref().len())?;
        self.width = width;
        self.height = height;
        self.fill(Cell::Unknown);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn copy_from_takes_size_geometry_and_cells_in_place_or_changes_nothing() {
        let geo = Geometry::new(100, -50, 20).expect("valid");
        let mut src = Grid::new(3, 2, geo, [0u8; 2]).expect("fits");
        src.set(2, 1, Cell::Obstacle).expect("inside");
        let mut dst = Grid::new(8, 8, Geometry::SEED_004, [0xFFu8; 16]).expect("fits");
        dst.copy_from(&src).expect("fits");
        assert_eq!((dst.width(), dst.height(), dst.geometry()), (3, 2, geo));
        assert_eq!(dst.get(2, 1), Cell::Obstacle);
        assert_eq!(dst.get(0, 0), Cell::Unknown);
        assert_eq!(&dst.as_bytes()[2..], &[0; 14], "the rest is cleared");
        let big = Grid::new(16, 16, geo, [0x55u8; 64]).expect("fits");
        let mut before = [0u8; 16];
        before.copy_from_slice(dst.as_bytes());
        assert!(dst.copy_from(&big).is_err());
        assert_eq!((dst.width(), dst.as_bytes()), (3, &before[..]));
    }

    #[test]
    fn cells_pack_four_to_a_byte_in_row_major_order() {
        let mut g = Grid::new(3, 2, Geometry::SEED_004, [0u8; 2]).expect("fits");
        g.set(1, 0, Cell::Free).expect("inside");
        g.set(0, 1, Cell::Obstacle).expect("inside");
        // cell 1 -> bits 2..4 of byte 0; cell 3 -> bits 6..8 of byte 0.
        assert_eq!(g.as_bytes(), &[0b1000_0100, 0]);
        assert_eq!(g.get(1, 0), Cell::Free);
        assert_eq!(g.get(0, 1), Cell::Obstacle);
        assert_eq!(g.get(3, 0), Cell::Unknown);
    }

    #[test]
    fn size_mismatch_is_an_error_not_a_panic() {
        let geo = Geometry::SEED_004;
        assert_eq!(
            Grid::new(17, 17, geo, [0u8; 10]),
            Err(GridError::StorageTooSmall {
                needed: 73,
                got: 10
            })
        );
        assert_eq!(Grid::new(0, 5, geo, [0u8; 10]), Err(GridError::Empty));
        assert!(matches!(
            Grid::new(4096, 1, geo, [0u8; 2048]),
            Err(GridError::GridTooLarge { .. })
        ));
        let mut g = Grid::new(2, 2, geo, [0u8; 1]).expect("fits");
        assert!(g.set(2, 0, Cell::Free).is_err());
        assert!(g.reshape(3, 3).is_err());
    }

    #[test]
    fn reserved_code_three_reads_as_unknown() {
        let g = Grid::new(4, 1, Geometry::SEED_004, [0xFFu8]).expect("fits");
        assert!((0..4).all(|x| g.get(x, 0) == Cell::Unknown));
    }

    #[test]
    fn world_and_grid_conversions_agree_with_the_seed_004_cell_size() {
        let geo = Geometry::from_metres(0.3, -1.5, 2.0).expect("valid");
        assert_eq!(geo.cell_mm(), 300);
        assert_eq!(geo.origin_mm(), (-1500, 2000));
        // 0.45 m right of the origin is the middle of cell 1.
        let p = geo.metres_to_grid(-1.05, 2.15);
        assert_eq!(p, GridPoint { x: 384, y: 128 });
        assert_eq!(p.cell(), (1, 0));
        assert_eq!(geo.cell_centre_mm(1, 0), (-1050, 2150));
        assert_eq!(geo.grid_to_metres(p), (-1.05, 2.15));
        assert_eq!(geo.to_grid(-1501, 2000).cell(), (-1, 0));
        assert!(Geometry::from_metres(0.0, 0.0, 0.0).is_err());
        assert!(Geometry::from_metres(f32::NAN, 0.0, 0.0).is_err());
    }
}
