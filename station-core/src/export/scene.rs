//! What Foxglove's 3D panel needs beside the poses: the map, the robot's regions and plan, the
//! arena's walls and the frame transforms, plus the sensors the robot lacks marked null.
//!
//! Layer: state carried along `export::walk` by `mcap::write`, one `Scene::extend` call per
//! item, adding messages to those the item already became (the per-record loop stays as it
//! is). Channels (Foxglove's own schemas, JSON encoding):
//! - `/tf` `foxglove.FrameTransform`: `map` -> `base_link` (believed pose, each telemetry
//!   frame) and `map` -> `truth` (the emulator's true pose);
//! - `/map` `foxglove.Grid` in frame `map`: each Map object that crossed the link (upload or
//!   download) once it is complete and its CRC-32C checks; one INT8 field `occupancy`
//!   (0 free, 100 obstacle, -1 unknown, as ROS's OccupancyGrid);
//! - `/regions`, `/plan` `foxglove.SceneUpdate`: the squares of a Regions object (placed on
//!   the last map) as line loops, a Plan's waypoints as a line strip (entity `plan`); on
//!   `/plan` too, the point of each go-to the robot accepted (`goal`) and the target of each
//!   plan request it accepted (`plan_target`), as labelled markers;
//! - `/arena` `foxglove.SceneUpdate`: the recording's arena (`Meta::arena`) at the start, when
//!   its file or built-in name can be loaded: its walls (`arena`), target areas as circles
//!   (`targets`), its goal point (`arena_goal`); and the beacon (`beacon`) where the arena puts
//!   it, moved again whenever the robot reports `beacon_x_m` or `beacon_y_m` (an Ack of a
//!   parameter read or write), so a recording without an arena shows it too once both are
//!   known.
//!
//! Invariants: an object is published only whole and verified (a torn or corrupted transfer
//! publishes nothing); memory is bounded by `MAX_OBJECT` per object in flight and
//! `MAX_IN_FLIGHT` objects.

use std::collections::BTreeMap;

use protocol::object::{MapView, PlanView, RegionsView};
use protocol::{caps, AckInfo, Command, Message, ObjectKind};
use robot_firmware::params;
use serde_json::{json, Value};

use super::mcap_msg::{Body, FrameTransform};
use super::{Direction, Item};
use crate::record::Recording;

/// Largest object reassembled, bytes: the largest a robot stages or sends (a 64 x 64 map is
/// about 1 KB). Each TransferBegin in a recording costs at most this much work, so a file of
/// many small Begins stays linear (at 1 MB a 20-byte Begin cost a 2 MB buffer).
const MAX_OBJECT: u32 = robot_firmware::transfer::OBJECT_CAPACITY as u32;
/// Objects reassembled at once (the link stages one per direction).
const MAX_IN_FLIGHT: usize = 4;
/// Go-to and plan commands waiting for their answer (the link has a few in flight at most;
/// one never answered is dropped when this many newer ones wait).
const MAX_ASKED: usize = 8;

/// A point the scene marks with a sphere and its name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mark {
    /// Where the robot was sent (`GoTo`), on `/plan`.
    Goal,
    /// Where the robot was asked to plan to (`Plan`), on `/plan`.
    PlanTarget,
    /// The arena file's goal point, on `/arena`.
    ArenaGoal,
    /// The beacon, on `/arena`.
    Beacon,
}

impl Mark {
    /// Its entity id and label, and colour.
    fn look(self) -> (&'static str, &'static str, Value) {
        match self {
            Mark::Goal => ("goal", "goal", colour(1.0, 0.2, 0.2)),
            Mark::PlanTarget => ("plan_target", "plan target", colour(1.0, 0.5, 0.5)),
            Mark::ArenaGoal => ("arena_goal", "arena goal", colour(0.2, 0.8, 0.2)),
            Mark::Beacon => ("beacon", "beacon", colour(1.0, 0.85, 0.0)),
        }
    }

