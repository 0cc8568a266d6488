//! The sending side of a transfer (PROTOCOL.md §8): `TransferBegin`, then a window of chunks
//! with selective retransmission, a retransmission timer from measured round trips, and a
//! chunk size that follows the line's loss.
//!
//! Layer: protocol state, no I/O and no clock (time comes in as wrapping milliseconds). What
//! can fail is an [`Outcome`].

use core::fmt;

use super::{shift, units, MAX_RESTARTS, MAX_TIMEOUTS, MIN_RTO_MS, SACK_SPAN, UNIT};
use crate::frame::crc32c;
use crate::msg::{
    Message, ObjectKind, TransferAck, TransferBegin, TransferData, TransferStatus, MAX_CHUNK,
};
use crate::timing::{TRANSFER_RETRY_MS, TRANSFER_WINDOW};

/// Chunks acknowledged with no loss before the chunk size grows by one unit.
const GROW_AFTER: u8 = 8;

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
    /// Sending chunks; everything before `acked` confirmed.
    Sending,
    Done(Outcome),
}

/// What a sender did, for reports and for tests that count instead of timing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SenderStats {
    /// Chunk frames sent.
    pub chunks: u32,
    /// Of which carried units sent before (known lost, probes, or after a timer expiry).
    pub resent: u32,
    /// Units found lost from the receiver's answers (a unit sent later is held).
    pub lost_units: u32,
    /// Chunks sent as probes: an unanswered unit sent again when nothing else could go.
    pub probes: u32,
    /// Retransmission timer expiries.
    pub timeouts: u32,
}

/// Units past `acked` a sender tracks: the span a `sack` bitmap names.
const SPAN_UNITS: usize = 32;

/// The sending side of one transfer. Holds no bytes: `poll` borrows them each time.
///
/// Unit bitmaps (`sacked`, `lost`) and the per-unit arrays count [`UNIT`]s from `acked`,
/// like the receiver's `sack`. Every chunk sent gets a transmission number; the line is a
/// FIFO, so a unit held whose every copy was sent after a missing unit's last copy proves
/// that copy lost (QUIC's packet threshold, RFC 9002 §6.1.1, with a threshold of one on a
/// line that never reorders).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sender {
    begin: TransferBegin,
    phase: Phase,
    /// Every byte before this is acknowledged.
    acked: u32,
    /// Units past `acked` the receiver holds.
    sacked: u32,
    /// Units past `acked` known lost and not yet sent again.
    lost: u32,
    /// Of those, the ones the timer gave up on: an earlier copy may still be on the line.
    suspect: u32,
    /// The next byte never sent.
    sent: u32,
    /// Per unit: the transmission number of its latest copy, of its earliest copy that may
    /// still be on the line, and when its latest copy went out (ms, wrapping).
    last_tx: [u16; SPAN_UNITS],
    first_tx: [u16; SPAN_UNITS],
    sent_at: [u16; SPAN_UNITS],
    /// The next transmission number.
    tx_seq: u16,
    /// `tx_seq` when the chunk size last shrank: a loss of a unit sent before it is one the
    /// shrinking already answered.
    shrunk_at: u16,
    /// Smoothed round trip and its mean deviation, ms (RFC 6298); 0: no sample yet.
    srtt_ms: u16,
    rttvar_ms: u16,
    /// When the retransmission timer fires, and when the transfer last made progress.
    deadline_ms: u32,
    progress_ms: u32,
    /// The clocks above are set (at the first `poll`).
    started: bool,
    begin_due: bool,
    /// When the receiver last answered (or the Begin went out).
    last_ack_ms: u32,
    /// Timer expiries in a row: the timeout doubles with each (backoff).
    timeouts: u8,
    restarts: u8,
    /// `UnknownId` answers still expected for chunks sent before the last restart.
    unknown_echoes: u8,
    /// Chunk size in units: on a noisy line a long frame is the likeliest to be hit (with 1 %
    /// of bytes dropped a 224-byte chunk arrives about 1 time in 12, a 32-byte one about
    /// 3 times in 5), so a loss halves it and loss-free progress grows it back.
    chunk_units: u8,
    /// Chunks acknowledged since the last loss or growth.
    clean: u8,
    /// The line is unknown (no loss measurement, no loss seen yet): the chunk size started
    /// small and doubles with every chunk acknowledged without loss, as TCP's slow start
    /// doubles its window, until the first loss, expiry or measurement.
    probing: bool,
    stats: SenderStats,
}

