//! Link authentication (PROTOCOL.md §13): a shared 32-byte key, a 13-byte signature trailer
//! (link id, 48-bit timestamp, 48-bit truncated HMAC-SHA256), per-link replay windows, and a
//! binding of every signature to its session and robot.
//!
//! Layer: pure state over caller buffers, like `frame`. `frame` parses the trailer; this
//! module decides whether a parsed frame is acceptable (`LinkAuth::verify`) and builds signed
//! frames with strictly increasing timestamps (`LinkAuth::encode`). Fixed size, no heap, never
//! panics. A frame `verify` refuses leaves every window and counter but the error counters
//! untouched, so a refused frame cannot move the replay state either.
//!
//! Why HMAC-SHA256 (RFC 2104) and not MAVLink's SHA-256(key || message): HMAC is a proven
//! PRF whatever the message structure, and the `hmac` and `sha2` crates are RustCrypto's,
//! no_std and heap-free. A frame costs two SHA-256 compressions more than MAVLink's plain
//! hash (the keyed pads); keeping the keyed states would save them for 48 more bytes, which
//! the robot's 32 KB does not have to spare.
//!
//! Why a binding: a fleet shares one key, and a signature over the frame alone is valid on
//! every robot's line. A man in the middle could then move robot 2's signed Stop onto robot
//! 1's line and robot 1's Ack back. The MAC therefore also covers the session the station's
//! Hello opened and the robot that answered it ([`Binding`], not sent: both ends know it), so
//! a frame moved to another robot or another session fails its MAC there (MAVLink 2 signs
//! its link id for the same reason).

use core::fmt;

use hmac::digest::{FixedOutput, KeyInit, Mac, Update};
use hmac::Hmac;
use sha2::Sha256;

use crate::frame::{finish_raw, serialize_payload, EncodeError, Frame, HEADER_LEN, MAX_RAW};
use crate::frame::{MAX_SIGNED_PAYLOAD, PROTOCOL_VERSION};
use crate::msg::{EventCode, Message};
pub use crate::trailer::{
    Signature, MAC_LEN, SIGNATURE_LEN, SIGNED_FLAG, TIMESTAMP_LEN, TIMESTAMP_MAX,
};

/// Bytes of a key.
pub const KEY_LEN: usize = 32;
/// Link ids with this bit are sent by the robot side (robot, emulator), without by a station.
pub const ROBOT_SIDE: u8 = 0x80;
/// The station's link id.
pub const STATION_LINK: u8 = 0x00;
/// The robot firmware's link id.
pub const ROBOT_LINK: u8 = 0x80;
/// The emulator's `EmuTruth` stream: its own sequence numbers, so its own timestamps.
pub const TRUTH_LINK: u8 = 0x81;
/// Streams a receiver keeps a replay window for: the station needs the robot's and the
/// emulator's truth stream, the robot one station.
pub const REPLAY_LINKS: usize = 2;
/// Unix time of the timestamp epoch, 2015-01-01T00:00:00Z (MAVLink's).
pub const EPOCH_UNIX_S: u64 = 1_420_070_400;
/// Timestamp units per second (10 µs units).
pub const TICKS_PER_S: u64 = 100_000;

/// Bytes of a binding in the MAC input: session u32 LE, robot id u8.
pub const BINDING_LEN: usize = 5;
/// The robot id of a binding made before the station knows which robot answers (a `Hello`,
/// and the robot's refusal of one).
pub const ANY_ROBOT: u8 = 0;
/// The binding of a frame that belongs to no session: the robot's `HandshakeRefused`, and
/// everything before a first session.
pub const NO_SESSION: Binding = Binding::new(0, ANY_ROBOT);

type HmacSha256 = Hmac<Sha256>;

/// What a signature binds a frame to besides its own bytes (PROTOCOL.md §13): the `session`
/// nonce of the station's `Hello` and the `robot_id` of the robot whose `HelloReply` accepted
/// it. It is not sent; the MAC is over its 5 bytes followed by the frame, so a frame signed for
/// another session or another robot does not verify.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Binding {
    pub session: u32,
    pub robot_id: u8,
}

impl Binding {
    pub const fn new(session: u32, robot_id: u8) -> Self {
        Binding { session, robot_id }
    }

    /// The bytes the MAC input starts with.
    pub fn bytes(&self) -> [u8; BINDING_LEN] {
        let [a, b, c, d] = self.session.to_le_bytes();
        [a, b, c, d, self.robot_id]
    }

