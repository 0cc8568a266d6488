//! A set of map cells, one bit a cell of the largest map (64 x 64: 512 bytes): the planned
//! search's walls seen from afar and the cells the robot has stood in, kept beside the map
//! because the map's cells have no spare code (its code 3 is refused on the link).
//!
//! What can fail: nothing; cells off the map or beyond 64 x 64 are not kept.

use crate::MAP_CAPACITY;

const BYTES: usize = MAP_CAPACITY * MAP_CAPACITY / 8;

/// A set of cells of a map of at most 64 x 64.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellSet {
    bits: [u8; BYTES],
    count: u16,
}

impl Default for CellSet {
    fn default() -> Self {
        Self::new()
    }
}

impl CellSet {
    pub const fn new() -> Self {
        CellSet {
            bits: [0; BYTES],
            count: 0,
        }
    }

    /// Forgets every mark.
    pub fn clear(&mut self) {
        self.bits = [0; BYTES];
        self.count = 0;
    }

    /// How many cells are marked.
    pub fn len(&self) -> usize {
        usize::from(self.count)
    }

    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    fn slot(cell: (i32, i32)) -> Option<(usize, u8)> {
        let (x, y) = (usize::try_from(cell.0).ok()?, usize::try_from(cell.1).ok()?);
        (x < MAP_CAPACITY && y < MAP_CAPACITY).then(|| {
            let i = y * MAP_CAPACITY + x;
            (i / 8, 1 << (i % 8))
        })
    }

    /// Puts `cell` in the set (`on`) or takes it out.
    pub fn set(&mut self, cell: (i32, i32), on: bool) {
        let Some((byte, bit)) = Self::slot(cell) else {
            return;
        };
        let Some(b) = self.bits.get_mut(byte) else {
            return;
        };
        if (*b & bit != 0) != on {
            *b ^= bit;
            self.count = if on {
                self.count.saturating_add(1)
            } else {
                self.count.saturating_sub(1)
            };
        }
    }

    /// The marked cells, (column, row).
    /// Whether `cell` is in the set.
    pub fn contains(&self, cell: (i32, i32)) -> bool {
        Self::slot(cell)
            .and_then(|(byte, bit)| self.bits.get(byte).map(|b| b & bit != 0))
            .unwrap_or(false)
    }

    /// The cells in the set, row by row.
    pub fn cells(&self) -> impl Iterator<Item = (i32, i32)> + '_ {
        self.bits
            .iter()
            .enumerate()
            .filter(|(_, &b)| b != 0)
            .flat_map(|(byte, &b)| {
                (0..8)
                    .filter(move |k| b & (1 << k) != 0)
                    .map(move |k| byte * 8 + k)
            })
            .map(|i| ((i % MAP_CAPACITY) as i32, (i / MAP_CAPACITY) as i32))
    }
}
