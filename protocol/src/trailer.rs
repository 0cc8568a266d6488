//! The signature trailer of a signed frame (PROTOCOL.md §13): its layout and its parsed form.
//!
//! Layer: constants and a plain struct, below both `frame` (which parses a trailer out of a
//! decoded frame) and `sign` (which makes and judges one), so that neither imports the other
//! for it.

/// Set in the version byte of a signed frame.
pub const SIGNED_FLAG: u8 = 0x80;
/// Bytes of the truncated MAC.
pub const MAC_LEN: usize = 6;
/// Bytes of the timestamp (48 bits, little-endian).
pub const TIMESTAMP_LEN: usize = 6;
/// Bytes of the trailer: link id, timestamp, MAC.
pub const SIGNATURE_LEN: usize = 1 + TIMESTAMP_LEN + MAC_LEN;
/// Largest timestamp.
pub const TIMESTAMP_MAX: u64 = (1 << 48) - 1;

/// The trailer of a signed frame, as parsed; `covered` is what the MAC is over after the
/// binding (the decoded frame from the version byte through the timestamp).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Signature<'a> {
    pub link_id: u8,
    pub timestamp: u64,
    pub mac: [u8; MAC_LEN],
    pub covered: &'a [u8],
}
