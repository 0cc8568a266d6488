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

use std::path::{Path, PathBuf};

use serde_yaml_ng::Value;

use super::error::{read_bytes, read_text, to_u32, unknown_name, ArenaError, Text};
use super::raster::{obstacle_walls, RasterMap};
use super::{pgm, Arena, ArenaFormat, Cell};
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
    let text = read_text(path)?;
    parse(path, &text)
}

/// Parses a map YAML's text (the image is read from disk).
pub fn parse(path: &Path, text: &str) -> Result<Arena, ArenaError> {
    let mut warnings = Vec::new();
    let meta = parse_meta(path, text, &mut warnings)?;
    let bytes = read_bytes(&meta.image)?;
    let img = pgm::decode(&meta.image, &bytes)?;
    if let Some(at) = img.trailing {
        warnings.push(format!(
            "{}: byte {at}: data after the image ignored",
            meta.image.display()
        ));
    }
    let (w, h) = (img.width as usize, img.height as usize);
    let mut cells = vec![Cell::Unknown; w * h];
    for (i, &p) in img.pixels.iter().enumerate() {
        // Image rows run top to bottom; raster rows bottom to top (y up).
        let (row, col) = (h - 1 - i / w, i % w);
        cells[row * w + col] = classify(p, img.maxval, &meta);
    }
    let raster = RasterMap {
        width: img.width,
        height: img.height,
        cell_m: meta.resolution,
        origin: [meta.origin[0], meta.origin[1]],
        cells,
        start: None,
        goal: None,
    };
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
        walls: obstacle_walls(&raster),
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
    let doc: Value = serde_yaml_ng::from_str(text).map_err(|e| {
        let msg = e.to_string();
        let msg = msg.split(" at line ").next().unwrap_or(&msg).to_string();
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
    let err = |key: &str, msg: String| {
        let (line, col) = key_position(t, key);
        ArenaError::at_line(path, line, col, msg)
    };
    for key in map.keys() {
        let Some(k) = key.as_str() else {
            return Err(ArenaError::at_line(
                path,
                1,
                None,
                format!("keys must be strings, found {key:?}"),
            ));
        };
        if !KEYS.contains(&k) {
            let (line, col) = key_position(t, k);
            match unknown_name("key", k, &KEYS) {
                Ok(w) => warnings.push(format!("{}:{line}: {w}", path.display())),
                Err(e) => return Err(ArenaError::at_line(path, line, col, e)),
            }
        }
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
        let (line, _) = key_position(t, "origin");
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
                "image '{image}' not found (looked for {})",
                resolved.display()
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

/// The line (and column) where a top-level key is written, for errors about its value; line 1
/// when it cannot be found (flow-style YAML).
fn key_position(t: Text<'_>, key: &str) -> (u32, Option<u32>) {
    for (i, line) in t.text.lines().enumerate() {
        let body = line.trim_start();
        let indent = line.len() - body.len();
        let body = body.trim_start_matches(['"', '\'']);
        if let Some(rest) = body.strip_prefix(key) {
            if rest
                .trim_start_matches(['"', '\''])
                .trim_start()
                .starts_with(':')
            {
                return (to_u32(i + 1), Some(to_u32(indent + 1)));
            }
        }
    }
    (1, None)
}

fn show(v: &Value) -> String {
    match v {
        Value::Null => "nothing".into(),
        Value::String(s) => format!("'{s}'"),
        other => serde_yaml_ng::to_string(other)
            .map(|s| s.trim().replace('\n', " "))
            .unwrap_or_default(),
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
