//! The robot's objects: its map, plan and regions, moved by chunked transfer (PROTOCOL.md §8,
//! §12) and made on board by segmentation and planning (seed 004 §6); and its light
//! calibration (seed 000 §5.3), which the robot owns elsewhere but uploads and downloads here.
//!
//! Layer: between the link and `nav`. [`Objects`] owns the fixed navigation instance
//! ([`Nav64`]), the installed plan (its object bytes, which are also the waypoints the executor
//! reads), one staging buffer for uploads and one snapshot buffer for downloads, and drives the
//! protocol's [`Receiver`] and [`Sender`]. The free functions build and load objects from the
//! generic nav types, so the station calls them over `Vec` storage and gets the same bytes.
//!
//! Invariants:
//! - installs are atomic: an upload lands in `staging`; the map or plan in use changes only when
//!   all bytes have arrived, their CRC-32C matched and the object decoded and fitted; a
//!   refused transfer or command leaves every object as it was;
//! - a download sends a snapshot taken when it was asked for, so a map or plan that changes
//!   meanwhile cannot tear it;
//! - a partial upload survives a new session, so a station can resume it.
//!
//! What can fail: commands answer `NackReason`s (no map, no plan, bad point, unreachable,
//! capacity exceeded); transfers answer `TransferStatus`es. Nothing here panics.

use protocol::object::{
    encode_map, encode_regions, finish_plan, map_crc, plan_object_len, LightView, MapHeader,
    MapView, ObjectError, PlanMeta, PlanView, Problem, SquareRec, LIGHT_OBJECT_LEN, MAP_HEADER_LEN,
    PLAN_HEADER_LEN,
};
use protocol::transfer::{Outcome, Receiver, Sender, Verified};
use protocol::{
    crc32c, AckInfo, Message, NackReason, ObjectKind, PointMm, TransferAck, TransferBegin,
    TransferData,
};

use crate::light_calibration::LightCalibration;
use crate::nav::{
    grid_bytes, Geometry, Grid, GridError, GridPoint, IdStore, Nav64, Plan, PlanError, Regions,
    Route, SegmentError, Smoothed, WaveRoute,
};
use crate::odometry::Point;
use crate::MAP_CAPACITY;

/// Bytes of the robot's grid storage (64 x 64 cells, 2 bits each).
const GRID_BYTES: usize = grid_bytes(MAP_CAPACITY, MAP_CAPACITY);
/// Largest Map object the robot takes: header and a full 64 x 64 grid.
pub const MAP_OBJECT_MAX: usize = MAP_HEADER_LEN + GRID_BYTES;
/// Largest object the robot holds: a plan through all 256 regions a `Nav64` plan can have,
/// with its 258 waypoints (8 + 24 + 4 * 256 + 4 + 8 * 258). Regions objects (at most
/// 12 + 6 * 255 = 1542 bytes) and maps fit too.
pub const OBJECT_CAPACITY: usize = 3124;
// `Objects::plan_len` is a `u16`.
const _: () = assert!(OBJECT_CAPACITY <= u16::MAX as usize);

/// The map the robot holds besides its cells: the id it is known by and its points.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MapInfo {
    /// The id the map was uploaded under (the station's CRC-32C of it, by convention).
    pub id: u32,
    /// CRC-32C of the map's object encoding.
    pub crc: u32,
    pub start: Option<PointMm>,
    pub goal: Option<PointMm>,
}

/// What a completed upload installed (the robot reports it and reacts).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Installed {
    Map { id: u32 },
    Plan { id: u32 },
    LightCalibration { id: u32 },
}

/// The robot's navigation objects and its transfers.
pub struct Objects {
    nav: Nav64,
    map: Option<MapInfo>,
    /// The grid was changed in place: `map`'s id and CRC are recomputed when next needed.
    map_dirty: bool,
    /// The installed plan object; `plan_len == 0` means no plan. (`u16`, as the snapshot's
    /// length is the download sender's own: the robot's state is at its 32 KB budget, and
    /// these bytes pay for the selective-repeat state of `Receiver` and `Sender`.)
    plan: [u8; OBJECT_CAPACITY],
    plan_len: u16,
    plan_id: u32,
    plan_crc: u32,
    /// Uploads land here until verified (and stay, for resuming, if interrupted).
    staging: [u8; OBJECT_CAPACITY],
    rx: Receiver,
    /// The snapshot a download sends.
    out: [u8; OBJECT_CAPACITY],
    tx: Option<Sender>,
    last_download: Option<Outcome>,
    /// The tag of the last download's `TransferBegin`: the next one uses the one after.
    last_tag: u8,
}

