//! Chunked object transfer (PROTOCOL.md §8): the sender's and the receiver's state machines,
//! used by the robot and by the station alike.
//!
//! Layer: protocol state with no I/O and no clock (like `seq.rs`). Time comes in as wrapping
//! milliseconds; frames go out through a caller's `send` closure that says whether it queued
//! the frame; object bytes live in caller buffers (`[u8; N]` on the robot, `Vec<u8>` on the
//! station), so nothing here allocates or owns storage.
//!
//! [`Receiver`] accepts a chunk only at `offset == next` (go-back-N), answers every chunk with
//! a cumulative `TransferAck`, keeps a partial object for resuming when the same id and CRC
//! begin again, and hands the staged bytes to the owner's `install` closure only when all of
//! them are there and their CRC-32C matches. The owner installs atomically (validate, then
//! replace), so the old object stays in use until a verified new one replaces it.
//!
//! [`Sender`] sends `TransferBegin`, waits for the receiver's answer, then keeps up to
//! `timing::TRANSFER_WINDOW` chunks unacknowledged. It rewinds to the last acknowledged offset
//! once per stall on a duplicate ack (a lost chunk) and after `timing::TRANSFER_RETRY_MS` with
//! no progress, halving its chunk size at each such timeout (down to [`MIN_CHUNK`]); after
//! [`MAX_TIMEOUTS`] timeouts in a row it gives up.
//!
//! What can fail: every failure is an [`Outcome`] the sender reports (refused, CRC mismatch,
//! unknown id, timed out, object changed under it); the receiver never fails, it answers a
//! status. No function here panics on any input.

use core::fmt;

use crate::frame::crc32c;
use crate::msg::{
    Message, ObjectKind, TransferAck, TransferBegin, TransferChunk, TransferStatus, MAX_CHUNK,
};
use crate::timing::{TRANSFER_RETRY_MS, TRANSFER_WINDOW};

/// Timeouts in a row (no progress for `TRANSFER_RETRY_MS` each) before a sender gives up.
pub const MAX_TIMEOUTS: u8 = 5;
/// The smallest chunk a sender falls back to after timeouts, bytes.
pub const MIN_CHUNK: u32 = 32;
/// `UnknownId` answers a sender survives (it restarts with `TransferBegin` each time).
pub const MAX_RESTARTS: u8 = 5;
/// Bytes a sender keeps unacknowledged: the window in whole chunks.
const WINDOW_BYTES: u32 = TRANSFER_WINDOW * MAX_CHUNK as u32;

/// Staged object bytes whose CRC matched, handed to the owner's `install`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Verified<'a> {
    pub object: ObjectKind,
    pub id: u32,
    pub crc: u32,
    pub bytes: &'a [u8],
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum RxState {
    Idle,
    Receiving {
        object: ObjectKind,
        id: u32,
        len: u32,
        crc: u32,
        next: u32,
    },
    /// The last transfer ended; its answer is repeated to late or duplicated chunks.
    Finished {
        id: u32,
        next: u32,
        status: TransferStatus,
    },
}

/// The receiving side of transfers: one object at a time, staged in a caller buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Receiver {
    state: RxState,
}

impl Default for Receiver {
    fn default() -> Self {
        Self::new()
    }
}

fn ack(id: u32, next: u32, status: TransferStatus) -> TransferAck {
    TransferAck { id, next, status }
}

impl Receiver {
    pub const fn new() -> Self {
        Receiver {
            state: RxState::Idle,
        }
    }