/// Whether wrapping time `now` has reached `deadline`.
fn due(now: u32, deadline: u32) -> bool {
    now.wrapping_sub(deadline) < 0x8000_0000
}

/// Units a chunk of the largest size spans.
const MAX_CHUNK_UNITS: u8 = (MAX_CHUNK as u32 / UNIT) as u8;

/// The retransmission timeout before the first round trip is measured, ms, doubled with
/// each expiry in a row up to `TRANSFER_RETRY_MS`.
const FIRST_RTO_MS: u32 = 150;

/// Units of the first chunks on a line nothing is known of (`probing`). 224-byte chunks are
/// the clean line's best, and a lossy line's worst: with 1 % of bytes dropped 91 % of them
/// are lost, no round trip is measured, and the 400 ms first timeout runs out (measured:
/// uploads begun that way took about 1 s, against 0.2 s for those that began at 32 or 64
/// bytes). Two units arrive half the time at 1 %; doubling on each clean answer reaches 224
/// bytes within the first round trips of a clean line.
const PROBE_START_UNITS: u8 = 2;

/// Units the window holds at least, whatever the chunk size: with small chunks on a lossy
/// line, `TRANSFER_WINDOW` chunks would not cover a round trip with an ack queued behind a
/// telemetry frame, and the line would idle.
pub const MIN_WINDOW_UNITS: u32 = 8;

impl Sender {
    /// A transfer of `len` bytes whose CRC-32C the caller states as `crc` (normally
    /// `crc32c(bytes)`; a wrong value makes the receiver answer `CrcMismatch`), named `tag`
    /// on the wire (the caller's [`next_tag`] after its previous transfer's).
    pub const fn new(object: ObjectKind, id: u32, len: u32, crc: u32, tag: u8) -> Self {
        Sender {
            begin: TransferBegin {
                object,
                id,
                len,
                crc,
                tag,
            },
            phase: Phase::Begin,
            acked: 0,
            sacked: 0,
            lost: 0,
            suspect: 0,
            sent: 0,
            last_tx: [0; SPAN_UNITS],
            first_tx: [0; SPAN_UNITS],
            sent_at: [0; SPAN_UNITS],
            tx_seq: 0,
            shrunk_at: 0,
            srtt_ms: 0,
            rttvar_ms: 0,
            deadline_ms: 0,
            progress_ms: 0,
            started: false,
            begin_due: true,
            last_ack_ms: 0,
            timeouts: 0,
            restarts: 0,
            unknown_echoes: 0,
            chunk_units: PROBE_START_UNITS,
            clean: 0,
            probing: true,
            stats: SenderStats {
                chunks: 0,
                resent: 0,
                lost_units: 0,
                probes: 0,
                timeouts: 0,
            },
        }
    }

    /// A transfer of `bytes` under the id convention (id = CRC-32C of the bytes); `None` if
    /// the object is longer than `u32::MAX` bytes.
    pub fn for_object(object: ObjectKind, bytes: &[u8], tag: u8) -> Option<Self> {
        let len = u32::try_from(bytes.len()).ok()?;
        let crc = crc32c(bytes);
        Some(Sender::new(object, crc, len, crc, tag))
    }

