//! ROS map_server maps: a YAML file (`image`, `resolution`, `origin: [x, y, yaw]`, `negate`,
//! `occupied_thresh`, `free_thresh`, optional `mode`) naming a PGM image (P5 or P2).
//!
//! Layer: arena importer. Cells are classified exactly as ROS 1 map_server's image loader does
//! (nav2's map_io agrees): with `p` the pixel and `max` the image's maxval,
//! `occ = (max - p) / max` (`p / max` when `negate`); `occ > occupied_thresh` is an obstacle,
//! `occ < free_thresh` is free, anything between is unknown. `mode: scale` differs from
//! `trinary` only in the in-between probabilities (1..99), which a three-state [`Cell`] cannot
//! hold, so both give unknown there. `mode: raw` takes the 8-bit value `v` (after `negate`) as
//! an occupancy percentage: `v > 100` is unknown, else `v / 100` meets the same thresholds.
//! The image's top row is the map's max y; the lower-left pixel's corner is at `origin`.
//! The `image` path is relative to the YAML's folder unless absolute.
//!
//! What can fail (YAML errors at file:line:column, PGM errors at a byte offset or line:column of
//! the image): YAML syntax, a root that is not a mapping, a missing or mistyped key, a
//! non-finite or out-of-range number, free_thresh >= occupied_thresh, a misspelt key
//! (`resoluton`), an image file that does not exist or is not a PGM, and every PGM defect.
//! A non-zero origin yaw is ignored with a warning, as map_server does.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use serde_yaml_ng::Value;

use super::error::{
    excerpt, excerpt_n, read_bytes, read_head, read_text, to_u32, unknown_name, ArenaError, Text,
};
use super::raster::{obstacle_walls_within, RasterMap};
use super::{pgm, Arena, ArenaFormat, Cell, GridLimit, LoadOptions};
use crate::geometry::{Aabb, Point};

/// How pixel values map to occupancy (map_server's `mode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum MapMode {
    /// Occupied / free / unknown by the two thresholds (the default).
    #[default]
    Trinary,
    /// As trinary, but in-between values are probabilities (unknown here).
    Scale,
    /// Pixel values are occupancy percentages.
    Raw,
}

/// The settings of a map YAML.
#[derive(Clone, Debug, PartialEq)]
pub struct MapMeta {
    /// The image file, resolved against the YAML's folder.
    pub image: PathBuf,
    /// Metres per pixel.
    pub resolution: f64,
    /// The lower-left pixel's corner in the map frame, and a yaw (ignored).
    pub origin: [f64; 3],
    /// True when white means occupied.
    pub negate: bool,
    /// Occupancy probability above which a cell is an obstacle.
    pub occupied_thresh: f64,
    /// Occupancy probability below which a cell is free.
    pub free_thresh: f64,
    /// Pixel interpretation.
    pub mode: MapMode,
}

/// Deepest nesting of YAML collections accepted: a map YAML needs 1 (`origin`); the YAML
/// parser's cost grows with depth times length (100,000 nested `[` took minutes), so deeper
/// files are refused before they reach it.
pub const MAX_YAML_DEPTH: usize = 32;

/// Largest map YAML read: map_server's are a few hundred bytes, and the YAML library holds
/// about 70 bytes of events and values per byte of a dense list, so this bounds its memory.
pub const MAX_YAML_BYTES: usize = 4 << 20;

/// Unknown keys warned about one by one; the rest are counted in one line.
const MAX_KEY_WARNINGS: usize = 8;

const KEYS: [&str; 7] = [
    "image",
    "resolution",
    "origin",
    "negate",
    "occupied_thresh",
    "free_thresh",
    "mode",
];

/// Loads a map YAML and its image.
pub fn load(path: &Path) -> Result<Arena, ArenaError> {
    load_with(path, &LoadOptions::default())
}

/// Loads a map YAML and its image, refusing from the image's header (before its pixels are
/// read) a map larger than `opts.grid_limit`, and before its walls are built one that would
/// make more walls than `opts.world_limit` takes.
pub fn load_with(path: &Path, opts: &LoadOptions) -> Result<Arena, ArenaError> {
    let text = read_text(path)?;
    parse_with(path, &text, opts)
}

/// Parses a map YAML's text (the image is read from disk).
pub fn parse(path: &Path, text: &str) -> Result<Arena, ArenaError> {
    parse_with(path, text, &LoadOptions::default())
}

