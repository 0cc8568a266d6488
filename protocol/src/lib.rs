//! The robot link's wire protocol, shared by the robot firmware, the emulator and the station.
//!
//! `#![no_std]` and heap-free: message types borrow strings and byte slices from the frame
//! buffer; the encoder writes into a caller's slice; the decoder owns one 255-byte buffer.
//! See PROTOCOL.md beside this crate for every byte on the wire.
//!
//! - `msg`: the message set and the kind numbering.
//! - `frame`: header, CRC-32C, COBS framing, the streaming `FrameDecoder`.
//! - `seq`: loss and duplicate accounting from sequence numbers.
//! - `packed`: eight 10-bit sensor readings in 10 bytes.
//! - `telemetry_range`: the ranges that bound a telemetry frame to 80 bytes on the wire.
//! - `fingerprint`: the schema hash exchanged at handshake.
//! - `trailer`: the signature trailer's layout, below `frame` and `sign`.
//! - `sign`: optional link authentication, HMAC-SHA256 signatures and replay windows (§13).
//! - `transfer`: the chunked-transfer sender and receiver state machines (§8).
//! - `object`: the byte layouts of the Map, Plan and Regions objects (§12).
#![no_std]
#![deny(unsafe_code)]

pub mod frame;
pub mod hil;
pub mod msg;
pub mod object;
pub mod packed;
pub mod seq;
pub mod sign;
pub mod telemetry_range;
pub mod trailer;
pub mod transfer;
pub mod units;

pub use frame::{
    crc32c, encode, encode_raw, parse_raw, retry_digest, DecoderStats, EncodeError, Feed, Frame,
    FrameDecoder, FrameError, Header, PayloadError, MAX_FRAME, MAX_PAYLOAD, MAX_SIGNED_PAYLOAD,
    PROTOCOL_VERSION,
};
pub use msg::*;
pub use packed::Packed10x8;
pub use seq::{SeqEvent, SeqTracker};
pub use sign::{
    encode_signed, AuthError, AuthStats, Binding, KeyError, LinkAuth, LinkKey, Signature,
};

/// The schema fingerprint: FNV-1a 64 over the protocol name, version and the full postcard
/// schema of `Message` (every variant, field name and type, in order). Two builds whose
/// message definitions differ in any way have different fingerprints and refuse each other.
pub const FINGERPRINT: [u8; FINGERPRINT_LEN] =
    postcard_schema::key::Key::for_path::<Message<'static>>(FINGERPRINT_PATH).to_bytes();

/// The path hashed in front of the schema.
pub const FINGERPRINT_PATH: &str = "robot-link/1";

/// Timing constants of the link (milliseconds); PROTOCOL.md explains each.
pub mod timing {
    /// Each side sends a heartbeat at least this often when it has nothing else to send.
    pub const HEARTBEAT_PERIOD_MS: u32 = 250;
    /// No frame for this long: the link is down (station reconnects, robot forgets session).
    pub const LINK_TIMEOUT_MS: u32 = 1500;
    /// A command not acknowledged within this time is sent again, same sequence number.
    pub const COMMAND_RETRY_MS: u32 = 200;
    /// Sends of one command before it is reported failed (first try included).
    pub const COMMAND_ATTEMPTS: u32 = 5;
    /// How long the robot remembers a command's reply to answer its retries: twice the
    /// station's retry budget (`COMMAND_RETRY_MS` x `COMMAND_ATTEMPTS`), so a true retry is
    /// always recognised and a number reused later never is (PROTOCOL.md §7).
    pub const REPLY_MEMORY_MS: u32 = 2 * COMMAND_RETRY_MS * COMMAND_ATTEMPTS;
    /// Manual-mode failsafe default: motors stop after this much silence from the station.
    pub const FAILSAFE_DEFAULT_MS: u16 = 300;
    /// Chunks a transfer sender keeps unacknowledged.
    pub const TRANSFER_WINDOW: u32 = 4;
    /// A transfer with no progress for this long is resumed from the last acknowledged offset.
    pub const TRANSFER_RETRY_MS: u32 = 400;
    /// Default telemetry rate at session start.
    pub const TELEMETRY_DEFAULT_HZ: u8 = 10;
}
