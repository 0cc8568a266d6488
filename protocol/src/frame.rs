//! Frame codec: header + postcard payload + CRC-32C, COBS-encoded, ended by 0x00.
//!
//! Layer: pure functions over caller buffers. `encode` writes one frame into a caller's slice;
//! `FrameDecoder` is fed byte chunks of any size and yields frames or typed errors, always
//! resynchronising at the next 0x00 (COBS guarantees 0x00 appears nowhere else). It holds one
//! fixed buffer of `MAX_ENCODED` bytes, never allocates and never panics: every index below is
//! bounded by a length check or a `get`. A frame it yields has passed COBS, length, CRC,
//! version, kind and a complete payload decode with no trailing bytes.
//!
//! Decoded frame layout (before COBS):
//! `[version u8][kind u8][seq u16 LE][payload: postcard][crc32c u32 LE]`, with the CRC taken
//! over version..payload. A signed frame (PROTOCOL.md §13) has `SIGNED_FLAG` in the version
//! byte and `[link id u8][timestamp u48 LE][mac 6]` between payload and CRC, the CRC then
//! covering the trailer too; the decoder parses the trailer (`trailer`), `sign::LinkAuth`
//! judges it and `sign::encode_signed` makes it.

use core::fmt;

use crate::msg::{
    Ack, Command, EmuTruth, Event, Heartbeat, Hello, HelloReply, Kind, Log, Message, Nack,
    Telemetry, TransferAck, TransferBegin, TransferChunk,
};
use crate::trailer::{Signature, MAC_LEN, SIGNATURE_LEN, SIGNED_FLAG, TIMESTAMP_LEN};

/// The protocol version carried in every header.
pub const PROTOCOL_VERSION: u8 = 1;
/// Header bytes: version, kind, sequence number (u16 little-endian).
pub const HEADER_LEN: usize = 4;
/// CRC-32C bytes at the end of the decoded frame.
pub const CRC_LEN: usize = 4;
/// Largest frame on the wire, COBS overhead and the 0x00 delimiter included.
pub const MAX_FRAME: usize = 256;
/// Largest COBS-encoded frame without its delimiter.
pub const MAX_ENCODED: usize = MAX_FRAME - 1;
/// Largest decoded frame: header + payload + CRC.
pub const MAX_RAW: usize = 254;
/// Largest postcard payload.
pub const MAX_PAYLOAD: usize = MAX_RAW - HEADER_LEN - CRC_LEN;
/// Largest postcard payload of a signed frame.
pub const MAX_SIGNED_PAYLOAD: usize = MAX_PAYLOAD - SIGNATURE_LEN;

// COBS adds at most one byte per 254: a 254-byte raw frame encodes to 255, plus the 0x00.
const _: () = assert!(cobs::max_encoding_length(MAX_RAW) <= MAX_ENCODED);

/// CRC-32C (Castagnoli): poly 0x1EDC6F41, reflected, init and xor-out 0xFFFFFFFF.
/// Check value over b"123456789" is 0xE3069283.
pub const CRC32C: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISCSI);

/// CRC-32C of a byte string, as used for frames and for whole transferred objects.
pub fn crc32c(bytes: &[u8]) -> u32 {
    CRC32C.checksum(bytes)
}

/// A frame's header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Header {
    pub version: u8,
    pub kind: Kind,
    pub seq: u16,
}

/// A decoded frame that passed the CRC and decoded. Borrowed strings and byte slices point
/// into the decoder. A signature is parsed, not yet verified: `sign::LinkAuth::verify` does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame<'a> {
    pub header: Header,
    pub message: Message<'a>,
    pub signature: Option<Signature<'a>>,
}

/// Why a frame could not be encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EncodeError {
    /// The payload does not fit `MAX_PAYLOAD` bytes (a string or chunk too long).
    PayloadTooLarge,
    /// The output slice is shorter than the encoded frame (use `MAX_FRAME`).
    OutputTooSmall,
    /// A string is longer than its field allows (`Message::check_limits`).
    FieldTooLong { field: &'static str, limit: usize },
}

