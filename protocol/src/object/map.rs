//! The Map object (PROTOCOL.md §12): header, then the nav grid's 2-bit packed cells verbatim.
//!
//! Invariants: what `MapView::parse` accepts re-encodes to the same bytes (no reserved cell
//! code, zero padding bits, zero absent points). What can fail: see `ObjectError`.

use super::{
    check_len, check_prefix, check_side, output, point_at, put, put_point, u16_at, u32_at, u8_at,
    ObjectError, Problem, MAP_HEADER_LEN, OBJECT_VERSION,
};
use crate::msg::{ObjectKind, PointMm};

/// Map flag: the start point is present.
const MAP_HAS_START: u8 = 1 << 0;
/// Map flag: the goal point is present.
const MAP_HAS_GOAL: u8 = 1 << 1;

/// The Map header: size, geometry in integer millimetres, optional start and goal points.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MapHeader {
    pub width: u16,
    pub height: u16,
    /// Cell side, millimetres.
    pub cell_mm: u32,
    /// Map-frame position of cell (0, 0)'s corner with the smallest x and y.
    pub origin: PointMm,
    pub start: Option<PointMm>,
    pub goal: Option<PointMm>,
}

impl MapHeader {
    /// Number of cells.
    pub const fn cells(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Bytes of packed cells: four cells to a byte.
    pub const fn cell_bytes(&self) -> usize {
        self.cells().div_ceil(4)
    }

    /// Bytes of the whole object.
    pub const fn object_len(&self) -> usize {
        MAP_HEADER_LEN + self.cell_bytes()
    }

    fn check(&self) -> Result<(), ObjectError> {
        check_side(self.width, self.height, 4)?;
        if self.cell_mm == 0 || self.cell_mm > i32::MAX as u32 {
            let cell_mm = self.cell_mm;
            return Err(ObjectError::at(8, Problem::BadCellSize { cell_mm }));
        }
        Ok(())
    }

    /// The 36 header bytes.
    pub fn to_bytes(&self) -> [u8; MAP_HEADER_LEN] {
        let mut h = [0u8; MAP_HEADER_LEN];
        let flags = if self.start.is_some() {
            MAP_HAS_START
        } else {
            0
        } | if self.goal.is_some() { MAP_HAS_GOAL } else { 0 };
        h[0] = OBJECT_VERSION;
        h[1] = ObjectKind::Map as u8;
        h[2] = flags;
        put(&mut h, 4, &self.width.to_le_bytes());
        put(&mut h, 6, &self.height.to_le_bytes());
        put(&mut h, 8, &self.cell_mm.to_le_bytes());
        put_point(&mut h, 12, self.origin);
        put_point(&mut h, 20, self.start.unwrap_or_default());
        put_point(&mut h, 28, self.goal.unwrap_or_default());
        h
    }
}

/// Mask of the bits of the last cell byte that hold cells (the rest is padding).
const fn last_byte_mask(cells: usize) -> u8 {
    match cells % 4 {
        0 => 0xFF,
        r => (1u8 << (2 * r)) - 1,
    }
}

/// Whether `byte` holds the reserved code 3 in one of its cells under `mask`; returns the
/// first such cell (0..4) of the byte.
fn reserved_cell(byte: u8, mask: u8) -> Option<u32> {
    // A 2-bit code is 3 exactly when both its bits are set.
    let both = byte & (byte >> 1) & 0b0101_0101 & mask;
    (both != 0).then(|| both.trailing_zeros() / 2)
}

/// Checks packed cells: no reserved code; zero padding. `base` is the cells' object offset.
fn check_cells(cells: &[u8], count: usize, base: usize) -> Result<(), ObjectError> {
    let n = cells.len();
    for (i, &b) in cells.iter().enumerate() {
        let mask = if i + 1 == n {
            last_byte_mask(count)
        } else {
            0xFF
        };
        if let Some(k) = reserved_cell(b, mask) {
            let cell = u32::try_from(i * 4).unwrap_or(u32::MAX).saturating_add(k);
            return Err(ObjectError::at(
                base + i,
                Problem::ReservedCellCode { cell },
            ));
        }
        if b & !mask != 0 {
            return Err(ObjectError::at(base + i, Problem::PaddingNotZero));
        }
    }
    Ok(())
}

/// Encodes a map: the header and the first `header.cell_bytes()` bytes of `cells` (the nav
/// grid's packed bytes, `Grid::as_bytes`), padding bits cleared. Returns the length written.
pub fn encode_map(header: &MapHeader, cells: &[u8], out: &mut [u8]) -> Result<usize, ObjectError> {
    header.check()?;
    let n = header.cell_bytes();
    let src = cells.get(..n).ok_or(ObjectError::at(
        MAP_HEADER_LEN + cells.len(),
        Problem::Truncated {
            needed: header.object_len(),
        },
    ))?;
    let out = output(out, header.object_len())?;
    let (head, body) = out.split_at_mut(MAP_HEADER_LEN);
    head.copy_from_slice(&header.to_bytes());
    body.copy_from_slice(src);
    if let Some(last) = body.last_mut() {
        *last &= last_byte_mask(header.cells());
    }
    check_cells(body, header.cells(), MAP_HEADER_LEN)?;
    Ok(header.object_len())
}

/// CRC-32C of the map object `encode_map` would write, without a buffer (the map's id).
pub fn map_crc(header: &MapHeader, cells: &[u8]) -> Result<u32, ObjectError> {
    header.check()?;
    let n = header.cell_bytes();
    let src = cells.get(..n).ok_or(ObjectError::at(
        MAP_HEADER_LEN + cells.len(),
        Problem::Truncated {
            needed: header.object_len(),
        },
    ))?;
    let mut digest = crate::frame::CRC32C.digest();
    digest.update(&header.to_bytes());
    if let Some((last, rest)) = src.split_last() {
        digest.update(rest);
        digest.update(&[*last & last_byte_mask(header.cells())]);
    }
    Ok(digest.finalize())
}

/// A parsed Map object.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MapView<'a> {
    pub header: MapHeader,
    cells: &'a [u8],
}

