//! Chunked object transfer (PROTOCOL.md §8): the sender's and the receiver's state machines,
//! used by the robot and by the station alike.
//!
//! Layer: protocol state with no I/O and no clock (like `seq.rs`). Time comes in as wrapping
//! milliseconds; frames go out through a caller's `send` closure that says whether it queued
//! the frame; object bytes live in caller buffers (`[u8; N]` on the robot, `Vec<u8>` on the
//! station), so nothing here allocates or owns storage.
//!
//! Selective repeat over [`UNIT`]-byte units. [`Receiver`] takes a chunk at `next` and also
//! one past it that starts on the unit grid within [`SACK_SPAN`] bytes, answers every chunk
//! with a `TransferAck` whose `next` is cumulative and whose `sack` bitmap names the units
//! past `next` it holds, keeps a partial object for resuming when the same id and CRC begin
//! again, and hands the staged bytes to the owner's `install` closure only when all of them
//! are there and their CRC-32C matches. The owner installs atomically (validate, then
//! replace), so the old object stays in use until a verified new one replaces it.
//!
//! [`Sender`] sends `TransferBegin`, waits for the receiver's answer, then keeps at most
//! `timing::TRANSFER_WINDOW` chunks' worth of unacknowledged units in flight. The line is a
//! FIFO, so a unit missing below one the receiver holds that was sent after it is lost: those
//! units go again at once (selective retransmission, one round per window of evidence, as in
//! RFC 6675). A retransmission timer from measured round trips (RFC 6298: Karn's rule,
//! Jacobson's mean and variance, backoff) covers a lost tail; each loss round halves the chunk
//! size (down to [`MIN_CHUNK`]) and loss-free progress grows it back. With no progress for
//! [`MAX_TIMEOUTS`] x `TRANSFER_RETRY_MS` it gives up.
//!
//! What can fail: every failure is an [`Outcome`] the sender reports (refused, CRC mismatch,
//! unknown id, timed out, object changed under it); the receiver never fails, it answers a
//! status. No function here panics on any input.

use crate::msg::{TransferAck, TransferChunk, TransferStatus, MAX_CHUNK};

mod receiver;
mod sender;

pub use receiver::{Receiver, Verified};
pub use sender::{Outcome, Sender, SenderStats, MIN_WINDOW_UNITS};

/// No progress for `MAX_TIMEOUTS` x `TRANSFER_RETRY_MS` and a sender gives up.
pub const MAX_TIMEOUTS: u8 = 5;
/// The unit of selective acknowledgement, bytes: chunks past `next` start on this grid and
/// are a whole number of units long (or end the object).
pub const UNIT: u32 = 32;
/// Bytes past `next` a `sack` bitmap covers (32 units): chunks past it are not taken.
pub const SACK_SPAN: u32 = 32 * UNIT;
/// The smallest chunk a sender falls back to on a lossy line, bytes.
pub const MIN_CHUNK: u32 = UNIT;
/// `UnknownId` answers a sender survives (it restarts with `TransferBegin` each time).
pub const MAX_RESTARTS: u8 = 5;
/// The retransmission timeout never goes below this, ms: the robot answers within its 1 ms
/// cycle, so a shorter timer only fires on frames still on the wire.
pub const MIN_RTO_MS: u32 = 20;
/// Bytes a `TransferData` frame carries besides its data (COBS 1, delimiter 1, header 4,
/// CRC 4, tag 1, offset 2 as a varint past byte 127): the cost [`chunk_for_loss`] weighs
/// against the loss of a longer frame.
pub const CHUNK_OVERHEAD: u32 = 13;
/// The tag no transfer has: a receiver refuses a `TransferBegin` carrying it, and answers a
/// retired kind-8 chunk with it (nothing to confuse with a transfer in progress).
pub const NO_TAG: u8 = 0;

/// The tag a sender uses after `prev`: the next value, skipping [`NO_TAG`], so two transfers
/// in a row never share one (a late answer to the previous one is not taken for this one's).
pub const fn next_tag(prev: u8) -> u8 {
    match prev.wrapping_add(1) {
        NO_TAG => 1,
        t => t,
    }
}

/// The answer to a retired protocol-1 chunk (kind 8, named by a 32-bit id): refused, with
/// [`NO_TAG`], and nothing changed. Its sender is a build from before tags, which the
/// handshake refuses already; this keeps a raw client's frame from being read as anything.
pub const fn refuse_retired_chunk(_: &TransferChunk<'_>) -> TransferAck {
    ack(NO_TAG, 0, TransferStatus::Rejected)
}
/// The chunk size (a whole number of units, `MIN_CHUNK..=MAX_CHUNK`) that carries the most
/// data per line byte when each byte is lost with probability `loss_ppm` / 1e6: a chunk of
/// `c` bytes arrives with probability `(1 - p)^(c + CHUNK_OVERHEAD)`, and carries
/// `c / (c + CHUNK_OVERHEAD)` of what it costs. A clean line gets `MAX_CHUNK`.
pub fn chunk_for_loss(loss_ppm: u32) -> u32 {
    let q = 1.0 - f64::from(loss_ppm.min(1_000_000)) / 1e6;
    let mut best = (0.0, MIN_CHUNK);
    let mut c = MIN_CHUNK;
    while c <= MAX_CHUNK as u32 {
        let frame = c + CHUNK_OVERHEAD;
        let mut arrive = 1.0;
        for _ in 0..frame {
            arrive *= q;
        }
        let gain = arrive * f64::from(c) / f64::from(frame);
        if gain > best.0 {
            best = (gain, c);
        }
        c += UNIT;
    }
    best.1
}

const fn ack(tag: u8, next: u32, status: TransferStatus) -> TransferAck {
    TransferAck {
        tag,
        next,
        status,
        sack: 0,
    }
}

/// Units `first..last` as a bitmap (bits past 31 dropped).
fn units(first: u32, last: u32) -> u32 {
    let ones = |n: u32| if n >= 32 { u32::MAX } else { (1u32 << n) - 1 };
    ones(last) & !ones(first)
}

/// `map` with its units moved down by `bytes` (a multiple of `UNIT`; otherwise nothing of it
/// is kept, which only costs resends).
fn shift(map: u32, bytes: u32) -> u32 {
    if bytes % UNIT != 0 {
        return 0;
    }
    map.checked_shr(bytes / UNIT).unwrap_or(0)
}

#[cfg(test)]
mod tests;
