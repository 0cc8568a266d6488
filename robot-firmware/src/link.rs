//! The robot's side of the link: handshake, command bookkeeping, outgoing queue, timers.
//!
//! Layer: protocol state with no I/O and no clock. `Robot::step` feeds it received bytes and
//! the time, asks it what to do with each command, and drains its queue into the serial port.
//! Invariants, each from PROTOCOL.md §4 and §7:
//! - no command is executed before a valid handshake (`Nack NoHandshake`);
//! - a command is answered from memory only if it is a true retry: the same sequence number
//!   and the same content (a digest of its payload) as one of the last `REPLY_CACHE` answered,
//!   at most `REPLY_MEMORY_MS` ago by the robot's clock. Anything else is a new command and is
//!   executed or refused: the station's 16-bit counter wraps in a long session, and a Stop that
//!   reuses an old number must stop the robot, not get the old command's Ack;
//! - a frame goes into the outgoing queue whole or not at all, so the wire never carries a
//!   torn frame; telemetry is skipped (and counted) rather than crowding out replies;
//! - with a key (`set_key`, PROTOCOL.md §13) every frame sent is signed and only frames that
//!   verify are acted on: a refused frame changes nothing, not even the link timeout or the
//!   failsafe clock; a refused `Hello` is answered with `Event HandshakeRefused` and a
//!   negative reason, so the station can say why instead of timing out;
//! - every signed frame is bound to the session of the `Hello` the robot accepted and to the
//!   robot id it stated in its `HelloReply`: a frame signed for another robot or session
//!   (a fleet shares one key) fails its MAC and is refused like a forgery.
//!
//! Memory: one 262-byte decoder, `REPLY_CACHE` remembered replies of 24 bytes, a
//! `TX_QUEUE`-byte queue, the 112-byte signing state, a few dozen bytes of other state.

use heapless::Deque;
use protocol::sign::{AuthError, AuthStats, Binding, LinkAuth, LinkKey, KEY_LEN, ROBOT_LINK};
use protocol::timing::REPLY_MEMORY_MS;
use protocol::{
    retry_digest, Ack, AckInfo, Command, Event, EventCode, Feed, Frame, FrameDecoder, HelloReply,
    Message, Nack, NackReason, SeqTracker, FINGERPRINT, MAX_FRAME, PROTOCOL_VERSION,
};

/// Bytes of the outgoing queue: several frames, so a burst of replies never blocks.
pub const TX_QUEUE: usize = 1024;
/// Replies remembered for retry detection (PROTOCOL.md §7).
pub const REPLY_CACHE: usize = 8;
/// Free queue space telemetry must leave for replies.
const TELEMETRY_RESERVE: usize = 2 * MAX_FRAME;

/// The answer to one command.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reply {
    Ack(AckInfo),
    Nack(NackReason),
}

/// What the link made of one received frame, for the robot to act on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Inbound<'a> {
    /// A command to execute now (handshake and retry checks passed).
    Command { seq: u16, command: Command },
    /// A transfer frame (begin, chunk or ack) from a handshaken station.
    Transfer(Message<'a>),
    /// A station completed the handshake: a new session starts.
    Connected,
}

/// What the robot answers to an `Inbound`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Response {
    Nothing,
    /// The answer to a command (queued as Ack or Nack and remembered for retries).
    Reply(Reply),
    /// A frame to send, e.g. a `TransferAck`.
    Send(Message<'static>),
    /// To `Connected`: the robot's settings in the session that starts now, which its
    /// `HelloReply` states (a new session resets the telemetry rate, PROTOCOL.md §4).
    Session(LinkStatus),
}

/// A command's reply, remembered to answer that command's retries (PROTOCOL.md §7). 24 bytes:
/// the seq lives in the digest (a retry's own header supplies it for the answer), so eight
/// of these cost 24 bytes more than the seq-only memory they replaced.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Remembered {
    /// The robot's clock when the command was executed, ms.
    at_ms: u32,
    /// `retry_digest` of the command's seq and payload: a new command reusing the number
    /// has another content, so it is not a retry.
    digest: u32,
    reply: Reply,
}