impl Default for Objects {
    fn default() -> Self {
        Self::new()
    }
}

impl Objects {
    /// No map, no plan, no transfer.
    pub const fn new() -> Self {
        Objects {
            nav: Nav64::new(Geometry::SEED_004),
            map: None,
            map_dirty: false,
            plan: [0; OBJECT_CAPACITY],
            plan_len: 0,
            plan_id: 0,
            plan_crc: 0,
            staging: [0; OBJECT_CAPACITY],
            rx: Receiver::new(),
            out: [0; OBJECT_CAPACITY],
            tx: None,
            last_download: None,
            last_tag: protocol::transfer::NO_TAG,
        }
    }

    /// The navigation instance (grid, last segmentation, last plan search).
    pub fn nav(&self) -> &Nav64 {
        &self.nav
    }

    /// The navigation instance for a planning of the robot's own (exploration); the grid is
    /// not changed through it (that goes through [`grid_mut`](Self::grid_mut)).
    pub(crate) fn nav_mut(&mut self) -> &mut Nav64 {
        &mut self.nav
    }

    /// The map's id and points, if the robot holds a map (the id is refreshed first if the
    /// grid was changed in place).
    pub fn map(&mut self) -> Option<MapInfo> {
        if self.map_dirty {
            self.map_dirty = false;
            if let Some(m) = self.map.as_mut() {
                // Sizes were checked when the map was installed, so this cannot fail.
                let crc = map_object_crc(self.nav.grid(), m.start, m.goal).unwrap_or(0);
                (m.id, m.crc) = (crc, crc);
            }
        }
        self.map
    }

    /// The grid, for changes in place (exploration marking cells); `None` without a map. The
    /// segmentation is forgotten and the map's id becomes the CRC-32C of its new content.
    pub fn grid_mut(&mut self) -> Option<&mut Grid<[u8; GRID_BYTES]>> {
        self.map?;
        self.map_dirty = true;
        Some(self.nav.grid_mut())
    }

    /// The map's goal point, if the robot holds a map with one.
    pub fn map_goal(&self) -> Option<PointMm> {
        self.map.and_then(|m| m.goal)
    }

    pub fn has_map(&self) -> bool {
        self.map.is_some()
    }

    pub fn has_plan(&self) -> bool {
        self.plan_len > 0
    }

    /// The installed plan: its id and a view of its object.
    pub fn plan(&self) -> Option<(u32, PlanView<'_>)> {
        let bytes = self
            .plan
            .get(..usize::from(self.plan_len))
            .filter(|b| !b.is_empty())?;
        PlanView::parse(bytes).ok().map(|v| (self.plan_id, v))
    }

    /// Fills `out` with the installed plan's waypoints in metres; returns how many.
    pub fn plan_points(&self, out: &mut [Point]) -> usize {
        let Some((_, view)) = self.plan() else {
            return 0;
        };
        let mut n = 0;
        for (slot, p) in out.iter_mut().zip(view.waypoints()) {
            *slot = Point::new(p.x_mm as f32 / 1000.0, p.y_mm as f32 / 1000.0);
            n += 1;
        }
        n
    }

    /// The installed plan's object bytes.
    pub fn plan_bytes(&self) -> &[u8] {
        self.plan.get(..usize::from(self.plan_len)).unwrap_or(&[])
    }

    /// The upload in progress: (object, id, bytes held, total).
    pub fn upload_progress(&self) -> Option<(ObjectKind, u32, u32, u32)> {
        self.rx.progress()
    }

    /// The download in progress: (object, bytes acknowledged, total).
    pub fn download_progress(&self) -> Option<(ObjectKind, u32, u32)> {
        let tx = self.tx.as_ref()?;
        let (acked, len) = tx.progress();
        Some((tx.begin().object, acked, len))
    }