    /// The marker at `at` (metres, map frame): a sphere with its label above it.
    fn entity(self, at: (f64, f64)) -> Value {
        let (id, label, c) = self.look();
        let sphere = json!({
            "pose": origin_pose(at.0, at.1),
            "size": {"x": MARK_M, "y": MARK_M, "z": MARK_M},
            "color": c.clone(),
        });
        let text = json!({
            "pose": pose_at(at.0, at.1, MARK_M * 1.5), "billboard": true, "font_size": 14.0,
            "scale_invariant": true, "color": c, "text": label,
        });
        entity(id, vec![], vec![sphere], vec![text])
    }
}

/// A marker's sphere, metres across.
const MARK_M: f64 = 0.08;

/// An object being put together from recorded chunks.
struct Partial {
    kind: ObjectKind,
    crc: u32,
    bytes: Vec<u8>,
    held: Vec<bool>,
    missing: usize,
}

/// Where the last map put cell (0, 0) and how large a cell is, metres.
#[derive(Clone, Copy)]
struct Placement {
    origin: (f64, f64),
    cell_m: f64,
}

/// The state `mcap::write` carries along the walk.
#[derive(Default)]
pub struct Scene {
    /// The arena's `/arena` update, until it is published.
    arena: Option<Value>,
    /// The beacon's position as far as known (x, y), and where it was last published.
    beacon: [Option<f64>; 2],
    beacon_shown: Option<(f64, f64)>,
    /// Go-to and plan commands waiting for their answer: sequence number, marker, point.
    asked: Vec<(u16, Mark, (f64, f64))>,
    caps: Option<u32>,
    partial: BTreeMap<u32, Partial>,
    /// The object id each direction's latest `TransferBegin` tagged: `TransferData` names
    /// its transfer by that tag (PROTOCOL.md §8), [from the robot, to the robot].
    tagged: [Option<(u8, u32)>; 2],
    placement: Option<Placement>,
}

impl Scene {
    /// A scene for `rec`; its arena's walls are loaded now (a note on stderr if they cannot
    /// be: the export goes on without `/arena`).
    pub fn new(rec: &Recording) -> Scene {
        let name = rec.meta.arena.trim();
        let loaded = if name.is_empty() {
            None
        } else {
            match emulator::builtin::load(name, &emulator::arena::LoadOptions::default()) {
                Ok(a) => Some(a),
                Err(e) => {
                    eprintln!(
                        "station: arena {}: {}; /arena left out",
                        crate::terminal_text::printable_text(name),
                        crate::terminal_text::printable_text(&e.to_string())
                    );
                    None
                }
            }
        };
        let mut scene = Scene::default();
        if let Some(a) = loaded {
            let mut entities = vec![walls(&a)];
            if !a.targets.is_empty() {
                entities.push(targets(&a.targets));
            }
            if let Some(g) = a.goal {
                entities.push(Mark::ArenaGoal.entity((g.x, g.y)));
            }
            if let Some(b) = a.beacon() {
                scene.beacon = [Some(b.position.x), Some(b.position.y)];
                scene.beacon_shown = Some((b.position.x, b.position.y));
                entities.push(Mark::Beacon.entity((b.position.x, b.position.y)));
            }
            scene.arena = Some(scene_update(entities));
        }
        scene
    }