/// [`parse`] with a caller's limits (see [`load_with`]).
pub fn parse_with(path: &Path, text: &str, opts: &LoadOptions) -> Result<Arena, ArenaError> {
    let limit = opts.grid_limit;
    let mut warnings = Vec::new();
    let meta = parse_meta(path, text, &mut warnings)?;
    // The header from the file's first bytes; if it does not fit in them, the full decode
    // below reports whatever is wrong with it.
    let head = read_head(&meta.image, HEADER_BYTES)?;
    if let Ok(h) = pgm::header(&meta.image, &head) {
        // The message names the YAML too: it is the file the user gave.
        check_limit(&meta, h.width, h.height, limit).map_err(|e| match e {
            ArenaError::Invalid { at, message } => ArenaError::Invalid {
                at,
                message: format!("{message} (the image of {})", path.display()),
            },
            e => e,
        })?;
    }
    let bytes = read_bytes(&meta.image)?;
    let (raster, trailing) = raster_from_pgm(&meta, &bytes, limit)?;
    drop(bytes);
    if let Some(at) = trailing {
        warnings.push(format!(
            "{}: byte {at}: data after the image ignored",
            meta.image.display()
        ));
    }
    let (w, h) = (raster.width as usize, raster.height as usize);
    let bounds = Aabb {
        min: Point::new(meta.origin[0], meta.origin[1]),
        max: Point::new(
            meta.origin[0] + w as f64 * meta.resolution,
            meta.origin[1] + h as f64 * meta.resolution,
        ),
    };
    Ok(Arena {
        name: path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        source: path.to_path_buf(),
        format: ArenaFormat::RosMap,
        bounds,
        enclosed: false,
        walls: obstacle_walls_within(path, &raster, opts.world_limit)?,
        raster: Some(raster),
        beacons: Vec::new(),
        targets: Vec::new(),
        lights: Vec::new(),
        starts: Vec::new(),
        goal: None,
        unit_m: meta.resolution,
        warnings,
    })
}

/// The occupancy grid of a map's PGM (`meta.image` names it in errors), one byte a cell,
/// refused from its header when beyond `limit`; also the offset of data after the image.
pub fn raster_from_pgm(
    meta: &MapMeta,
    bytes: &[u8],
    limit: Option<GridLimit>,
) -> Result<(RasterMap, Option<usize>), ArenaError> {
    let hdr = pgm::header(&meta.image, bytes)?;
    check_limit(meta, hdr.width, hdr.height, limit)?;
    if !hdr.fits(bytes.len()) {
        // Too short for its header's size: decoding without storing finds the fault.
        pgm::decode(&meta.image, bytes, |_, _| {})?;
    }
    let (w, h) = (hdr.width as usize, hdr.height as usize);
    // Each pixel value classified once (at most 65,536 of them).
    let table: Vec<Cell> = (0..=hdr.maxval)
        .map(|p| classify(p, hdr.maxval, meta))
        .collect();
    let mut cells = vec![Cell::Unknown; w * h];
    let img = pgm::decode(&meta.image, bytes, |i, p| {
        // Image rows run top to bottom; raster rows bottom to top (y up).
        let (row, col) = (h - 1 - i / w, i % w);
        if let (Some(c), Some(&v)) = (cells.get_mut(row * w + col), table.get(usize::from(p))) {
            *c = v;
        }
    })?;
    let raster = RasterMap {
        width: hdr.width,
        height: hdr.height,
        cell_m: meta.resolution,
        origin: [meta.origin[0], meta.origin[1]],
        cells,
        start: None,
        goal: None,
    };
    Ok((raster, img.trailing))
}

/// Bytes read for an image's header before the whole image: its magic and three numbers, with
/// room for comments.
const HEADER_BYTES: u64 = 4096;

/// Refuses a `width` x `height` image that `limit` will refuse anyway, naming the sizes.
fn check_limit(
    meta: &MapMeta,
    width: u32,
    height: u32,
    limit: Option<GridLimit>,
) -> Result<(), ArenaError> {
    let Some(l) = limit else { return Ok(()) };
    let (wm, hm) = (
        f64::from(width) * meta.resolution,
        f64::from(height) * meta.resolution,
    );
    let cells = |m: f64| (m / l.cell_m - 1e-9).ceil().max(1.0);
    let (cw, ch) = (cells(wm), cells(hm));
    let max = f64::from(l.max_side);
    if cw <= max && ch <= max {
        return Ok(());
    }
    let coarser = (wm.max(hm) / max * 1000.0).ceil() / 1000.0;
    Err(ArenaError::at_file(
        &meta.image,
        format!(
            "a {width} x {height} image at {} m/pixel is {wm:.1} x {hm:.1} m: {cw} x {ch} cells \
             of {} m, beyond the {max} cells a side {} takes (refused before reading the \
             pixels); use cells of at least {coarser} m",
            meta.resolution, l.cell_m, l.who
        ),
    ))
}

