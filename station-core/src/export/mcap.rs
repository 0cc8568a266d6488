//! A recording as MCAP, for Foxglove: each message logged at the time it crossed the link.
//!
//! Layer: formatting over `export::walk`, written by the `mcap` crate's `Writer` to any writer
//! (seeking is not needed: each chunk is put together in memory and written whole). Channels:
//! - `/telemetry`: every telemetry frame, the fields of `csv::TelemetryRow` (SI-ish units);
//! - `/pose`, `/truth_pose`: the believed and the true pose as `foxglove.PoseInFrame` in frame
//!   `map`, so the 3D panel draws them;
//! - `/truth`: the emulator's `EmuTruth`;
//! - `/events`: robot events by name (`format::event_name`) and in the station's words, with
//!   their wire code and value; `/log`: as `foxglove.Log` (the Log panel), the robot's log
//!   lines (`name` "robot") and the station's own, recorded while it ran (`name`
//!   `station/command`, `station/event`, ...: refusals, give-ups, events in its words);
//! - `/link`: connection changes, gap markers included;
//! - `/tf`, `/map`, `/regions`, `/plan`, `/arena`: the scene for the 3D panel (`scene`);
//! - `/qt_model`: the QT world model rebuilt from an ALICE's situations, once a second within a
//!   budget in proportion to the recording (`qt`);
//! - `/commands`: the station's own commands (decoded from its recorded bytes), with their
//!   sequence numbers; `/replies`: the robot's Acks and Nacks naming them.
//!
//! Encodings ([`Encoding`]): the topics of every frame (`/telemetry`, `/pose`, `/truth`,
//! `/truth_pose`, `/tf`) are `protobuf` (`mcap_proto`) by default, or `json` with JSON schemas
//! as before; the occasional topics are always `json` with a `jsonschema`. Field names are the
//! same in both, so a Foxglove layout that plots `/telemetry.x_m` reads either.
//!
//! `log_time` and `publish_time` are the recording's start (wall clock, from its header) plus
//! the record's time, in nanoseconds. Chunks are not compressed (no C dependencies). What can
//! fail: the writer (`ExportError::Mcap`).

use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;

use mcap::records::{MessageHeader, Metadata};
use mcap::write::NoSeek;
use protocol::{LogLevel, Message};
use serde_json::{json, Value};

use super::csv::TelemetryRow;
use super::mcap_msg::{Body, PoseInFrame, Truth};
use super::mcap_proto;
use super::{walk, Direction, ExportError, Item};
use crate::format::{event_name, event_text};
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
            // Counters and bit sets are integers; a sensor the robot lacks is null.
            let kind = if INTEGER_COLUMNS.contains(c) {
                "integer"
            } else {
                "number"
            };
            let t = if super::scene::nullable(c) {
                json!({"type": [kind, "null"]})
            } else {
                json!({"type": kind})
            };
            telemetry.insert((*c).to_string(), t);
        }
    }
    telemetry.insert("mode".into(), string());
    let readings = json!({"type": ["array", "null"], "items": int(), "minItems": 8, "maxItems": 8});
    telemetry.insert("ir".into(), readings.clone());
    telemetry.insert("light".into(), readings);
    for b in ["on_goal", "on_line", "contact", "failsafe", "goal_reached"] {
        let t = if super::scene::nullable(b) {
            json!({"type": ["boolean", "null"]})
        } else {
            json!({"type": "boolean"})
        };
        telemetry.insert(b.into(), t);
    }
    let mut all = vec![
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
            obj(json!({"name": string(), "text": string(), "code": string(), "value": int()})),
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
    ];
    all.extend(super::scene::channels());
    all.extend(super::qt::channels());
    all
}

/// `/telemetry` fields that are whole numbers (the rest are measurements in SI-ish units).
const INTEGER_COLUMNS: &[&str] = &[
    "enc_left",
    "enc_right",
    "flags",
    "line_events",
    "beacon_strength",
    "behaviours",
    "cycle_overruns",
    "collisions",
];

/// How the topics of every frame are encoded (`station export --mcap-encoding`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Encoding {
    /// Protocol Buffers: Foxglove's well-known schemas for poses and transforms, the station's
    /// for telemetry and truth; a file of about 40 % of JSON's bytes, written in about two
    /// thirds of the time.
    #[default]
    Protobuf,
    /// JSON text with JSON schemas, for scripts that parse the messages' JSON themselves (an
    /// MCAP reader and a JSON parser, no protobuf); a lacking sensor's reading is `null`.
    Json,
}

/// What an MCAP export wrote.
#[derive(Debug, Default)]
pub struct Written {
    /// Messages.
    pub messages: u64,
    /// What the reader should know about the file (a budget that left snapshots out).
    pub notes: Vec<String>,
}

/// Writes `rec` as MCAP to `w`.
pub fn write<W: Write>(
    rec: &Recording,
    enc: Encoding,
    w: W,
    path: &Path,
) -> Result<Written, ExportError> {
    write_robots(&rec.meta, &[("", rec)], enc, w, path)
}