    /// Answers a `TransferBegin`. `limit` is the most bytes the owner accepts for this kind
    /// (at most its staging buffer; 0 refuses the kind); `have` says the owner already holds
    /// an object of this kind with this id and CRC. A refusal or `AlreadyHave` changes nothing,
    /// so a partial object of another transfer is kept for resuming.
    pub fn on_begin(&mut self, b: &TransferBegin, limit: usize, have: bool) -> TransferAck {
        if have {
            return ack(b.id, b.len, TransferStatus::AlreadyHave);
        }
        let too_big = usize::try_from(b.len).map_or(true, |len| len > limit);
        if b.len == 0 || too_big {
            return ack(b.id, 0, TransferStatus::Rejected);
        }
        if let RxState::Receiving {
            object,
            id,
            len,
            crc,
            next,
        } = self.state
        {
            if (object, id, len, crc) == (b.object, b.id, b.len, b.crc) {
                // The same object again (a retry or a restarted sender): resume.
                return ack(id, next, TransferStatus::Receiving);
            }
        }
        self.state = RxState::Receiving {
            object: b.object,
            id: b.id,
            len: b.len,
            crc: b.crc,
            next: 0,
        };
        ack(b.id, 0, TransferStatus::Receiving)
    }

    /// Answers a `TransferChunk`, writing its data to `staging` when it is the next one. When
    /// the object is whole and its CRC matches, calls `install` with it: `true` means
    /// installed (`Complete`), `false` refused as malformed (`Rejected`, old object kept).
    pub fn on_chunk<F>(
        &mut self,
        c: &TransferChunk<'_>,
        staging: &mut [u8],
        install: F,
    ) -> TransferAck
    where
        F: FnOnce(Verified<'_>) -> bool,
    {
        let (object, id, len, crc, next) = match self.state {
            RxState::Receiving {
                object,
                id,
                len,
                crc,
                next,
            } if id == c.id => (object, id, len, crc, next),
            RxState::Finished { id, next, status } if id == c.id => return ack(id, next, status),
            _ => return ack(c.id, 0, TransferStatus::UnknownId),
        };
        let receiving = ack(id, next, TransferStatus::Receiving);
        // Go-back-N: anything but the next chunk is dropped and answered with `next`.
        let end = next as usize + c.data.len();
        if c.offset != next || c.data.is_empty() || c.data.len() > MAX_CHUNK || end > len as usize {
            return receiving;
        }
        let Some(slot) = staging.get_mut(next as usize..end) else {
            // The owner's buffer is smaller than the limit it allowed: refuse, never panic.
            return self.finish(id, 0, TransferStatus::Rejected);
        };
        slot.copy_from_slice(c.data);
        let next = end as u32;
        if next < len {
            self.state = RxState::Receiving {
                object,
                id,
                len,
                crc,
                next,
            };
            return ack(id, next, TransferStatus::Receiving);
        }
        let bytes = staging.get(..len as usize).unwrap_or(&[]);
        if crc32c(bytes) != crc {
            return self.finish(id, 0, TransferStatus::CrcMismatch);
        }
        let verified = Verified {
            object,
            id,
            crc,
            bytes,
        };
        if install(verified) {
            self.finish(id, len, TransferStatus::Complete)
        } else {
            self.finish(id, 0, TransferStatus::Rejected)
        }
    }

    fn finish(&mut self, id: u32, next: u32, status: TransferStatus) -> TransferAck {
        self.state = RxState::Finished { id, next, status };
        ack(id, next, status)
    }

    /// The transfer in progress: (object, id, bytes held, total bytes).
    pub fn progress(&self) -> Option<(ObjectKind, u32, u32, u32)> {
        match self.state {
            RxState::Receiving {
                object,
                id,
                len,
                next,
                ..
            } => Some((object, id, next, len)),
            _ => None,
        }
    }

    /// Forgets any partial object (it can no longer be resumed).
    pub fn reset(&mut self) {
        self.state = RxState::Idle;
    }
}

/// How a sender's transfer ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// The receiver verified and installed the object.
    Complete,
    /// The receiver already held it; nothing (more) was sent.
    AlreadyHave,
    /// The receiver refused it: too large, a kind it does not take, or malformed.
    Rejected,
    /// All bytes arrived but their CRC-32C did not match the one announced.
    CrcMismatch,
    /// The receiver kept forgetting the transfer (`UnknownId` after every restart).
    UnknownId,
    /// `MAX_TIMEOUTS` retry periods in a row passed without progress.
    TimedOut,
    /// The receiver cannot take the object now (the robot is calibrating); nothing changed.
    Busy,
    /// The bytes handed to `poll` are not as long as the object announced.
    ObjectChanged,
}

