//! Object layouts: the Map, Plan, Regions and LightCalibration byte strings that move by
//! chunked transfer (§8).
//!
//! Layer: pure functions over byte slices, like the frame codec. `encode_*` writes into a
//! caller's slice; `*View::parse` checks untrusted bytes and returns a zero-copy view that the
//! firmware reads a cell, a square or a waypoint out of without copying. No heap, no panic.
//! PROTOCOL.md §12 documents every byte with a hex example each (checked by `tests/objects.rs`).
//!
//! Every field is fixed-width little-endian, not postcard: fixed offsets let a reader index
//! straight into the object (waypoint `i` is at a computable offset) and keep chunk boundaries
//! independent of the content. Every object opens with `version` ([`OBJECT_VERSION`]) and
//! `kind` (the [`ObjectKind`] index: 0 Map, 1 Plan, 2 Regions, 3 LightCalibration).
//!
//! Invariant: encodings are canonical. Reserved bytes and bits are zero, absent points are
//! zero, padding bits after the last map cell are zero, and the decoder refuses anything else.
//! One content therefore has exactly one encoding, and its CRC-32C (the id convention, §8)
//! names the content: equal ids mean equal objects, which `AlreadyHave` relies on.
//!
//! What can fail: decoding reports an [`ObjectError`] naming the problem and the byte offset
//! where it was found; encoding reports an output buffer that is too small or inputs that
//! could not be decoded back (a bad size, a reserved cell code, inconsistent counts).

use core::fmt;

use crate::msg::{ObjectKind, PointMm};

mod light;
mod map;
mod plan;
mod regions;

pub use light::{
    encode_light, LightNeuron, LightView, LIGHT_HEADER_LEN, LIGHT_INPUTS, LIGHT_MAX_OUTPUT,
    LIGHT_NEURONS, LIGHT_NEURON_LEN, LIGHT_OBJECT_LEN,
};
pub use map::{encode_map, map_crc, MapHeader, MapView};
pub use plan::{encode_plan, finish_plan, plan_object_len, NavPlan, PlanMeta, PlanView};
pub use regions::{encode_regions, RegionsHeader, RegionsView, SquareRec};

/// Format version in byte 0 of every object.
pub const OBJECT_VERSION: u8 = 1;
/// Largest map width or height (the navigation code's limit, `robot_firmware::nav::MAX_SIDE`).
pub const MAX_SIDE: u16 = 2048;
/// Bytes of the Map header before the cells.
pub const MAP_HEADER_LEN: usize = 36;
/// Bytes of the Plan header before the navigation block.
pub const PLAN_HEADER_LEN: usize = 8;
/// Bytes of the navigation block's fixed part (`robot_firmware::nav::Plan::HEADER_BYTES`).
pub const PLAN_NAV_HEADER_LEN: usize = 24;
/// Bytes of the Regions header before the squares.
pub const REGIONS_HEADER_LEN: usize = 12;
/// Bytes per square in a Regions object.
pub const SQUARE_LEN: usize = 6;
/// Bytes per waypoint in a Plan object.
pub const WAYPOINT_LEN: usize = 8;

/// What is wrong with an object's bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Problem {
    /// The bytes end before a field or before the length the header implies.
    Truncated { needed: usize },
    /// Bytes left after the object's last field.
    TrailingBytes { extra: usize },
    /// Byte 0 is not [`OBJECT_VERSION`].
    UnsupportedVersion { version: u8 },
    /// Byte 1 is not an object kind (0..=3).
    UnknownKind { kind: u8 },
    /// Byte 1 names another kind than the caller expected.
    WrongKind { found: ObjectKind },
    /// A reserved byte or flag bit is not zero.
    ReservedNotZero,
    /// A width or height of 0 or above [`MAX_SIDE`].
    BadSize { width: u16, height: u16 },
    /// A cell size of 0 mm or above `i32::MAX`.
    BadCellSize { cell_mm: u32 },
    /// A point flagged absent whose coordinates are not zero.
    AbsentPointNotZero,
    /// A cell with the reserved 2-bit code 3.
    ReservedCellCode { cell: u32 },
    /// Bits after the last cell of the last byte are not zero.
    PaddingNotZero,
    /// A plan with no waypoint.
    NoWaypoints,
    /// A square of side 0, or one that reaches past the map's width or height.
    BadSquare { index: u16 },
    /// A count field disagrees with the items given to an encoder.
    CountMismatch,
    /// The output buffer is too small for the encoding.
    OutputTooSmall { needed: usize },
    /// A light network of another shape than 60 neurons x 6 inputs.
    BadShape { neurons: u8, inputs: u8 },
    /// A light neuron's output (angle + 90 deg, hundredths) above 180 deg.
    BadOutput { index: u16, output: u16 },
}

/// A problem and the byte offset (from the object's first byte) where it was found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ObjectError {
    pub offset: usize,
    pub problem: Problem,
}