    /// Starts with chunks of `bytes` (rounded down to whole units, `MIN_CHUNK..=MAX_CHUNK`)
    /// instead of probing a line nothing is known of: what the owner knows of the line, e.g.
    /// [`chunk_for_loss`].
    pub fn set_chunk(&mut self, bytes: u32) {
        self.chunk_units = (bytes / UNIT).clamp(1, u32::from(MAX_CHUNK_UNITS)) as u8;
        self.probing = false;
    }

    /// What the owner learned of the line during the transfer, e.g. its first loss
    /// measurement ([`chunk_for_loss`]), as chunk bytes: caps the chunk size at it, or, while
    /// the sender still probes an unknown line, replaces the guess with it. Otherwise it
    /// never grows the chunk: growth is earned by loss-free progress.
    pub fn limit_chunk(&mut self, bytes: u32) {
        let units = (bytes / UNIT).clamp(1, u32::from(MAX_CHUNK_UNITS)) as u8;
        if self.probing {
            self.probing = false;
            self.chunk_units = units;
            self.clean = 0;
        } else if units < self.chunk_units {
            self.chunk_units = units;
            self.clean = 0;
        }
    }

    /// The chunk size in use, bytes.
    pub const fn chunk(&self) -> u32 {
        self.chunk_units as u32 * UNIT
    }

    /// The `TransferBegin` this sender announces.
    pub const fn begin(&self) -> TransferBegin {
        self.begin
    }

    /// Bytes acknowledged and total bytes (for a progress bar).
    pub const fn progress(&self) -> (u32, u32) {
        (self.acked, self.begin.len)
    }

    /// What the sender did so far.
    pub const fn stats(&self) -> SenderStats {
        self.stats
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

    /// The retransmission timeout, ms: RFC 6298's `SRTT + 4 RTTVAR` within
    /// `MIN_RTO_MS..=TRANSFER_RETRY_MS`, doubled per expiry in a row (up to the same cap);
    /// `TRANSFER_RETRY_MS` before the first sample.
    fn rto(&self) -> u32 {
        let base = if self.srtt_ms == 0 {
            FIRST_RTO_MS
        } else {
            u32::from(self.srtt_ms) + (4 * u32::from(self.rttvar_ms)).max(1)
        };
        let base = base.clamp(MIN_RTO_MS, TRANSFER_RETRY_MS);
        base.checked_shl(u32::from(self.timeouts))
            .unwrap_or(u32::MAX)
            .min(TRANSFER_RETRY_MS)
    }

    /// How long an unanswered unit waits before it may go again as a probe, ms: a round
    /// trip and its deviation (QUIC's probe timeout without the backoff, RFC 9002 §6.2; a
    /// probe only uses line time nothing else wanted). `None` before the first sample.
    fn probe_after(&self) -> Option<u32> {
        (self.srtt_ms != 0).then(|| u32::from(self.srtt_ms) + 2 * u32::from(self.rttvar_ms).max(1))
    }

    /// Units from `acked` up to `sent`, as a bitmap.
    fn outstanding(&self) -> u32 {
        units(0, (self.sent - self.acked).div_ceil(UNIT))
    }

    /// Units sent and neither held nor known lost: what is on the line.
    fn in_flight(&self) -> u32 {
        (self.outstanding() & !self.sacked & !self.lost).count_ones()
    }

    /// The window, units: `TRANSFER_WINDOW` chunks, at least `MIN_WINDOW_UNITS`, at most the
    /// span a `sack` names.
    fn window(&self) -> u32 {
        (TRANSFER_WINDOW * u32::from(self.chunk_units))
            .max(MIN_WINDOW_UNITS)
            .min(SPAN_UNITS as u32)
    }

    /// Sends what is due at `now_ms`: the `TransferBegin` (first time and after timeouts)
    /// with one chunk behind it, then lost units again, new chunks of `bytes` within the
    /// window, and probes when nothing else can go. `send` returns whether it queued the
    /// frame; a frame it could not take is offered again later.
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
        if !self.started {
            self.started = true;
            self.deadline_ms = now_ms.wrapping_add(self.rto());
            self.progress_ms = now_ms;
        }
        let give_up = u32::from(MAX_TIMEOUTS) * TRANSFER_RETRY_MS;
        if due(now_ms, self.progress_ms.wrapping_add(give_up)) {
            self.phase = Phase::Done(Outcome::TimedOut);
            return;
        }
        if due(now_ms, self.deadline_ms) {
            self.on_timeout(now_ms);
        }
        if self.begin_due {
            if !send(&Message::TransferBegin(self.begin)) {
                return;
            }
            self.begin_due = false;
            self.last_ack_ms = now_ms;
        }
        // While the Begin's answer is awaited, new chunks go right behind it (at most
        // `MIN_WINDOW_UNITS` units, or one chunk), so the line is not idle for its round trip
        // and a lost answer is made good by the chunks' answers. The receiver takes them
        // once the Begin has set up the transfer (the line keeps order); a resumed or
        // already-held object costs these bytes of line time.
        let eager = self.phase == Phase::Begin;
        if !eager && self.phase != Phase::Sending {
            return;
        }
        let window = self.window();
        let chunk = u32::from(self.chunk_units);
        loop {
            let Some((start, end, kind)) = self.next_chunk(chunk, now_ms) else {
                return;
            };
            if eager && (kind != Sent::Fresh || (start > 0 && end > MIN_WINDOW_UNITS * UNIT)) {
                return;
            }
            let added = match kind {
                // A probe's units are counted in flight already.
                Sent::Probe => 0,
                _ => (end - start).div_ceil(UNIT),
            };
            if added > 0 && self.in_flight() + added > window {
                return;
            }
            if kind == Sent::Probe && self.in_flight() >= window {
                return;
            }
            let Some(data) = bytes.get(start as usize..end as usize) else {
                return;
            };
            let frame = TransferData {
                tag: self.begin.tag,
                offset: start,
                data,
            };
            if !send(&Message::TransferData(frame)) {
                return;
            }
            if kind == Sent::Fresh {
                self.sent = end;
            }
            self.record(start, end, kind, now_ms);
        }
    }

