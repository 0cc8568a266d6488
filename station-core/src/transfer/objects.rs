//! Objects from the station's planner, checked before they travel, and written safely.
//!
//! Layer: std glue between `plan` (the station's [`NavMap`] and [`Planner`]) and the object
//! encoders the robot uses (`robot_firmware::transfer::encode_map_object`,
//! `encode_plan_object`), so the station and the robot make the same bytes, hence the same
//! ids, from the same grid. Conventions:
//! - a map file becomes a Map object whose start is the map's start marker and whose goal is
//!   the planner's default goal (the marker, or the free point of the goal area nearest it,
//!   PROTOCOL.md §12 and `plan::map`): so `Plan` on the robot with no `to` plans to the same
//!   goal as `station plan`;
//! - a plan's `map_id` is the id of that Map object, so a plan made here for an uploaded map
//!   names it exactly as the robot's own plan would.
//!
//! What can fail: a file that cannot be read or is neither an object nor a map
//! ([`ObjectFileError`]), a map larger than the robot holds ([`CapacityError`]), an object
//! that cannot be encoded (`ObjectError`), an I/O error writing a file.

use std::path::{Path, PathBuf};

use protocol::object::{
    kind_of, parse, plan_object_len, MapView, ObjectError, PlanView, MAP_HEADER_LEN, OBJECT_VERSION,
};
use protocol::{crc32c, MapCapacity, ObjectKind, PointMm};
use robot_firmware::nav::grid_bytes;
use robot_firmware::transfer::{encode_map_object, encode_plan_object};

use super::object_name;
use crate::input_file::{InputError, InputKind};
use crate::plan::{MapOptions, NavError, NavMap, PlanResult, Planner};

/// What a file given to `upload-map --map` may be (`input_file`'s rule): an object, a light
/// calibration or any arena file, so the arena files' limit.
pub const MAP_FILE: InputKind = InputKind {
    what: "map files",
    max_bytes: emulator::arena::MAX_FILE_BYTES,
    pipes: false,
};

/// What an object file (`upload-plan --plan`) may be: a 2048 x 2048 Map object, the largest
/// the station makes, is 1 MiB; a robot holds a few KB.
pub const OBJECT_FILE: InputKind = InputKind {
    what: "object files",
    max_bytes: 16 << 20,
    pipes: false,
};

/// A Map object built from a [`NavMap`].
#[derive(Clone, Debug, PartialEq)]
pub struct MapObject {
    pub bytes: Vec<u8>,
    /// CRC-32C of the bytes: the id it travels under.
    pub id: u32,
    pub width: u16,
    pub height: u16,
    pub cell_mm: u32,
    pub start: Option<PointMm>,
    pub goal: Option<PointMm>,
}

/// A map the robot cannot hold.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error(
    "the map is {width} x {height} cells of {cell_m} m; the robot holds at most {cap_w} x \
     {cap_h} cells: use --cell {suggest_m} or larger, or a smaller map"
)]
pub struct CapacityError {
    pub width: u16,
    pub height: u16,
    pub cell_m: f64,
    pub cap_w: u16,
    pub cap_h: u16,
    pub suggest_m: f64,
}

/// Why a file cannot be uploaded.
#[derive(Debug, thiserror::Error)]
pub enum ObjectFileError {
    #[error(transparent)]
    Input(#[from] InputError),
    #[error("{path} is a {found} object, not a {expected} object")]
    WrongKind {
        path: PathBuf,
        found: &'static str,
        expected: &'static str,
    },
    #[error("{path} is not a valid object: {source}")]
    Object { path: PathBuf, source: ObjectError },
    #[error("{0}")]
    Map(#[from] NavError),
    /// A map file that loads but cannot be gridded (a load error names the file itself).
    #[error("{path}: {source}")]
    MapFile { path: String, source: NavError },
    #[error("cannot encode the object: {0}")]
    Encode(ObjectError),
    #[error("the planner holds no segmentation for this map")]
    NotSegmented,
    #[error(
        "regions cannot be uploaded: the robot segments its own map (send `segment` or `plan`)"
    )]
    Regions,
    /// A light calibration file that cannot be read (the message names the file).
    #[error("{0}")]
    Calibration(String),
}