impl ObjectError {
    const fn at(offset: usize, problem: Problem) -> Self {
        ObjectError { offset, problem }
    }
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Problem::Truncated { needed } => write!(f, "object ends early, needs {needed} bytes"),
            Problem::TrailingBytes { extra } => write!(f, "{extra} bytes after the object"),
            Problem::UnsupportedVersion { version } => {
                write!(
                    f,
                    "object format {version}, this build reads {OBJECT_VERSION}"
                )
            }
            Problem::UnknownKind { kind } => write!(f, "unknown object kind {kind}"),
            Problem::WrongKind { found } => write!(f, "expected another object, found {found:?}"),
            Problem::ReservedNotZero => write!(f, "reserved byte or bit is not zero"),
            Problem::BadSize { width, height } => {
                write!(f, "map size {width} x {height} outside 1..={MAX_SIDE}")
            }
            Problem::BadCellSize { cell_mm } => write!(f, "cell size {cell_mm} mm is invalid"),
            Problem::AbsentPointNotZero => write!(f, "an absent point is not all zero"),
            Problem::ReservedCellCode { cell } => write!(f, "cell {cell} has reserved code 3"),
            Problem::PaddingNotZero => write!(f, "padding bits after the last cell are not zero"),
            Problem::NoWaypoints => write!(f, "plan has no waypoint"),
            Problem::BadSquare { index } => write!(f, "square {index} is empty or off the map"),
            Problem::CountMismatch => write!(f, "a count disagrees with the items"),
            Problem::OutputTooSmall { needed } => write!(f, "output needs {needed} bytes"),
            Problem::BadShape { neurons, inputs } => write!(
                f,
                "light network of {neurons} neurons x {inputs} inputs, expected \
                 {LIGHT_NEURONS} x {LIGHT_INPUTS}"
            ),
            Problem::BadOutput { index, output } => write!(
                f,
                "neuron {index}'s output {}.{:02} deg is above 180 deg",
                output / 100,
                output % 100
            ),
        }
    }
}

impl fmt::Display for ObjectError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "byte {}: {}", self.offset, self.problem)
    }
}

impl core::error::Error for ObjectError {}

// ---------------------------------------------------------------------------------------------
// Little-endian field access that reports the offset instead of panicking.

fn field<const N: usize>(b: &[u8], at: usize) -> Result<[u8; N], ObjectError> {
    let end = at.saturating_add(N);
    let mut out = [0u8; N];
    out.copy_from_slice(
        b.get(at..end)
            .ok_or(ObjectError::at(b.len(), Problem::Truncated { needed: end }))?,
    );
    Ok(out)
}

fn u8_at(b: &[u8], at: usize) -> Result<u8, ObjectError> {
    field::<1>(b, at).map(|[v]| v)
}

fn u16_at(b: &[u8], at: usize) -> Result<u16, ObjectError> {
    field(b, at).map(u16::from_le_bytes)
}

fn u32_at(b: &[u8], at: usize) -> Result<u32, ObjectError> {
    field(b, at).map(u32::from_le_bytes)
}

fn i32_at(b: &[u8], at: usize) -> Result<i32, ObjectError> {
    field(b, at).map(i32::from_le_bytes)
}

fn point_at(b: &[u8], at: usize) -> Result<PointMm, ObjectError> {
    Ok(PointMm {
        x_mm: i32_at(b, at)?,
        y_mm: i32_at(b, at + 4)?,
    })
}

/// Copies `bytes` to `out[at..]`; the caller has checked the length.
fn put(out: &mut [u8], at: usize, bytes: &[u8]) {
    if let Some(dst) = out.get_mut(at..at + bytes.len()) {
        dst.copy_from_slice(bytes);
    }
}

fn put_point(out: &mut [u8], at: usize, p: PointMm) {
    put(out, at, &p.x_mm.to_le_bytes());
    put(out, at + 4, &p.y_mm.to_le_bytes());
}

/// `out` of at least `needed` bytes, or the error an encoder reports.
fn output(out: &mut [u8], needed: usize) -> Result<&mut [u8], ObjectError> {
    out.get_mut(..needed)
        .ok_or(ObjectError::at(0, Problem::OutputTooSmall { needed }))
}

/// Checks version and kind (bytes 0 and 1) against `expected`.
fn check_prefix(b: &[u8], expected: ObjectKind) -> Result<(), ObjectError> {
    let found = kind_of(b)?;
    if found != expected {
        return Err(ObjectError::at(1, Problem::WrongKind { found }));
    }
    Ok(())
}

/// Checks that an object of `len` bytes has exactly `needed` bytes.
fn check_len(len: usize, needed: usize) -> Result<(), ObjectError> {
    if len < needed {
        return Err(ObjectError::at(len, Problem::Truncated { needed }));
    }
    if len > needed {
        let extra = len - needed;
        return Err(ObjectError::at(needed, Problem::TrailingBytes { extra }));
    }
    Ok(())
}

fn check_side(width: u16, height: u16, at: usize) -> Result<(), ObjectError> {
    if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE {
        return Err(ObjectError::at(at, Problem::BadSize { width, height }));
    }
    Ok(())
}

/// The kind of an object, from its first two bytes.
pub fn kind_of(bytes: &[u8]) -> Result<ObjectKind, ObjectError> {
    let version = u8_at(bytes, 0)?;
    if version != OBJECT_VERSION {
        return Err(ObjectError::at(0, Problem::UnsupportedVersion { version }));
    }
    match u8_at(bytes, 1)? {
        0 => Ok(ObjectKind::Map),
        1 => Ok(ObjectKind::Plan),
        2 => Ok(ObjectKind::Regions),
        3 => Ok(ObjectKind::LightCalibration),
        kind => Err(ObjectError::at(1, Problem::UnknownKind { kind })),
    }
}

/// Any object, parsed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ObjectView<'a> {
    Map(MapView<'a>),
    Plan(PlanView<'a>),
    Regions(RegionsView<'a>),
    LightCalibration(LightView<'a>),
}

/// Parses an object of any kind.
pub fn parse(bytes: &[u8]) -> Result<ObjectView<'_>, ObjectError> {
    Ok(match kind_of(bytes)? {
        ObjectKind::Map => ObjectView::Map(MapView::parse(bytes)?),
        ObjectKind::Plan => ObjectView::Plan(PlanView::parse(bytes)?),
        ObjectKind::Regions => ObjectView::Regions(RegionsView::parse(bytes)?),
        ObjectKind::LightCalibration => ObjectView::LightCalibration(LightView::parse(bytes)?),
    })
}