    /// Notes a chunk `start..end` sent as `kind` at `now_ms` (offsets at or past `acked`).
    fn record(&mut self, start: u32, end: u32, kind: Sent, now_ms: u32) {
        let seq = self.tx_seq;
        self.tx_seq = seq.wrapping_add(1);
        self.stats.chunks = self.stats.chunks.saturating_add(1);
        let (first, last) = (
            (start - self.acked) / UNIT,
            (end - self.acked).div_ceil(UNIT),
        );
        for i in first..last.min(SPAN_UNITS as u32) {
            let i = i as usize;
            if let (Some(l), Some(f), Some(t)) = (
                self.last_tx.get_mut(i),
                self.first_tx.get_mut(i),
                self.sent_at.get_mut(i),
            ) {
                *l = seq;
                *t = now_ms as u16;
                // A probe, or a resend the timer asked for, leaves the earlier copy possibly
                // on the line; a unit known lost, or new, has no other copy.
                if kind != Sent::Probe && self.suspect >> i & 1 == 0 {
                    *f = seq;
                }
            }
        }
        match kind {
            Sent::Fresh => {}
            Sent::Lost | Sent::Probe => {
                self.lost &= !units(first, last);
                self.suspect &= !units(first, last);
                self.stats.resent = self.stats.resent.saturating_add(1);
                if kind == Sent::Probe {
                    self.stats.probes = self.stats.probes.saturating_add(1);
                }
            }
        }
    }