impl fmt::Display for EncodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EncodeError::PayloadTooLarge => {
                write!(f, "payload larger than {MAX_PAYLOAD} bytes")
            }
            EncodeError::OutputTooSmall => write!(f, "output buffer smaller than the frame"),
            EncodeError::FieldTooLong { field, limit } => {
                write!(f, "{field} is longer than its limit of {limit} bytes")
            }
        }
    }
}

/// What was wrong with a payload that passed the CRC but did not decode.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PayloadError {
    /// The payload ended inside a field.
    Truncated,
    /// A varint longer than its type allows.
    BadVarint,
    /// An enum discriminant with no variant (serde's derive reports it as a custom error).
    BadEnum,
    /// A bool byte other than 0 or 1.
    BadBool,
    /// A string that is not UTF-8.
    BadUtf8,
    /// An `Option` tag other than 0 or 1.
    BadOption,
    /// Bytes left over after the message.
    TrailingBytes { count: u8 },
    /// A string longer than its field allows (`Message::check_limits`).
    FieldTooLong { field: &'static str, limit: usize },
    /// Any other postcard error.
    Other,
}

impl PayloadError {
    fn from_postcard(e: postcard::Error) -> Self {
        use postcard::Error as P;
        match e {
            P::DeserializeUnexpectedEnd => PayloadError::Truncated,
            P::DeserializeBadVarint => PayloadError::BadVarint,
            P::DeserializeBadEnum | P::SerdeDeCustom => PayloadError::BadEnum,
            P::DeserializeBadBool => PayloadError::BadBool,
            P::DeserializeBadUtf8 | P::DeserializeBadChar => PayloadError::BadUtf8,
            P::DeserializeBadOption => PayloadError::BadOption,
            _ => PayloadError::Other,
        }
    }
}

/// Why bytes between two delimiters were not a frame. The decoder has already dropped them
/// and is ready for the next frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameError {
    /// The COBS encoding was invalid (a code byte pointed past the end).
    BadCobs,
    /// Decoded frame shorter than header + CRC.
    TooShort { len: usize },
    /// CRC mismatch: `stated` was in the frame, `computed` over its bytes.
    BadCrc { stated: u32, computed: u32 },
    /// More than `MAX_ENCODED` bytes before a delimiter; `len` bytes were dropped.
    Oversize { len: usize },
    /// A header version this build does not speak.
    UnsupportedVersion { version: u8 },
    /// A header kind with no message.
    UnknownKind { kind: u8 },
    /// The payload of a `kind` frame did not decode.
    Undecodable { kind: Kind, reason: PayloadError },
}

impl fmt::Display for FrameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FrameError::BadCobs => write!(f, "invalid COBS encoding"),
            FrameError::TooShort { len } => {
                write!(f, "frame of {len} bytes is shorter than header and CRC")
            }
            FrameError::BadCrc { stated, computed } => write!(
                f,
                "CRC mismatch: frame says {stated:#010x}, bytes give {computed:#010x}"
            ),
            FrameError::Oversize { len } => {
                write!(f, "{len} bytes without a delimiter (limit {MAX_ENCODED})")
            }
            FrameError::UnsupportedVersion { version } => write!(
                f,
                "peer speaks protocol version {version}, this build speaks {PROTOCOL_VERSION}"
            ),
            FrameError::UnknownKind { kind } => write!(f, "unknown message kind {kind}"),
            FrameError::Undecodable { kind, reason } => {
                write!(f, "{kind:?} payload does not decode: {reason:?}")
            }
        }
    }
}