impl Outcome {
    /// Whether the receiver now holds the object.
    pub const fn is_success(self) -> bool {
        matches!(self, Outcome::Complete | Outcome::AlreadyHave)
    }
}

impl fmt::Display for Outcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Outcome::Complete => "transfer complete",
            Outcome::AlreadyHave => "receiver already holds the object",
            Outcome::Rejected => "receiver refused the object (too large or malformed)",
            Outcome::CrcMismatch => "object CRC mismatch at the receiver",
            Outcome::UnknownId => "receiver does not know the transfer",
            Outcome::TimedOut => "transfer timed out",
            Outcome::Busy => {
                "receiver is busy with the object (the robot is calibrating); try later"
            }
            Outcome::ObjectChanged => "object changed during the transfer",
        })
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    /// `TransferBegin` sent (or due); waiting for the receiver's first answer.
    Begin,
    /// Sending chunks from `sent`, everything before `acked` confirmed.
    Sending,
    Done(Outcome),
}

/// The sending side of one transfer. Holds no bytes: `poll` borrows them each time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sender {
    begin: TransferBegin,
    phase: Phase,
    /// Every byte before this is acknowledged.
    acked: u32,
    /// The next byte to send.
    sent: u32,
    begin_due: bool,
    /// The `acked` value at which the last duplicate-ack rewind happened.
    rewound_at: Option<u32>,
    /// When the current retry period ends; set at the first `poll`.
    deadline_ms: Option<u32>,
    timeouts: u8,
    restarts: u8,
    /// Bytes per chunk: `MAX_CHUNK`, halved after each timeout (down to `MIN_CHUNK`), because
    /// on a noisy line a long frame is the likeliest to be hit: with 1e-3 bit flips and 1 % of
    /// bytes dropped a full chunk frame arrives intact about 1 time in 75, a 32-byte one about
    /// 2 times in 5 (PROTOCOL.md §8).
    chunk: u32,
}

/// Whether wrapping time `now` has reached `deadline`.
fn due(now: u32, deadline: u32) -> bool {
    now.wrapping_sub(deadline) < 0x8000_0000
}

impl Sender {
    /// A transfer of `len` bytes whose CRC-32C the caller states as `crc` (normally
    /// `crc32c(bytes)`; a wrong value makes the receiver answer `CrcMismatch`).
    pub const fn new(object: ObjectKind, id: u32, len: u32, crc: u32) -> Self {
        Sender {
            begin: TransferBegin {
                object,
                id,
                len,
                crc,
            },
            phase: Phase::Begin,
            acked: 0,
            sent: 0,
            begin_due: true,
            rewound_at: None,
            deadline_ms: None,
            timeouts: 0,
            restarts: 0,
            chunk: MAX_CHUNK as u32,
        }
    }

    /// A transfer of `bytes` under the id convention (id = CRC-32C of the bytes); `None` if
    /// the object is longer than `u32::MAX` bytes.
    pub fn for_object(object: ObjectKind, bytes: &[u8]) -> Option<Self> {
        let len = u32::try_from(bytes.len()).ok()?;
        let crc = crc32c(bytes);
        Some(Sender::new(object, crc, len, crc))
    }

    /// The `TransferBegin` this sender announces.
    pub const fn begin(&self) -> TransferBegin {
        self.begin
    }

    /// Bytes acknowledged and total bytes (for a progress bar).
    pub const fn progress(&self) -> (u32, u32) {
        (self.acked, self.begin.len)
    }

    /// How the transfer ended, once it has.
    pub const fn outcome(&self) -> Option<Outcome> {
        match self.phase {
            Phase::Done(o) => Some(o),
            _ => None,
        }
    }

    /// Whether the transfer has ended (see [`outcome`](Self::outcome)).
    pub const fn is_done(&self) -> bool {
        matches!(self.phase, Phase::Done(_))
    }

