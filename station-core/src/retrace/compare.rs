//! Comparing the retraced robot's frames with the recorded ones, and the events of two
//! retraces.
//!
//! Layer: pure. Frames are compared as the COBS bytes between delimiters, byte for byte (the
//! emulator's truth frames were left out when loading: the firmware never sent them). The
//! first difference is named by message kind and field (the first field whose value differs in
//! the two decoded messages).

use protocol::{EventCode, Feed, FrameDecoder, Message};
use serde::Serialize;

use super::load::RecFrame;
use super::run::OutFrame;

/// The first frame that differs.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrameDivergence {
    /// Index among the firmware's frames.
    pub index: usize,
    pub file_offset: u64,
    pub step: u64,
    pub cycle: u64,
    pub time_ms: u32,
    pub kind: String,
    pub field: String,
    pub recorded: String,
    pub retraced: String,
}

fn decode(raw: &[u8]) -> Option<String> {
    let mut bytes = raw.to_vec();
    bytes.push(0);
    let mut dec = FrameDecoder::new();
    match dec.feed(&bytes) {
        Feed::Frame { frame, .. } => Some(format!("{:?}", frame.message)),
        _ => None,
    }
}

/// A frame's kind, from its header (COBS-decoded).
pub fn kind_of(raw: &[u8]) -> Option<protocol::Kind> {
    let mut bytes = raw.to_vec();
    bytes.push(0);
    let mut dec = FrameDecoder::new();
    match dec.feed(&bytes) {
        Feed::Frame { frame, .. } => Some(frame.header.kind),
        _ => None,
    }
}

/// The first frame of `retraced` unlike `recorded`'s, over the frames both have.
pub fn compare_frames(recorded: &[RecFrame], retraced: &[OutFrame]) -> Option<FrameDivergence> {
    let (i, (a, b)) = recorded
        .iter()
        .zip(retraced)
        .enumerate()
        .find(|(_, (a, b))| a.raw != b.raw)?;
    let (da, db) = (
        decode(&a.raw).unwrap_or_else(|| "(undecodable)".into()),
        decode(&b.raw).unwrap_or_else(|| "(undecodable)".into()),
    );
    let kind = |s: &str| s.split('(').next().unwrap_or("").to_string();
    let (field, ra, rb) = if kind(&da) != kind(&db) {
        ("kind".to_string(), kind(&da), kind(&db))
    } else {
        first_field_diff(&da, &db)
    };
    Some(FrameDivergence {
        index: i,
        file_offset: a.file_offset,
        step: b.step,
        cycle: b.cycle,
        time_ms: b.time_ms,
        kind: kind(&da),
        field,
        recorded: ra,
        retraced: rb,
    })
}

/// The innermost field name before the first difference of two Debug renderings, and the two
/// values there. Equal renderings (frames that differ only in sequence number or CRC) give
/// "header".
pub fn first_field_diff(a: &str, b: &str) -> (String, String, String) {
    let p = a
        .bytes()
        .zip(b.bytes())
        .position(|(x, y)| x != y)
        .unwrap_or(a.len().min(b.len()));
    if a == b {
        return ("header".into(), String::new(), String::new());
    }
    let before = &a[..p];
    let field = before
        .rfind(": ")
        .map(|i| {
            let name_end = i;
            let name_start = before[..name_end]
                .rfind(|c: char| !(c.is_alphanumeric() || c == '_'))
                .map_or(0, |j| j + 1);
            before[name_start..name_end].to_string()
        })
        .unwrap_or_default();
    let value = |s: &str| {
        let from = before.rfind(": ").map_or(p, |i| i + 2).min(s.len());
        let rest = &s[from..];
        let end = rest.find([',', '}', ')']).unwrap_or(rest.len());
        rest[..end].trim().to_string()
    };
    (field, value(a), value(b))
}

/// An event and when its frame was sent.
#[derive(Clone, Debug, PartialEq)]
pub struct EventAt {
    pub time_ms: u32,
    pub code: EventCode,
    pub value: i32,
}

/// The events among a retrace's frames.
pub fn events(frames: &[OutFrame]) -> Vec<EventAt> {
    frames
        .iter()
        .filter_map(|f| {
            let mut bytes = f.raw.clone();
            bytes.push(0);
            let mut dec = FrameDecoder::new();
            match dec.feed(&bytes) {
                Feed::Frame { frame, .. } => match frame.message {
                    Message::Event(e) => Some(EventAt {
                        time_ms: f.time_ms,
                        code: e.code,
                        value: e.value,
                    }),
                    _ => None,
                },
                _ => None,
            }
        })
        .collect()
}

/// Events in `a` and not in `b`, and in `b` and not in `a` (as multisets, matched in order).
pub fn diff_events(a: &[EventAt], b: &[EventAt]) -> (Vec<EventAt>, Vec<EventAt>) {
    let mut used = vec![false; b.len()];
    let mut only_a = Vec::new();
    for e in a {
        match b.iter().enumerate().find(|(j, x)| !used[*j] && *x == e) {
            Some((j, _)) => used[j] = true,
            None => only_a.push(e.clone()),
        }
    }
    let only_b = b
        .iter()
        .zip(&used)
        .filter(|(_, u)| !**u)
        .map(|(e, _)| e.clone())
        .collect();
    (only_a, only_b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_differing_field_is_named_with_both_values() {
        let a = "Telemetry(Telemetry { time_ms: 100, pose: Pose { x_mm: 12, y_mm: 5 } })";
        let b = "Telemetry(Telemetry { time_ms: 100, pose: Pose { x_mm: 13, y_mm: 5 } })";
        assert_eq!(
            first_field_diff(a, b),
            ("x_mm".to_string(), "12".to_string(), "13".to_string())
        );
    }

    #[test]
    fn events_are_matched_as_multisets() {
        let e = |t, v| EventAt {
            time_ms: t,
            code: EventCode::ModeChanged,
            value: v,
        };
        let (a, b) = diff_events(&[e(1, 1), e(2, 2), e(2, 2)], &[e(2, 2), e(3, 3)]);
        assert_eq!(a, vec![e(1, 1), e(2, 2)]);
        assert_eq!(b, vec![e(3, 3)]);
    }
}