/// One pixel's cell, by map_server's rules (see the module doc).
pub fn classify(pixel: u16, maxval: u16, meta: &MapMeta) -> Cell {
    let (p, max) = (f64::from(pixel), f64::from(maxval.max(1)));
    let occ = match meta.mode {
        MapMode::Trinary | MapMode::Scale => {
            if meta.negate {
                p / max
            } else {
                (max - p) / max
            }
        }
        MapMode::Raw => {
            let v = (p * 255.0 / max).round();
            let v = if meta.negate { 255.0 - v } else { v };
            if v > 100.0 {
                return Cell::Unknown;
            }
            v / 100.0
        }
    };
    if occ > meta.occupied_thresh {
        Cell::Obstacle
    } else if occ < meta.free_thresh {
        Cell::Free
    } else {
        Cell::Unknown
    }
}

/// Parses and checks a map YAML's settings.
pub fn parse_meta(
    path: &Path,
    text: &str,
    warnings: &mut Vec<String>,
) -> Result<MapMeta, ArenaError> {
    let t = Text { path, text };
    if text.len() > MAX_YAML_BYTES {
        return Err(ArenaError::at_file(
            path,
            format!(
                "map YAML is {} bytes; map_server YAMLs are a few hundred (limit {MAX_YAML_BYTES})",
                text.len()
            ),
        ));
    }
    if let Some(at) = too_deep(text, MAX_YAML_DEPTH) {
        return Err(t.err_at(
            at,
            format!("YAML nested deeper than {MAX_YAML_DEPTH} levels; a map YAML needs 1"),
        ));
    }
    let doc: Value = serde_yaml_ng::from_str(text).map_err(|e| {
        let msg = e.to_string();
        let msg = excerpt_n_bytes(msg.split(" at line ").next().unwrap_or(&msg));
        match e.location() {
            Some(l) => ArenaError::at_line(
                path,
                to_u32(l.line()),
                Some(to_u32(l.column())),
                format!("YAML: {msg}"),
            ),
            None => ArenaError::at_file(path, format!("YAML: {msg}")),
        }
    })?;
    let Value::Mapping(map) = doc else {
        return Err(ArenaError::at_line(
            path,
            1,
            None,
            format!(
                "expected a mapping of map_server keys ({})",
                KEYS.join(", ")
            ),
        ));
    };
    // One pass over the text for every key's position: looking each up anew was quadratic
    // in the number of keys (60,000 unknown keys took a minute).
    let positions = key_positions(text);
    let key_position = |key: &str| positions.get(key).copied().unwrap_or((1, None));
    let err = |key: &str, msg: String| {
        let (line, col) = key_position(key);
        ArenaError::at_line(path, line, col, msg)
    };
    let mut unknown = 0usize;
    for key in map.keys() {
        let Some(k) = key.as_str() else {
            return Err(ArenaError::at_line(
                path,
                1,
                None,
                format!("keys must be strings, found {}", show(key)),
            ));
        };
        if !KEYS.contains(&k) {
            let (line, col) = key_position(k);
            match unknown_name("key", k, &KEYS) {
                Ok(w) => {
                    unknown += 1;
                    if unknown <= MAX_KEY_WARNINGS {
                        warnings.push(format!("{}:{line}: {w}", path.display()));
                    }
                }
                Err(e) => return Err(ArenaError::at_line(path, line, col, e)),
            }
        }
    }
    if unknown > MAX_KEY_WARNINGS {
        warnings.push(format!(
            "{}: {} more unknown keys ignored",
            path.display(),
            unknown - MAX_KEY_WARNINGS
        ));
    }
    let get = |key: &str| {
        map.get(key)
            .ok_or_else(|| ArenaError::at_file(path, format!("missing key '{key}'")))
    };
    let number = |key: &str, v: &Value| match v.as_f64() {
        Some(x) if x.is_finite() => Ok(x),
        Some(x) => Err(err(key, format!("{key} {x} is not a finite number"))),
        None => Err(err(
            key,
            format!("{key} must be a number, found {}", show(v)),
        )),
    };
    let image = match get("image")? {
        Value::String(s) if !s.trim().is_empty() => s.trim().to_string(),
        v => {
            return Err(err(
                "image",
                format!("image must be a file name, found {}", show(v)),
            ))
        }
    };
    let resolution = number("resolution", get("resolution")?)?;
    if !(resolution > 0.0 && resolution <= 1000.0) {
        return Err(err(
            "resolution",
            format!("resolution {resolution} m/pixel must be > 0 and <= 1000"),
        ));
    }
    let origin = match get("origin")? {
        Value::Sequence(s) if s.len() == 3 => {
            let mut o = [0.0; 3];
            for (slot, v) in o.iter_mut().zip(s) {
                *slot = number("origin", v)?;
            }
            if o.iter().any(|v| v.abs() > 1e7) {
                return Err(err(
                    "origin",
                    format!("origin {o:?} is absurd (beyond 1e7 m)"),
                ));
            }
            o
        }
        v => {
            return Err(err(
                "origin",
                format!("origin must be [x, y, yaw], found {}", show(v)),
            ))
        }
    };
    if origin[2] != 0.0 {
        let (line, _) = key_position("origin");
        warnings.push(format!(
            "{}:{line}: origin yaw {} ignored (map_server ignores it too)",
            path.display(),
            origin[2]
        ));
    }
    let negate = match get("negate")? {
        Value::Bool(b) => *b,
        v if v.as_i64() == Some(0) => false,
        v if v.as_i64() == Some(1) => true,
        v => {
            return Err(err(
                "negate",
                format!("negate must be 0, 1, true or false, found {}", show(v)),
            ))
        }
    };
    let occupied_thresh = number("occupied_thresh", get("occupied_thresh")?)?;
    let free_thresh = number("free_thresh", get("free_thresh")?)?;
    for (k, v) in [
        ("occupied_thresh", occupied_thresh),
        ("free_thresh", free_thresh),
    ] {
        if !(0.0..=1.0).contains(&v) {
            return Err(err(k, format!("{k} {v} must be between 0 and 1")));
        }
    }
    if free_thresh >= occupied_thresh {
        return Err(err(
            "free_thresh",
            format!("free_thresh {free_thresh} must be below occupied_thresh {occupied_thresh}"),
        ));
    }
    let mode = match map.get("mode") {
        None => MapMode::Trinary,
        Some(Value::String(s)) if s == "trinary" => MapMode::Trinary,
        Some(Value::String(s)) if s == "scale" => MapMode::Scale,
        Some(Value::String(s)) if s == "raw" => MapMode::Raw,
        Some(v) => {
            return Err(err(
                "mode",
                format!("mode must be trinary, scale or raw, found {}", show(v)),
            ))
        }
    };
    let image_path = Path::new(&image);
    let resolved = if image_path.is_absolute() {
        image_path.to_path_buf()
    } else {
        path.parent().unwrap_or(Path::new("")).join(image_path)
    };
    if !resolved.is_file() {
        return Err(err(
            "image",
            format!(
                "image '{}' not found (looked for {})",
                excerpt(&image),
                excerpt(&resolved.display().to_string())
            ),
        ));
    }
    Ok(MapMeta {
        image: resolved,
        resolution,
        origin,
        negate,
        occupied_thresh,
        free_thresh,
        mode,
    })
}