impl Remembered {
    fn expired(&self, now_ms: u32) -> bool {
        now_ms.wrapping_sub(self.at_ms) > REPLY_MEMORY_MS
    }
}

/// Link counters for diagnostics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LinkCounters {
    pub frames_out: u32,
    pub bytes_out: u64,
    /// Telemetry frames skipped because the queue was too full.
    pub telemetry_skipped: u32,
    /// Other frames dropped because the queue had no room (the station's retry recovers them).
    pub frames_dropped: u32,
    pub retries_answered: u32,
    pub refused_before_handshake: u32,
    pub handshakes: u32,
    pub handshakes_refused: u32,
}

/// Identity the robot states in its `HelloReply`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Identity {
    pub firmware: &'static str,
    pub firmware_version: &'static str,
    pub profile: protocol::ProfileId,
    pub capabilities: u32,
    pub map_capacity: protocol::MapCapacity,
}

/// The link's state: the decoder, and everything else in `LinkState` so that a decoded
/// frame (which borrows the decoder) can be answered while it is alive.
pub struct Link {
    rx: FrameDecoder,
    st: LinkState,
}

struct LinkState {
    tx: Deque<u8, TX_QUEUE>,
    tx_seq: u16,
    session: Option<u32>,
    /// Time of the last valid frame from the station.
    last_rx_ms: u32,
    /// Time of the last frame queued to the station.
    last_tx_ms: u32,
    replies: [Option<Remembered>; REPLY_CACHE],
    peer_seq: SeqTracker,
    counters: LinkCounters,
    auth: LinkAuth,
}

impl Default for Link {
    fn default() -> Self {
        Self::new()
    }
}

impl Link {
    pub fn new() -> Self {
        Link {
            rx: FrameDecoder::new(),
            st: LinkState {
                tx: Deque::new(),
                tx_seq: 0,
                session: None,
                last_rx_ms: 0,
                last_tx_ms: 0,
                replies: [None; REPLY_CACHE],
                peer_seq: SeqTracker::new(),
                counters: LinkCounters {
                    frames_out: 0,
                    bytes_out: 0,
                    telemetry_skipped: 0,
                    frames_dropped: 0,
                    retries_answered: 0,
                    refused_before_handshake: 0,
                    handshakes: 0,
                    handshakes_refused: 0,
                },
                auth: LinkAuth::new(None, ROBOT_LINK),
            },
        }
    }

    /// Sets (or clears) the link key: from now on every frame is signed and only signed
    /// frames that verify are accepted (PROTOCOL.md §13). Ends any session.
    pub fn set_key(&mut self, key: Option<&[u8; KEY_LEN]>) {
        self.st.auth = LinkAuth::new(key.map(LinkKey::new), ROBOT_LINK);
        self.st.session = None;
    }

    /// Whether the link signs and requires signatures.
    pub fn keyed(&self) -> bool {
        self.st.auth.keyed()
    }

    /// Frames verified and refused by the authentication layer.
    pub fn auth_stats(&self) -> &AuthStats {
        self.st.auth.stats()
    }

    /// The session and robot id the robot's signed frames are bound to now.
    pub fn binding(&self) -> Binding {
        self.st.auth.binding()
    }

    /// Whether a station has completed the handshake and not timed out.
    pub fn connected(&self) -> bool {
        self.st.session.is_some()
    }

    /// Time of the last valid frame from the station, ms.
    pub fn last_rx_ms(&self) -> u32 {
        self.st.last_rx_ms
    }

    pub fn counters(&self) -> &LinkCounters {
        &self.st.counters
    }

    pub fn decoder_stats(&self) -> &protocol::DecoderStats {
        self.rx.stats()
    }