/// Encodes `msg` with sequence number `seq` into `out`, delimiter included. Returns the
/// number of bytes written; `out` of `MAX_FRAME` bytes always suffices.
pub fn encode(seq: u16, msg: &Message<'_>, out: &mut [u8]) -> Result<usize, EncodeError> {
    let mut raw = [0u8; MAX_RAW];
    let body = raw
        .get_mut(HEADER_LEN..HEADER_LEN + MAX_PAYLOAD)
        .ok_or(EncodeError::PayloadTooLarge)?;
    let n = serialize_payload(msg, body)?;
    finish_raw(&mut raw, PROTOCOL_VERSION, msg.kind() as u8, seq, n, out)
}

/// Encodes a frame from raw parts: any version, any kind byte, any payload bytes. For tests,
/// test vectors and tools that speak the framing without the message set.
pub fn encode_raw(
    version: u8,
    kind: u8,
    seq: u16,
    payload: &[u8],
    out: &mut [u8],
) -> Result<usize, EncodeError> {
    let mut raw = [0u8; MAX_RAW];
    let body = raw
        .get_mut(HEADER_LEN..HEADER_LEN + payload.len())
        .filter(|_| payload.len() <= MAX_PAYLOAD)
        .ok_or(EncodeError::PayloadTooLarge)?;
    body.copy_from_slice(payload);
    finish_raw(&mut raw, version, kind, seq, payload.len(), out)
}

pub(crate) fn finish_raw(
    raw: &mut [u8; MAX_RAW],
    version: u8,
    kind: u8,
    seq: u16,
    payload_len: usize,
    out: &mut [u8],
) -> Result<usize, EncodeError> {
    let [s0, s1] = seq.to_le_bytes();
    raw[..HEADER_LEN].copy_from_slice(&[version, kind, s0, s1]);
    let crc_at = HEADER_LEN + payload_len;
    let crc = crc32c(raw.get(..crc_at).ok_or(EncodeError::PayloadTooLarge)?);
    let end = crc_at + CRC_LEN;
    raw.get_mut(crc_at..end)
        .ok_or(EncodeError::PayloadTooLarge)?
        .copy_from_slice(&crc.to_le_bytes());
    let n = cobs::try_encode(&raw[..end], out).map_err(|_| EncodeError::OutputTooSmall)?;
    *out.get_mut(n).ok_or(EncodeError::OutputTooSmall)? = 0;
    Ok(n + 1)
}

/// CRC-32C of `seq` (little-endian) followed by `msg`'s payload as `encode` writes it: one
/// number for "this message under this sequence number", the same for every send of it
/// whatever its signature or timestamp. The robot keys a remembered command reply by it, so
/// that only a true retry is answered from memory (PROTOCOL.md §7). Postcard's encoding is
/// canonical, so equal messages give equal digests.
pub fn retry_digest(seq: u16, msg: &Message<'_>) -> Result<u32, EncodeError> {
    let mut body = [0u8; MAX_PAYLOAD];
    let n = serialize_payload(msg, &mut body)?;
    let mut digest = CRC32C.digest();
    digest.update(&seq.to_le_bytes());
    digest.update(body.get(..n).ok_or(EncodeError::PayloadTooLarge)?);
    Ok(digest.finalize())
}

pub(crate) fn serialize_payload(msg: &Message<'_>, body: &mut [u8]) -> Result<usize, EncodeError> {
    msg.check_limits()
        .map_err(|(field, limit)| EncodeError::FieldTooLong { field, limit })?;
    fn ser<T: serde::Serialize>(v: &T, body: &mut [u8]) -> Result<usize, EncodeError> {
        postcard::to_slice(v, body)
            .map(|s| s.len())
            .map_err(|_| EncodeError::PayloadTooLarge)
    }
    match msg {
        Message::Hello(m) => ser(m, body),
        Message::HelloReply(m) => ser(m, body),
        Message::Heartbeat(m) => ser(m, body),
        Message::Telemetry(m) => ser(m, body),
        Message::Command(m) => ser(m, body),
        Message::Ack(m) => ser(m, body),
        Message::Nack(m) => ser(m, body),
        Message::TransferBegin(m) => ser(m, body),
        Message::TransferChunk(m) => ser(m, body),
        Message::TransferAck(m) => ser(m, body),
        Message::Event(m) => ser(m, body),
        Message::Log(m) => ser(m, body),
        Message::EmuTruth(m) => ser(m, body),
        Message::Localization(m) => ser(m, body),
        Message::Progress(m) => ser(m, body),
        Message::HalTrace(m) => ser(m, body),
        Message::AliceSituation(m) => ser(m, body),
        Message::TransferData(m) => ser(m, body),
    }
}