    /// The next chunk to send, `(start, end, kind)`: lost units first (a run of them, at
    /// most `chunk` units), then new bytes from `sent` up to the first unit the receiver
    /// already holds, inside the span its `sack` can name; when neither can go, a probe.
    fn next_chunk(&mut self, chunk: u32, now_ms: u32) -> Option<(u32, u32, Sent)> {
        let len = self.begin.len;
        if self.lost != 0 {
            let first = self.lost.trailing_zeros();
            let run = (self.lost >> first).trailing_ones().min(chunk);
            let start = self.acked + first * UNIT;
            let end = (start + run * UNIT).min(len);
            return Some((start, end, Sent::Lost));
        }
        // Skip units the receiver holds already (a resumed transfer).
        while self.sent < len {
            let i = (self.sent - self.acked) / UNIT;
            if i >= 32 || self.sacked & (1 << i) == 0 {
                break;
            }
            self.sent = (self.sent + UNIT).min(len);
        }
        if self.sent < len {
            let i = (self.sent - self.acked) / UNIT;
            // The first held unit past `sent` bounds the chunk.
            let held = self.sacked.checked_shr(i).unwrap_or(0);
            let room = if held == 0 {
                chunk
            } else {
                held.trailing_zeros().min(chunk)
            };
            let end = len
                .min(self.sent + room * UNIT)
                .min(self.acked.saturating_add(SACK_SPAN));
            if end > self.sent {
                return Some((self.sent, end, Sent::Fresh));
            }
        }
        self.probe(chunk, now_ms)
    }

    /// The unanswered run to send again as a probe: starting at the unit whose latest copy
    /// is oldest, if that copy went out `probe_after` ago; then the units after it that are
    /// as old.
    fn probe(&self, chunk: u32, now_ms: u32) -> Option<(u32, u32, Sent)> {
        let wait = self.probe_after()?;
        // Answers still coming mean the line is still delivering what was queued.
        if now_ms.wrapping_sub(self.last_ack_ms) < wait {
            return None;
        }
        let waiting = self.outstanding() & !self.sacked & !self.lost;
        let age = |i: u32| {
            let at = self.sent_at.get(i as usize).copied().unwrap_or(0);
            u32::from((now_ms as u16).wrapping_sub(at))
        };
        let seq_age = |i: u32| {
            let s = self.last_tx.get(i as usize).copied().unwrap_or(0);
            self.tx_seq.wrapping_sub(s)
        };
        let old = |i: u32| waiting.checked_shr(i).unwrap_or(0) & 1 == 1 && age(i) >= wait;
        let first = (0..SPAN_UNITS as u32)
            .filter(|&i| old(i))
            .max_by_key(|&i| (seq_age(i), u32::MAX - i))?;
        let mut last = first + 1;
        while last - first < chunk && old(last) {
            last += 1;
        }
        let start = self.acked + first * UNIT;
        let end = (self.acked + last * UNIT).min(self.begin.len);
        (end > start).then_some((start, end, Sent::Probe))
    }

    /// The retransmission timer fired: the Begin again, or every unit not held again.
    fn on_timeout(&mut self, now_ms: u32) {
        self.timeouts = self.timeouts.saturating_add(1);
        self.stats.timeouts = self.stats.timeouts.saturating_add(1);
        self.deadline_ms = now_ms.wrapping_add(self.rto());
        if self.phase == Phase::Begin {
            self.begin_due = true;
        } else {
            self.shrink();
        }
        // No answer for a whole timeout: everything unanswered is taken as lost (RFC 6298
        // §5.4), an earlier copy of it possibly still on the line. The chunks sent behind an
        // unanswered Begin too: once a later Begin is answered they go at once, instead of
        // filling the window until a further timeout (measured: 400 ms idle after the answer).
        self.lost = self.outstanding() & !self.sacked;
        self.suspect = self.lost;
    }

    /// A loss of a unit sent since the chunk size last changed: halve it (and the line is
    /// known to lose: no more probing).
    fn shrink(&mut self) {
        self.probing = false;
        self.chunk_units = (self.chunk_units / 2).max(1);
        self.clean = 0;
        self.shrunk_at = self.tx_seq;
    }