    /// The binding a frame carrying `msg` is signed and verified with, when `self` is the
    /// session in force on this side. The handshake's frames carry their own: a `Hello` opens
    /// its session before anyone knows which robot answers (robot id 0), and a `HelloReply`
    /// names both in its payload. The robot's `HandshakeRefused` answers a `Hello` that opened
    /// nothing, so it is bound to no session (0, 0): a station can then verify a refusal
    /// whatever session it is in, and tell a robot with another key (whose refusal does not
    /// verify) from a refusal of another station's Hello (which does, and is older than its
    /// own Hello, so stale). Every other frame is bound to the session in force.
    pub fn for_message(self, msg: &Message<'_>) -> Binding {
        match msg {
            Message::Hello(h) => Binding::new(h.session, ANY_ROBOT),
            Message::HelloReply(r) => Binding::new(r.session, r.robot_id),
            Message::Event(e) if e.code == EventCode::HandshakeRefused => NO_SESSION,
            _ => self,
        }
    }
}

/// A shared link key. `Debug` never prints it.
#[derive(Clone)]
pub struct LinkKey {
    key: [u8; KEY_LEN],
}

impl fmt::Debug for LinkKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("LinkKey(..)")
    }
}

/// Why text is not a key.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KeyError {
    /// Not 64 hex digits once surrounding white space is trimmed.
    Length { digits: usize },
    /// A character that is not a hex digit, at this offset of the trimmed text.
    NotHex { offset: usize },
    /// All 32 bytes zero: a placeholder, not a key.
    AllZero,
}

impl fmt::Display for KeyError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            KeyError::Length { digits } => write!(
                f,
                "a key is 64 hex digits (32 bytes); found {digits} characters"
            ),
            KeyError::NotHex { offset } => {
                write!(f, "character {} is not a hex digit", offset + 1)
            }
            KeyError::AllZero => write!(f, "the key is all zeros; generate a random one"),
        }
    }
}

impl LinkKey {
    pub fn new(key: &[u8; KEY_LEN]) -> Self {
        LinkKey { key: *key }
    }

    fn keyed(&self) -> HmacSha256 {
        // HMAC pads a key shorter than the 64-byte block with zeros (RFC 2104 §2); doing it
        // here makes keying infallible.
        let mut block = [0u8; 64];
        block[..KEY_LEN].copy_from_slice(&self.key);
        <HmacSha256 as KeyInit>::new(&block.into())
    }

    /// A key from 64 hex digits (either case), surrounding white space ignored.
    pub fn from_hex(text: &str) -> Result<Self, KeyError> {
        parse_key_hex(text).map(|k| LinkKey::new(&k))
    }

    /// The first `MAC_LEN` bytes of HMAC-SHA256(key, binding bytes || covered).
    pub fn mac(&self, binding: &Binding, covered: &[u8]) -> [u8; MAC_LEN] {
        let mut m = self.keyed();
        Update::update(&mut m, &binding.bytes());
        Update::update(&mut m, covered);
        let full = m.finalize_fixed();
        let mut out = [0u8; MAC_LEN];
        out.copy_from_slice(&full[..MAC_LEN]);
        out
    }

    /// Whether `tag` is the MAC of `covered` under `binding`, compared in constant time.
    pub fn verify(&self, binding: &Binding, covered: &[u8], tag: &[u8; MAC_LEN]) -> bool {
        let mut m = self.keyed();
        Update::update(&mut m, &binding.bytes());
        Update::update(&mut m, covered);
        m.verify_truncated_left(tag).is_ok()
    }
}

/// The 32 key bytes from 64 hex digits (either case), surrounding white space ignored; an
/// all-zero key is refused as a placeholder.
pub fn parse_key_hex(text: &str) -> Result<[u8; KEY_LEN], KeyError> {
    let t = text.trim();
    let digits = t.chars().count();
    if digits != 2 * KEY_LEN {
        return Err(KeyError::Length { digits });
    }
    let mut key = [0u8; KEY_LEN];
    for (i, c) in t.chars().enumerate() {
        let nibble = c.to_digit(16).ok_or(KeyError::NotHex { offset: i })? as u8;
        if let Some(b) = key.get_mut(i / 2) {
            *b = *b << 4 | nibble;
        }
    }
    if key.iter().all(|&b| b == 0) {
        return Err(KeyError::AllZero);
    }
    Ok(key)
}

