//! A recording as MCAP, for Foxglove: JSON messages on JSON-schema channels, logged at the
//! time they crossed the link.
//!
//! Layer: formatting over `export::walk`, writing through the `mcap` crate to any seekable
//! writer. Channels (all `json`, each with a `jsonschema`):
//! - `/telemetry`: every telemetry frame, the fields of `csv::TelemetryRow` (SI-ish units);
//! - `/pose`, `/truth_pose`: the believed and the true pose as `foxglove.PoseInFrame` in frame
//!   `map`, so the 3D panel draws them;
//! - `/truth`: the emulator's `EmuTruth`;
//! - `/events`: robot events; `/log`: robot log lines as `foxglove.Log` (the Log panel);
//! - `/link`: connection changes, gap markers included;
//! - `/commands`: the station's own commands (decoded from its recorded bytes), with their
//!   sequence numbers; `/replies`: the robot's Acks and Nacks naming them.
//!
//! `log_time` and `publish_time` are the recording's start (wall clock, from its header) plus
//! the record's time, in nanoseconds. Chunks are not compressed (no C dependencies). What can
//! fail: the writer (`ExportError::Mcap`).

use std::collections::BTreeMap;
use std::io::{Seek, Write};
use std::path::Path;

use mcap::records::MessageHeader;
use mcap::{WriteOptions, Writer};
use protocol::{EmuTruth, LogLevel, Message, Pose};
use serde_json::{json, Value};

use super::csv::{fixed, uint, TelemetryRow};
use super::{walk, Direction, ExportError, Item};
use crate::link::api::command_text;
use crate::record::Recording;

/// The channels, in the order they are added: topic, schema name, JSON schema.
fn channels() -> Vec<(&'static str, &'static str, Value)> {
    let num = || json!({"type": "number"});
    let int = || json!({"type": "integer"});
    let string = || json!({"type": "string"});
    let obj = |props: Value| json!({"type": "object", "properties": props});
    let pose = obj(json!({
        "timestamp": obj(json!({"sec": int(), "nsec": int()})),
        "frame_id": string(),
        "pose": obj(json!({
            "position": obj(json!({"x": num(), "y": num(), "z": num()})),
            "orientation": obj(json!({"x": num(), "y": num(), "z": num(), "w": num()})),
        })),
    }));
    let mut telemetry = serde_json::Map::new();
    for c in super::csv::COLUMNS {
        if !c.starts_with("ir") && !c.starts_with("light") {
            telemetry.insert((*c).to_string(), num());
        }
    }
    telemetry.insert("mode".into(), string());
    let readings = json!({"type": "array", "items": int(), "minItems": 8, "maxItems": 8});
    telemetry.insert("ir".into(), readings.clone());
    telemetry.insert("light".into(), readings);
    for b in ["on_goal", "on_line", "contact", "failsafe", "goal_reached"] {
        telemetry.insert(b.into(), json!({"type": "boolean"}));
    }
    vec![
        (
            "/telemetry",
            "station.Telemetry",
            obj(Value::Object(telemetry)),
        ),
        ("/pose", "foxglove.PoseInFrame", pose.clone()),
        ("/truth_pose", "foxglove.PoseInFrame", pose),
        (
            "/truth",
            "station.Truth",
            obj(json!({"robot_time_s": num(), "x_m": num(), "y_m": num(),
                       "heading_rad": num(), "collisions": int()})),
        ),
        (
            "/events",
            "station.Event",
            obj(json!({"code": string(), "value": int()})),
        ),
        (
            "/log",
            "foxglove.Log",
            obj(json!({
                "timestamp": obj(json!({"sec": int(), "nsec": int()})),
                "level": int(), "message": string(), "name": string(),
                "file": string(), "line": int(),
            })),
        ),
        (
            "/link",
            "station.Link",
            obj(json!({"state": string(), "text": string()})),
        ),
        (
            "/commands",
            "station.Command",
            obj(json!({"seq": int(), "text": string(), "command": {"type": "object"}})),
        ),
        (
            "/replies",
            "station.Reply",
            obj(json!({"cmd_seq": int(), "outcome": string(), "detail": {}})),
        ),
    ]
}