/// Writes several robots' recordings (the links of one file, `meta` its header) as one MCAP
/// file, each robot's channels under its prefix ([`topic_name`]). Robots are written one after
/// the other: MCAP readers order by log time.
pub fn write_robots<W: Write>(
    meta: &crate::record::Meta,
    robots: &[(&str, &Recording)],
    enc: Encoding,
    w: W,
    path: &Path,
) -> Result<Written, ExportError> {
    let err = mcap_error(path);
    let library = format!("station {}", env!("CARGO_PKG_VERSION"));
    let mut out = mcap::WriteOptions::new()
        .compression(None)
        .profile("")
        .library(library)
        .disable_seeking(true)
        .create(NoSeek::new(w))
        .map_err(err)?;
    // First, while no chunk is open: a metadata record closes the open chunk, and a chunk of
    // schemas and channels without messages has no message index to find it by.
    let meta = serde_json::to_value(meta).unwrap_or(Value::Null);
    let meta: BTreeMap<String, String> = meta
        .as_object()
        .map(|m| {
            m.iter()
                .map(|(k, v)| (k.clone(), v.as_str().map_or(v.to_string(), str::to_string)))
                .collect()
        })
        .unwrap_or_default();
    out.write_metadata(&Metadata {
        name: "recording".into(),
        metadata: meta,
    })
    .map_err(err)?;
    let mut schemas = BTreeMap::new();
    let mut written = Written::default();
    for (prefix, rec) in robots {
        write_robot(
            &mut out,
            &mut schemas,
            (prefix, rec),
            enc,
            path,
            &mut written,
        )?;
    }
    out.finish().map_err(err)?;
    out.into_inner()
        .flush()
        .map_err(|e| err(mcap::McapError::Io(e)))?;
    Ok(written)
}

/// The file being written.
type Out<W> = mcap::Writer<NoSeek<W>>;

