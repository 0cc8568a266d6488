//! Object layouts: the Map, Plan and Regions byte strings that move by chunked transfer (§8).
//!
//! Layer: pure functions over byte slices, like the frame codec. `encode_*` writes into a
//! caller's slice; `*View::parse` checks untrusted bytes and returns a zero-copy view that the
//! firmware reads a cell, a square or a waypoint out of without copying. No heap, no panic.
//! PROTOCOL.md §12 documents every byte with a hex example each (checked by `tests/objects.rs`).
//!
//! Every field is fixed-width little-endian, not postcard: fixed offsets let a reader index
//! straight into the object (waypoint `i` is at a computable offset) and keep chunk boundaries
//! independent of the content. Every object opens with `version` ([`OBJECT_VERSION`]) and
//! `kind` (the [`ObjectKind`] index: 0 Map, 1 Plan, 2 Regions).
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

/// Map flag: the start point is present.
const MAP_HAS_START: u8 = 1 << 0;
/// Map flag: the goal point is present.
const MAP_HAS_GOAL: u8 = 1 << 1;
/// Plan flag: the waypoints are a smoothed path, not the region centres.
const PLAN_SMOOTHED: u8 = 1 << 0;

/// What is wrong with an object's bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Problem {
    /// The bytes end before a field or before the length the header implies.
    Truncated { needed: usize },
    /// Bytes left after the object's last field.
    TrailingBytes { extra: usize },
    /// Byte 0 is not [`OBJECT_VERSION`].
    UnsupportedVersion { version: u8 },
    /// Byte 1 is not an object kind (0..=2).
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
                write!(f, "object format {version}, this build reads {OBJECT_VERSION}")
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
        kind => Err(ObjectError::at(1, Problem::UnknownKind { kind })),
    }
}

/// Any object, parsed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ObjectView<'a> {
    Map(MapView<'a>),
    Plan(PlanView<'a>),
    Regions(RegionsView<'a>),
}

/// Parses an object of any kind.
pub fn parse(bytes: &[u8]) -> Result<ObjectView<'_>, ObjectError> {
    Ok(match kind_of(bytes)? {
        ObjectKind::Map => ObjectView::Map(MapView::parse(bytes)?),
        ObjectKind::Plan => ObjectView::Plan(PlanView::parse(bytes)?),
        ObjectKind::Regions => ObjectView::Regions(RegionsView::parse(bytes)?),
    })
}

// ---------------------------------------------------------------------------------------------
// Map

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
        let flags = if self.start.is_some() { MAP_HAS_START } else { 0 }
            | if self.goal.is_some() { MAP_HAS_GOAL } else { 0 };
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
            return Err(ObjectError::at(base + i, Problem::ReservedCellCode { cell }));
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

// ---------------------------------------------------------------------------------------------
// Plan

/// The Plan header fields outside the navigation block.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PlanMeta {
    /// The waypoints are a smoothed path (else: start, region centres, goal; seed 004 §7).
    pub smoothed: bool,
    /// Id of the map the plan was made on; 0 when unknown.
    pub map_id: u32,
}

/// The fixed part of the navigation block (`robot_firmware::nav::Plan`): points in 1/256 of a
/// cell relative to the map's origin corner, the region count and the cost in the same unit.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NavPlan {
    pub start: [i32; 2],
    pub goal: [i32; 2],
    pub regions: u32,
    pub cost: u32,
}

/// Length of a plan object with `regions` region ids and `waypoints` waypoints.
pub fn plan_object_len(regions: u32, waypoints: usize) -> Option<usize> {
    let ids = usize::try_from(regions).ok()?.checked_mul(4)?;
    let pts = waypoints.checked_mul(WAYPOINT_LEN)?;
    (PLAN_HEADER_LEN + PLAN_NAV_HEADER_LEN + 4)
        .checked_add(ids)?
        .checked_add(pts)
}

/// Reads the navigation block's fixed part at `at`.
fn nav_at(b: &[u8], at: usize) -> Result<NavPlan, ObjectError> {
    Ok(NavPlan {
        start: [i32_at(b, at)?, i32_at(b, at + 4)?],
        goal: [i32_at(b, at + 8)?, i32_at(b, at + 12)?],
        regions: u32_at(b, at + 16)?,
        cost: u32_at(b, at + 20)?,
    })
}

/// Completes a plan object in place. `out[8..8 + nav_len]` must already hold the navigation
/// block as `robot_firmware::nav::Plan::encode` writes it (24 bytes + 4 per region); this
/// writes the 8-byte header in front and the waypoint list after it. Returns the length.
pub fn finish_plan<W>(
    out: &mut [u8],
    meta: PlanMeta,
    nav_len: usize,
    waypoints: W,
) -> Result<usize, ObjectError>
where
    W: IntoIterator<Item = PointMm>,
    W::IntoIter: ExactSizeIterator,
{
    let waypoints = waypoints.into_iter();
    let count = waypoints.len();
    let nav = nav_at(out, PLAN_HEADER_LEN)?;
    let tail = PLAN_HEADER_LEN + nav_len;
    if plan_object_len(nav.regions, 0) != Some(tail + 4) {
        return Err(ObjectError::at(PLAN_HEADER_LEN + 16, Problem::CountMismatch));
    }
    let n = u16::try_from(count).map_err(|_| ObjectError::at(tail, Problem::CountMismatch))?;
    if n == 0 {
        return Err(ObjectError::at(tail, Problem::NoWaypoints));
    }
    let needed = tail + 4 + count * WAYPOINT_LEN;
    let out = output(out, needed)?;
    let flags = if meta.smoothed { PLAN_SMOOTHED } else { 0 };
    put(out, 0, &[OBJECT_VERSION, ObjectKind::Plan as u8, flags, 0]);
    put(out, 4, &meta.map_id.to_le_bytes());
    put(out, tail, &n.to_le_bytes());
    put(out, tail + 2, &[0, 0]);
    for (i, p) in waypoints.enumerate().take(count) {
        put_point(out, tail + 4 + i * WAYPOINT_LEN, p);
    }
    Ok(needed)
}