/// Decodes a payload of the given kind; the whole payload must be consumed.
pub fn decode_payload(kind: Kind, payload: &[u8]) -> Result<Message<'_>, PayloadError> {
    fn de<'a, T: serde::Deserialize<'a>>(p: &'a [u8]) -> Result<T, PayloadError> {
        let (v, rest) = postcard::take_from_bytes::<T>(p).map_err(PayloadError::from_postcard)?;
        if rest.is_empty() {
            Ok(v)
        } else {
            Err(PayloadError::TrailingBytes {
                count: u8::try_from(rest.len()).unwrap_or(u8::MAX),
            })
        }
    }
    let msg = match kind {
        Kind::Hello => Message::Hello(de::<Hello>(payload)?),
        Kind::HelloReply => Message::HelloReply(de::<HelloReply>(payload)?),
        Kind::Heartbeat => Message::Heartbeat(de::<Heartbeat>(payload)?),
        Kind::Telemetry => Message::Telemetry(de::<Telemetry>(payload)?),
        Kind::Command => Message::Command(de::<Command>(payload)?),
        Kind::Ack => Message::Ack(de::<Ack>(payload)?),
        Kind::Nack => Message::Nack(de::<Nack>(payload)?),
        Kind::TransferBegin => Message::TransferBegin(de::<TransferBegin>(payload)?),
        Kind::TransferChunk => Message::TransferChunk(de::<TransferChunk>(payload)?),
        Kind::TransferAck => Message::TransferAck(de::<TransferAck>(payload)?),
        Kind::Event => Message::Event(de::<Event>(payload)?),
        Kind::Log => Message::Log(de::<Log>(payload)?),
        Kind::EmuTruth => Message::EmuTruth(de::<EmuTruth>(payload)?),
        Kind::Localization => Message::Localization(de::<crate::msg::Localization>(payload)?),
        Kind::Progress => Message::Progress(de::<crate::msg::Progress>(payload)?),
        Kind::HalTrace => Message::HalTrace(de::<crate::msg::HalTrace>(payload)?),
        Kind::AliceSituation => Message::AliceSituation(de::<crate::msg::AliceSituation>(payload)?),
        Kind::TransferData => {
            // Tag and offset, then the data to the end of the payload (no length: PROTOCOL.md §6).
            let ((tag, offset), data) = postcard::take_from_bytes::<(u8, u32)>(payload)
                .map_err(PayloadError::from_postcard)?;
            Message::TransferData(crate::msg::TransferData { tag, offset, data })
        }
    };
    msg.check_limits()
        .map_err(|(field, limit)| PayloadError::FieldTooLong { field, limit })?;
    Ok(msg)
}

