//! The receiving side of a transfer (PROTOCOL.md §8): one object at a time, staged in a
//! caller buffer, answered chunk by chunk, installed only when whole and its CRC matches.
//!
//! Layer: protocol state, no I/O and no clock. Never fails: every chunk gets a status.

use super::{ack, shift, units, NO_TAG, SACK_SPAN, UNIT};
use crate::frame::crc32c;
use crate::msg::{ObjectKind, TransferAck, TransferBegin, TransferData, TransferStatus, MAX_CHUNK};

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
        /// The sender's name for this transfer (its chunks and our answers carry it).
        tag: u8,
        len: u32,
        crc: u32,
        next: u32,
        /// Units past `next` held (bit i: `[next + UNIT i, next + UNIT (i + 1))`).
        sack: u32,
    },
    /// The last transfer ended; its answer is repeated to late or duplicated chunks.
    Finished {
        tag: u8,
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
            // A late chunk of this id gets this same final answer again (PROTOCOL.md §8),
            // not the `Complete` of an earlier transfer of it; a partial object of another
            // transfer is kept for resuming, so then such a chunk gets `UnknownId`.
            if !matches!(self.state, RxState::Receiving { .. }) {
                self.state = RxState::Finished {
                    tag: b.tag,
                    next: b.len,
                    status: TransferStatus::AlreadyHave,
                };
            }
            return ack(b.tag, b.len, TransferStatus::AlreadyHave);
        }
        let too_big = usize::try_from(b.len).map_or(true, |len| len > limit);
        if b.len == 0 || too_big || b.tag == NO_TAG {
            return ack(b.tag, 0, TransferStatus::Rejected);
        }
        if let RxState::Receiving {
            object,
            id,
            len,
            crc,
            next,
            sack,
            ..
        } = self.state
        {
            if (object, id, len, crc) == (b.object, b.id, b.len, b.crc) {
                // The same object again (a retry or a restarted sender): resume, under the
                // tag this Begin gives (a new sender picks a new one).
                self.state = RxState::Receiving {
                    object,
                    id,
                    tag: b.tag,
                    len,
                    crc,
                    next,
                    sack,
                };
                return TransferAck {
                    sack,
                    ..ack(b.tag, next, TransferStatus::Receiving)
                };
            }
        }
        self.state = RxState::Receiving {
            object: b.object,
            id: b.id,
            tag: b.tag,
            len: b.len,
            crc: b.crc,
            next: 0,
            sack: 0,
        };
        ack(b.tag, 0, TransferStatus::Receiving)
    }

    /// Answers a `TransferData` chunk, writing its data to `staging` when it is new and in the
    /// span (at `next`, or past it on the unit grid). When the object is whole and its CRC
    /// matches, calls `install` with it: `true` means installed (`Complete`), `false` refused
    /// as malformed (`Rejected`, old object kept).
    pub fn on_chunk<F>(
        &mut self,
        c: &TransferData<'_>,
        staging: &mut [u8],
        install: F,
    ) -> TransferAck
    where
        F: FnOnce(Verified<'_>) -> bool,
    {
        let (object, id, tag, len, crc, mut next, mut sack) = match self.state {
            RxState::Receiving {
                object,
                id,
                tag,
                len,
                crc,
                next,
                sack,
            } if tag == c.tag && tag != NO_TAG => (object, id, tag, len, crc, next, sack),
            RxState::Finished { tag, next, status } if tag == c.tag && tag != NO_TAG => {
                return ack(tag, next, status)
            }
            _ => return ack(c.tag, 0, TransferStatus::UnknownId),
        };
        let current = TransferAck {
            sack,
            ..ack(tag, next, TransferStatus::Receiving)
        };
        let end = u64::from(c.offset) + c.data.len() as u64;
        if c.data.is_empty() || c.data.len() > MAX_CHUNK || end > u64::from(len) {
            return current;
        }
        let end = end as u32;
        if end <= next {
            return current; // A duplicate of bytes held.
        }
        // Bytes before `next` are held already: only the rest of the chunk is new.
        let start = c.offset.max(next);
        let data = c.data.get((start - c.offset) as usize..).unwrap_or(&[]);
        let ahead = start - next;
        // Past `next`, only whole units on the grid inside the span can be named in `sack`.
        let whole = data.len() as u32 % UNIT == 0 || end == len;
        if ahead > 0 && (ahead % UNIT != 0 || !whole || end - next > SACK_SPAN) {
            return current;
        }
        let Some(slot) = staging.get_mut(start as usize..end as usize) else {
            // The owner's buffer is smaller than the limit it allowed: refuse, never panic.
            return self.finish(tag, 0, TransferStatus::Rejected);
        };
        slot.copy_from_slice(data);
        if ahead > 0 {
            sack |= units(ahead / UNIT, (end - next).div_ceil(UNIT));
        } else {
            sack = shift(sack, end - next);
            next = end;
        }
        // Units held past the new `next` join it while they are contiguous.
        while sack & 1 == 1 && next < len {
            next = next.saturating_add(UNIT).min(len);
            sack >>= 1;
        }
        if next < len {
            self.state = RxState::Receiving {
                object,
                id,
                tag,
                len,
                crc,
                next,
                sack,
            };
            return TransferAck {
                sack,
                ..ack(tag, next, TransferStatus::Receiving)
            };
        }
        let bytes = staging.get(..len as usize).unwrap_or(&[]);
        if crc32c(bytes) != crc {
            return self.finish(tag, 0, TransferStatus::CrcMismatch);
        }
        let verified = Verified {
            object,
            id,
            crc,
            bytes,
        };
        if install(verified) {
            self.finish(tag, len, TransferStatus::Complete)
        } else {
            self.finish(tag, 0, TransferStatus::Rejected)
        }
    }

    fn finish(&mut self, tag: u8, next: u32, status: TransferStatus) -> TransferAck {
        self.state = RxState::Finished { tag, next, status };
        ack(tag, next, status)
    }

    /// The transfer in progress: (object, id, bytes held in order, total bytes).
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

    /// The object of the transfer in progress under `tag`, if there is one.
    pub fn receiving(&self, tag: u8) -> Option<ObjectKind> {
        match self.state {
            RxState::Receiving { object, tag: t, .. } if t == tag && t != NO_TAG => Some(object),
            _ => None,
        }
    }

    /// A new session began (a handshake, PROTOCOL.md §8 "Tags"): chunks are taken only after
    /// a Begin of this session has tagged the transfer, so a chunk of an earlier session (or
    /// of an earlier station that used the same tag) is answered `UnknownId` and lands
    /// nowhere. A partial object is kept for resuming; a finished transfer's answer is
    /// forgotten.
    pub fn new_session(&mut self) {
        match &mut self.state {
            RxState::Receiving { tag, .. } => *tag = NO_TAG,
            RxState::Finished { .. } => self.state = RxState::Idle,
            RxState::Idle => {}
        }
    }

    /// Forgets any partial object (it can no longer be resumed).
    pub fn reset(&mut self) {
        self.state = RxState::Idle;
    }
}
