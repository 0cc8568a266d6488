//! Reading exported MCAP messages back as JSON values, whatever their channel's encoding: `json`
//! as it is, `protobuf` decoded by the schema the file carries (its `FileDescriptorSet`), the way
//! Foxglove reads it (protobufjs `toObject` with defaults: a plain field left out is its
//! default, a proto3 `optional` field left out is no value, here `null`; a
//! `google.protobuf.Timestamp` is `{sec, nsec}`). The decoder knows nothing of the station's
//! schemas: the names, numbers and types all come from the file.
#![allow(clippy::unwrap_used, clippy::panic, dead_code)]

pub mod tui;

use std::collections::BTreeMap;

use serde_json::{json, Map, Value};

/// A field as a `FieldDescriptorProto` declares it.
#[derive(Clone, Debug, Default)]
pub struct FieldDesc {
    pub name: String,
    pub number: u64,
    /// 1 optional (proto3: plain), 3 repeated.
    pub label: u64,
    /// descriptor.proto's type numbers: 1 double, 3 int64, 5 int32, 8 bool, 9 string,
    /// 11 message, 13 uint32.
    pub ty: u64,
    pub type_name: String,
    pub proto3_optional: bool,
}

/// Every message of a `FileDescriptorSet`, by full name (`foxglove.PoseInFrame`).
pub type Messages = BTreeMap<String, Vec<FieldDesc>>;

/// One wire-format field: number, then a varint, 8 bytes, or a length-delimited slice.
enum Wire<'a> {
    Varint(u64),
    Fixed64(u64),
    Bytes(&'a [u8]),
}

fn varint(b: &[u8], at: &mut usize) -> u64 {
    let mut v = 0u64;
    for shift in (0..64).step_by(7) {
        let byte = b[*at];
        *at += 1;
        v |= u64::from(byte & 0x7f) << shift;
        if byte < 0x80 {
            return v;
        }
    }
    panic!("varint too long");
}

/// The fields of a message's bytes, in order.
fn fields(b: &[u8]) -> Vec<(u64, Wire<'_>)> {
    let mut at = 0;
    let mut out = Vec::new();
    while at < b.len() {
        let key = varint(b, &mut at);
        let value = match key & 7 {
            0 => Wire::Varint(varint(b, &mut at)),
            1 => {
                let v = u64::from_le_bytes(b[at..at + 8].try_into().unwrap());
                at += 8;
                Wire::Fixed64(v)
            }
            2 => {
                let len = varint(b, &mut at) as usize;
                let s = &b[at..at + len];
                at += len;
                Wire::Bytes(s)
            }
            w => panic!("wire type {w} at byte {at}"),
        };
        out.push((key >> 3, value));
    }
    out
}

fn text(b: &[u8]) -> String {
    String::from_utf8(b.to_vec()).unwrap()
}

/// Parses a `FileDescriptorSet` (file = 1; a file's package = 2, message_type = 4; a message's
/// name = 1, field = 2; a field's name = 1, number = 3, label = 4, type = 5, type_name = 6,
/// proto3_optional = 17).
pub fn descriptor_set(b: &[u8]) -> Messages {
    let mut out = Messages::new();
    for (n, file) in fields(b) {
        let (1, Wire::Bytes(file)) = (n, file) else {
            continue;
        };
        let mut package = String::new();
        let mut messages = Vec::new();
        for (n, v) in fields(file) {
            match (n, v) {
                (2, Wire::Bytes(p)) => package = text(p),
                (4, Wire::Bytes(m)) => messages.push(m),
                _ => {}
            }
        }
        for m in messages {
            let mut name = String::new();
            let mut descs = Vec::new();
            for (n, v) in fields(m) {
                match (n, v) {
                    (1, Wire::Bytes(s)) => name = text(s),
                    (2, Wire::Bytes(f)) => {
                        let mut d = FieldDesc::default();
                        for (n, v) in fields(f) {
                            match (n, v) {
                                (1, Wire::Bytes(s)) => d.name = text(s),
                                (3, Wire::Varint(x)) => d.number = x,
                                (4, Wire::Varint(x)) => d.label = x,
                                (5, Wire::Varint(x)) => d.ty = x,
                                (6, Wire::Bytes(s)) => {
                                    d.type_name = text(s).trim_start_matches('.').to_string()
                                }
                                (17, Wire::Varint(x)) => d.proto3_optional = x != 0,
                                _ => {}
                            }
                        }
                        descs.push(d);
                    }
                    _ => {}
                }
            }
            out.insert(format!("{package}.{name}"), descs);
        }
    }
    out
}

/// A scalar's value from its wire form.
fn scalar(d: &FieldDesc, w: &Wire<'_>) -> Value {
    match (d.ty, w) {
        (1, Wire::Fixed64(bits)) => json!(f64::from_bits(*bits)),
        (3, Wire::Varint(v)) => json!(*v as i64),
        (5, Wire::Varint(v)) => json!(*v as i64 as i32),
        (8, Wire::Varint(v)) => json!(*v != 0),
        (13, Wire::Varint(v)) => json!(*v as u32),
        (9, Wire::Bytes(s)) => json!(text(s)),
        (t, _) => panic!("{}: type {t} with another wire type", d.name),
    }
}

