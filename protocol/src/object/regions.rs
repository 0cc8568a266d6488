//! The Regions object (PROTOCOL.md §12): the segmentation's squares in region-id order.
//!
//! Invariants: a parsed square has a side of at least 1 and lies inside the map; squares are
//! not checked for overlap (segmentation guarantees it; the check would be quadratic).

use super::{
    check_len, check_prefix, check_side, output, put, u16_at, u32_at, ObjectError, Problem,
    OBJECT_VERSION, REGIONS_HEADER_LEN, SQUARE_LEN,
};
use crate::msg::ObjectKind;

/// One square region: top-left (smallest x and y) cell and side, in cells.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SquareRec {
    pub x: u16,
    pub y: u16,
    pub size: u16,
}

/// The Regions header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RegionsHeader {
    pub count: u16,
    /// The segmented map's size, in cells.
    pub width: u16,
    pub height: u16,
    /// Id of the map that was segmented; 0 when unknown.
    pub map_id: u32,
}

impl RegionsHeader {
    /// Bytes of the whole object.
    pub const fn object_len(&self) -> usize {
        REGIONS_HEADER_LEN + self.count as usize * SQUARE_LEN
    }
}

fn check_square(h: &RegionsHeader, s: SquareRec, index: u16) -> Result<(), ObjectError> {
    let fits = |at: u16, side: u16| u32::from(at) + u32::from(s.size) <= u32::from(side);
    if s.size == 0 || !fits(s.x, h.width) || !fits(s.y, h.height) {
        let at = REGIONS_HEADER_LEN + usize::from(index) * SQUARE_LEN;
        return Err(ObjectError::at(at, Problem::BadSquare { index }));
    }
    Ok(())
}

/// Encodes a regions object: the squares in region-id order (id = index).
pub fn encode_regions<I>(
    width: u16,
    height: u16,
    map_id: u32,
    squares: I,
    out: &mut [u8],
) -> Result<usize, ObjectError>
where
    I: IntoIterator<Item = SquareRec>,
    I::IntoIter: ExactSizeIterator,
{
    check_side(width, height, 4)?;
    let squares = squares.into_iter();
    let count =
        u16::try_from(squares.len()).map_err(|_| ObjectError::at(2, Problem::CountMismatch))?;
    let h = RegionsHeader {
        count,
        width,
        height,
        map_id,
    };
    let out = output(out, h.object_len())?;
    put(out, 0, &[OBJECT_VERSION, ObjectKind::Regions as u8]);
    put(out, 2, &count.to_le_bytes());
    put(out, 4, &width.to_le_bytes());
    put(out, 6, &height.to_le_bytes());
    put(out, 8, &map_id.to_le_bytes());
    for (i, s) in squares.enumerate().take(usize::from(count)) {
        check_square(&h, s, u16::try_from(i).unwrap_or(u16::MAX))?;
        let at = REGIONS_HEADER_LEN + i * SQUARE_LEN;
        put(out, at, &s.x.to_le_bytes());
        put(out, at + 2, &s.y.to_le_bytes());
        put(out, at + 4, &s.size.to_le_bytes());
    }
    Ok(h.object_len())
}

/// A parsed Regions object.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RegionsView<'a> {
    pub header: RegionsHeader,
    bytes: &'a [u8],
}

impl<'a> RegionsView<'a> {
    /// Checks `bytes` as a Regions object (sizes and bounds; not that squares are disjoint).
    pub fn parse(bytes: &'a [u8]) -> Result<Self, ObjectError> {
        check_prefix(bytes, ObjectKind::Regions)?;
        let header = RegionsHeader {
            count: u16_at(bytes, 2)?,
            width: u16_at(bytes, 4)?,
            height: u16_at(bytes, 6)?,
            map_id: u32_at(bytes, 8)?,
        };
        check_side(header.width, header.height, 4)?;
        check_len(bytes.len(), header.object_len())?;
        let view = RegionsView { header, bytes };
        for i in 0..header.count {
            let s = view.square_unchecked(i)?;
            check_square(&header, s, i)?;
        }
        Ok(view)
    }

    fn square_unchecked(&self, i: u16) -> Result<SquareRec, ObjectError> {
        let at = REGIONS_HEADER_LEN + usize::from(i) * SQUARE_LEN;
        Ok(SquareRec {
            x: u16_at(self.bytes, at)?,
            y: u16_at(self.bytes, at + 2)?,
            size: u16_at(self.bytes, at + 4)?,
        })
    }

    /// Square `i` (region id `i`).
    pub fn square(&self, i: u16) -> Option<SquareRec> {
        (i < self.header.count)
            .then(|| self.square_unchecked(i).ok())
            .flatten()
    }

    /// The squares in region-id order.
    pub fn squares(&self) -> impl Iterator<Item = SquareRec> + 'a {
        let view = *self;
        (0..self.header.count).filter_map(move |i| view.square(i))
    }
}