    /// How the last download ended.
    pub fn last_download(&self) -> Option<Outcome> {
        self.last_download
    }

    /// Encodes the robot's map (its Map object) into `out`.
    pub fn map_object(&self, out: &mut [u8]) -> Result<usize, NackReason> {
        let m = self.map.ok_or(NackReason::NoMap)?;
        encode_map_object(self.nav.grid(), m.start, m.goal, out)
            .map_err(|_| NackReason::CapacityExceeded)
    }

    /// Installs a map the robot made itself (exploration): `grid` cells replace the map and
    /// its id becomes the CRC-32C of its encoding.
    pub fn set_map<S: AsRef<[u8]>>(
        &mut self,
        grid: &Grid<S>,
        start: Option<PointMm>,
        goal: Option<PointMm>,
    ) -> Result<u32, NackReason> {
        let (w, h) = (usize::from(grid.width()), usize::from(grid.height()));
        if w > MAP_CAPACITY || h > MAP_CAPACITY {
            return Err(NackReason::CapacityExceeded);
        }
        let crc = map_object_crc(grid, start, goal).map_err(|_| NackReason::CapacityExceeded)?;
        if grid.as_bytes().len() < grid_bytes(w, h) {
            return Err(NackReason::CapacityExceeded);
        }
        // In place: a copy of the grid on the stack would be 1 KB (issue 15).
        self.nav
            .grid_mut()
            .copy_from(grid)
            .map_err(|_| NackReason::CapacityExceeded)?;
        self.map_dirty = false;
        self.map = Some(MapInfo {
            id: crc,
            crc,
            start,
            goal,
        });
        Ok(crc)
    }

    /// Replaces the map's goal point (exploration: where the goal area was found); the cells
    /// stay, the map's id becomes the CRC-32C of its new encoding. No map, nothing to change.
    pub fn set_goal(&mut self, goal: PointMm) {
        if let Some(m) = self.map.as_mut() {
            m.goal = Some(goal);
            self.map_dirty = true;
        }
    }

    /// `Command::Segment`: segments the map (seed 004 §6); returns the number of regions.
    pub fn segment(&mut self) -> Result<usize, NackReason> {
        if self.map.is_none() {
            return Err(NackReason::NoMap);
        }
        self.nav.segment().map_err(segment_nack)
    }

    /// `Command::Plan`: plans from `from` to `to` (default: the map's goal) and installs the
    /// result as the robot's plan; returns its id. On any refusal the old plan stays.
    pub fn plan_route(&mut self, from: PointMm, to: Option<PointMm>) -> Result<u32, NackReason> {
        let map = self.map().ok_or(NackReason::NoMap)?;
        // No goal given and none in the map: there is no point to plan to.
        let to = to.or(map.goal).ok_or(NackReason::BadPoint)?;
        let geo = self.nav.grid().geometry();
        let start = geo.to_grid(from.x_mm, from.y_mm);
        let goal = geo.to_grid(to.x_mm, to.y_mm);
        // Squares + A* (seed 004 §6) when the segmentation fits, else the grid planner; the
        // object says which (a grid plan has no regions).
        // Writes nothing unless it succeeds, so a refusal keeps the old plan intact.
        let n = match self.nav.route(start, goal).map_err(plan_nack)? {
            Route::Squares(plan) => {
                let regions = self.nav.regions().ok_or(NackReason::BadState)?;
                encode_plan_object(&regions, &plan, self.nav.path(), map.id, &mut self.plan)
            }
            Route::Grid(plan) => {
                let route = self.nav.wave_route(plan).ok_or(NackReason::BadState)?;
                encode_wave_plan_object(&route, map.id, &mut self.plan)
            }
        }
        .map_err(|_| NackReason::CapacityExceeded)?;
        self.plan_len = n as u16; // At most OBJECT_CAPACITY.
        self.plan_crc = crc32c(self.plan.get(..n).unwrap_or(&[]));
        self.plan_id = self.plan_crc;
        Ok(self.plan_id)
    }

