//! The MCAP container, written lean: the records of the MCAP v0 specification that an export
//! needs (header, schemas, channels, metadata, uncompressed chunks with their message indexes,
//! data end, and a summary with statistics, chunk and metadata indexes and summary offsets,
//! then the footer), each record's bytes put together in memory and written in a few large
//! writes.
//!
//! Layer: bytes to any `Write`; no seeking (a chunk is complete in memory before its header is
//! written). Why not the `mcap` crate's writer: it writes each message's header field by field
//! through three CRC-computing writer layers, about 30 % of an export of 10 minutes (issue 15);
//! here a message is appended to the chunk's buffer and each CRC is one pass over a whole
//! chunk. The `mcap` crate still reads these files back in the tests, which check every record
//! (message indexes, chunk indexes, statistics, the summary and data CRCs).
//!
//! Invariants: schema ids start at 1 (0 means "no schema"), channel ids at 0; a chunk holds
//! schemas, channels and messages only (metadata is written between chunks); the data CRC
//! covers every byte from the magic to the end of the last record before `DataEnd`, the summary
//! CRC every byte from the summary's start through the footer's `summary_offset_start`.

use std::collections::BTreeMap;
use std::io::{self, Write};

/// The file's first and last eight bytes.
pub const MAGIC: &[u8; 8] = b"\x89MCAP0\r\n";

mod op {
    pub const HEADER: u8 = 0x01;
    pub const FOOTER: u8 = 0x02;
    pub const SCHEMA: u8 = 0x03;
    pub const CHANNEL: u8 = 0x04;
    pub const MESSAGE: u8 = 0x05;
    pub const CHUNK: u8 = 0x06;
    pub const MESSAGE_INDEX: u8 = 0x07;
    pub const CHUNK_INDEX: u8 = 0x08;
    pub const STATISTICS: u8 = 0x0B;
    pub const METADATA: u8 = 0x0C;
    pub const METADATA_INDEX: u8 = 0x0D;
    pub const SUMMARY_OFFSET: u8 = 0x0E;
    pub const DATA_END: u8 = 0x0F;
}

/// A chunk is closed once its records pass this many bytes (the `mcap` crate's default).
const CHUNK_SIZE: usize = 1 << 20;

/// Bytes of a message record before its data: opcode, length, channel, sequence, two times.
const MESSAGE_HEAD: usize = 1 + 8 + 2 + 4 + 8 + 8;

fn u16le(out: &mut Vec<u8>, v: u16) {
    out.extend_from_slice(&v.to_le_bytes());
}

fn u32le(out: &mut Vec<u8>, v: u32) {
    out.extend_from_slice(&v.to_le_bytes());
}

fn u64le(out: &mut Vec<u8>, v: u64) {
    out.extend_from_slice(&v.to_le_bytes());
}

/// MCAP's `String`: a u32 byte length, then UTF-8.
fn string(out: &mut Vec<u8>, s: &str) {
    u32le(out, s.len() as u32);
    out.extend_from_slice(s.as_bytes());
}

/// A record: opcode, u64 length, then what `body` appends.
fn record(out: &mut Vec<u8>, opcode: u8, body: impl FnOnce(&mut Vec<u8>)) {
    out.push(opcode);
    let at = out.len();
    u64le(out, 0);
    body(out);
    let len = (out.len() - at - 8) as u64;
    out[at..at + 8].copy_from_slice(&len.to_le_bytes());
}

/// A `Map<u16, u64>` (chunk index offsets, channel message counts): its byte length, then
/// each pair.
fn int_map(out: &mut Vec<u8>, map: &BTreeMap<u16, u64>) {
    u32le(out, (map.len() * 10) as u32);
    for (k, v) in map {
        u16le(out, *k);
        u64le(out, *v);
    }
}