    /// Adds this item's scene messages to `out` and marks sensors the robot lacks as null.
    pub fn extend(&mut self, item: &Item<'_>, out: &mut Vec<(&'static str, Body)>) {
        if let Some(a) = self.arena.take() {
            out.push(("/arena", Body::Json(a)));
        }
        let Item::Frame { dir, msg, seq, .. } = item else {
            return;
        };
        match (dir, msg) {
            (Direction::FromRobot, Message::HelloReply(r)) if r.accepted => {
                self.caps = Some(r.capabilities);
            }
            (Direction::FromRobot, Message::Telemetry(t)) => {
                for (_, body) in out.iter_mut() {
                    if let Body::Telemetry { caps, .. } = body {
                        *caps = self.caps;
                    }
                }
                out.push((
                    "/tf",
                    Body::Transform(FrameTransform::from_map("base_link", &t.pose)),
                ));
            }
            (Direction::FromRobot, Message::EmuTruth(t)) => {
                out.push((
                    "/tf",
                    Body::Transform(FrameTransform::from_map("truth", &t.pose)),
                ));
            }
            (Direction::ToRobot, Message::Command(c)) => {
                let asked = match *c {
                    Command::GoTo(p) => Some((Mark::Goal, p)),
                    Command::Plan { to: Some(p), .. } => Some((Mark::PlanTarget, p)),
                    _ => None,
                };
                if let Some((mark, p)) = asked {
                    // A resend has the same sequence number: the newest is kept.
                    self.asked.retain(|(s, ..)| s != seq);
                    if self.asked.len() >= MAX_ASKED {
                        self.asked.remove(0);
                    }
                    self.asked.push((*seq, mark, (mm(p.x_mm), mm(p.y_mm))));
                }
            }
            (Direction::FromRobot, Message::Ack(a)) => {
                if let Some(i) = self.asked.iter().position(|(s, ..)| *s == a.cmd_seq) {
                    let (_, mark, at) = self.asked.remove(i);
                    out.push(("/plan", Body::Json(scene_update(vec![mark.entity(at)]))));
                }
                if let AckInfo::Param { id, value } = a.info {
                    self.on_param(id.0, f64::from(value), out);
                }
            }
            (Direction::FromRobot, Message::Nack(n)) => {
                self.asked.retain(|(s, ..)| *s != n.cmd_seq);
            }
            (d, Message::TransferBegin(b)) => {
                self.tagged[usize::from(*d == Direction::ToRobot)] = Some((b.tag, b.id));
                self.begin(b.id, b.object, b.len, b.crc);
            }
            (d, Message::TransferData(c)) => {
                let id = match self.tagged[usize::from(*d == Direction::ToRobot)] {
                    Some((tag, id)) if tag == c.tag => id,
                    _ => return,
                };
                if let Some(bytes) = self.chunk(id, c.offset, c.data) {
                    self.publish(&bytes, out);
                }
            }
            _ => {}
        }
    }

    /// A parameter value the robot reported: the beacon's, when it moved it.
    fn on_param(&mut self, id: u16, value: f64, out: &mut Vec<(&'static str, Body)>) {
        let axis = match id {
            params::id::BEACON_X_M => 0,
            params::id::BEACON_Y_M => 1,
            _ => return,
        };
        self.beacon[axis] = Some(value);
        if let [Some(x), Some(y)] = self.beacon {
            if self.beacon_shown != Some((x, y)) {
                self.beacon_shown = Some((x, y));
                out.push((
                    "/arena",
                    Body::Json(scene_update(vec![Mark::Beacon.entity((x, y))])),
                ));
            }
        }
    }

    fn begin(&mut self, id: u32, kind: ObjectKind, len: u32, crc: u32) {
        if len == 0 || len > MAX_OBJECT || kind == ObjectKind::LightCalibration {
            return;
        }
        if let Some(p) = self.partial.get(&id) {
            // A resumed transfer of the same object keeps what arrived.
            if p.kind == kind && p.crc == crc && p.bytes.len() == len as usize {
                return;
            }
        }
        if self.partial.len() >= MAX_IN_FLIGHT && !self.partial.contains_key(&id) {
            self.partial.pop_first();
        }
        self.partial.insert(
            id,
            Partial {
                kind,
                crc,
                bytes: vec![0; len as usize],
                held: vec![false; len as usize],
                missing: len as usize,
            },
        );
    }

    /// Stores a chunk; the whole object once its last byte arrived and its CRC checks.
    fn chunk(&mut self, id: u32, offset: u32, data: &[u8]) -> Option<Vec<u8>> {
        let p = self.partial.get_mut(&id)?;
        let start = offset as usize;
        let end = start.checked_add(data.len())?;
        if end > p.bytes.len() {
            return None;
        }
        for (i, &b) in (start..end).zip(data) {
            if !p.held[i] {
                p.held[i] = true;
                p.missing -= 1;
            }
            p.bytes[i] = b;
        }
        if p.missing > 0 {
            return None;
        }
        let p = self.partial.remove(&id)?;
        (protocol::crc32c(&p.bytes) == p.crc).then_some(p.bytes)
    }

    fn publish(&mut self, bytes: &[u8], out: &mut Vec<(&'static str, Body)>) {
        if let Ok(m) = MapView::parse(bytes) {
            let h = m.header;
            let placement = Placement {
                origin: (mm(h.origin.x_mm), mm(h.origin.y_mm)),
                cell_m: f64::from(h.cell_mm) / 1000.0,
            };
            self.placement = Some(placement);
            out.push(("/map", Body::Json(grid(&m, placement))));
        } else if let Ok(r) = RegionsView::parse(bytes) {
            if let Some(at) = self.placement {
                out.push(("/regions", Body::Json(regions(&r, at))));
            }
        } else if let Ok(p) = PlanView::parse(bytes) {
            out.push(("/plan", Body::Json(plan(&p))));
        }
    }
}

fn mm(v: i32) -> f64 {
    f64::from(v) / 1000.0
}

/// Fields of `/telemetry` that hold a sensor's reading, and the capability it needs.
const SENSOR_FIELDS: &[(&str, u32)] = &[
    ("enc_left", caps::ENCODERS),
    ("enc_right", caps::ENCODERS),
    ("ir", caps::IR_PROXIMITY),
    ("light", caps::AMBIENT_LIGHT),
    ("compass_deg", caps::COMPASS),
    ("on_goal", caps::GROUND_SENSOR),
    ("on_line", caps::LINE_SENSOR),
    ("line_events", caps::LINE_SENSOR),
    ("beacon_bearing_deg", caps::BEACON),
    ("beacon_strength", caps::BEACON),
    ("battery_v", caps::BATTERY),
];

/// The fields `SENSOR_FIELDS` names, for the schema: these may be null.
pub fn nullable(field: &str) -> bool {
    SENSOR_FIELDS.iter().any(|(f, _)| *f == field)
}

/// Whether a robot with `robot_caps` has the sensor behind `/telemetry` field `field`. A robot
/// without a sensor sends 0 in its field (PROTOCOL.md §6): that is no reading, exported as null.
pub fn robot_has(field: &str, robot_caps: u32) -> bool {
    SENSOR_FIELDS
        .iter()
        .find(|(f, _)| *f == field)
        .is_none_or(|&(_, need)| robot_caps & need == need)
}

fn quaternion(heading: f64) -> Value {
    json!({"x": 0.0, "y": 0.0, "z": (heading / 2.0).sin(), "w": (heading / 2.0).cos()})
}

fn origin_pose(x: f64, y: f64) -> Value {
    pose_at(x, y, 0.0)
}

fn pose_at(x: f64, y: f64, z: f64) -> Value {
    json!({"position": {"x": x, "y": y, "z": z}, "orientation": quaternion(0.0)})
}

/// foxglove.NumericType INT8.
const INT8: u32 = 2;

fn grid(m: &MapView<'_>, at: Placement) -> Value {
    let h = m.header;
    let mut data = Vec::with_capacity(h.cells());
    for y in 0..h.height {
        for x in 0..h.width {
            data.push(match m.cell(x, y) {
                Some(1) => 0u8,
                Some(2) => 100,
                _ => 0xff, // -1: unknown
            });
        }
    }
    json!({
        "timestamp": null,
        "frame_id": "map",
        "pose": origin_pose(at.origin.0, at.origin.1),
        "column_count": h.width,
        "cell_size": {"x": at.cell_m, "y": at.cell_m},
        "row_stride": h.width,
        "cell_stride": 1,
        "fields": [{"name": "occupancy", "offset": 0, "type": INT8}],
        "data": base64(&data),
    })
}

fn colour(r: f64, g: f64, b: f64) -> Value {
    json!({"r": r, "g": g, "b": b, "a": 1.0})
}

/// foxglove.LinePrimitive types.
const LINE_STRIP: u32 = 0;
const LINE_LOOP: u32 = 1;
const LINE_LIST: u32 = 2;

fn line(kind: u32, points: Vec<Value>, thickness: f64, c: Value) -> Value {
    json!({
        "type": kind, "pose": origin_pose(0.0, 0.0), "thickness": thickness,
        "scale_invariant": false, "points": points, "color": c, "colors": [], "indices": [],
    })
}

/// A `foxglove.SceneUpdate` adding (or replacing, by id) `entities`.
fn scene_update(entities: Vec<Value>) -> Value {
    json!({"deletions": [], "entities": entities})
}

/// A `foxglove.SceneEntity` in frame `map`, for good (no lifetime).
fn entity(id: &str, lines: Vec<Value>, spheres: Vec<Value>, texts: Vec<Value>) -> Value {
    json!({
        "timestamp": null, "frame_id": "map", "id": id,
        "lifetime": {"sec": 0, "nsec": 0}, "frame_locked": false, "metadata": [],
        "arrows": [], "cubes": [], "spheres": spheres, "cylinders": [], "lines": lines,
        "triangles": [], "texts": texts, "models": [],
    })
}

fn point(x: f64, y: f64) -> Value {
    json!({"x": x, "y": y, "z": 0.0})
}

fn regions(r: &RegionsView<'_>, at: Placement) -> Value {
    let mut points = Vec::new();
    for s in r.squares() {
        let x0 = at.origin.0 + f64::from(s.x) * at.cell_m;
        let y0 = at.origin.1 + f64::from(s.y) * at.cell_m;
        let side = f64::from(s.size) * at.cell_m;
        let c = [
            (x0, y0),
            (x0 + side, y0),
            (x0 + side, y0 + side),
            (x0, y0 + side),
        ];
        for i in 0..4 {
            let (a, b) = (c[i], c[(i + 1) % 4]);
            points.push(point(a.0, a.1));
            points.push(point(b.0, b.1));
        }
    }
    scene_update(vec![entity(
        "regions",
        vec![line(LINE_LIST, points, 0.01, colour(0.2, 0.6, 1.0))],
        vec![],
        vec![],
    )])
}

fn plan(p: &PlanView<'_>) -> Value {
    let points = p
        .waypoints()
        .map(|w| point(mm(w.x_mm), mm(w.y_mm)))
        .collect();
    scene_update(vec![entity(
        "plan",
        vec![line(LINE_STRIP, points, 0.03, colour(1.0, 0.5, 0.0))],
        vec![],
        vec![],
    )])
}

fn walls(a: &emulator::arena::Arena) -> Value {
    let mut points = Vec::new();
    for s in a.segments() {
        points.push(point(s.a.x, s.a.y));
        points.push(point(s.b.x, s.b.y));
    }
    entity(
        "arena",
        vec![line(LINE_LIST, points, 0.02, colour(0.6, 0.6, 0.6))],
        vec![],
        vec![],
    )
}

/// The arena's target areas, each a circle on the floor.
fn targets(areas: &[emulator::arena::Target]) -> Value {
    const SIDES: usize = 32;
    let lines = areas
        .iter()
        .map(|t| {
            let points = (0..SIDES)
                .map(|i| {
                    let a = std::f64::consts::TAU * i as f64 / SIDES as f64;
                    point(
                        t.centre.x + t.radius_m * a.cos(),
                        t.centre.y + t.radius_m * a.sin(),
                    )
                })
                .collect();
            line(LINE_LOOP, points, 0.02, colour(0.2, 0.8, 0.2))
        })
        .collect();
    entity("targets", lines, vec![], vec![])
}

/// Standard base64 with padding (RFC 4648 §4): how JSON-encoded MCAP carries `bytes` fields.
fn base64(bytes: &[u8]) -> String {
    const ABC: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for c in bytes.chunks(3) {
        let n = (u32::from(c[0]) << 16)
            | (u32::from(c.get(1).copied().unwrap_or(0)) << 8)
            | u32::from(c.get(2).copied().unwrap_or(0));
        for (i, shift) in [18, 12, 6, 0].into_iter().enumerate() {
            if i <= c.len() {
                out.push(char::from(ABC[(n >> shift) as usize & 63]));
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// The JSON schemas of these channels: topic, schema name, schema.
pub fn channels() -> Vec<(&'static str, &'static str, Value)> {
    let num = || json!({"type": "number"});
    let int = || json!({"type": "integer"});
    let string = || json!({"type": "string"});
    let obj = |props: Value| json!({"type": "object", "properties": props});
    let time = obj(json!({"sec": int(), "nsec": int()}));
    let vec3 = obj(json!({"x": num(), "y": num(), "z": num()}));
    let quat = obj(json!({"x": num(), "y": num(), "z": num(), "w": num()}));
    let pose = obj(json!({"position": vec3.clone(), "orientation": quat.clone()}));
    let colour = obj(json!({"r": num(), "g": num(), "b": num(), "a": num()}));
    let array = |items: Value| json!({"type": "array", "items": items});
    let line = obj(json!({
        "type": int(), "pose": pose.clone(), "thickness": num(),
        "scale_invariant": {"type": "boolean"}, "points": array(vec3.clone()),
        "color": colour.clone(), "colors": array(colour.clone()), "indices": array(int()),
    }));
    let sphere = obj(json!({"pose": pose.clone(), "size": vec3.clone(), "color": colour.clone()}));
    let text = obj(json!({
        "pose": pose.clone(), "billboard": {"type": "boolean"}, "font_size": num(),
        "scale_invariant": {"type": "boolean"}, "color": colour, "text": string(),
    }));
    let scene = obj(json!({
        "deletions": array(obj(json!({"timestamp": time.clone(), "type": int(), "id": string()}))),
        "entities": array(obj(json!({
            "timestamp": time.clone(), "frame_id": string(), "id": string(),
            "lifetime": time.clone(), "frame_locked": {"type": "boolean"},
            "metadata": array(obj(json!({"key": string(), "value": string()}))),
            "arrows": array(json!({})), "cubes": array(json!({})), "spheres": array(sphere),
            "cylinders": array(json!({})), "lines": array(line), "triangles": array(json!({})),
            "texts": array(text), "models": array(json!({})),
        }))),
    }));
    vec![
        (
            "/tf",
            "foxglove.FrameTransform",
            obj(json!({
                "timestamp": time.clone(), "parent_frame_id": string(),
                "child_frame_id": string(), "translation": vec3, "rotation": quat,
            })),
        ),
        (
            "/map",
            "foxglove.Grid",
            obj(json!({
                "timestamp": time, "frame_id": string(), "pose": pose,
                "column_count": int(), "cell_size": obj(json!({"x": num(), "y": num()})),
                "row_stride": int(), "cell_stride": int(),
                "fields": array(obj(json!({"name": string(), "offset": int(), "type": int()}))),
                "data": {"type": "string", "contentEncoding": "base64"},
            })),
        ),
        ("/regions", "foxglove.SceneUpdate", scene.clone()),
        ("/plan", "foxglove.SceneUpdate", scene.clone()),
        ("/arena", "foxglove.SceneUpdate", scene),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_rfc_4648_test_vectors() {
        for (plain, coded) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(plain.as_bytes()), coded);
        }
    }
}