    /// `Command::Download`: snapshots the object, starts sending it, and returns the Ack's
    /// info. Replaces a download in progress; a refusal leaves it running. `light` is the
    /// robot's calibration, sent when asked for and trained.
    pub fn start_download(
        &mut self,
        object: ObjectKind,
        light: Option<&LightCalibration>,
    ) -> Result<AckInfo, NackReason> {
        self.map();
        let len = self.object_len(object, light)?;
        let (id, n) = match object {
            ObjectKind::Map => {
                let m = self.map.ok_or(NackReason::NoMap)?;
                let n = encode_map_object(self.nav.grid(), m.start, m.goal, &mut self.out)
                    .map_err(|_| NackReason::CapacityExceeded)?;
                let crc = crc32c(self.out.get(..n).unwrap_or(&[]));
                // The id it was uploaded under, while the content is what was uploaded.
                (if crc == m.crc { m.id } else { crc }, n)
            }
            ObjectKind::Regions => {
                let m = self.map.ok_or(NackReason::NoMap)?;
                let regions = self.nav.regions().ok_or(NackReason::BadState)?;
                let n = encode_regions_object(&regions, m.id, &mut self.out)
                    .map_err(|_| NackReason::CapacityExceeded)?;
                (crc32c(self.out.get(..n).unwrap_or(&[])), n)
            }
            ObjectKind::Plan => {
                let (src, dst) = (self.plan.get(..len), self.out.get_mut(..len));
                let (Some(src), Some(dst)) = (src, dst) else {
                    return Err(NackReason::NoPlan);
                };
                dst.copy_from_slice(src);
                (self.plan_id, len)
            }
            ObjectKind::LightCalibration => {
                let n = light
                    .ok_or(NackReason::BadState)?
                    .encode(&mut self.out)
                    .map_err(|_| NackReason::CapacityExceeded)?;
                (crc32c(self.out.get(..n).unwrap_or(&[])), n)
            }
        };
        let crc = crc32c(self.out.get(..n).unwrap_or(&[]));
        let len = u32::try_from(n).map_err(|_| NackReason::CapacityExceeded)?;
        self.last_tag = protocol::transfer::next_tag(self.last_tag);
        self.tx = Some(Sender::new(object, id, len, crc, self.last_tag));
        Ok(AckInfo::Object {
            object,
            id,
            len,
            crc,
        })
    }

    /// Length of the object a download would send, or why there is none.
    fn object_len(
        &self,
        object: ObjectKind,
        light: Option<&LightCalibration>,
    ) -> Result<usize, NackReason> {
        match object {
            ObjectKind::Map => {
                let m = self.map.ok_or(NackReason::NoMap)?;
                Ok(map_header(self.nav.grid(), m.start, m.goal).object_len())
            }
            ObjectKind::Regions => {
                self.map.ok_or(NackReason::NoMap)?;
                let r = self.nav.regions().ok_or(NackReason::BadState)?;
                Ok(protocol::object::REGIONS_HEADER_LEN + r.len() * protocol::object::SQUARE_LEN)
            }
            ObjectKind::Plan if self.plan_len > 0 => Ok(usize::from(self.plan_len)),
            ObjectKind::Plan => Err(NackReason::NoPlan),
            // An untrained network is random numbers, not a calibration.
            ObjectKind::LightCalibration if light.is_some_and(|l| l.trained) => {
                Ok(LIGHT_OBJECT_LEN)
            }
            ObjectKind::LightCalibration => Err(NackReason::BadState),
        }
    }

    /// Stops a download (a new session asks again).
    pub fn abort_download(&mut self) {
        self.tx = None;
    }

    /// A new session: an upload's partial object is kept for resuming, but only a Begin of
    /// this session names it again (PROTOCOL.md §8 "Tags").
    pub fn new_session(&mut self) {
        self.rx.new_session();
    }

    /// The object of the upload in progress under `tag`.
    pub fn uploading(&self, tag: u8) -> Option<ObjectKind> {
        self.rx.receiving(tag)
    }