/// How a failure to write the file is reported.
fn mcap_error(path: &Path) -> impl Fn(mcap::McapError) -> ExportError + Copy + '_ {
    move |e| ExportError::Mcap {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// A robot's topic: `topic` itself for the only robot of a file (today's names), else under
/// the robot's prefix (`/robot1/telemetry`, `/robot1/tf`, ...).
pub fn topic_name(prefix: &str, topic: &str) -> String {
    if prefix.is_empty() {
        topic.to_string()
    } else {
        format!("/{prefix}{topic}")
    }
}

/// One robot's channels and messages into `out`.
fn write_robot<W: Write>(
    out: &mut Out<W>,
    schemas: &mut BTreeMap<&'static str, (u16, bool)>,
    (prefix, rec): (&str, &Recording),
    enc: Encoding,
    path: &Path,
    written: &mut Written,
) -> Result<(), ExportError> {
    let err = mcap_error(path);
    // Channel ids, per-channel sequence numbers and whether the channel is protobuf, in
    // `channels()` order. A schema `mcap_proto` has is binary unless JSON was asked for.
    let mut topics = Vec::new();
    for (topic, name, schema) in channels() {
        let (schema_id, protobuf) = match schemas.get(name) {
            Some(&known) => known,
            None => {
                let binary = match enc {
                    Encoding::Protobuf => mcap_proto::descriptor_set(name),
                    Encoding::Json => None,
                };
                let known = match binary {
                    Some(set) => (out.add_schema(name, "protobuf", &set).map_err(err)?, true),
                    None => {
                        let mut data = Vec::new();
                        let _ = crate::json_text::write(&mut data, &schema);
                        (
                            out.add_schema(name, "jsonschema", &data).map_err(err)?,
                            false,
                        )
                    }
                };
                schemas.insert(name, known);
                known
            }
        };
        let encoding = if protobuf { "protobuf" } else { "json" };
        let id = out
            .add_channel(
                schema_id,
                &topic_name(prefix, topic),
                encoding,
                &BTreeMap::new(),
            )
            .map_err(err)?;
        topics.push((topic, id, 0u32, protobuf));
    }
    written.messages += write_messages(out, &mut topics, rec, path, |note| {
        let robot = match prefix {
            "" => String::new(),
            p => format!("/{p}"),
        };
        written.notes.push(format!("{robot}{note}"));
    })?;
    Ok(())
}

/// Every message of `rec` on its channel (`topics`: topic, channel id, messages so far).
fn write_messages<W: Write>(
    out: &mut Out<W>,
    topics: &mut [(&'static str, u16, u32, bool)],
    rec: &Recording,
    path: &Path,
    mut note: impl FnMut(String),
) -> Result<u64, ExportError> {
    let err = mcap_error(path);
    let base_ns = rec.meta.created_unix_ms.saturating_mul(1_000_000);
    let mut count = 0u64;
    let mut failure = None;
    let mut scene = super::scene::Scene::new(rec);
    let mut qt = super::qt::QtExport::new(&rec.records);
    // Reused for every item: its messages, and a message's bytes.
    let mut messages = Vec::new();
    let mut data = Vec::new();
    let mut encoder = mcap_proto::Encoder::default();
    walk(rec, |item| {
        if failure.is_some() {
            return;
        }
        messages.clear();
        let t_us = item_messages(&item, &mut messages);
        scene.extend(&item, &mut messages);
        qt.extend(&item, &mut messages);
        let ns = base_ns.saturating_add(t_us.saturating_mul(1000));
        for (topic, body) in &mut messages {
            // Every topic is in `channels()`; a linear look-up over 14 beats a map's.
            let Some((_, channel_id, n, protobuf)) = topics.iter_mut().find(|(t, ..)| t == topic)
            else {
                continue;
            };
            body.stamp(ns);
            *n += 1;
            data.clear();
            body.write(protobuf.then_some(&mut encoder), &mut data);
            let header = MessageHeader {
                channel_id: *channel_id,
                sequence: *n,
                log_time: ns,
                publish_time: ns,
            };
            if let Err(e) = out.write_to_known_channel(&header, &data) {
                failure = Some(err(e));
                return;
            }
            count += 1;
        }
    });
    if let Some(e) = failure {
        return Err(e);
    }
    if let Some(n) = qt.note() {
        note(n);
    }
    Ok(count)
}

/// Adds the messages one walk item becomes to `out`; returns its time.
fn item_messages(item: &Item<'_>, out: &mut Vec<(&'static str, Body)>) -> u64 {
    match item {
        Item::Link { t_us, state, text } => {
            out.push(("/link", Body::Json(json!({"state": state, "text": text}))));
            *t_us
        }
        Item::BadFrame { t_us, dir, error } => {
            out.push((
                "/link",
                Body::Json(
                    json!({"state": "bad_frame", "text": format!("{}: {error}", dir_name(*dir))}),
                ),
            ));
            *t_us
        }
        Item::Frame {
            t_us,
            dir,
            seq,
            msg,
        } => {
            frame_messages(*t_us, *dir, *seq, msg, out);
            *t_us
        }
        Item::StationLog { t_us, line } => {
            out.push(("/log", log(line.level, &line.text, line.source.name())));
            *t_us
        }
    }
}

/// A `/log` line as `foxglove.Log`; `name` says whose (`robot`, `station/command`, ...).
fn log(level: LogLevel, text: &str, name: &str) -> Body {
    // foxglove.Log levels: 1 debug, 2 info, 3 warning, 4 error, 5 fatal.
    let level = match level {
        LogLevel::Debug => 1,
        LogLevel::Info => 2,
        LogLevel::Warn => 3,
        LogLevel::Error => 4,
    };
    Body::Json(json!({"timestamp": null, "level": level, "message": text,
                      "name": name, "file": "", "line": 0}))
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
    out: &mut Vec<(&'static str, Body)>,
) {
    let json = |topic, v| (topic, Body::Json(v));
    match (dir, msg) {
        (Direction::FromRobot, Message::Telemetry(t)) => {
            out.push((
                "/telemetry",
                Body::Telemetry {
                    row: Box::new(TelemetryRow::new(t_us, t)),
                    caps: None,
                },
            ));
            out.push(("/pose", Body::Pose(PoseInFrame::map(&t.pose))));
        }
        (Direction::FromRobot, Message::EmuTruth(t)) => {
            out.push((
                "/truth",
                Body::Truth(Truth {
                    robot_time_s: f64::from(t.time_ms) / 1000.0,
                    x_m: f64::from(t.pose.x_mm) / 1000.0,
                    y_m: f64::from(t.pose.y_mm) / 1000.0,
                    heading_rad: f64::from(t.pose.heading_mrad) / 1000.0,
                    collisions: t.collisions,
                }),
            ));
            out.push(("/truth_pose", Body::Pose(PoseInFrame::map(&t.pose))));
        }
        (Direction::FromRobot, Message::Event(e)) => out.push(json(
            "/events",
            json!({"name": event_name(e.code), "text": event_text(e).1,
                   "code": format!("{:?}", e.code), "value": e.value}),
        )),
        (Direction::FromRobot, Message::Log(l)) => out.push(("/log", log(l.level, l.text, "robot"))),
        (Direction::FromRobot, Message::Ack(a)) => out.push(json(
            "/replies",
            json!({"cmd_seq": a.cmd_seq, "outcome": "ack", "detail": a.info}),
        )),
        (Direction::FromRobot, Message::Nack(n)) => out.push(json(
            "/replies",
            json!({"cmd_seq": n.cmd_seq, "outcome": "nack", "detail": n.reason}),
        )),
        (Direction::FromRobot, Message::HelloReply(r)) => out.push(json(
            "/link",
            json!({"state": "hello_reply", "text": format!(
                "{} {} {:?}, accepted {}", r.firmware, r.firmware_version, r.profile, r.accepted)}),
        )),
        (Direction::ToRobot, Message::Command(c)) => out.push(json(
            "/commands",
            json!({"seq": seq, "text": command_text(c), "command": c}),
        )),
        (Direction::ToRobot, Message::Hello(h)) => out.push(json(
            "/link",
            json!({"state": "hello", "text": format!("session {:#010x} from {}", h.session, h.station)}),
        )),
        _ => {}
    }
}