/// Verifies and decodes one decoded (un-COBSed) frame.
pub fn parse_raw(raw: &[u8]) -> Result<Frame<'_>, FrameError> {
    let len = raw.len();
    if len < HEADER_LEN + CRC_LEN {
        return Err(FrameError::TooShort { len });
    }
    let (body, crc_bytes) = raw.split_at(len - CRC_LEN);
    let mut stated = [0u8; CRC_LEN];
    stated.copy_from_slice(crc_bytes);
    let stated = u32::from_le_bytes(stated);
    let computed = crc32c(body);
    if stated != computed {
        return Err(FrameError::BadCrc { stated, computed });
    }
    let (head, payload) = body.split_at(HEADER_LEN);
    let (version_byte, kind_byte, seq) = match head {
        [v, k, s0, s1] => (*v, *k, u16::from_le_bytes([*s0, *s1])),
        _ => return Err(FrameError::TooShort { len }),
    };
    let version = version_byte & !SIGNED_FLAG;
    if version != PROTOCOL_VERSION {
        return Err(FrameError::UnsupportedVersion {
            version: version_byte,
        });
    }
    let (payload, signature) = if version_byte & SIGNED_FLAG == 0 {
        (payload, None)
    } else {
        let Some(trailer_at) = payload.len().checked_sub(SIGNATURE_LEN) else {
            return Err(FrameError::TooShort { len });
        };
        let (payload, trailer) = payload.split_at(trailer_at);
        let mac_at = body.len() - MAC_LEN;
        let mut ts = [0u8; 8];
        let mut mac = [0u8; MAC_LEN];
        let (link_id, ts_bytes, mac_bytes) = (
            trailer.first().copied().unwrap_or(0),
            trailer.get(1..1 + TIMESTAMP_LEN).unwrap_or(&[]),
            trailer.get(1 + TIMESTAMP_LEN..).unwrap_or(&[]),
        );
        if ts_bytes.len() != TIMESTAMP_LEN || mac_bytes.len() != MAC_LEN {
            return Err(FrameError::TooShort { len });
        }
        ts[..TIMESTAMP_LEN].copy_from_slice(ts_bytes);
        mac.copy_from_slice(mac_bytes);
        let sig = Signature {
            link_id,
            timestamp: u64::from_le_bytes(ts),
            mac,
            covered: body.get(..mac_at).unwrap_or(&[]),
        };
        (payload, Some(sig))
    };
    let kind = Kind::from_u8(kind_byte).ok_or(FrameError::UnknownKind { kind: kind_byte })?;
    let message =
        decode_payload(kind, payload).map_err(|reason| FrameError::Undecodable { kind, reason })?;
    Ok(Frame {
        header: Header { version, kind, seq },
        message,
        signature,
    })
}

/// Counters a decoder keeps; all wrap-free u64/u32 for a link that runs for years.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DecoderStats {
    /// Bytes fed in.
    pub bytes_in: u64,
    /// Bytes that belonged to no good frame (bad frames with their delimiter, overflow).
    pub bytes_dropped: u64,
    /// Frames yielded.
    pub frames_ok: u32,
    pub bad_cobs: u32,
    pub too_short: u32,
    pub bad_crc: u32,
    pub oversize: u32,
    pub bad_version: u32,
    pub unknown_kind: u32,
    pub undecodable: u32,
}

impl DecoderStats {
    /// All frame errors together.
    pub fn errors(&self) -> u32 {
        self.bad_cobs
            .saturating_add(self.too_short)
            .saturating_add(self.bad_crc)
            .saturating_add(self.oversize)
            .saturating_add(self.bad_version)
            .saturating_add(self.unknown_kind)
            .saturating_add(self.undecodable)
    }

    fn count(&mut self, e: &FrameError) {
        let c = match e {
            FrameError::BadCobs => &mut self.bad_cobs,
            FrameError::TooShort { .. } => &mut self.too_short,
            FrameError::BadCrc { .. } => &mut self.bad_crc,
            FrameError::Oversize { .. } => &mut self.oversize,
            FrameError::UnsupportedVersion { .. } => &mut self.bad_version,
            FrameError::UnknownKind { .. } => &mut self.unknown_kind,
            FrameError::Undecodable { .. } => &mut self.undecodable,
        };
        *c = c.saturating_add(1);
    }
}