    /// Ends the transfer with `outcome` (e.g. the owner aborts it).
    pub fn abort(&mut self, outcome: Outcome) {
        if !self.is_done() {
            self.phase = Phase::Done(outcome);
        }
    }

    /// Sends what is due at `now_ms`: the `TransferBegin` (first time and after timeouts),
    /// then chunks of `bytes` within the window. `send` returns whether it queued the frame;
    /// a frame it could not take is offered again at the next poll.
    pub fn poll<F>(&mut self, now_ms: u32, bytes: &[u8], mut send: F)
    where
        F: FnMut(&Message<'_>) -> bool,
    {
        if self.is_done() {
            return;
        }
        if bytes.len() != self.begin.len as usize {
            self.phase = Phase::Done(Outcome::ObjectChanged);
            return;
        }
        let deadline = *self
            .deadline_ms
            .get_or_insert(now_ms.wrapping_add(TRANSFER_RETRY_MS));
        if due(now_ms, deadline) && !self.on_timeout(now_ms) {
            return;
        }
        if self.begin_due {
            if !send(&Message::TransferBegin(self.begin)) {
                return;
            }
            self.begin_due = false;
        }
        if self.phase != Phase::Sending {
            return;
        }
        while self.sent < self.begin.len && self.sent.saturating_sub(self.acked) < WINDOW_BYTES {
            let end = self.begin.len.min(self.sent.saturating_add(self.chunk));
            let Some(data) = bytes.get(self.sent as usize..end as usize) else {
                return;
            };
            let chunk = TransferChunk {
                id: self.begin.id,
                offset: self.sent,
                data,
            };
            if !send(&Message::TransferChunk(chunk)) {
                return;
            }
            self.sent = end;
        }
    }

    /// A retry period passed without progress: rewind, or give up. Returns whether to go on.
    fn on_timeout(&mut self, now_ms: u32) -> bool {
        self.timeouts = self.timeouts.saturating_add(1);
        self.chunk = (self.chunk / 2).max(MIN_CHUNK);
        if self.timeouts >= MAX_TIMEOUTS {
            self.phase = Phase::Done(Outcome::TimedOut);
            return false;
        }
        self.deadline_ms = Some(now_ms.wrapping_add(TRANSFER_RETRY_MS));
        match self.phase {
            Phase::Begin => self.begin_due = true,
            _ => {
                self.sent = self.acked;
                self.rewound_at = None;
            }
        }
        true
    }

    fn progressed(&mut self, now_ms: u32) {
        self.timeouts = 0;
        self.deadline_ms = Some(now_ms.wrapping_add(TRANSFER_RETRY_MS));
    }

    /// Takes the receiver's `TransferAck` into account (acks for other ids are ignored).
    pub fn on_ack(&mut self, a: &TransferAck, now_ms: u32) {
        if self.is_done() || a.id != self.begin.id {
            return;
        }
        let outcome = match a.status {
            TransferStatus::Receiving => return self.on_receiving(a.next, now_ms),
            TransferStatus::Complete => Outcome::Complete,
            TransferStatus::AlreadyHave => Outcome::AlreadyHave,
            TransferStatus::CrcMismatch => Outcome::CrcMismatch,
            TransferStatus::Rejected => Outcome::Rejected,
            TransferStatus::Busy => Outcome::Busy,
            TransferStatus::UnknownId => {
                // The receiver lost the transfer (restarted, or took another): begin again.
                self.restarts = self.restarts.saturating_add(1);
                if self.restarts <= MAX_RESTARTS {
                    self.phase = Phase::Begin;
                    self.begin_due = true;
                    self.progressed(now_ms);
                    return;
                }
                Outcome::UnknownId
            }
        };
        if outcome == Outcome::Complete {
            self.acked = self.begin.len;
        }
        self.phase = Phase::Done(outcome);
    }

    fn on_receiving(&mut self, next: u32, now_ms: u32) {
        if next > self.begin.len {
            return; // Not an answer to this object: ignore rather than trust it.
        }
        if self.phase == Phase::Begin {
            self.phase = Phase::Sending;
            self.acked = next;
            self.sent = next;
            self.rewound_at = None;
            self.progressed(now_ms);
        } else if next > self.acked {
            self.acked = next;
            self.sent = self.sent.max(next);
            self.rewound_at = None;
            self.progressed(now_ms);
        } else if next == self.acked && self.sent > next && self.rewound_at != Some(next) {
            // A duplicate ack: a chunk at `next` was lost (or overtaken). Go back once for
            // this offset; the retry timer covers the rest.
            self.sent = next;
            self.rewound_at = Some(next);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frames(s: &mut Sender, now: u32, bytes: &[u8]) -> (usize, [u32; 8]) {
        let mut offsets = [u32::MAX; 8];
        let mut n = 0;
        s.poll(now, bytes, |m| {
            if let Message::TransferChunk(c) = m {
                if let Some(slot) = offsets.get_mut(n) {
                    *slot = c.offset;
                }
            }
            n += 1;
            true
        });
        (n, offsets)
    }

    #[test]
    fn the_sender_waits_for_the_begin_answer_then_fills_the_window() {
        let bytes = [7u8; 1000];
        let mut s = Sender::for_object(ObjectKind::Map, &bytes).expect("small");
        let (n, _) = frames(&mut s, 0, &bytes);
        assert_eq!(n, 1, "only TransferBegin before the receiver answers");
        let id = s.begin().id;
        s.on_ack(&ack(id, 0, TransferStatus::Receiving), 1);
        let (n, offs) = frames(&mut s, 1, &bytes);
        assert_eq!(n, 4);
        assert_eq!(offs[..4], [0, 224, 448, 672]);
        s.on_ack(&ack(id, 224, TransferStatus::Receiving), 2);
        let (n, offs) = frames(&mut s, 2, &bytes);
        assert_eq!((n, offs[0]), (1, 896));
    }

    #[test]
    fn the_sender_gives_up_after_five_silent_retry_periods() {
        let bytes = [1u8; 10];
        let mut s = Sender::for_object(ObjectKind::Plan, &bytes).expect("small");
        let mut begins = 0;
        for t in (0..10_000).step_by(10) {
            s.poll(t, &bytes, |_| {
                begins += 1;
                true
            });
        }
        assert_eq!(s.outcome(), Some(Outcome::TimedOut));
        assert_eq!(begins, 5, "first Begin and four resends");
    }

    #[test]
    fn the_receiver_drops_out_of_order_chunks_and_repeats_its_final_answer() {
        let data = [3u8; 300];
        let crc = crc32c(&data);
        let mut rx = Receiver::new();
        let begin = TransferBegin {
            object: ObjectKind::Map,
            id: 9,
            len: 300,
            crc,
        };
        assert_eq!(
            rx.on_begin(&begin, 100, false).status,
            TransferStatus::Rejected
        );
        assert_eq!(rx.on_begin(&begin, 300, false).next, 0);
        let mut staging = [0u8; 300];
        let chunk = |offset: u32, d: &'static [u8]| TransferChunk {
            id: 9,
            offset,
            data: d,
        };
        let never = |_: Verified<'_>| -> bool { panic!("not yet") };
        let a = rx.on_chunk(&chunk(224, &[3; 76]), &mut staging, never);
        assert_eq!((a.next, a.status), (0, TransferStatus::Receiving));
        let a = rx.on_chunk(&chunk(0, &[3; 224]), &mut staging, never);
        assert_eq!(a.next, 224);
        assert_eq!(rx.on_begin(&begin, 300, false).next, 224, "resume");
        let a = rx.on_chunk(&chunk(224, &[3; 76]), &mut staging, |v| v.bytes == data);
        assert_eq!((a.next, a.status), (300, TransferStatus::Complete));
        let a = rx.on_chunk(&chunk(224, &[3; 76]), &mut staging, never);
        assert_eq!(a.status, TransferStatus::Complete);
        let other = TransferChunk {
            id: 10,
            offset: 0,
            data: &[1],
        };
        assert_eq!(
            rx.on_chunk(&other, &mut staging, never).status,
            TransferStatus::UnknownId
        );
    }
}