fn default(d: &FieldDesc) -> Value {
    match d.ty {
        1 => json!(0.0),
        3 | 5 | 13 => json!(0),
        8 => json!(false),
        9 => json!(""),
        _ => Value::Null,
    }
}

/// Decodes message `name`'s bytes by `schema`.
pub fn decode(schema: &Messages, name: &str, b: &[u8]) -> Value {
    let descs = schema
        .get(name)
        .unwrap_or_else(|| panic!("{name} not in the schema"));
    let got = fields(b);
    let mut obj = Map::new();
    for d in descs {
        let mine: Vec<&Wire<'_>> = got
            .iter()
            .filter(|(n, _)| *n == d.number)
            .map(|(_, w)| w)
            .collect();
        let value = if d.label == 3 {
            let mut items = Vec::new();
            for w in mine {
                match (d.ty, w) {
                    // Packed scalars: a run of varints.
                    (13 | 3 | 5 | 8, Wire::Bytes(run)) => {
                        let mut at = 0;
                        while at < run.len() {
                            let v = varint(run, &mut at);
                            items.push(scalar(d, &Wire::Varint(v)));
                        }
                    }
                    (11, Wire::Bytes(m)) => items.push(decode(schema, &d.type_name, m)),
                    _ => items.push(scalar(d, w)),
                }
            }
            Value::Array(items)
        } else {
            match mine.last() {
                None if d.proto3_optional => Value::Null,
                None if d.ty == 11 => Value::Null,
                None => default(d),
                Some(Wire::Bytes(m)) if d.ty == 11 => decode(schema, &d.type_name, m),
                Some(w) => scalar(d, w),
            }
        };
        obj.insert(d.name.clone(), value);
    }
    if name == "google.protobuf.Timestamp" {
        return json!({"sec": obj["seconds"], "nsec": obj["nanos"]});
    }
    Value::Object(obj)
}

/// A message read back as JSON: `json` parsed, `protobuf` decoded by its channel's schema.
pub fn message_json(m: &mcap::Message<'_>) -> Value {
    let schema = m.channel.schema.as_ref().unwrap();
    match m.channel.message_encoding.as_str() {
        "json" => {
            assert_eq!(schema.encoding, "jsonschema");
            serde_json::from_slice(&m.data).unwrap()
        }
        "protobuf" => {
            assert_eq!(schema.encoding, "protobuf");
            decode(&descriptor_set(&schema.data), &schema.name, &m.data)
        }
        e => panic!("{}: encoding {e}", m.channel.topic),
    }
}

/// Checks an MCAP file as a whole with the `mcap` crate: read start to end with every CRC
/// validated (data section, summary section, each chunk before its messages); the summary's
/// statistics count what the stream holds; and every chunk's message indexes hold each of its
/// messages once, in log-time order per channel, and find those sampled. Returns the number of chunks.
pub fn check_container(bytes: &[u8]) -> usize {
    use mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default()
            .with_validate_data_section_crc(true)
            .with_validate_summary_section_crc(true)
            .with_prevalidate_chunk_crcs(true),
    );
    let mut at = 0;
    let mut streamed = 0u64;
    while let Some(event) = reader.next_event() {
        match event.unwrap() {
            LinearReadEvent::ReadRequest(n) => {
                let n = n.min(bytes.len() - at);
                reader.insert(n).copy_from_slice(&bytes[at..at + n]);
                reader.notify_read(n);
                at += n;
            }
            LinearReadEvent::Record { opcode, .. } => streamed += u64::from(opcode == 0x05),
        }
    }
    let summary = mcap::Summary::read(bytes).unwrap().unwrap();
    let stats = summary.stats.as_ref().unwrap();
    assert_eq!(stats.message_count, streamed);
    assert_eq!(stats.chunk_count as usize, summary.chunk_indexes.len());
    assert_eq!(stats.channel_message_counts.values().sum::<u64>(), streamed);
    let mut indexed = 0u64;
    for chunk in &summary.chunk_indexes {
        let indexes = summary.read_message_indexes(bytes, chunk).unwrap();
        for (channel, entries) in indexes {
            assert!(entries.windows(2).all(|w| w[0].log_time <= w[1].log_time));
            indexed += entries.len() as u64;
            // Each seek parses its chunk again: the first, the last and every 101st.
            let last = entries.len().saturating_sub(1);
            for (i, e) in entries.into_iter().enumerate() {
                if i % 101 != 0 && i != last {
                    continue;
                }
                let m = summary.seek_message(bytes, chunk, &e).unwrap();
                assert_eq!(m.channel.id, channel.id);
                assert_eq!(m.log_time, e.log_time);
                assert!(
                    chunk.message_start_time <= m.log_time && m.log_time <= chunk.message_end_time
                );
            }
        }
    }
    assert_eq!(indexed, streamed, "every message is indexed once");
    summary.chunk_indexes.len()
}