    pub fn peer_seq(&self) -> &SeqTracker {
        &self.st.peer_seq
    }

    /// Forgets the session when the station has been silent for `timeout_ms`, and replies
    /// older than `REPLY_MEMORY_MS` (called every cycle, so none outlives it by more than a
    /// cycle, and the wrapping clock can never make an old one look young).
    pub fn expire(&mut self, now_ms: u32, timeout_ms: u32) {
        if self.st.session.is_some() && now_ms.wrapping_sub(self.st.last_rx_ms) > timeout_ms {
            self.st.session = None;
        }
        self.st.forget_expired(now_ms);
    }

    /// Feeds received bytes and calls `on` for every frame the robot must act on; queues what
    /// it answers (a command's reply is also remembered for retries).
    pub fn receive(
        &mut self,
        bytes: &[u8],
        now_ms: u32,
        identity: &Identity,
        status: LinkStatus,
        on: &mut dyn FnMut(Inbound<'_>) -> Response,
    ) {
        let mut input = bytes;
        let st = &mut self.st;
        loop {
            let (frame, rest) = match self.rx.feed(input) {
                Feed::NeedMore => return,
                Feed::Error { rest, .. } => {
                    input = rest;
                    continue;
                }
                Feed::Frame { frame, rest } => (frame, rest),
            };
            input = rest;
            if let Err(e) = st.auth.verify(&frame) {
                if frame.header.kind == protocol::Kind::Hello {
                    st.refuse_unauthenticated(e, now_ms);
                }
                continue;
            }
            // The frame borrows the decoder; everything below touches other fields only.
            let Frame {
                header, message, ..
            } = frame;
            st.last_rx_ms = now_ms;
            st.peer_seq.observe(header.seq);
            match message {
                Message::Hello(h) => {
                    let accepted = h.fingerprint == FINGERPRINT && h.protocol == PROTOCOL_VERSION;
                    // The reply names the Hello's session and this robot, and is signed so.
                    let answer_in = Binding::new(h.session, status.robot_id);
                    let mut status = status;
                    if accepted {
                        st.auth.bind(answer_in);
                        st.session = Some(h.session);
                        st.replies = [None; REPLY_CACHE];
                        st.counters.handshakes = st.counters.handshakes.wrapping_add(1);
                        if let Response::Session(now) = on(Inbound::Connected) {
                            status = now;
                        }
                    } else {
                        st.session = None;
                        st.counters.handshakes_refused =
                            st.counters.handshakes_refused.wrapping_add(1);
                    }
                    let reply = HelloReply {
                        fingerprint: FINGERPRINT,
                        protocol: PROTOCOL_VERSION,
                        session: h.session,
                        accepted,
                        firmware: identity.firmware,
                        firmware_version: identity.firmware_version,
                        profile: identity.profile,
                        capabilities: identity.capabilities,
                        map_capacity: identity.map_capacity,
                        telemetry_hz: status.telemetry_hz,
                        failsafe_ms: status.failsafe_ms,
                        robot_id: status.robot_id,
                    };
                    st.send_in(answer_in, &Message::HelloReply(reply), now_ms);
                    if !accepted {
                        let ev = Event {
                            code: EventCode::HandshakeRefused,
                            value: i32::from(h.protocol),
                        };
                        st.send_in(answer_in, &Message::Event(ev), now_ms);
                    }
                }
                Message::Command(command) => {
                    let seq = header.seq;
                    // The command decoded, so it re-encodes; 0 could only fail to match.
                    let digest = retry_digest(seq, &Message::Command(command)).unwrap_or(0);
                    st.forget_expired(now_ms);
                    let reply = if st.session.is_none() {
                        st.counters.refused_before_handshake =
                            st.counters.refused_before_handshake.wrapping_add(1);
                        Reply::Nack(NackReason::NoHandshake)
                    } else if let Some(r) = st.remembered(digest) {
                        st.counters.retries_answered = st.counters.retries_answered.wrapping_add(1);
                        r
                    } else {
                        let r = match on(Inbound::Command { seq, command }) {
                            Response::Reply(r) => r,
                            // A command always gets an answer; "nothing" means it was not
                            // acted on.
                            Response::Nothing | Response::Send(_) | Response::Session(_) => {
                                Reply::Nack(NackReason::BadState)
                            }
                        };
                        st.remember(digest, r, now_ms);
                        r
                    };
                    st.send_reply(seq, reply, now_ms);
                }
                m @ (Message::TransferBegin(_)
                | Message::TransferChunk(_)
                | Message::TransferData(_)
                | Message::TransferAck(_))
                    if st.session.is_some() =>
                {
                    if let Response::Send(out) = on(Inbound::Transfer(m)) {
                        st.send(&out, now_ms);
                    }
                }
                // Heartbeats only refresh `last_rx_ms`; robot-bound kinds from a station
                // (telemetry, acks, ...) are ignored.
                _ => {}
            }
        }
    }

    /// Queues a frame if it fits whole; returns whether it was queued.
    pub fn send(&mut self, msg: &Message<'_>, now_ms: u32) -> bool {
        self.st.send(msg, now_ms)
    }

    /// Queues telemetry (or any low-priority frame) only if replies keep their reserve.
    pub fn send_low_priority(&mut self, msg: &Message<'_>, now_ms: u32) -> bool {
        self.st.send_low_priority(msg, now_ms)
    }

    /// Sends a heartbeat if nothing was sent for `period_ms` while connected.
    pub fn heartbeat(&mut self, now_ms: u32, period_ms: u32) {
        self.st.heartbeat(now_ms, period_ms)
    }

    /// Hands queued bytes to `write` (which returns how many it took) until it takes none.
    pub fn flush(&mut self, write: &mut dyn FnMut(&[u8]) -> usize) {
        self.st.flush(write)
    }

    /// Bytes waiting to be sent.
    pub fn queued(&self) -> usize {
        self.st.tx.len()
    }

    /// Whether a reply is remembered for a retry (`expire` forgets it in time).
    pub fn remembers_replies(&self) -> bool {
        self.st.replies.iter().any(Option::is_some)
    }
}

impl LinkState {
    /// Tells the station why its `Hello` was not even read. Only a `Hello` is answered, so a
    /// flood of forged frames gets at most one small frame per frame back, and the answer
    /// yields to replies like telemetry does.
    fn refuse_unauthenticated(&mut self, e: AuthError, now_ms: u32) {
        let ev = Event {
            code: EventCode::HandshakeRefused,
            value: auth_refusal_code(&e),
        };
        self.send_low_priority(&Message::Event(ev), now_ms);
    }