/// The line (and column) where each key is first written (`key:` at the start of a line,
/// optionally quoted), for errors about its value; keys not found this way (flow-style YAML)
/// are reported at line 1. One pass over the text.
fn key_positions(text: &str) -> HashMap<&str, (u32, Option<u32>)> {
    let mut out = HashMap::new();
    for (i, line) in text.lines().enumerate() {
        let body = line.trim_start();
        let indent = line.len() - body.len();
        let body = body.trim_start_matches(['"', '\'']);
        let Some(colon) = body.find(':') else {
            continue;
        };
        let key = body[..colon].trim_end().trim_end_matches(['"', '\'']);
        if !key.is_empty() {
            out.entry(key)
                .or_insert((to_u32(i + 1), Some(to_u32(indent + 1))));
        }
    }
    out
}

/// The byte offset where YAML collections nest deeper than `max` (flow `[`/`{`, and block
/// sequences opened on one line, `- - - x`), if they do. A linear scan that skips quoted
/// scalars and comments; brackets inside plain scalars (`a[1].pgm`) count too, which can only
/// refuse a file with more than `max` of them unclosed.
fn too_deep(text: &str, max: usize) -> Option<usize> {
    let bytes = text.as_bytes();
    let mut depth = 0usize;
    let mut i = 0;
    let mut line_start = true;
    let mut block = 0usize;
    let mut prev = b'\n';
    while let Some(&b) = bytes.get(i) {
        match b {
            b'\n' => {
                line_start = true;
                block = 0;
            }
            b'#' if prev.is_ascii_whitespace() => {
                while bytes.get(i).is_some_and(|&c| c != b'\n') {
                    i += 1;
                }
                continue;
            }
            b'\'' | b'"'
                if matches!(
                    prev,
                    b' ' | b'\t' | b'\n' | b'[' | b'{' | b',' | b':' | b'-'
                ) =>
            {
                // A quoted scalar: skip to its closing quote ('' and \" escape one).
                i += 1;
                while let Some(&c) = bytes.get(i) {
                    if b == b'"' && c == b'\\' {
                        i += 2;
                        continue;
                    }
                    if c == b {
                        if b == b'\'' && bytes.get(i + 1) == Some(&b'\'') {
                            i += 2;
                            continue;
                        }
                        break;
                    }
                    i += 1;
                }
                line_start = false;
            }
            b'[' | b'{' => {
                depth += 1;
                line_start = false;
            }
            b']' | b'}' => {
                depth = depth.saturating_sub(1);
                line_start = false;
            }
            b'-' if line_start && matches!(bytes.get(i + 1), Some(b' ' | b'\t')) => block += 1,
            b' ' | b'\t' => {}
            _ => line_start = false,
        }
        if depth + block > max {
            return Some(i);
        }
        prev = bytes.get(i).copied().unwrap_or(b'\n');
        i += 1;
    }
    None
}