/// Writes `rec` as MCAP to `w`; returns the number of messages.
pub fn write<W: Write + Seek>(rec: &Recording, w: W, path: &Path) -> Result<u64, ExportError> {
    let err = |e: mcap::McapError| ExportError::Mcap {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    let opts = WriteOptions::new()
        .compression(None)
        .profile("")
        .library(format!("station {}", env!("CARGO_PKG_VERSION")));
    let mut out = Writer::with_options(w, opts).map_err(err)?;
    let mut ids = BTreeMap::new();
    for (topic, name, schema) in channels() {
        let data = serde_json::to_vec(&schema).unwrap_or_default();
        let schema_id = out.add_schema(name, "jsonschema", &data).map_err(err)?;
        let id = out
            .add_channel(schema_id, topic, "json", &BTreeMap::new())
            .map_err(err)?;
        ids.insert(topic, id);
    }
    let meta = serde_json::to_value(&rec.meta).unwrap_or(Value::Null);
    let meta: BTreeMap<String, String> = meta
        .as_object()
        .map(|m| {
            m.iter()
                .map(|(k, v)| (k.clone(), v.as_str().map_or(v.to_string(), str::to_string)))
                .collect()
        })
        .unwrap_or_default();
    out.write_metadata(&mcap::records::Metadata {
        name: "recording".into(),
        metadata: meta,
    })
    .map_err(err)?;

    let base_ns = rec.meta.created_unix_ms.saturating_mul(1_000_000);
    let mut seq: BTreeMap<u16, u32> = BTreeMap::new();
    let mut count = 0u64;
    let mut failure = None;
    // The hot path: telemetry and truth frames (nearly every message) are written as JSON by
    // hand into one reused buffer (`TelemetryRow::write_json`, `pose_json`, `truth_json`: the
    // objects `pose_in_frame` and serde would make), on channels looked up once; the rest
    // build a JSON value as before.
    let hot = HotChannels::new(&ids);
    let mut data = Vec::with_capacity(1024);
    let mut text = String::with_capacity(1024);
    let mut send = |out: &mut Writer<W>, channel_id: u16, ns: u64, data: &[u8]| {
        let n = seq.entry(channel_id).or_insert(0);
        *n += 1;
        let header = MessageHeader {
            channel_id,
            sequence: *n,
            log_time: ns,
            publish_time: ns,
        };
        out.write_to_known_channel(&header, data)
    };
    walk(rec, |item| {
        if failure.is_some() {
            return;
        }
        if let (
            Some(hot),
            Item::Frame {
                t_us,
                dir: Direction::FromRobot,
                msg,
                ..
            },
        ) = (&hot, &item)
        {
            let ns = base_ns.saturating_add(t_us.saturating_mul(1000));
            let mut emit = |channel_id: u16, data: &[u8]| {
                if failure.is_none() {
                    match send(&mut out, channel_id, ns, data) {
                        Ok(()) => count += 1,
                        Err(e) => failure = Some(err(e)),
                    }
                }
            };
            match msg {
                Message::Telemetry(t) => {
                    text.clear();
                    TelemetryRow::new(*t_us, t).write_json(&mut text);
                    emit(hot.telemetry, text.as_bytes());
                    pose_json(&mut text, &t.pose, ns);
                    emit(hot.pose, text.as_bytes());
                    return;
                }
                Message::EmuTruth(t) => {
                    truth_json(&mut text, t);
                    emit(hot.truth, text.as_bytes());
                    pose_json(&mut text, &t.pose, ns);
                    emit(hot.truth_pose, text.as_bytes());
                    return;
                }
                _ => {}
            }
        }
        let (t_us, messages) = messages(&item);
        let ns = base_ns.saturating_add(t_us.saturating_mul(1000));
        for (topic, mut value) in messages {
            let Some(&channel_id) = ids.get(topic) else {
                continue;
            };
            stamp(&mut value, ns);
            data.clear();
            if serde_json::to_writer(&mut data, &value).is_err() {
                data.clear();
            }
            if let Err(e) = send(&mut out, channel_id, ns, &data) {
                failure = Some(err(e));
                return;
            }
            count += 1;
        }
    });
    if let Some(e) = failure {
        return Err(e);
    }
    out.finish().map_err(err)?;
    Ok(count)
}

/// The channels of the hot path, looked up once.
struct HotChannels {
    telemetry: u16,
    pose: u16,
    truth: u16,
    truth_pose: u16,
}

impl HotChannels {
    fn new(ids: &BTreeMap<&str, u16>) -> Option<HotChannels> {
        Some(HotChannels {
            telemetry: *ids.get("/telemetry")?,
            pose: *ids.get("/pose")?,
            truth: *ids.get("/truth")?,
            truth_pose: *ids.get("/truth_pose")?,
        })
    }
}

/// `foxglove.PoseInFrame` of `p` in frame `map` at `ns`, as JSON in `out` (cleared first):
/// the object `pose_in_frame` and `stamp` make, written by hand.
fn pose_json(out: &mut String, p: &Pose, ns: u64) {
    let h = f64::from(p.heading_mrad) / 1000.0;
    out.clear();
    out.push_str("{\"timestamp\":{\"sec\":");
    uint(out, ns / 1_000_000_000);
    out.push_str(",\"nsec\":");
    uint(out, ns % 1_000_000_000);
    out.push_str("},\"frame_id\":\"map\",\"pose\":{\"position\":{\"x\":");
    fixed(out, f64::from(p.x_mm) / 1000.0, 3);
    out.push_str(",\"y\":");
    fixed(out, f64::from(p.y_mm) / 1000.0, 3);
    out.push_str(",\"z\":0.0},\"orientation\":{\"x\":0.0,\"y\":0.0,\"z\":");
    float(out, (h / 2.0).sin());
    out.push_str(",\"w\":");
    float(out, (h / 2.0).cos());
    out.push_str("}}}");
}

/// `/truth` for `t` as JSON in `out` (cleared first).
fn truth_json(out: &mut String, t: &EmuTruth) {
    out.clear();
    out.push_str("{\"robot_time_s\":");
    fixed(out, f64::from(t.time_ms) / 1000.0, 3);
    out.push_str(",\"x_m\":");
    fixed(out, f64::from(t.pose.x_mm) / 1000.0, 3);
    out.push_str(",\"y_m\":");
    fixed(out, f64::from(t.pose.y_mm) / 1000.0, 3);
    out.push_str(",\"heading_rad\":");
    fixed(out, f64::from(t.pose.heading_mrad) / 1000.0, 3);
    out.push_str(",\"collisions\":");
    uint(out, u64::from(t.collisions));
    out.push('}');
}

/// A finite float in the shortest form that reads back to it (`Debug`: `0.5`, `1e-7`, both
/// valid JSON); `null` otherwise, as serde_json writes.
fn float(out: &mut String, v: f64) {
    use std::fmt::Write as _;
    if v.is_finite() {
        let _ = write!(out, "{v:?}");
    } else {
        out.push_str("null");
    }
}

/// Fills in `timestamp` fields (foxglove schemas) with the log time.
fn stamp(v: &mut Value, ns: u64) {
    if let Some(t) = v.get_mut("timestamp") {
        *t = json!({"sec": ns / 1_000_000_000, "nsec": ns % 1_000_000_000});
    }
}

fn pose_in_frame(p: &Pose) -> Value {
    let h = f64::from(p.heading_mrad) / 1000.0;
    json!({
        "timestamp": null,
        "frame_id": "map",
        "pose": {
            "position": {"x": f64::from(p.x_mm) / 1000.0, "y": f64::from(p.y_mm) / 1000.0, "z": 0.0},
            "orientation": {"x": 0.0, "y": 0.0, "z": (h / 2.0).sin(), "w": (h / 2.0).cos()},
        },
    })
}

/// The messages one walk item becomes, and its time.
fn messages(item: &Item<'_>) -> (u64, Vec<(&'static str, Value)>) {
    match item {
        Item::Link { t_us, state, text } => (
            *t_us,
            vec![("/link", json!({"state": state, "text": text}))],
        ),
        Item::BadFrame { t_us, dir, error } => (
            *t_us,
            vec![(
                "/link",
                json!({"state": "bad_frame", "text": format!("{}: {error}", dir_name(*dir))}),
            )],
        ),
        Item::Frame {
            t_us,
            dir,
            seq,
            msg,
        } => (*t_us, frame_messages(*t_us, *dir, *seq, msg)),
    }
}

