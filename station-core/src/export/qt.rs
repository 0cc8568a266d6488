//! The QT world model (seed 001 ch. 4-5) in an MCAP export: `/qt_model`, the model the station
//! builds from an ALICE's situations (message kind 16), the same way the live view does
//! (`app::qt_feed`), so the export shows what the station showed.
//!
//! Layer: formatting over `export::walk`, beside `scene`. A snapshot of the whole network is
//! large (a cell, its edges and JSON: some 160 bytes; 120-190 cells at equilibrium, 2,000 at
//! the model's cap), so one is written per second of robot time, not per situation (3 a
//! second), plus the first. Each holds the cells (id, position, updates), the edges with their
//! confidences, the winner, the model's corrected pose and its counters.
//!
//! Budget: the seconds are the situations' claim, and random situations grow the network to
//! its cap, so a 116 KB recording of situations a second apart gave a 277 MB file (issue 31).
//! The snapshots may take at most [`BUDGET_FLOOR`] bytes plus [`BUDGET_PER_BYTE`] per byte of
//! the recording's records walked so far; a snapshot due when the budget cannot take one as
//! large as the last is left out (the next situation tries again), and [`QtExport::note`] says
//! how many were. An honest ALICE recording (1.15 KB a robot second, telemetry and
//! situations) earns about 37 KB a second, room for 230 cells a snapshot every second.

use protocol::Message;
use serde_json::{json, Value};

use super::mcap_msg::Body;
use super::{Direction, Item};
use crate::qt_state::QtState;
use crate::record::Record;

/// Robot time between two snapshots, milliseconds.
pub const SNAPSHOT_MS: u32 = 1000;
/// Snapshot bytes allowed before the recording has earned any.
pub const BUDGET_FLOOR: u64 = 1 << 20;
/// Snapshot bytes each byte of the recording's records earns.
pub const BUDGET_PER_BYTE: u64 = 32;

/// The model being rebuilt, when the last snapshot was written, and the budget.
pub struct QtExport<'a> {
    qt: QtState,
    /// The robot-time period (`time_ms / SNAPSHOT_MS`) of the last snapshot.
    last_period: Option<u32>,
    /// A period whose snapshot is due but was left out (so far).
    pending: Option<u32>,
    /// The recording's records, the next not yet counted, and the data bytes counted.
    records: &'a [Record],
    next: usize,
    read: u64,
    /// Snapshot bytes written, the last snapshot's size, due snapshots left out, most cells.
    written: u64,
    last_size: u64,
    left_out: u64,
    most_cells: usize,
}

impl<'a> QtExport<'a> {
    /// The export of the model `records` build.
    pub fn new(records: &'a [Record]) -> Self {
        QtExport {
            qt: QtState::default(),
            last_period: None,
            pending: None,
            records,
            next: 0,
            read: 0,
            written: 0,
            last_size: 0,
            left_out: 0,
            most_cells: 0,
        }
    }

    /// Feeds this item's situation, if it is one, and adds a snapshot to `out` when due and
    /// within the budget.
    pub fn extend(&mut self, item: &Item<'_>, out: &mut Vec<(&'static str, Body)>) {
        let Item::Frame {
            t_us,
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
        if self.last_period == Some(period) || self.qt.model.is_none() {
            return;
        }
        if self.pending.is_some_and(|p| p != period) {
            self.left_out += 1;
        }
        self.pending = Some(period);
        let cells = self.qt.model.as_ref().map_or(0, |m| m.network().len());
        self.most_cells = self.most_cells.max(cells);
        while let Some(r) = self.records.get(self.next).filter(|r| r.t_us <= *t_us) {
            self.read += r.data.len() as u64;
            self.next += 1;
        }
        let budget = BUDGET_FLOOR.saturating_add(self.read.saturating_mul(BUDGET_PER_BYTE));
        if self.written.saturating_add(self.last_size) > budget {
            return;
        }
        let json = snapshot_json(&self.qt, s.time_ms);
        self.last_size = json.len() as u64;
        self.written += self.last_size;
        self.last_period = Some(period);
        self.pending = None;
        out.push(("/qt_model", Body::JsonText(json)));
    }

    /// What the budget left out, if anything, for the export's report.
    pub fn note(&self) -> Option<String> {
        let left_out = self.left_out + u64::from(self.pending.is_some());
        (left_out > 0).then(|| {
            format!(
                "/qt_model: {left_out} of the snapshots due (one a second of robot time) left \
                 out to keep the export in proportion to the recording: snapshots take at most \
                 {BUDGET_FLOOR} bytes plus {BUDGET_PER_BYTE} per recorded byte ({} bytes \
                 written; the network reached {} cells, the last snapshot {} bytes)",
                self.written, self.most_cells, self.last_size
            )
        })
    }
}

/// The snapshot's JSON text.
fn snapshot_json(qt: &QtState, time_ms: u32) -> Vec<u8> {
    let mut out = Vec::new();
    let _ = crate::json_text::write(&mut out, &snapshot(qt, time_ms));
    out
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