fn mm((x_mm, y_mm): (i32, i32)) -> PointMm {
    PointMm { x_mm, y_mm }
}

/// The Map object of `map` (see the module notes for its start and goal).
pub fn map_object(map: &NavMap) -> Result<MapObject, ObjectFileError> {
    let start = map.resolve_start(None).ok().map(|e| mm(e.mm));
    let goal = map.resolve_goal(None).ok().map(|e| mm(e.mm));
    let (w, h) = (map.grid.width(), map.grid.height());
    let mut bytes = vec![0u8; MAP_HEADER_LEN + grid_bytes(w.into(), h.into())];
    let n =
        encode_map_object(&map.grid, start, goal, &mut bytes).map_err(ObjectFileError::Encode)?;
    bytes.truncate(n);
    Ok(MapObject {
        id: crc32c(&bytes),
        width: w,
        height: h,
        cell_mm: map.grid.geometry().cell_mm(),
        start,
        goal,
        bytes,
    })
}

/// Refuses a map larger than `cap`, suggesting the cell size that would fit.
pub fn check_capacity(
    width: u16,
    height: u16,
    cell_mm: u32,
    cap: MapCapacity,
) -> Result<(), CapacityError> {
    if width <= cap.width && height <= cap.height {
        return Ok(());
    }
    let cell_m = f64::from(cell_mm) / 1000.0;
    let ratio = (f64::from(width) / f64::from(cap.width.max(1)))
        .max(f64::from(height) / f64::from(cap.height.max(1)));
    // Whole centimetres, rounded up, plus one: the raster's edge cells need a little room.
    let suggest_m = ((cell_m * ratio * 100.0).ceil() + 1.0) / 100.0;
    Err(CapacityError {
        width,
        height,
        cell_m,
        cap_w: cap.width,
        cap_h: cap.height,
        suggest_m,
    })
}

/// The Plan object of a plan made by `planner` on its map, naming the map by `map_id`.
pub fn plan_object(
    planner: &Planner,
    r: &PlanResult,
    map_id: u32,
) -> Result<Vec<u8>, ObjectFileError> {
    let regions = planner.regions().ok_or(ObjectFileError::NotSegmented)?;
    let n = plan_object_len(r.plan.len, r.plan.waypoint_count())
        .ok_or(ObjectFileError::NotSegmented)?;
    let mut out = vec![0u8; n];
    let k = encode_plan_object(&regions, &r.plan, &r.path[..], map_id, &mut out)
        .map_err(ObjectFileError::Encode)?;
    out.truncate(k);
    Ok(out)
}

/// What a file holds, ready to upload.
#[derive(Clone, Debug, PartialEq)]
pub struct Loaded {
    pub object: ObjectKind,
    pub bytes: Vec<u8>,
    /// The map's size when it was built from a map file (for the capacity check).
    pub map: Option<MapObject>,
    /// One line saying what it is.
    pub summary: String,
}

