//! The occupancy grid (seed 004 §5).

/// One grid cell's state. Unknown counts as an obstacle for segmentation (seed 004 §6).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
#[repr(u8)]
pub enum Cell {
    #[default]
    Unknown = 0,
    Free = 1,
    Obstacle = 2,
}