/// A `Map<string, string>`: its byte length, then each pair.
fn string_map(out: &mut Vec<u8>, map: &BTreeMap<String, String>) {
    let at = out.len();
    u32le(out, 0);
    for (k, v) in map {
        string(out, k);
        string(out, v);
    }
    let len = (out.len() - at - 4) as u32;
    out[at..at + 4].copy_from_slice(&len.to_le_bytes());
}

/// The writer below, counting its position and computing the data section's CRC.
struct Counted<W> {
    inner: W,
    at: u64,
    crc: crc32fast::Hasher,
}

impl<W: Write> Counted<W> {
    fn put(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.inner.write_all(bytes)?;
        self.crc.update(bytes);
        self.at += bytes.len() as u64;
        Ok(())
    }
}

/// The chunk's index entry (the summary's `ChunkIndex`).
struct ChunkIndex {
    start_time: u64,
    end_time: u64,
    offset: u64,
    length: u64,
    message_index_offsets: BTreeMap<u16, u64>,
    message_index_length: u64,
    size: u64,
}

/// An MCAP file being written. Records are added with [`Writer::add_schema`],
/// [`Writer::add_channel`], [`Writer::metadata`] and [`Writer::message`]; [`Writer::finish`]
/// writes the summary and footer.
pub struct Writer<W: Write> {
    out: Counted<W>,
    /// The open chunk's records, its message times, and per channel its messages' log times
    /// and offsets within the records.
    chunk: Vec<u8>,
    chunk_times: Option<(u64, u64)>,
    chunk_index: BTreeMap<u16, Vec<(u64, u64)>>,
    /// The schema and channel records, repeated in the summary.
    schemas: Vec<Vec<u8>>,
    channels: Vec<Vec<u8>>,
    chunks: Vec<ChunkIndex>,
    metadata: Vec<(u64, u64, String)>,
    message_count: u64,
    times: Option<(u64, u64)>,
    channel_counts: BTreeMap<u16, u64>,
    /// Reused scratch for records written outside chunks.
    scratch: Vec<u8>,
}

impl<W: Write> Writer<W> {
    /// Starts a file: the magic and the header (`profile`, `library`).
    pub fn new(inner: W, profile: &str, library: &str) -> io::Result<Writer<W>> {
        let mut w = Writer {
            out: Counted {
                inner,
                at: 0,
                crc: crc32fast::Hasher::new(),
            },
            chunk: Vec::with_capacity(CHUNK_SIZE + 64 * 1024),
            chunk_times: None,
            chunk_index: BTreeMap::new(),
            schemas: Vec::new(),
            channels: Vec::new(),
            chunks: Vec::new(),
            metadata: Vec::new(),
            message_count: 0,
            times: None,
            channel_counts: BTreeMap::new(),
            scratch: Vec::new(),
        };
        let mut head = MAGIC.to_vec();
        record(&mut head, op::HEADER, |out| {
            string(out, profile);
            string(out, library);
        });
        w.out.put(&head)?;
        Ok(w)
    }

    /// Adds a schema (into the open chunk, or between chunks); returns its id.
    pub fn add_schema(&mut self, name: &str, encoding: &str, data: &[u8]) -> io::Result<u16> {
        let id = self.schemas.len() as u16 + 1;
        let mut rec = Vec::with_capacity(data.len() + name.len() + 32);
        record(&mut rec, op::SCHEMA, |out| {
            u16le(out, id);
            string(out, name);
            string(out, encoding);
            u32le(out, data.len() as u32);
            out.extend_from_slice(data);
        });
        self.definition(&rec)?;
        self.schemas.push(rec);
        Ok(id)
    }

    /// Adds a channel (into the open chunk, or between chunks); returns its id.
    pub fn add_channel(
        &mut self,
        schema_id: u16,
        topic: &str,
        message_encoding: &str,
        metadata: &BTreeMap<String, String>,
    ) -> io::Result<u16> {
        let id = self.channels.len() as u16;
        let mut rec = Vec::with_capacity(topic.len() + 32);
        record(&mut rec, op::CHANNEL, |out| {
            u16le(out, id);
            u16le(out, schema_id);
            string(out, topic);
            string(out, message_encoding);
            string_map(out, metadata);
        });
        self.definition(&rec)?;
        self.channels.push(rec);
        Ok(id)
    }