/// Why an authenticated link refused a frame that passed the CRC. Nothing else happened.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AuthError {
    /// This side has a key; the frame is not signed.
    Unsigned,
    /// This side has no key; the frame is signed.
    UnexpectedSignature { link_id: u8 },
    /// The MAC does not match: another key, a frame of another session or robot, or a
    /// forgery.
    BadSignature { link_id: u8 },
    /// The timestamp is not above the last one accepted on this link: a replay or a
    /// duplicate.
    StaleTimestamp { link_id: u8, last: u64, got: u64 },
    /// Signed by this side's own direction: a frame reflected back at its sender.
    WrongDirection { link_id: u8 },
    /// A new link id when every replay window is taken.
    TooManyLinks { link_id: u8 },
}

impl fmt::Display for AuthError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AuthError::Unsigned => write!(f, "unsigned frame on an authenticated link"),
            AuthError::UnexpectedSignature { link_id } => write!(
                f,
                "signed frame (link {link_id:#04x}) but this side has no key"
            ),
            AuthError::BadSignature { link_id } => {
                write!(f, "bad signature on link {link_id:#04x} (another key?)")
            }
            AuthError::StaleTimestamp { link_id, last, got } => write!(
                f,
                "stale timestamp {got} on link {link_id:#04x} (last accepted {last}): replay?"
            ),
            AuthError::WrongDirection { link_id } => {
                write!(f, "frame of link {link_id:#04x} came back to its own side")
            }
            AuthError::TooManyLinks { link_id } => write!(
                f,
                "link {link_id:#04x} refused: already {REPLAY_LINKS} links in use"
            ),
        }
    }
}

/// Frames refused, by reason, and frames verified.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AuthStats {
    pub verified: u32,
    pub unsigned: u32,
    pub unexpected_signature: u32,
    pub bad_signature: u32,
    pub stale_timestamp: u32,
    pub wrong_direction: u32,
    pub too_many_links: u32,
}

impl AuthStats {
    /// Every refusal together.
    pub fn refused(&self) -> u32 {
        self.unsigned
            .saturating_add(self.unexpected_signature)
            .saturating_add(self.bad_signature)
            .saturating_add(self.stale_timestamp)
            .saturating_add(self.wrong_direction)
            .saturating_add(self.too_many_links)
    }

    fn count(&mut self, e: &AuthError) {
        let c = match e {
            AuthError::Unsigned => &mut self.unsigned,
            AuthError::UnexpectedSignature { .. } => &mut self.unexpected_signature,
            AuthError::BadSignature { .. } => &mut self.bad_signature,
            AuthError::StaleTimestamp { .. } => &mut self.stale_timestamp,
            AuthError::WrongDirection { .. } => &mut self.wrong_direction,
            AuthError::TooManyLinks { .. } => &mut self.too_many_links,
        };
        *c = c.saturating_add(1);
    }
}

/// The last timestamp accepted on each of up to `N` link ids, and a floor below which
/// nothing is accepted on any link.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReplayWindows<const N: usize> {
    /// The last timestamp accepted on each link id in `ids[..len]`.
    stamps: [u64; N],
    ids: [u8; N],
    len: u8,
    floor: u64,
}

impl<const N: usize> Default for ReplayWindows<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> ReplayWindows<N> {
    pub const fn new() -> Self {
        ReplayWindows {
            stamps: [0; N],
            ids: [0; N],
            len: 0,
            floor: 0,
        }
    }

    /// Forgets every link; from now on only timestamps above `floor` are accepted.
    pub fn reset(&mut self, floor: u64) {
        self.len = 0;
        self.floor = floor;
    }

    fn slot(&self, link_id: u8) -> Option<usize> {
        self.ids
            .get(..usize::from(self.len))
            .and_then(|ids| ids.iter().position(|&l| l == link_id))
    }

    /// The highest timestamp accepted on any link, or the floor.
    pub fn max(&self) -> u64 {
        self.stamps
            .get(..usize::from(self.len))
            .into_iter()
            .flatten()
            .fold(self.floor, |m, &t| m.max(t))
    }