/// What one call to `FrameDecoder::feed` produced.
#[derive(Debug)]
pub enum Feed<'d, 'i> {
    /// All input was consumed without completing a frame.
    NeedMore,
    /// A good frame, and the input not yet consumed.
    Frame { frame: Frame<'d>, rest: &'i [u8] },
    /// Bytes up to a delimiter were not a frame (already dropped), and the input not yet
    /// consumed.
    Error { error: FrameError, rest: &'i [u8] },
}

/// Streaming decoder: feed it chunks, get frames. 262 bytes of state.
pub struct FrameDecoder {
    buf: [u8; MAX_ENCODED],
    /// Bytes of the current frame held in `buf`.
    len: usize,
    /// Bytes of the current frame seen, including any beyond `buf`'s capacity.
    seen: usize,
    stats: DecoderStats,
}

impl Default for FrameDecoder {
    fn default() -> Self {
        Self::new()
    }
}

impl FrameDecoder {
    pub const fn new() -> Self {
        FrameDecoder {
            buf: [0; MAX_ENCODED],
            len: 0,
            seen: 0,
            stats: DecoderStats {
                bytes_in: 0,
                bytes_dropped: 0,
                frames_ok: 0,
                bad_cobs: 0,
                too_short: 0,
                bad_crc: 0,
                oversize: 0,
                bad_version: 0,
                unknown_kind: 0,
                undecodable: 0,
            },
        }
    }

    /// The counters so far.
    pub fn stats(&self) -> &DecoderStats {
        &self.stats
    }

    /// Drops a partly received frame (e.g. after the port was reopened) and counts it dropped.
    pub fn reset(&mut self) {
        self.stats.bytes_dropped += self.seen as u64;
        self.len = 0;
        self.seen = 0;
    }

    /// Consumes `input` up to and including the first delimiter that ends a non-empty frame.
    /// Call again with `rest` until `NeedMore`. A lone 0x00 (an empty frame) is ignored: a
    /// sender may send one to flush the receiver after a line glitch.
    pub fn feed<'d, 'i>(&'d mut self, input: &'i [u8]) -> Feed<'d, 'i> {
        let mut input = input;
        loop {
            match input.iter().position(|&b| b == 0) {
                None => {
                    self.absorb(input);
                    return Feed::NeedMore;
                }
                Some(pos) => {
                    let (frame_part, after) = input.split_at(pos);
                    self.absorb(frame_part);
                    self.stats.bytes_in += 1;
                    input = after.get(1..).unwrap_or(&[]);
                    if self.seen > 0 {
                        break;
                    }
                }
            }
        }
        match self.finish() {
            Ok(frame) => Feed::Frame { frame, rest: input },
            Err(error) => Feed::Error { error, rest: input },
        }
    }

    fn absorb(&mut self, bytes: &[u8]) {
        self.stats.bytes_in += bytes.len() as u64;
        let room = MAX_ENCODED.saturating_sub(self.len);
        let take = bytes.len().min(room);
        if let (Some(dst), Some(src)) = (
            self.buf.get_mut(self.len..self.len + take),
            bytes.get(..take),
        ) {
            dst.copy_from_slice(src);
            self.len += take;
        }
        self.seen = self.seen.saturating_add(bytes.len());
    }

    fn finish(&mut self) -> Result<Frame<'_>, FrameError> {
        let (len, seen) = (self.len, self.seen);
        self.len = 0;
        self.seen = 0;
        let result = if seen > MAX_ENCODED {
            Err(FrameError::Oversize { len: seen })
        } else {
            match self.buf.get_mut(..len).map(cobs::decode_in_place) {
                Some(Ok(n)) => Ok(n),
                _ => Err(FrameError::BadCobs),
            }
        };
        let parsed = match result {
            Ok(n) => parse_raw(self.buf.get(..n).unwrap_or(&[])),
            Err(e) => Err(e),
        };
        match parsed {
            Ok(frame) => {
                self.stats.frames_ok = self.stats.frames_ok.saturating_add(1);
                Ok(frame)
            }
            Err(e) => {
                self.stats.count(&e);
                // The frame's bytes and its delimiter.
                self.stats.bytes_dropped += seen as u64 + 1;
                Err(e)
            }
        }
    }
}