/// A YAML library message, cut and escaped like every quote of file content (it may quote a
/// key or scalar).
fn excerpt_n_bytes(msg: &str) -> String {
    excerpt_n(msg, 160)
}

/// A value for an error message: its kind and size for collections (a two-million-element
/// `origin` was once echoed whole), an excerpt for scalars.
fn show(v: &Value) -> String {
    match v {
        Value::Null => "nothing".into(),
        Value::String(s) => format!("'{}'", excerpt(s)),
        Value::Sequence(s) => format!("a list of {} items", s.len()),
        Value::Mapping(m) => format!("a mapping of {} keys", m.len()),
        Value::Tagged(t) => format!("a value tagged {}", excerpt(&t.tag.to_string())),
        other => excerpt(
            &serde_yaml_ng::to_string(other)
                .map(|s| s.trim().replace('\n', " "))
                .unwrap_or_default(),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn meta(negate: bool, mode: MapMode) -> MapMeta {
        MapMeta {
            image: PathBuf::new(),
            resolution: 0.05,
            origin: [0.0; 3],
            negate,
            occupied_thresh: 0.65,
            free_thresh: 0.196,
            mode,
        }
    }

    #[test]
    fn pixels_classify_as_map_server_does() {
        let m = meta(false, MapMode::Trinary);
        assert_eq!(classify(0, 255, &m), Cell::Obstacle);
        assert_eq!(classify(254, 255, &m), Cell::Free);
        assert_eq!(classify(205, 255, &m), Cell::Unknown); // the usual unknown grey
                                                           // occ = (255 - 89) / 255 = 0.651 > 0.65; occ(90) = 0.647 is not.
        assert_eq!(classify(89, 255, &m), Cell::Obstacle);
        assert_eq!(classify(90, 255, &m), Cell::Unknown);
        // occ(205) = 0.196078 is not below 0.196; occ(206) = 0.19215 is.
        assert_eq!(classify(206, 255, &m), Cell::Free);
        let n = meta(true, MapMode::Trinary);
        assert_eq!(classify(255, 255, &n), Cell::Obstacle);
        assert_eq!(classify(0, 255, &n), Cell::Free);
    }

    #[test]
    fn raw_mode_reads_percentages() {
        let m = meta(false, MapMode::Raw);
        assert_eq!(classify(0, 255, &m), Cell::Free);
        assert_eq!(classify(100, 255, &m), Cell::Obstacle);
        assert_eq!(classify(50, 255, &m), Cell::Unknown);
        assert_eq!(classify(255, 255, &m), Cell::Unknown);
    }
}