    /// A schema or channel record goes where the next messages go: into the open chunk, or
    /// straight into the data section when none is open.
    fn definition(&mut self, rec: &[u8]) -> io::Result<()> {
        if self.chunk.is_empty() {
            self.out.put(rec)
        } else {
            self.chunk.extend_from_slice(rec);
            Ok(())
        }
    }

    /// Writes a metadata record (between chunks: the open one is closed first).
    pub fn metadata(&mut self, name: &str, map: &BTreeMap<String, String>) -> io::Result<()> {
        self.close_chunk()?;
        let mut rec = std::mem::take(&mut self.scratch);
        rec.clear();
        record(&mut rec, op::METADATA, |out| {
            string(out, name);
            string_map(out, map);
        });
        self.metadata
            .push((self.out.at, rec.len() as u64, name.to_string()));
        let done = self.out.put(&rec);
        self.scratch = rec;
        done
    }

    /// Appends a message on `channel` whose data `body` appends to the buffer it is given.
    pub fn message(
        &mut self,
        channel: u16,
        sequence: u32,
        log_time: u64,
        publish_time: u64,
        body: impl FnOnce(&mut Vec<u8>),
    ) -> io::Result<()> {
        let offset = self.chunk.len() as u64;
        let chunk = &mut self.chunk;
        chunk.push(op::MESSAGE);
        let len_at = chunk.len();
        u64le(chunk, 0);
        u16le(chunk, channel);
        u32le(chunk, sequence);
        u64le(chunk, log_time);
        u64le(chunk, publish_time);
        body(chunk);
        let len = (chunk.len() - len_at - 8) as u64;
        chunk[len_at..len_at + 8].copy_from_slice(&len.to_le_bytes());
        debug_assert!(chunk.len() - offset as usize >= MESSAGE_HEAD);

        self.chunk_times = Some(widen(self.chunk_times, log_time));
        self.times = Some(widen(self.times, log_time));
        self.chunk_index
            .entry(channel)
            .or_default()
            .push((log_time, offset));
        self.message_count += 1;
        *self.channel_counts.entry(channel).or_default() += 1;
        if self.chunk.len() >= CHUNK_SIZE {
            self.close_chunk()?;
        }
        Ok(())
    }

    /// Writes the open chunk and its message indexes, if it holds any record.
    fn close_chunk(&mut self) -> io::Result<()> {
        if self.chunk.is_empty() {
            return Ok(());
        }
        let (start_time, end_time) = self.chunk_times.take().unwrap_or((0, 0));
        let size = self.chunk.len() as u64;
        let crc = crc32fast::hash(&self.chunk);
        let offset = self.out.at;
        let mut head = std::mem::take(&mut self.scratch);
        head.clear();
        // Chunk: start, end, uncompressed size and CRC, compression "" (none), then the
        // records with their u64 length (the compressed size, the same when uncompressed).
        head.push(op::CHUNK);
        u64le(&mut head, 8 + 8 + 8 + 4 + 4 + 8 + size);
        u64le(&mut head, start_time);
        u64le(&mut head, end_time);
        u64le(&mut head, size);
        u32le(&mut head, crc);
        string(&mut head, "");
        u64le(&mut head, size);
        self.out.put(&head)?;
        self.out.put(&self.chunk)?;
        let length = self.out.at - offset;
        self.chunk.clear();

        head.clear();
        let index_start = self.out.at;
        let mut message_index_offsets = BTreeMap::new();
        for (channel, entries) in &self.chunk_index {
            message_index_offsets.insert(*channel, index_start + head.len() as u64);
            record(&mut head, op::MESSAGE_INDEX, |out| {
                u16le(out, *channel);
                u32le(out, (entries.len() * 16) as u32);
                for (t, at) in entries {
                    u64le(out, *t);
                    u64le(out, *at);
                }
            });
        }
        self.chunk_index.clear();
        self.out.put(&head)?;
        self.chunks.push(ChunkIndex {
            start_time,
            end_time,
            offset,
            length,
            message_index_offsets,
            message_index_length: head.len() as u64,
            size,
        });
        self.scratch = head;
        Ok(())
    }

