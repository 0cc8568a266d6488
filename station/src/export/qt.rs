//! The QT world model (seed 001 ch. 4-5) in an MCAP export: `/qt_model`, the model the station
//! builds from an ALICE's situations (message kind 16), the same way the live view does
//! (`app::qt_feed`), so the export shows what the station showed.
//!
//! Layer: formatting over `export::walk`, beside `scene`. A snapshot of the whole network is
//! large (a cell, its edges and JSON: some 100 bytes; 120-190 cells at equilibrium), so one is
//! written per second of robot time, not per situation (3 a second), plus the first.
//! Each holds the cells (id, position, updates), the edges with their confidences, the winner,
//! the model's corrected pose and its counters.

use protocol::Message;
use serde_json::{json, Value};

use super::mcap_msg::Body;
use super::{Direction, Item};
use crate::app::qt_state::QtState;

/// Robot time between two snapshots, milliseconds.
pub const SNAPSHOT_MS: u32 = 1000;

/// The model being rebuilt and when the last snapshot was written.
#[derive(Default)]
pub struct QtExport {
    qt: QtState,
    /// The robot-time period (`time_ms / SNAPSHOT_MS`) of the last snapshot.
    last_period: Option<u32>,
}

impl QtExport {
    /// Feeds this item's situation, if it is one, and adds a snapshot to `out` when due.
    pub fn extend(&mut self, item: &Item<'_>, out: &mut Vec<(&'static str, Body)>) {
        let Item::Frame {
            dir: Direction::FromRobot,
            msg: Message::AliceSituation(s),
            ..
        } = item
        else {
            return;
        };
        self.qt.on_situation(s);
        // The first situation of each period of robot time: one a second whatever the
        // situations' spacing (at 333 ms, waiting 1000 ms from the last would make it 1.33 s).
        let period = s.time_ms / SNAPSHOT_MS;
        if self.last_period != Some(period) && self.qt.model.is_some() {
            self.last_period = Some(period);
            out.push(("/qt_model", Body::Json(snapshot(&self.qt, s.time_ms))));
        }
    }
}

/// The model as one `/qt_model` message.
pub fn snapshot(qt: &QtState, time_ms: u32) -> Value {
    let Some(m) = qt.model.as_ref() else {
        return Value::Null;
    };
    let net = m.network();
    let cells: Vec<Value> = net
        .cells()
        .map(|(id, c)| {
            let (x, y) = net.position(id);
            json!({"id": id, "x_m": x, "y_m": y, "updates": c.updates})
        })
        .collect();
    let edges: Vec<Value> = net
        .edges()
        .map(|(a, b, w)| json!({"a": a, "b": b, "confidence": w}))
        .collect();
    let p = m.pose();
    json!({
        "robot_time_s": f64::from(time_ms) / 1000.0,
        "samples": m.stats().samples,
        "received": qt.received,
        "lost": qt.lost,
        "refused": qt.refused,
        "cell_count": cells.len(),
        "edge_count": edges.len(),
        "winner": m.winner(),
        "pose": {"x_m": p.x, "y_m": p.y, "heading_rad": p.heading},
        "cells": cells,
        "edges": edges,
    })
}

/// The channel's JSON schema: topic, schema name, schema.
pub fn channels() -> Vec<(&'static str, &'static str, Value)> {
    let num = || json!({"type": "number"});
    let int = || json!({"type": "integer"});
    let obj = |props: Value| json!({"type": "object", "properties": props});
    let array = |items: Value| json!({"type": "array", "items": items});
    vec![(
        "/qt_model",
        "station.QtModel",
        obj(json!({
            "robot_time_s": num(), "samples": int(), "received": int(), "lost": int(),
            "refused": int(), "cell_count": int(), "edge_count": int(),
            "winner": {"type": ["integer", "null"]},
            "pose": obj(json!({"x_m": num(), "y_m": num(), "heading_rad": num()})),
            "cells": array(obj(json!({"id": int(), "x_m": num(), "y_m": num(), "updates": int()}))),
            "edges": array(obj(json!({"a": int(), "b": int(), "confidence": num()}))),
        })),
    )]
}