    /// The reply to a true retry: same number and content (one digest), still remembered.
    fn remembered(&self, digest: u32) -> Option<Reply> {
        self.replies
            .iter()
            .flatten()
            .find(|r| r.digest == digest)
            .map(|r| r.reply)
    }

    /// Remembers a reply in a free slot, or in place of the oldest one.
    fn remember(&mut self, digest: u32, reply: Reply, now_ms: u32) {
        let age = |slot: &Option<Remembered>| match slot {
            None => u32::MAX,
            Some(r) => now_ms.wrapping_sub(r.at_ms),
        };
        if let Some(slot) = self.replies.iter_mut().max_by_key(|s| age(s)) {
            *slot = Some(Remembered {
                at_ms: now_ms,
                digest,
                reply,
            });
        }
    }

    fn forget_expired(&mut self, now_ms: u32) {
        for slot in &mut self.replies {
            if slot.is_some_and(|r| r.expired(now_ms)) {
                *slot = None;
            }
        }
    }

    fn send_reply(&mut self, cmd_seq: u16, reply: Reply, now_ms: u32) {
        let msg = match reply {
            Reply::Ack(info) => Message::Ack(Ack { cmd_seq, info }),
            Reply::Nack(reason) => Message::Nack(Nack { cmd_seq, reason }),
        };
        self.send(&msg, now_ms);
    }