impl<'a> MapView<'a> {
    /// Checks `bytes` as a Map object.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, ObjectError> {
        check_prefix(bytes, ObjectKind::Map)?;
        let flags = u8_at(bytes, 2)?;
        if flags & !(MAP_HAS_START | MAP_HAS_GOAL) != 0 {
            return Err(ObjectError::at(2, Problem::ReservedNotZero));
        }
        if u8_at(bytes, 3)? != 0 {
            return Err(ObjectError::at(3, Problem::ReservedNotZero));
        }
        let optional = |on: bool, at: usize| -> Result<Option<PointMm>, ObjectError> {
            let p = point_at(bytes, at)?;
            match on {
                true => Ok(Some(p)),
                false if p == PointMm::default() => Ok(None),
                false => Err(ObjectError::at(at, Problem::AbsentPointNotZero)),
            }
        };
        let header = MapHeader {
            width: u16_at(bytes, 4)?,
            height: u16_at(bytes, 6)?,
            cell_mm: u32_at(bytes, 8)?,
            origin: point_at(bytes, 12)?,
            start: optional(flags & MAP_HAS_START != 0, 20)?,
            goal: optional(flags & MAP_HAS_GOAL != 0, 28)?,
        };
        header.check()?;
        check_len(bytes.len(), header.object_len())?;
        let cells = bytes.get(MAP_HEADER_LEN..).unwrap_or(&[]);
        check_cells(cells, header.cells(), MAP_HEADER_LEN)?;
        Ok(MapView { header, cells })
    }

    /// The packed cells, `Grid::as_bytes` layout.
    pub fn cells(&self) -> &'a [u8] {
        self.cells
    }

    /// The 2-bit code of cell (`x`, `y`): 0 unknown, 1 free, 2 obstacle; `None` off the map.
    pub fn cell(&self, x: u16, y: u16) -> Option<u8> {
        if x >= self.header.width || y >= self.header.height {
            return None;
        }
        let i = usize::from(y) * usize::from(self.header.width) + usize::from(x);
        Some((self.cells.get(i / 4)? >> (2 * (i % 4))) & 3)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(width: u16, height: u16) -> MapHeader {
        MapHeader {
            width,
            height,
            cell_mm: 300,
            origin: PointMm::default(),
            start: None,
            goal: Some(PointMm {
                x_mm: 450,
                y_mm: 150,
            }),
        }
    }

    #[test]
    fn reserved_cell_codes_are_found_with_their_cell_number() {
        assert_eq!(reserved_cell(0b0110_1001, 0xFF), None);
        assert_eq!(reserved_cell(0b1100_0000, 0xFF), Some(3));
        assert_eq!(reserved_cell(0b0000_1100, 0xFF), Some(1));
        assert_eq!(reserved_cell(0b1100_0000, 0b0011_1111), None);
    }

    #[test]
    fn map_padding_is_cleared_on_encode_and_refused_on_decode() {
        let h = header(3, 1);
        let mut out = [0u8; 64];
        // Cells free, free, obstacle; the fourth (padding) slot says free.
        let n = encode_map(&h, &[0b0110_0101], &mut out).expect("fits");
        assert_eq!(n, MAP_HEADER_LEN + 1);
        assert_eq!(out[MAP_HEADER_LEN], 0b0010_0101);
        assert_eq!(map_crc(&h, &[0b0110_0101]), Ok(crate::crc32c(&out[..n])));
        let view = MapView::parse(&out[..n]).expect("valid");
        assert_eq!(view.cell(2, 0), Some(2));
        assert_eq!(view.cell(3, 0), None);
        out[MAP_HEADER_LEN] |= 0b0100_0000;
        assert_eq!(
            MapView::parse(&out[..n]),
            Err(ObjectError::at(MAP_HEADER_LEN, Problem::PaddingNotZero))
        );
    }
}