    /// Answers an upload's `TransferBegin`. The robot takes maps up to 64 x 64, plans and
    /// light calibrations; it computes regions itself and refuses them.
    pub fn on_begin(&mut self, b: &TransferBegin) -> TransferAck {
        self.map();
        let (limit, have) = match b.object {
            ObjectKind::Map => (
                MAP_OBJECT_MAX,
                self.map.is_some_and(|m| (m.id, m.crc) == (b.id, b.crc)),
            ),
            ObjectKind::Plan => (
                OBJECT_CAPACITY,
                self.has_plan() && (self.plan_id, self.plan_crc) == (b.id, b.crc),
            ),
            ObjectKind::Regions => (0, false),
            // Nothing remembers which calibration was uploaded; 844 bytes are cheap to resend.
            ObjectKind::LightCalibration => (LIGHT_OBJECT_LEN, false),
        };
        self.rx.on_begin(b, limit, have)
    }

    /// Answers an upload's `TransferData`; installs the object when it is whole and verified
    /// (a light calibration into `light`).
    pub fn on_chunk(
        &mut self,
        c: &TransferData<'_>,
        mut light: Option<&mut LightCalibration>,
    ) -> (TransferAck, Option<Installed>) {
        let mut installed = None;
        let Objects {
            nav,
            map,
            map_dirty,
            plan,
            plan_len,
            plan_id,
            plan_crc,
            staging,
            rx,
            ..
        } = self;
        let ack = rx.on_chunk(c, staging, |v| {
            installed = match v.object {
                ObjectKind::Map => {
                    let done = install_map(nav, map, &v);
                    *map_dirty &= done.is_none();
                    done
                }
                ObjectKind::Plan => {
                    let ok = PlanView::parse(v.bytes).is_ok();
                    let slot = plan.get_mut(..v.bytes.len()).filter(|_| ok);
                    slot.map(|slot| {
                        slot.copy_from_slice(v.bytes);
                        // The slot is at most OBJECT_CAPACITY bytes, so this fits.
                        (*plan_len, *plan_id, *plan_crc) = (v.bytes.len() as u16, v.id, v.crc);
                        Installed::Plan { id: v.id }
                    })
                }
                ObjectKind::Regions => None,
                // A robot without a light calibration refuses its upload at the begin; a chunk
                // that gets here anyway installs nothing.
                ObjectKind::LightCalibration => match (LightView::parse(v.bytes), light.as_mut()) {
                    (Ok(view), Some(light)) => {
                        light.install_object(&view);
                        Some(Installed::LightCalibration { id: v.id })
                    }
                    _ => None,
                },
            };
            installed.is_some()
        });
        (ack, installed)
    }

    /// Takes the station's `TransferAck` for a download.
    pub fn on_ack(&mut self, a: &TransferAck, now_ms: u32) {
        if let Some(tx) = self.tx.as_mut() {
            tx.on_ack(a, now_ms);
        }
    }