    /// Queues a frame if it fits whole; returns whether it was queued.
    // Not inlined: `receive` sends from several places, and each inlined copy kept its own
    // frame buffer in `receive`'s frame, under the decoder's and the handler's (issue 15).
    fn send(&mut self, msg: &Message<'_>, now_ms: u32) -> bool {
        self.send_in(self.auth.binding(), msg, now_ms)
    }

    /// `send`, signed as if `session` were in force (the answers to a `Hello`).
    #[inline(never)]
    fn send_in(&mut self, session: Binding, msg: &Message<'_>, now_ms: u32) -> bool {
        let mut buf = [0u8; MAX_FRAME];
        // The robot has no wall clock: its timestamps count on from the station's.
        let Ok(n) = self.auth.encode_in(session, self.tx_seq, msg, 0, &mut buf) else {
            self.counters.frames_dropped = self.counters.frames_dropped.wrapping_add(1);
            return false;
        };
        if self.tx.capacity() - self.tx.len() < n {
            self.counters.frames_dropped = self.counters.frames_dropped.wrapping_add(1);
            return false;
        }
        for b in buf.iter().take(n) {
            // Room was checked above, so no push can fail.
            let _ = self.tx.push_back(*b);
        }
        self.tx_seq = self.tx_seq.wrapping_add(1);
        self.last_tx_ms = now_ms;
        self.counters.frames_out = self.counters.frames_out.wrapping_add(1);
        true
    }

    /// Queues telemetry (or any low-priority frame) only if replies keep their reserve.
    fn send_low_priority(&mut self, msg: &Message<'_>, now_ms: u32) -> bool {
        self.keeps_reserve() && self.send(msg, now_ms)
    }

    /// Whether a low-priority frame may be queued now; counts it skipped if not.
    fn keeps_reserve(&mut self) -> bool {
        let room = self.tx.capacity() - self.tx.len() >= TELEMETRY_RESERVE;
        if !room {
            self.counters.telemetry_skipped = self.counters.telemetry_skipped.wrapping_add(1);
        }
        room
    }

    /// Sends a heartbeat if nothing was sent for `period_ms` while connected.
    fn heartbeat(&mut self, now_ms: u32, period_ms: u32) {
        if self.session.is_some() && now_ms.wrapping_sub(self.last_tx_ms) >= period_ms {
            let hb = protocol::Heartbeat { time_ms: now_ms };
            self.send_low_priority(&Message::Heartbeat(hb), now_ms);
        }
    }

    /// Hands queued bytes to `write` (which returns how many it took) until it takes none.
    fn flush(&mut self, write: &mut dyn FnMut(&[u8]) -> usize) {
        loop {
            let (front, _) = self.tx.as_slices();
            if front.is_empty() {
                return;
            }
            let n = write(front).min(front.len());
            if n == 0 {
                return;
            }
            for _ in 0..n {
                self.tx.pop_front();
            }
            self.counters.bytes_out += n as u64;
        }
    }
}

/// `Event HandshakeRefused`'s value for a `Hello` the authentication layer refused
/// (PROTOCOL.md §13); a refused fingerprint or version reports the version, a positive number.
pub fn auth_refusal_code(e: &AuthError) -> i32 {
    match e {
        AuthError::Unsigned => -1,
        AuthError::BadSignature { .. } => -2,
        AuthError::StaleTimestamp { .. } => -3,
        AuthError::UnexpectedSignature { .. } => -4,
        AuthError::WrongDirection { .. } => -5,
        AuthError::TooManyLinks { .. } => -6,
    }
}

/// Values the `HelloReply` reports that live outside the link.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LinkStatus {
    pub telemetry_hz: u8,
    pub failsafe_ms: u16,
    pub robot_id: u8,
}