    /// Whether `timestamp` on `link_id` would be accepted.
    pub fn check(&self, link_id: u8, timestamp: u64) -> Result<(), AuthError> {
        let last = match self.slot(link_id) {
            Some(i) => self.stamps.get(i).copied().unwrap_or(0).max(self.floor),
            None if usize::from(self.len) >= N => return Err(AuthError::TooManyLinks { link_id }),
            None => self.floor,
        };
        if timestamp > last {
            Ok(())
        } else {
            Err(AuthError::StaleTimestamp {
                link_id,
                last,
                got: timestamp,
            })
        }
    }

    /// Records an accepted timestamp (after `check` said yes).
    pub fn accept(&mut self, link_id: u8, timestamp: u64) {
        let i = match self.slot(link_id) {
            Some(i) => i,
            None if usize::from(self.len) < N => {
                let i = usize::from(self.len);
                if let Some(id) = self.ids.get_mut(i) {
                    *id = link_id;
                }
                self.len += 1;
                i
            }
            None => return,
        };
        if let Some(t) = self.stamps.get_mut(i) {
            *t = timestamp;
        }
    }

    /// The last timestamp accepted on `link_id`.
    pub fn last(&self, link_id: u8) -> Option<u64> {
        self.slot(link_id).and_then(|i| self.stamps.get(i).copied())
    }
}

/// One side's authentication state: its key (if any), its own link id and outgoing
/// timestamps, the binding in force, and its replay windows for the other side's links.
#[derive(Clone, Debug)]
pub struct LinkAuth {
    key: Option<LinkKey>,
    link_id: u8,
    /// The session and robot this side's frames are bound to now (`bind`).
    binding: Binding,
    /// The last timestamp this side signed with.
    tx_timestamp: u64,
    replay: ReplayWindows<REPLAY_LINKS>,
    stats: AuthStats,
}

impl LinkAuth {
    /// `key: None` is an unauthenticated link, which refuses signed frames.
    pub fn new(key: Option<LinkKey>, link_id: u8) -> Self {
        LinkAuth {
            key,
            link_id,
            binding: NO_SESSION,
            tx_timestamp: 0,
            replay: ReplayWindows::new(),
            stats: AuthStats::default(),
        }
    }

    /// Whether this side signs and requires signatures.
    pub fn keyed(&self) -> bool {
        self.key.is_some()
    }

    pub fn stats(&self) -> &AuthStats {
        &self.stats
    }

    /// This side's link id.
    pub fn link_id(&self) -> u8 {
        self.link_id
    }

    /// Binds this side's frames from now on to `binding` (the station when it starts a
    /// handshake and when a `HelloReply` accepts it; the robot when it accepts a `Hello`).
    pub fn bind(&mut self, binding: Binding) {
        self.binding = binding;
    }

    /// The session and robot in force.
    pub fn binding(&self) -> Binding {
        self.binding
    }

    /// Forgets the other side's links and accepts only timestamps above `floor` from now on
    /// (the station calls it at each handshake with the timestamp of its first `Hello`).
    pub fn reset_replay(&mut self, floor: u64) {
        self.replay.reset(floor);
    }

    /// The replay windows (for tests and diagnostics).
    pub fn replay(&self) -> &ReplayWindows<REPLAY_LINKS> {
        &self.replay
    }

    /// The timestamp the next signed frame will carry if `clock` (this side's wall clock in
    /// ticks since the epoch; 0 without one) is what it is now.
    pub fn next_timestamp(&self, clock: u64) -> u64 {
        // Above everything accepted from the other side too (a Lamport clock), so a side
        // without a clock follows the one with it; the station's reset floor is its own
        // Hello's timestamp, which this also stays above.
        clock
            .max(self.tx_timestamp.saturating_add(1))
            .max(self.replay.max().saturating_add(1))
            .min(TIMESTAMP_MAX)
    }

    /// Checks a decoded frame against this side's key and replay windows, and counts the
    /// outcome. On success the frame's timestamp becomes the last accepted on its link.
    pub fn verify(&mut self, frame: &Frame<'_>) -> Result<(), AuthError> {
        let r = self.check(frame);
        match &r {
            Ok(Some(sig)) => {
                self.replay.accept(sig.link_id, sig.timestamp);
                self.stats.verified = self.stats.verified.saturating_add(1);
            }
            Ok(None) => {}
            Err(e) => self.stats.count(e),
        }
        r.map(|_| ())
    }