    fn progressed(&mut self, now_ms: u32) {
        self.timeouts = 0;
        self.progress_ms = now_ms;
        self.deadline_ms = now_ms.wrapping_add(self.rto());
    }

    /// A round-trip sample, ms (RFC 6298 §2).
    fn sample(&mut self, rtt_ms: u32) {
        let r = rtt_ms.clamp(1, u32::from(u16::MAX));
        let (srtt, var) = (u32::from(self.srtt_ms), u32::from(self.rttvar_ms));
        let (srtt, var) = if srtt == 0 {
            (r, r / 2)
        } else {
            ((7 * srtt + r) / 8, (3 * var + srtt.abs_diff(r)) / 4)
        };
        self.srtt_ms = srtt.clamp(1, u32::from(u16::MAX)) as u16;
        self.rttvar_ms = var.min(u32::from(u16::MAX)) as u16;
    }

    /// Takes the receiver's `TransferAck` into account (acks for other tags are ignored).
    pub fn on_ack(&mut self, a: &TransferAck, now_ms: u32) {
        if self.is_done() || a.tag != self.begin.tag {
            return;
        }
        let outcome = match a.status {
            TransferStatus::Receiving => return self.on_receiving(a.next, a.sack, now_ms),
            TransferStatus::Complete => Outcome::Complete,
            TransferStatus::AlreadyHave => Outcome::AlreadyHave,
            TransferStatus::CrcMismatch => Outcome::CrcMismatch,
            TransferStatus::Rejected => Outcome::Rejected,
            TransferStatus::Busy => Outcome::Busy,
            TransferStatus::UnknownId => {
                // Answers to chunks sent before the restart's Begin say the same again: each
                // chunk on the line then gets one (a lost Begin followed by chunks, too).
                if self.unknown_echoes > 0 {
                    self.unknown_echoes -= 1;
                    return;
                }
                // The receiver lost the transfer (restarted, or took another): begin again.
                self.unknown_echoes = self.outstanding().count_ones().saturating_sub(1) as u8;
                self.restarts = self.restarts.saturating_add(1);
                if self.restarts <= MAX_RESTARTS {
                    self.phase = Phase::Begin;
                    self.begin_due = true;
                    (self.acked, self.sent, self.sacked, self.lost, self.suspect) = (0, 0, 0, 0, 0);
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

    /// Moves the per-unit arrays down by `k` units (`acked` moved on by them).
    fn slide(&mut self, k: u32) {
        let k = (k as usize).min(SPAN_UNITS);
        for a in [&mut self.last_tx, &mut self.first_tx, &mut self.sent_at] {
            a.copy_within(k.., 0);
        }
    }

    fn on_receiving(&mut self, next: u32, sack: u32, now_ms: u32) {
        if next > self.begin.len || next < self.acked {
            // Not an answer to this object, or older than one already taken.
            return;
        }
        if self.phase == Phase::Begin {
            // The Begin's answer (or, that lost, the eager chunk's): `next` and `sack` say
            // what the receiver holds already. Its round trip is not sampled: a 24-byte
            // Begin's is a fraction of a full chunk's (measured: the timer then fired and
            // probes went while chunks were still on the wire, 90 % -> 30 % on a clean line).
            self.phase = Phase::Sending;
            let k = next.div_ceil(UNIT);
            self.slide(k);
            (self.acked, self.sent) = (next, self.sent.max(next));
            // Chunks a Begin timeout took as lost (sent behind an unanswered Begin) stay
            // lost unless the receiver holds them: they go first.
            let kept = |bits: u32| bits.checked_shr(k).unwrap_or(0) & !sack;
            (self.sacked, self.lost, self.suspect) = (sack, kept(self.lost), kept(self.suspect));
            self.last_ack_ms = now_ms;
            self.progressed(now_ms);
            return;
        }
        self.last_ack_ms = now_ms;
        let moved = next - self.acked;
        let k = moved.div_ceil(UNIT);
        let was_outstanding = self.outstanding();
        // The latest transmission the receiver's new holdings prove arrived (every copy of a
        // newly held unit was sent at or after its `first_tx`).
        let mut proof: Option<u16> = None;
        // The newest newly held unit (by its latest copy) times a round trip if every copy of
        // it is that latest one (sent once, or again after its earlier copy was proven lost):
        // Karn's rule, and QUIC's "largest acknowledged newly acknowledged" (RFC 9002 §5.1),
        // so an answer that was lost and made good by a later one never times the wait.
        let mut timed: Option<(u16, bool, u16)> = None;
        let mut prove = |s: &Self, i: u32| {
            let f = s.first_tx.get(i as usize).copied().unwrap_or(0);
            let l = s.last_tx.get(i as usize).copied().unwrap_or(0);
            let newer = |a: u16, b: u16| s.tx_seq.wrapping_sub(a) < s.tx_seq.wrapping_sub(b);
            if proof.is_none_or(|p| newer(f, p)) {
                proof = Some(f);
            }
            if timed.is_none_or(|(t, ..)| newer(l, t)) {
                timed = Some((l, f == l, s.sent_at.get(i as usize).copied().unwrap_or(0)));
            }
        };
        let newly_below = units(0, k) & was_outstanding & !self.sacked;
        for i in 0..k.min(SPAN_UNITS as u32) {
            if newly_below >> i & 1 == 1 {
                prove(self, i);
            }
        }
        let old_sacked = shift(self.sacked, moved);
        self.slide(k);
        self.acked = next;
        self.sent = self.sent.max(next);
        let outstanding = self.outstanding();
        // Units past `sent` held are a resumed transfer's: `next_chunk` skips them.
        let sacked = old_sacked | sack;
        let newly = sacked & !old_sacked & outstanding;
        for i in 0..SPAN_UNITS as u32 {
            if newly >> i & 1 == 1 {
                prove(self, i);
            }
        }
        let progress = moved > 0 || newly != 0;
        self.sacked = sacked;
        self.lost = shift(self.lost, moved) & !sacked & outstanding;
        self.suspect = shift(self.suspect, moved) & self.lost;
        if let Some((_, true, at)) = timed {
            self.sample(u32::from((now_ms as u16).wrapping_sub(at)));
        }
        // Every unit not held whose latest copy went out before the proven one is lost.
        let mut loss = false;
        if let Some(p) = proof {
            let holes = outstanding & !sacked & !self.lost;
            let before = |s: u16| self.tx_seq.wrapping_sub(s) > self.tx_seq.wrapping_sub(p);
            let mut shrink = false;
            for i in 0..SPAN_UNITS as u32 {
                let last = self.last_tx.get(i as usize).copied().unwrap_or(0);
                if holes >> i & 1 == 1 && before(last) {
                    self.lost |= 1 << i;
                    self.stats.lost_units = self.stats.lost_units.saturating_add(1);
                    loss = true;
                    // A loss the last shrinking did not already answer.
                    shrink |=
                        self.tx_seq.wrapping_sub(last) <= self.tx_seq.wrapping_sub(self.shrunk_at);
                }
            }
            if shrink {
                self.shrink();
            }
        }
        if progress {
            self.progressed(now_ms);
            if !loss && self.probing {
                self.chunk_units = self.chunk_units.saturating_mul(2).min(MAX_CHUNK_UNITS);
            } else if !loss {
                self.clean = self.clean.saturating_add(1);
                if self.clean >= GROW_AFTER && self.chunk_units < MAX_CHUNK_UNITS {
                    self.chunk_units += 1;
                    self.clean = 0;
                }
            }
        }
    }
}

/// How a chunk's units were sent.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Sent {
    /// For the first time.
    Fresh,
    /// Again, known lost (no copy of them is on the line).
    Lost,
    /// Again, unanswered for a round trip and nothing else could go (a copy may still be on
    /// the line).
    Probe,
}