    /// Closes the data section and writes the summary, the footer and the closing magic;
    /// returns the writer below, flushed.
    pub fn finish(mut self) -> io::Result<W> {
        self.close_chunk()?;
        let data_crc = self.out.crc.clone().finalize();
        let mut end = Vec::new();
        record(&mut end, op::DATA_END, |out| u32le(out, data_crc));
        self.out.put(&end)?;

        let summary_start = self.out.at;
        let mut s = Vec::new();
        // Each group's records, and where the group lies (a SummaryOffset each).
        let mut groups: Vec<(u8, u64, u64)> = Vec::new();
        let mut group = |s: &mut Vec<u8>, opcode: u8, write: &mut dyn FnMut(&mut Vec<u8>)| {
            let at = s.len();
            write(s);
            if s.len() > at {
                groups.push((opcode, summary_start + at as u64, (s.len() - at) as u64));
            }
        };
        group(&mut s, op::SCHEMA, &mut |s| {
            self.schemas.iter().for_each(|r| s.extend_from_slice(r))
        });
        group(&mut s, op::CHANNEL, &mut |s| {
            self.channels.iter().for_each(|r| s.extend_from_slice(r))
        });
        let (start_time, end_time) = self.times.unwrap_or((0, 0));
        group(&mut s, op::STATISTICS, &mut |s| {
            record(s, op::STATISTICS, |out| {
                u64le(out, self.message_count);
                u16le(out, self.schemas.len() as u16);
                u32le(out, self.channels.len() as u32);
                u32le(out, 0); // attachments
                u32le(out, self.metadata.len() as u32);
                u32le(out, self.chunks.len() as u32);
                u64le(out, start_time);
                u64le(out, end_time);
                int_map(out, &self.channel_counts);
            })
        });
        group(&mut s, op::CHUNK_INDEX, &mut |s| {
            for c in &self.chunks {
                record(s, op::CHUNK_INDEX, |out| {
                    u64le(out, c.start_time);
                    u64le(out, c.end_time);
                    u64le(out, c.offset);
                    u64le(out, c.length);
                    int_map(out, &c.message_index_offsets);
                    u64le(out, c.message_index_length);
                    string(out, "");
                    u64le(out, c.size);
                    u64le(out, c.size);
                });
            }
        });
        group(&mut s, op::METADATA_INDEX, &mut |s| {
            for (offset, length, name) in &self.metadata {
                record(s, op::METADATA_INDEX, |out| {
                    u64le(out, *offset);
                    u64le(out, *length);
                    string(out, name);
                });
            }
        });
        let summary_offset_start = summary_start + s.len() as u64;
        for (opcode, start, length) in groups {
            record(&mut s, op::SUMMARY_OFFSET, |out| {
                out.push(opcode);
                u64le(out, start);
                u64le(out, length);
            });
        }
        s.push(op::FOOTER);
        u64le(&mut s, 8 + 8 + 4);
        u64le(&mut s, summary_start);
        u64le(&mut s, summary_offset_start);
        let summary_crc = crc32fast::hash(&s);
        u32le(&mut s, summary_crc);
        s.extend_from_slice(MAGIC);
        self.out.put(&s)?;
        self.out.inner.flush()?;
        Ok(self.out.inner)
    }
}

/// `times` widened to include `t`.
fn widen(times: Option<(u64, u64)>, t: u64) -> (u64, u64) {
    match times {
        None => (t, t),
        Some((a, b)) => (a.min(t), b.max(t)),
    }
}