    fn check<'a>(&self, frame: &Frame<'a>) -> Result<Option<Signature<'a>>, AuthError> {
        match (&self.key, frame.signature) {
            (None, None) => Ok(None),
            (None, Some(sig)) => Err(AuthError::UnexpectedSignature {
                link_id: sig.link_id,
            }),
            (Some(_), None) => Err(AuthError::Unsigned),
            (Some(key), Some(sig)) => {
                // The MAC first: only the key holder can make the replay windows matter.
                let binding = self.binding.for_message(&frame.message);
                if !key.verify(&binding, sig.covered, &sig.mac) {
                    return Err(AuthError::BadSignature {
                        link_id: sig.link_id,
                    });
                }
                if (sig.link_id ^ self.link_id) & ROBOT_SIDE == 0 {
                    return Err(AuthError::WrongDirection {
                        link_id: sig.link_id,
                    });
                }
                self.replay.check(sig.link_id, sig.timestamp)?;
                Ok(Some(sig))
            }
        }
    }

    /// Encodes `msg`: signed with the next timestamp when keyed (see `next_timestamp`) and
    /// bound to the session in force, plain otherwise. Returns the bytes written to `out`
    /// (`MAX_FRAME` always suffices).
    pub fn encode(
        &mut self,
        seq: u16,
        msg: &Message<'_>,
        clock: u64,
        out: &mut [u8],
    ) -> Result<usize, EncodeError> {
        self.encode_in(self.binding, seq, msg, clock, out)
    }

    /// `encode` as if `session` were in force, without binding this side to it: the robot's
    /// answer to a `Hello` it refuses, which must not end the session it is in.
    pub fn encode_in(
        &mut self,
        session: Binding,
        seq: u16,
        msg: &Message<'_>,
        clock: u64,
        out: &mut [u8],
    ) -> Result<usize, EncodeError> {
        match &self.key {
            None => crate::frame::encode(seq, msg, out),
            Some(key) => {
                let ts = self.next_timestamp(clock);
                let binding = session.for_message(msg);
                let n = encode_signed(seq, msg, key, &binding, self.link_id, ts, out)?;
                self.tx_timestamp = ts;
                Ok(n)
            }
        }
    }
}

/// Encodes `msg` as a signed frame (PROTOCOL.md §13) bound to `binding`, with the given link
/// id and timestamp. The payload budget is `MAX_SIGNED_PAYLOAD`. Callers keep timestamps
/// increasing and bind the handshake's frames as §13 says; use `sign::LinkAuth::encode`,
/// which does both.
pub fn encode_signed(
    seq: u16,
    msg: &Message<'_>,
    key: &LinkKey,
    binding: &Binding,
    link_id: u8,
    timestamp: u64,
    out: &mut [u8],
) -> Result<usize, EncodeError> {
    let mut raw = [0u8; MAX_RAW];
    let body = raw
        .get_mut(HEADER_LEN..HEADER_LEN + MAX_SIGNED_PAYLOAD)
        .ok_or(EncodeError::PayloadTooLarge)?;
    let n = serialize_payload(msg, body)?;
    let version = PROTOCOL_VERSION | SIGNED_FLAG;
    let kind = msg.kind() as u8;
    let [s0, s1] = seq.to_le_bytes();
    // The MAC covers the header, so it goes in before the MAC is taken.
    raw[..HEADER_LEN].copy_from_slice(&[version, kind, s0, s1]);
    let trailer_at = HEADER_LEN + n;
    let mac_at = trailer_at + SIGNATURE_LEN - MAC_LEN;
    let ts = timestamp.min(TIMESTAMP_MAX).to_le_bytes();
    let trailer = raw
        .get_mut(trailer_at..mac_at)
        .ok_or(EncodeError::PayloadTooLarge)?;
    trailer[0] = link_id;
    trailer[1..].copy_from_slice(&ts[..TIMESTAMP_LEN]);
    let mac = key.mac(
        binding,
        raw.get(..mac_at).ok_or(EncodeError::PayloadTooLarge)?,
    );
    raw.get_mut(mac_at..mac_at + MAC_LEN)
        .ok_or(EncodeError::PayloadTooLarge)?
        .copy_from_slice(&mac);
    finish_raw(&mut raw, version, kind, seq, n + SIGNATURE_LEN, out)
}

/// Ticks since the epoch for a Unix time in microseconds (0 before the epoch).
pub fn ticks_from_unix_us(unix_us: u64) -> u64 {
    (unix_us / 10)
        .saturating_sub(EPOCH_UNIX_S * TICKS_PER_S)
        .min(TIMESTAMP_MAX)
}