/// Loads `path` for upload: an object file (`station download-map --out`, `station plan
/// --out-object`) is taken as it is, after `protocol::object::parse` accepts it; anything
/// else is read as a map (any arena format `station plan` reads, or builtin:micro-rato-99)
/// and encoded with `opts`.
pub fn load_for_upload(path: &str, opts: &MapOptions) -> Result<Loaded, ObjectFileError> {
    // One read serves the object and calibration checks; arena files are parsed by path.
    let file = Path::new(path);
    // Not a regular file (a `builtin:` name, a device): never read here.
    let bytes = if file.is_file() {
        crate::input_file::read(file, &MAP_FILE)?
    } else {
        Vec::new()
    };
    if let Some(loaded) = load_calibration_file(file, &bytes)? {
        return Ok(loaded);
    }
    if is_object_file(file, &bytes)? {
        let object = kind_of(&bytes).map_err(|source| ObjectFileError::Object {
            path: path.into(),
            source,
        })?;
        if object == ObjectKind::Regions {
            return Err(ObjectFileError::Regions);
        }
        let summary = format!(
            "{} object {path}, {} bytes, id {:#010x}",
            object_name(object),
            bytes.len(),
            crc32c(&bytes)
        );
        let map = match object {
            ObjectKind::Map => MapView::parse(&bytes).ok().map(|v| MapObject {
                id: crc32c(&bytes),
                width: v.header.width,
                height: v.header.height,
                cell_mm: v.header.cell_mm,
                start: v.header.start,
                goal: v.header.goal,
                bytes: bytes.clone(),
            }),
            _ => None,
        };
        return Ok(Loaded {
            object,
            bytes,
            map,
            summary,
        });
    }
    let map = NavMap::load(path, opts).map_err(|e| match e {
        NavError::Load(_) => ObjectFileError::Map(e),
        source => ObjectFileError::MapFile {
            path: path.to_string(),
            source,
        },
    })?;
    let m = map_object(&map)?;
    let summary = format!(
        "map {} ({} x {} cells of {} m), {} bytes, id {:#010x}",
        map.name,
        m.width,
        m.height,
        f64::from(m.cell_mm) / 1000.0,
        m.bytes.len(),
        m.id
    );
    Ok(Loaded {
        object: ObjectKind::Map,
        bytes: m.bytes.clone(),
        map: Some(m),
        summary,
    })
}

/// Whether `bytes` (of `path`) look like an object (format version, then a kind); one that
/// does must pass `protocol::object::parse`, or the error names the byte.
fn is_object_file(path: &Path, bytes: &[u8]) -> Result<bool, ObjectFileError> {
    let looks = bytes.first() == Some(&OBJECT_VERSION) && bytes.get(1).is_some_and(|k| *k <= 3);
    if !looks {
        return Ok(false);
    }
    parse(bytes).map_err(|source| ObjectFileError::Object {
        path: path.into(),
        source,
    })?;
    Ok(true)
}

/// A light calibration in `station calibrate`'s file formats (binary "LSOM", or JSON naming
/// its format), as the LightCalibration object the robot takes; `None` for any other file.
fn load_calibration_file(path: &Path, bytes: &[u8]) -> Result<Option<Loaded>, ObjectFileError> {
    let json_form = bytes.first() == Some(&b'{')
        && std::str::from_utf8(bytes).is_ok_and(|t| t.contains("\"robot-station light-som\""));
    if !bytes.starts_with(b"LSOM") && !json_form {
        return Ok(None);
    }
    let object = crate::calibrate::decode_named(path, bytes)
        .and_then(|som| crate::calibrate::light_object(&som))
        .map_err(|e| ObjectFileError::Calibration(format!("{e:#}")))?;
    let summary = format!(
        "light calibration {}, {} bytes, id {:#010x}",
        path.display(),
        object.len(),
        crc32c(&object)
    );
    Ok(Some(Loaded {
        object: ObjectKind::LightCalibration,
        bytes: object,
        map: None,
        summary,
    }))
}

/// Reads a Plan object file, refusing anything else with the byte offset of the problem.
pub fn read_plan_file(path: &Path) -> Result<Vec<u8>, ObjectFileError> {
    let bytes = crate::input_file::read(path, &OBJECT_FILE)?;
    let bad = |source| ObjectFileError::Object {
        path: path.into(),
        source,
    };
    match kind_of(&bytes).map_err(bad)? {
        ObjectKind::Plan => {}
        other => {
            return Err(ObjectFileError::WrongKind {
                path: path.into(),
                found: object_name(other),
                expected: "plan",
            })
        }
    }
    PlanView::parse(&bytes).map_err(bad)?;
    Ok(bytes)
}