    /// Drives the download: offers `send` the frames due at `now_ms`.
    pub fn poll(&mut self, now_ms: u32, send: &mut dyn FnMut(&Message<'_>) -> bool) {
        let Some(tx) = self.tx.as_mut() else { return };
        // The snapshot is the sender's announced length long (set together in start_download).
        let len = tx.begin().len as usize;
        tx.poll(now_ms, self.out.get(..len).unwrap_or(&[]), send);
        if let Some(outcome) = tx.outcome() {
            self.last_download = Some(outcome);
            self.tx = None;
        }
    }
}

/// Installs a verified Map object into the robot's grid, or refuses it (`None`).
fn install_map(nav: &mut Nav64, map: &mut Option<MapInfo>, v: &Verified<'_>) -> Option<Installed> {
    let view = MapView::parse(v.bytes).ok()?;
    let h = view.header;
    if usize::from(h.width) > MAP_CAPACITY || usize::from(h.height) > MAP_CAPACITY {
        return None;
    }
    // A grid over the object's own cells, checked before the robot's grid (and its
    // segmentation) is touched, then copied in place: no 1 KB grid on the stack (issue 15).
    let geometry = Geometry::new(h.cell_mm, h.origin.x_mm, h.origin.y_mm).ok()?;
    let incoming = Grid::new(h.width, h.height, geometry, view.cells()).ok()?;
    if incoming.as_bytes().len() > GRID_BYTES {
        return None;
    }
    nav.grid_mut().copy_from(&incoming).ok()?;
    *map = Some(MapInfo {
        id: v.id,
        crc: v.crc,
        start: h.start,
        goal: h.goal,
    });
    Some(Installed::Map { id: v.id })
}

fn segment_nack(e: SegmentError) -> NackReason {
    match e {
        SegmentError::TooManyRegions { .. } | SegmentError::MapSizeMismatch { .. } => {
            NackReason::CapacityExceeded
        }
    }
}

fn plan_nack(e: PlanError) -> NackReason {
    match e {
        PlanError::StartBlocked | PlanError::GoalBlocked => NackReason::BadPoint,
        PlanError::Unreachable => NackReason::Unreachable,
        PlanError::ScratchTooSmall { .. }
        | PlanError::PathTooLong { .. }
        | PlanError::BufferTooSmall { .. } => NackReason::CapacityExceeded,
        PlanError::NotSegmented => NackReason::BadState,
    }
}

// ---------------------------------------------------------------------------------------------
// Objects from and to the generic nav types: the robot and the station call the same code.

/// The Map header for `grid` with optional start and goal points.
pub fn map_header<S: AsRef<[u8]>>(
    grid: &Grid<S>,
    start: Option<PointMm>,
    goal: Option<PointMm>,
) -> MapHeader {
    let geo = grid.geometry();
    let (x_mm, y_mm) = geo.origin_mm();
    MapHeader {
        width: grid.width(),
        height: grid.height(),
        cell_mm: geo.cell_mm(),
        origin: PointMm { x_mm, y_mm },
        start,
        goal,
    }
}

/// Encodes `grid` as a Map object (its cells verbatim, `Grid::as_bytes`).
pub fn encode_map_object<S: AsRef<[u8]>>(
    grid: &Grid<S>,
    start: Option<PointMm>,
    goal: Option<PointMm>,
    out: &mut [u8],
) -> Result<usize, ObjectError> {
    encode_map(&map_header(grid, start, goal), grid.as_bytes(), out)
}

/// CRC-32C (the id) of `grid`'s Map object, without a buffer.
pub fn map_object_crc<S: AsRef<[u8]>>(
    grid: &Grid<S>,
    start: Option<PointMm>,
    goal: Option<PointMm>,
) -> Result<u32, ObjectError> {
    map_crc(&map_header(grid, start, goal), grid.as_bytes())
}

/// A grid over `storage` holding a parsed Map object's cells and geometry.
pub fn load_map<S>(view: &MapView<'_>, mut storage: S) -> Result<Grid<S>, GridError>
where
    S: AsRef<[u8]> + AsMut<[u8]>,
{
    let h = view.header;
    let geometry = Geometry::new(h.cell_mm, h.origin.x_mm, h.origin.y_mm)?;
    let cells = view.cells();
    let bytes = storage.as_mut();
    let got = bytes.len();
    let (dst, rest) =
        bytes
            .split_at_mut_checked(cells.len())
            .ok_or(GridError::StorageTooSmall {
                needed: cells.len(),
                got,
            })?;
    dst.copy_from_slice(cells);
    rest.fill(0);
    Grid::new(h.width, h.height, geometry, storage)
}

/// Encodes the segmentation as a Regions object (squares in region-id order).
pub fn encode_regions_object<M: IdStore + ?Sized>(
    regions: &Regions<'_, M>,
    map_id: u32,
    out: &mut [u8],
) -> Result<usize, ObjectError> {
    let squares = regions.squares().iter().map(|s| SquareRec {
        x: s.x,
        y: s.y,
        size: s.size,
    });
    encode_regions(regions.width(), regions.height(), map_id, squares, out)
}

/// Encodes a raw plan as a Plan object: the nav block exactly as [`Plan::encode`] writes it,
/// then its waypoints (start, region centres, goal; seed 004 §7) in map-frame millimetres.
/// Checks everything first, so it writes nothing to `out` unless it succeeds.
pub fn encode_plan_object<M, P>(
    regions: &Regions<'_, M>,
    plan: &Plan,
    path: &P,
    map_id: u32,
    out: &mut [u8],
) -> Result<usize, ObjectError>
where
    M: IdStore + ?Sized,
    P: IdStore + ?Sized,
{
    let count = plan.waypoint_count();
    let geo = regions.geometry();
    let point = |i: usize| plan.waypoint(regions, path, i).map(|p| mm(geo, p));
    if (0..count).any(|i| point(i).is_none()) {
        return Err(ObjectError {
            offset: PLAN_HEADER_LEN + 16,
            problem: Problem::CountMismatch,
        });
    }
    let meta = PlanMeta {
        smoothed: false,
        map_id,
    };
    let waypoints = (0..count).map(|i| point(i).unwrap_or_default());
    write_plan(plan, path, meta, waypoints, out)
}

/// Encodes a smoothed plan as a Plan object: the raw plan's nav block and the smoothed
/// waypoints (start, `points`, goal) in millimetres, flagged smoothed.
pub fn encode_smoothed_plan_object<P: IdStore + ?Sized>(
    plan: &Plan,
    path: &P,
    smoothed: &Smoothed,
    points: &[GridPoint],
    geometry: Geometry,
    map_id: u32,
    out: &mut [u8],
) -> Result<usize, ObjectError> {
    let count = smoothed.waypoint_count();
    if (0..count).any(|i| smoothed.waypoint(points, i).is_none()) {
        return Err(ObjectError {
            offset: 0,
            problem: Problem::CountMismatch,
        });
    }
    let meta = PlanMeta {
        smoothed: true,
        map_id,
    };
    let waypoints = (0..count).map(|i| {
        let p = smoothed.waypoint(points, i).unwrap_or(smoothed.goal);
        mm(geometry, p)
    });
    write_plan(plan, path, meta, waypoints, out)
}

/// Encodes a plan of the grid planner (`nav::wave`, used when the squares do not fit) as a
/// Plan object: a nav block with no regions and its cost, then the waypoints (start, cell
/// centres, goal) in millimetres, flagged as not region centres. No regions is how a reader
/// tells it from seed 004's plan.
pub fn encode_wave_plan_object<S: AsRef<[u8]>>(
    route: &WaveRoute<'_, S>,
    map_id: u32,
    out: &mut [u8],
) -> Result<usize, ObjectError> {
    let p = route.plan;
    let plan = Plan {
        start: p.start,
        goal: p.goal,
        len: 0,
        cost: p.cost,
    };
    let meta = PlanMeta {
        smoothed: true,
        map_id,
    };
    let geo = route.geometry();
    let no_regions: &[u16] = &[];
    write_plan(
        &plan,
        no_regions,
        meta,
        route.waypoints().map(|q| mm(geo, q)),
        out,
    )
}

/// Checks sizes, then writes the nav block with [`Plan::encode`] and the rest with
/// `finish_plan` (which cannot fail once the sizes are checked).
fn write_plan<P, W>(
    plan: &Plan,
    path: &P,
    meta: PlanMeta,
    waypoints: W,
    out: &mut [u8],
) -> Result<usize, ObjectError>
where
    P: IdStore + ?Sized,
    W: ExactSizeIterator<Item = PointMm>,
{
    let too_many = ObjectError {
        offset: 0,
        problem: Problem::CountMismatch,
    };
    if u16::try_from(waypoints.len()).is_err() || path.len() < plan.len as usize {
        return Err(too_many);
    }
    let needed = plan_object_len(plan.len, waypoints.len()).ok_or(too_many)?;
    let small = ObjectError {
        offset: 0,
        problem: Problem::OutputTooSmall { needed },
    };
    if out.len() < needed {
        return Err(small);
    }
    let nav = out.get_mut(PLAN_HEADER_LEN..).ok_or(small)?;
    let nav_len = plan.encode(path, nav).map_err(|_| small)?;
    finish_plan(out, meta, nav_len, waypoints)
}

fn mm(geo: Geometry, p: GridPoint) -> PointMm {
    let (x_mm, y_mm) = geo.to_mm(p);
    PointMm { x_mm, y_mm }
}

#[cfg(test)]
mod tests;