fn dir_name(d: Direction) -> &'static str {
    match d {
        Direction::FromRobot => "from robot",
        Direction::ToRobot => "to robot",
    }
}

fn frame_messages(
    t_us: u64,
    dir: Direction,
    seq: u16,
    msg: &Message<'_>,
) -> Vec<(&'static str, Value)> {
    match (dir, msg) {
        (Direction::FromRobot, Message::Telemetry(t)) => vec![
            (
                "/telemetry",
                serde_json::to_value(TelemetryRow::new(t_us, t)).unwrap_or(Value::Null),
            ),
            ("/pose", pose_in_frame(&t.pose)),
        ],
        (Direction::FromRobot, Message::EmuTruth(t)) => vec![
            (
                "/truth",
                json!({
                    "robot_time_s": f64::from(t.time_ms) / 1000.0,
                    "x_m": f64::from(t.pose.x_mm) / 1000.0,
                    "y_m": f64::from(t.pose.y_mm) / 1000.0,
                    "heading_rad": f64::from(t.pose.heading_mrad) / 1000.0,
                    "collisions": t.collisions,
                }),
            ),
            ("/truth_pose", pose_in_frame(&t.pose)),
        ],
        (Direction::FromRobot, Message::Event(e)) => vec![(
            "/events",
            json!({"code": format!("{:?}", e.code), "value": e.value}),
        )],
        (Direction::FromRobot, Message::Log(l)) => {
            // foxglove.Log levels: 1 debug, 2 info, 3 warning, 4 error, 5 fatal.
            let level = match l.level {
                LogLevel::Debug => 1,
                LogLevel::Info => 2,
                LogLevel::Warn => 3,
                LogLevel::Error => 4,
            };
            vec![(
                "/log",
                json!({"timestamp": null, "level": level, "message": l.text,
                       "name": "robot", "file": "", "line": 0}),
            )]
        }
        (Direction::FromRobot, Message::Ack(a)) => vec![(
            "/replies",
            json!({"cmd_seq": a.cmd_seq, "outcome": "ack", "detail": a.info}),
        )],
        (Direction::FromRobot, Message::Nack(n)) => vec![(
            "/replies",
            json!({"cmd_seq": n.cmd_seq, "outcome": "nack", "detail": n.reason}),
        )],
        (Direction::FromRobot, Message::HelloReply(r)) => vec![(
            "/link",
            json!({"state": "hello_reply", "text": format!(
                "{} {} {:?}, accepted {}", r.firmware, r.firmware_version, r.profile, r.accepted)}),
        )],
        (Direction::ToRobot, Message::Command(c)) => vec![(
            "/commands",
            json!({"seq": seq, "text": command_text(c), "command": c}),
        )],
        (Direction::ToRobot, Message::Hello(h)) => vec![(
            "/link",
            json!({"state": "hello", "text": format!("session {:#010x} from {}", h.session, h.station)}),
        )],
        _ => Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hand_written_pose_and_truth_are_the_values_serde_makes() {
        let mut out = String::new();
        for i in -300i32..300 {
            let p = Pose {
                x_mm: i * 12_345,
                y_mm: -i * 7,
                heading_mrad: (i * 11) as i16,
            };
            let ns = 1_700_000_000_000_000_000 + u64::from(i.unsigned_abs()) * 20_000_123;
            pose_json(&mut out, &p, ns);
            let mut want = pose_in_frame(&p);
            stamp(&mut want, ns);
            // Both texts through the same parser (serde_json's default one is not exact to the
            // last bit, so a value is compared with a value read back the same way).
            let reread = |text: &str| serde_json::from_str::<Value>(text).unwrap();
            assert_eq!(reread(&out), reread(&want.to_string()), "{out}");
            let t = EmuTruth {
                time_ms: i.unsigned_abs() * 20,
                pose: p,
                collisions: i.unsigned_abs(),
            };
            truth_json(&mut out, &t);
            let mine: Value = serde_json::from_str(&out).unwrap();
            let want = frame_messages(0, Direction::FromRobot, 0, &Message::EmuTruth(t))
                .into_iter()
                .find(|(topic, _)| *topic == "/truth")
                .map(|(_, v)| v)
                .unwrap();
            assert_eq!(mine, want, "{out}");
        }
        for v in [0.0, -0.0, 1e-7, 0.5, 1e300, f64::NAN] {
            out.clear();
            float(&mut out, v);
            let back: Value = serde_json::from_str(&out).unwrap();
            let want = serde_json::to_value(v).unwrap().to_string();
            assert_eq!(back, serde_json::from_str::<Value>(&want).unwrap(), "{out}");
            assert_eq!(
                out.parse::<f64>().ok().filter(|b| b == &v),
                v.is_finite().then_some(v)
            );
        }
    }
}