/// A Map object drawn as text, top row (largest y) first: `#` obstacle, `.` free, `?`
/// unknown, `S` and `G` the start and goal cells.
pub fn map_ascii(bytes: &[u8]) -> Result<Vec<String>, ObjectError> {
    let v = MapView::parse(bytes)?;
    let h = v.header;
    let cell = |p: Option<PointMm>| {
        p.and_then(|p| {
            let c = i64::from(h.cell_mm);
            let x = (i64::from(p.x_mm) - i64::from(h.origin.x_mm)).div_euclid(c);
            let y = (i64::from(p.y_mm) - i64::from(h.origin.y_mm)).div_euclid(c);
            Some((u16::try_from(x).ok()?, u16::try_from(y).ok()?))
        })
    };
    let (start, goal) = (cell(h.start), cell(h.goal));
    Ok((0..h.height)
        .rev()
        .map(|y| {
            (0..h.width)
                .map(|x| match (Some((x, y)) == start, Some((x, y)) == goal) {
                    (_, true) => 'G',
                    (true, _) => 'S',
                    _ => match v.cell(x, y) {
                        Some(1) => '.',
                        Some(2) => '#',
                        _ => '?',
                    },
                })
                .collect()
        })
        .collect())
}

/// A Plan object's waypoints in metres.
pub fn plan_waypoints(bytes: &[u8]) -> Result<Vec<(f64, f64)>, ObjectError> {
    let v = PlanView::parse(bytes)?;
    Ok(v.waypoints()
        .map(|p| (f64::from(p.x_mm) / 1000.0, f64::from(p.y_mm) / 1000.0))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_builtin_arena_becomes_a_map_object_that_fits_the_robot_and_draws() {
        let map = NavMap::load(emulator::builtin::MICRO_RATO_99, &MapOptions::default())
            .expect("built in");
        let m = map_object(&map).expect("encodes");
        assert_eq!(m.id, crc32c(&m.bytes));
        let cap = MapCapacity {
            width: 64,
            height: 64,
        };
        assert_eq!(check_capacity(m.width, m.height, m.cell_mm, cap), Ok(()));
        assert!(m.start.is_some() && m.goal.is_some());
        let art = map_ascii(&m.bytes).expect("parses");
        assert_eq!(art.len(), usize::from(m.height));
        let text = art.concat();
        assert_eq!(text.matches('S').count(), 1, "{art:?}");
        assert_eq!(text.matches('G').count(), 1, "{art:?}");
        assert!(text.contains('#') && text.contains('.'));
    }

    #[test]
    fn a_map_too_large_for_the_robot_is_refused_with_a_cell_size_that_fits() {
        let cap = MapCapacity {
            width: 64,
            height: 64,
        };
        let e = check_capacity(100, 40, 100, cap).expect_err("too wide");
        assert!(e.to_string().contains("at most 64 x 64"), "{e}");
        // 100 cells of 0.1 m = 10 m; 64 cells need 0.157 m: 0.16 m plus a centimetre.
        assert_eq!(e.suggest_m, 0.17);
    }

    #[test]
    fn calibration_files_in_either_form_upload_as_one_light_calibration_object() {
        let dir = std::env::temp_dir().join(format!("station-cal-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let som = robot_firmware::som::LightSom::random(
            &mut robot_firmware::behaviour::XorShift32::new(3),
            (50.0, 500.0),
            (0.0, 180.0),
        );
        let bin = dir.join("som.bin");
        std::fs::write(&bin, crate::calibrate::encode_bin(&som)).expect("writes");
        let json = dir.join("som.json");
        let text = crate::calibrate::encode_json(&som, None).expect("encodes");
        std::fs::write(&json, text).expect("writes");
        let load = |p: &Path| load_for_upload(&p.display().to_string(), &MapOptions::default());
        let (a, b) = (load(&bin).expect("binary"), load(&json).expect("JSON"));
        assert_eq!(a.object, ObjectKind::LightCalibration);
        assert_eq!((b.object, &b.bytes), (a.object, &a.bytes));
        assert_eq!(
            crate::calibrate::from_light_object(&a.bytes).expect("parses"),
            som
        );
        // A damaged one is refused naming the file, not taken for a map.
        let mut bytes = std::fs::read(&bin).expect("reads");
        bytes[12] ^= 1;
        std::fs::write(&bin, bytes).expect("writes");
        let Err(e) = load(&bin) else {
            panic!("a damaged calibration was taken");
        };
        let e = e.to_string();
        assert!(e.contains("som.bin") && e.contains("CRC mismatch"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
