//! A recording's robot-to-station frames, split out for retracing: the hardware trace (kind 15,
//! joined by offset), the firmware's other frames as the station read them (byte for byte, to
//! compare with the retraced ones), and the emulator's truth.
//!
//! Layer: pure over the file's bytes (read whole: memory is linear in the file). Every record
//! is checked as `record::parse_record` checks it, and its time as `record::check_time` does
//! (never going back, at most a year); a damaged record is an error with the file's byte
//! offset; a trace frame whose offset jumps (lost on the wire), or a second stream, is reported
//! with it.

use protocol::{Feed, FrameDecoder, Message};

use crate::record::{check_time, parse_header, parse_record, LinkState, RecordKind};

/// One frame from the robot, as read.
#[derive(Clone, Debug)]
pub struct RecFrame {
    /// Byte offset in the file of the record the frame ended in.
    pub file_offset: u64,
    /// The COBS bytes without the 0x00 delimiter.
    pub raw: Vec<u8>,
}

/// Where the trace stream stopped before the recording did.
#[derive(Clone, Debug, PartialEq)]
pub enum TraceCut {
    /// A trace frame is missing (lost on the wire): the next one starts at `got`, not `want`.
    Lost {
        want: u32,
        got: u32,
        file_offset: u64,
    },
    /// Tracing was switched off and on: a second stream starts here (not retraced).
    Restarted { file_offset: u64 },
}

/// What retracing needs from a recording.
#[derive(Debug, Default)]
pub struct Loaded {
    /// The trace stream.
    pub trace: Vec<u8>,
    /// For each trace frame: (stream offset of its first byte, file offset of its record).
    pub trace_map: Vec<(usize, u64)>,
    pub cut: Option<TraceCut>,
    /// The firmware's frames (its trace's too, not the emulator's truth), in order.
    pub frames: Vec<RecFrame>,
    /// The emulator's truth: (robot time ms, heading mrad).
    pub truth: Vec<(u32, i32)>,
    /// The robot's firmware version, from its HelloReply.
    pub firmware_version: Option<String>,
    /// Frames that did not decode (CRC, COBS): not comparable, counted.
    pub bad_frames: u64,
    /// The robot said how many passes its trace dropped (the largest count seen).
    pub dropped_steps: u32,
    /// The recording's span: its last record's time less its first's, µs.
    pub span_us: u64,
}

impl Loaded {
    /// The file offset of the record that carried trace byte `at`.
    pub fn file_offset_of(&self, at: usize) -> u64 {
        let i = self.trace_map.partition_point(|&(s, _)| s <= at);
        self.trace_map
            .get(i.saturating_sub(1))
            .map_or(0, |&(_, f)| f)
    }
}

/// Reads the recording's bytes. Err: what is wrong and the byte offset.
pub fn load(bytes: &[u8]) -> Result<Loaded, String> {
    let (header, mut at) = parse_header(bytes).map_err(|e| e.to_string())?;
    let links = header.meta.link_ports().len();
    let mut out = Loaded::default();
    let mut frame: Vec<u8> = Vec::new();
    let mut stream_open = false;
    let (mut first_t, mut last_t) = (None, 0);
    while at < bytes.len() {
        let (rec, next) =
            parse_record(bytes, at, header.version, links).map_err(|e| e.to_string())?;
        check_time(last_t, rec.t_us, at).map_err(|e| e.to_string())?;
        last_t = rec.t_us;
        let offset = at as u64;
        at = next;
        let first_t = *first_t.get_or_insert(rec.t_us);
        out.span_us = rec.t_us - first_t;
        // A recording of several robots: the first link's robot is retraced.
        if rec.link != 0 {
            continue;
        }
        match rec.kind {
            RecordKind::FromRobot => {
                for &b in &rec.data {
                    if b != 0 {
                        // A frame longer than any the protocol makes is noise: drop it.
                        if frame.len() < protocol::MAX_FRAME {
                            frame.push(b);
                        }
                        continue;
                    }
                    let raw = std::mem::take(&mut frame);
                    if !raw.is_empty() {
                        take_frame(&mut out, raw, offset, &mut stream_open);
                    }
                }
            }
            RecordKind::Link => {
                // A closed port ends whatever frame was half read.
                if matches!(rec.link(), Some((LinkState::Closed, _))) {
                    frame.clear();
                }
            }
            _ => {}
        }
    }
    Ok(out)
}

fn take_frame(out: &mut Loaded, raw: Vec<u8>, file_offset: u64, stream_open: &mut bool) {
    let mut dec = FrameDecoder::new();
    let mut with_end = raw.clone();
    with_end.push(0);
    let message = match dec.feed(&with_end) {
        Feed::Frame { frame, .. } => frame.message,
        _ => {
            out.bad_frames += 1;
            return;
        }
    };
    if !matches!(message, Message::EmuTruth(_)) {
        // The firmware's own frames, its trace included: a retrace re-sends them all.
        out.frames.push(RecFrame {
            file_offset,
            raw: raw.clone(),
        });
    }
    match message {
        Message::HalTrace(t) => {
            out.dropped_steps = out.dropped_steps.max(t.dropped_steps);
            if out.cut.is_some() {
                return;
            }
            if t.offset == 0 && *stream_open {
                out.cut = Some(TraceCut::Restarted { file_offset });
                return;
            }
            let want = out.trace.len() as u32;
            if t.offset != want {
                out.cut = Some(TraceCut::Lost {
                    want,
                    got: t.offset,
                    file_offset,
                });
                return;
            }
            *stream_open = true;
            out.trace_map.push((out.trace.len(), file_offset));
            out.trace.extend_from_slice(t.data);
        }
        Message::EmuTruth(t) => out.truth.push((t.time_ms, i32::from(t.pose.heading_mrad))),
        Message::HelloReply(r) => {
            out.firmware_version
                .get_or_insert_with(|| r.firmware_version.to_string());
        }
        _ => {}
    }
}