/// Encodes a whole plan object from its parts (for writers without the nav code).
pub fn encode_plan<R, W>(
    meta: PlanMeta,
    nav: &NavPlan,
    regions: R,
    waypoints: W,
    out: &mut [u8],
) -> Result<usize, ObjectError>
where
    R: IntoIterator<Item = u32>,
    R::IntoIter: ExactSizeIterator,
    W: IntoIterator<Item = PointMm>,
    W::IntoIter: ExactSizeIterator,
{
    let regions = regions.into_iter();
    if u32::try_from(regions.len()) != Ok(nav.regions) {
        return Err(ObjectError::at(PLAN_HEADER_LEN + 16, Problem::CountMismatch));
    }
    let nav_len = PLAN_NAV_HEADER_LEN + regions.len() * 4;
    let at = PLAN_HEADER_LEN;
    output(out, at + nav_len)?;
    for (k, v) in [nav.start[0], nav.start[1], nav.goal[0], nav.goal[1]]
        .iter()
        .enumerate()
    {
        put(out, at + 4 * k, &v.to_le_bytes());
    }
    put(out, at + 16, &nav.regions.to_le_bytes());
    put(out, at + 20, &nav.cost.to_le_bytes());
    for (i, id) in regions.enumerate() {
        put(out, at + PLAN_NAV_HEADER_LEN + 4 * i, &id.to_le_bytes());
    }
    finish_plan(out, meta, nav_len, waypoints)
}

/// A parsed Plan object.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PlanView<'a> {
    pub meta: PlanMeta,
    pub nav: NavPlan,
    bytes: &'a [u8],
    waypoints: u16,
}

impl<'a> PlanView<'a> {
    /// Checks `bytes` as a Plan object.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, ObjectError> {
        check_prefix(bytes, ObjectKind::Plan)?;
        let flags = u8_at(bytes, 2)?;
        if flags & !PLAN_SMOOTHED != 0 {
            return Err(ObjectError::at(2, Problem::ReservedNotZero));
        }
        if u8_at(bytes, 3)? != 0 {
            return Err(ObjectError::at(3, Problem::ReservedNotZero));
        }
        let meta = PlanMeta {
            smoothed: flags & PLAN_SMOOTHED != 0,
            map_id: u32_at(bytes, 4)?,
        };
        let nav = nav_at(bytes, PLAN_HEADER_LEN)?;
        // The region count is untrusted: bound it by the bytes before computing offsets.
        let tail = plan_object_len(nav.regions, 0)
            .filter(|&t| t <= bytes.len())
            .map(|t| t - 4)
            .ok_or(ObjectError::at(
                PLAN_HEADER_LEN + 16,
                Problem::Truncated {
                    needed: plan_object_len(nav.regions, 0).unwrap_or(usize::MAX),
                },
            ))?;
        let waypoints = u16_at(bytes, tail)?;
        if u16_at(bytes, tail + 2)? != 0 {
            return Err(ObjectError::at(tail + 2, Problem::ReservedNotZero));
        }
        if waypoints == 0 {
            return Err(ObjectError::at(tail, Problem::NoWaypoints));
        }
        let needed = tail + 4 + usize::from(waypoints) * WAYPOINT_LEN;
        check_len(bytes.len(), needed)?;
        Ok(PlanView {
            meta,
            nav,
            bytes,
            waypoints,
        })
    }

    /// The navigation block exactly as `nav::Plan::encode` wrote it.
    pub fn nav_block(&self) -> &'a [u8] {
        let end = PLAN_HEADER_LEN + PLAN_NAV_HEADER_LEN + self.nav.regions as usize * 4;
        self.bytes.get(PLAN_HEADER_LEN..end).unwrap_or(&[])
    }

    /// Region `i` of the plan (an index into the Regions object of the same map).
    pub fn region(&self, i: u32) -> Option<u32> {
        if i >= self.nav.regions {
            return None;
        }
        u32_at(self.bytes, PLAN_HEADER_LEN + PLAN_NAV_HEADER_LEN + 4 * i as usize).ok()
    }

    /// Number of waypoints (at least 1).
    pub fn waypoint_count(&self) -> u16 {
        self.waypoints
    }

    /// Waypoint `i` in map-frame millimetres.
    pub fn waypoint(&self, i: u16) -> Option<PointMm> {
        if i >= self.waypoints {
            return None;
        }
        let tail = PLAN_HEADER_LEN + PLAN_NAV_HEADER_LEN + self.nav.regions as usize * 4;
        point_at(self.bytes, tail + 4 + usize::from(i) * WAYPOINT_LEN).ok()
    }

    /// The waypoints in order.
    pub fn waypoints(&self) -> impl Iterator<Item = PointMm> + 'a {
        let view = *self;
        (0..self.waypoints).filter_map(move |i| view.waypoint(i))
    }
}

// ---------------------------------------------------------------------------------------------
// Regions

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

    #[test]
    fn a_plan_count_that_overflows_is_an_error_not_a_panic() {
        let mut b = [0u8; 40];
        b[0] = OBJECT_VERSION;
        b[1] = 1;
        b[24..28].copy_from_slice(&u32::MAX.to_le_bytes());
        let e = PlanView::parse(&b).expect_err("absurd count");
        assert_eq!(e.offset, 24);
        assert!(matches!(e.problem, Problem::Truncated { .. }));
    }
}
