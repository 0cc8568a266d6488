//! The robot's serial port, timed in SIMULATED time at a configured baud rate.
//!
//! Layer: std, between the firmware's `Hal::serial_read/serial_write` (robot side) and
//! whatever carries the bytes to a station (host side: a pty, a test, a recorder). A pty
//! accepts any baud rate and would hide every timing problem (architecture.md), so this
//! models the wire: 8N1 framing, 10 bits per byte, `baud / 10` bytes per second each way.
//!
//! - TX: [`Uart::serial_write`] puts bytes into a 64-byte FIFO (taking fewer when it is full);
//!   [`Uart::tick`] shifts them out at the line rate; a byte becomes visible to the host
//!   ([`Uart::take_outbound`]) when its last bit has been sent.
//! - RX: the host queues bytes with [`Uart::push_inbound`]; they arrive at the line rate into
//!   a 256-byte FIFO that [`Uart::serial_read`] empties; a byte arriving at a full FIFO is
//!   lost and counted (`rx_overflow`), as on a UART whose driver is too slow. The bytes on
//!   their way are the station's serial transmit buffer, [`LINE_BUFFER`] bytes as in a
//!   Linux serial driver: what a burst adds beyond it is dropped and counted
//!   (`inbound_refused`). A pty takes any burst at once, which no serial line does, so a
//!   deeper queue would make the robot answer minutes late after a flood (1 MiB took 91 s at
//!   115200 baud), where a real robot answers as soon as the line is clear.
//! - Truth channel (emulator only): a `protocol::FrameDecoder` watches the robot's transmitted
//!   bytes; when a Telemetry frame has been sent, an `EmuTruth` frame (its own sequence
//!   counter; `time_ms` of that telemetry; the TRUE pose at that time, mm and mrad; collisions)
//!   is owed, on the same wire and out of the same bit budget, so the total never exceeds the
//!   baud rate. A real robot sends no truth, so it must not delay the robot's own bytes: a
//!   truth frame starts only between robot frames with the robot's FIFO empty (an ack queued
//!   behind a telemetry frame goes first), and once started it goes out whole. At most
//!   [`TRUTH_BACKLOG`] wait; once [`TRUTH_OWED_FIRST`] are owed, the oldest goes between two
//!   robot frames even with the FIFO full (a robot filling a slow line would starve truth
//!   otherwise); when more than the backlog are owed, the oldest unsent one is dropped
//!   (counted in `truth_dropped`). Each is numbered when it starts, so a dropped
//!   one leaves no gap the station would count as lost.
//!
//! Invariants: bytes leave in order, frames are never interleaved or cut; an idle line does not bank
//! time (a burst after silence still goes at the line rate); host-side queues are bounded
//! (inbound: `push_inbound` takes what fits; outbound: the oldest bytes are dropped and
//! counted if the host never takes them). Nothing here panics. What can fail: [`Uart::new`]
//! with a baud rate of 0 or above 10 Mbaud.

use std::collections::VecDeque;

use protocol::{encode, EmuTruth, Feed, FrameDecoder, Message, Pose as WirePose, MAX_FRAME};
use thiserror::Error;

use crate::arena::Pose;
use crate::sent_bytes::{SentBytes, BITS_PER_BYTE};

/// Default line rate.
pub const DEFAULT_BAUD: u32 = 115_200;
/// Transmit FIFO of the robot's UART, bytes.
pub const TX_FIFO: usize = 64;
/// Receive FIFO of the robot's UART, bytes.
pub const RX_FIFO: usize = 256;
/// Most bytes on their way to the robot: a serial driver's transmit buffer (Linux's
/// `UART_XMIT_SIZE`). The station's largest burst, a transfer window of 4 chunks with
/// commands and a heartbeat, is about 1.2 KB; it drains in 0.36 s at 115200 baud.
pub const LINE_BUFFER: usize = 4096;
/// Most transmitted bytes kept for the host before the oldest are dropped.
pub const OUTBOUND_LIMIT: usize = 1 << 20;
/// Highest baud rate accepted.
pub const MAX_BAUD: u32 = 10_000_000;
/// Milliseconds of truth history kept for `EmuTruth` look-ups.
pub const TRUTH_HISTORY_MS: usize = 4096;
/// Most `EmuTruth` frames waiting for the robot's bytes to clear the line: over 150 ms of
/// 50 Hz telemetry, long enough for any burst of the robot's, short enough that a truth frame
/// is not so stale that the station's plot lags.
pub const TRUTH_BACKLOG: usize = 8;
/// Truth frames owed after which the oldest goes ahead of the robot's next frame (never
/// inside one). At 115200 baud the robot's FIFO empties between its frames and one truth
/// frame at a time is owed, so acks still go first; at 9600 baud the robot's bytes fill the
/// line, and without this no truth frame would ever go out.
pub const TRUTH_OWED_FIRST: usize = 2;

/// Why a UART cannot be made.
#[derive(Clone, Copy, Debug, Error, PartialEq, Eq)]
pub enum UartError {
    /// Baud rate outside 1..=10,000,000.
    #[error("baud rate {0} is outside 1..={MAX_BAUD}")]
    BadBaud(u32),
}

/// The true state at one millisecond, for `EmuTruth`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TruthSample {
    /// Simulated time, ms (wrapping like the wire's `time_ms`).
    pub time_ms: u32,
    /// True pose.
    pub pose: Pose,
    /// Collisions so far.
    pub collisions: u32,
}

/// The last [`TRUTH_HISTORY_MS`] samples, one a millisecond: a ring over a vector that
/// stops growing at that length (a sample is written every simulated millisecond, so the
/// ring is a fixed slot write, not a deque's pop and push).
#[derive(Clone, Debug, Default)]
pub struct TruthHistory {
    ring: Vec<TruthSample>,
    /// Where the next sample goes.
    next: usize,
    /// The robot the samples are about (its `robot_id` parameter now), named in `EmuTruth`.
    pub robot_id: u8,
    /// The session and robot the robot's signed frames are bound to now: truth frames are
    /// signed as the robot's (PROTOCOL.md §13).
    pub binding: protocol::Binding,
}

impl TruthHistory {
    /// Appends a sample, forgetting the oldest beyond the history length.
    pub fn push(&mut self, s: TruthSample) {
        match self.ring.get_mut(self.next) {
            Some(slot) => *slot = s,
            None => self.ring.push(s),
        }
        self.next = (self.next + 1) % TRUTH_HISTORY_MS;
    }

    /// The sample at `time_ms`, or the newest one if that time is not held.
    pub fn at(&self, time_ms: u32) -> Option<TruthSample> {
        let len = self.ring.len();
        let newest_at = self.next.checked_sub(1).unwrap_or(len.checked_sub(1)?);
        let newest = self.ring.get(newest_at)?;
        let back = newest.time_ms.wrapping_sub(time_ms) as usize;
        let found = (back < len)
            .then(|| self.ring.get((newest_at + len - back) % len))
            .flatten()
            .filter(|s| s.time_ms == time_ms);
        Some(*found.unwrap_or(newest))
    }
}

/// Counters of the port.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct UartStats {
    /// Bytes sent on the wire (robot bytes and truth bytes).
    pub tx_bytes: u64,
    /// Of which the robot's own.
    pub tx_robot_bytes: u64,
    /// Bytes received into the RX FIFO.
    pub rx_bytes: u64,
    /// Bytes lost because the RX FIFO was full.
    pub rx_overflow: u64,
    /// Bytes the host offered beyond `LINE_BUFFER` (a burst faster than the line), dropped.
    pub inbound_refused: u64,
    /// Transmitted bytes dropped because the host did not take them.
    pub outbound_dropped: u64,
    /// `EmuTruth` frames sent.
    pub truth_frames: u32,
    /// `EmuTruth` frames dropped unsent because [`TRUTH_BACKLOG`] were already waiting.
    pub truth_dropped: u32,
}

impl UartStats {
    /// Bytes from the station that never reached the robot's software: refused by the line
    /// buffer or lost at a full receive FIFO.
    pub fn to_robot_dropped(&self) -> u64 {
        self.inbound_refused.saturating_add(self.rx_overflow)
    }
}

/// The serial port.
pub struct Uart {
    baud: u32,
    tx_fifo: VecDeque<u8>,
    /// The bytes of the truth frame on the wire, if one is.
    truth_queue: VecDeque<u8>,
    /// Truth owed, not started: the message and the telemetry's signing timestamp.
    /// Owed truth frames, each with the timestamp and binding of the signed telemetry frame
    /// it follows (none on an unsigned link).
    truth_pending: VecDeque<(EmuTruth, Option<(u64, protocol::Binding)>)>,
    /// The robot's last byte on the wire did not end a frame: only its bytes may follow.
    robot_mid_frame: bool,
    /// Sent bytes with the time each completed: the serving loop steps ahead of the wall
    /// clock by up to a millisecond and hands the station only what is complete.
    outbound: SentBytes,
    /// Bit-clock position of the TX line (bits since time 0).
    tx_bits: u64,
    inbound: VecDeque<u8>,
    rx_fifo: VecDeque<u8>,
    rx_bits: u64,
    /// Since when each line has had nothing to send (it banks no bits meanwhile).
    tx_idle_us: Option<u64>,
    rx_idle_us: Option<u64>,
    decoder: FrameDecoder,
    truth_enabled: bool,
    truth_seq: u16,
    /// Signs `EmuTruth` frames on their own link (PROTOCOL.md §13) when the robot is keyed.
    truth_key: Option<protocol::LinkKey>,
    stats: UartStats,
}

impl std::fmt::Debug for Uart {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Uart")
            .field("baud", &self.baud)
            .field("tx_fifo", &self.tx_fifo.len())
            .field("rx_fifo", &self.rx_fifo.len())
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

impl Uart {
    /// A port at `baud`; `truth` enables the `EmuTruth` channel.
    pub fn new(baud: u32, truth: bool) -> Result<Uart, UartError> {
        if baud == 0 || baud > MAX_BAUD {
            return Err(UartError::BadBaud(baud));
        }
        Ok(Uart {
            baud,
            tx_fifo: VecDeque::with_capacity(TX_FIFO),
            truth_queue: VecDeque::with_capacity(MAX_FRAME),
            truth_pending: VecDeque::with_capacity(TRUTH_BACKLOG),
            robot_mid_frame: false,
            outbound: SentBytes::default(),
            tx_bits: 0,
            inbound: VecDeque::new(),
            rx_fifo: VecDeque::with_capacity(RX_FIFO),
            rx_bits: 0,
            tx_idle_us: None,
            rx_idle_us: None,
            decoder: FrameDecoder::new(),
            truth_enabled: truth,
            truth_seq: 0,
            truth_key: None,
            stats: UartStats::default(),
        })
    }

    /// Signs `EmuTruth` frames with `key`, each with the timestamp of the telemetry frame it
    /// follows, so they pass a keyed station like the robot's own frames.
    pub fn set_truth_key(&mut self, key: Option<protocol::LinkKey>) {
        self.truth_key = key;
    }

    /// The line rate.
    pub fn baud(&self) -> u32 {
        self.baud
    }

    /// Counters so far.
    pub fn stats(&self) -> UartStats {
        self.stats
    }

    // ---- robot side ----

    /// Robot: offers bytes to the transmitter; returns how many the FIFO took.
    pub fn serial_write(&mut self, bytes: &[u8]) -> usize {
        let room = TX_FIFO.saturating_sub(self.tx_fifo.len());
        let n = bytes.len().min(room);
        self.tx_fifo.extend(bytes.iter().take(n));
        n
    }

    /// Robot: takes received bytes; returns how many.
    pub fn serial_read(&mut self, buf: &mut [u8]) -> usize {
        let n = buf.len().min(self.rx_fifo.len());
        if n == 0 {
            // The firmware asks every simulated millisecond; an empty drain is not free.
            return 0;
        }
        for (slot, b) in buf.iter_mut().zip(self.rx_fifo.drain(..n)) {
            *slot = b;
        }
        n
    }

    // ---- host side ----

    /// Host: queues bytes to send to the robot; returns how many fitted (the rest are
    /// dropped and counted).
    pub fn push_inbound(&mut self, bytes: &[u8]) -> usize {
        let room = LINE_BUFFER.saturating_sub(self.inbound.len());
        let n = bytes.len().min(room);
        self.inbound.extend(bytes.iter().take(n));
        self.stats.inbound_refused += (bytes.len() - n) as u64;
        n
    }

    /// Host: bytes queued towards the robot and not yet on the wire.
    pub fn inbound_len(&self) -> usize {
        self.inbound.len()
    }

    /// Host: every byte whose transmission completed since the last take.
    pub fn take_outbound(&mut self) -> Vec<u8> {
        self.outbound.take_all()
    }

    /// Host: moves up to `buf.len()` transmitted bytes into `buf`; returns how many.
    pub fn take_outbound_into(&mut self, buf: &mut [u8]) -> usize {
        self.outbound.take_into(buf)
    }

    /// Host: moves into `buf` the transmitted bytes whose last bit had left by `now_us`
    /// (the line may have been moved on further, `tick` to the end of a step); returns how
    /// many.
    pub fn take_outbound_until(&mut self, now_us: u64, buf: &mut [u8]) -> usize {
        let bits = self.line_bits(now_us);
        self.outbound.take_until(bits, buf)
    }

    /// Host: when the next frame delimiter already on the line completes, µs (rounded up):
    /// the moment a station can next decode a whole frame. `None` when no transmitted byte
    /// waiting to be taken is a delimiter.
    pub fn next_frame_end_us(&self) -> Option<u64> {
        let bits = self.outbound.done_bits_of_first(0)?;
        let us = (u128::from(bits) * 1_000_000).div_ceil(u128::from(self.baud));
        u64::try_from(us).ok()
    }

    /// Robot side: when the next frame delimiter on its way to the robot completes (its last
    /// bit received, so a tick to then puts it in the receive FIFO), µs rounded up: the moment
    /// a robot whose receive path reacts to a delimiter (an RX interrupt, or a main loop far
    /// faster than the control cycle) can act on a whole frame. `None` when no byte still on
    /// its way in is a delimiter.
    pub fn next_inbound_frame_end_us(&self) -> Option<u64> {
        let index = u64::try_from(self.inbound.iter().position(|&b| b == 0)?).ok()?;
        // As `tick_rx` moves the line: an idle line starts no earlier than it became busy.
        let start = match self.rx_idle_us {
            Some(t) => self.rx_bits.max(self.bit_at_or_after(t)),
            None => self.rx_bits,
        };
        let bits = start.saturating_add((index + 1).saturating_mul(BITS_PER_BYTE));
        let us = (u128::from(bits) * 1_000_000).div_ceil(u128::from(self.baud));
        u64::try_from(us).ok()
    }

    /// Host: queues bytes to send to the robot that reached the line at `at_us`: on an idle
    /// line their first bit starts then, not at the line's last tick (which may be up to a
    /// millisecond either side). Returns how many fitted, as `push_inbound`.
    pub fn push_inbound_at(&mut self, bytes: &[u8], at_us: u64) -> usize {
        if self.inbound.is_empty() && !bytes.is_empty() {
            // The line banks no bits while idle: `tick_rx` starts it at the later of its last
            // byte's end and this.
            self.rx_idle_us = Some(at_us);
        }
        self.push_inbound(bytes)
    }

    /// Host: transmitted bytes waiting to be taken.
    pub fn outbound_len(&self) -> usize {
        self.outbound.len()
    }

    /// Whether nothing is on its way to the robot: no byte arriving, none received unread.
    pub fn nothing_for_robot(&self) -> bool {
        self.inbound.is_empty() && self.rx_fifo.is_empty()
    }

    /// Whether no byte is on its way in either direction (nothing to send, nothing arriving,
    /// nothing received that the robot has not read): stepping then moves no byte.
    pub fn idle(&self) -> bool {
        self.tx_fifo.is_empty()
            && self.truth_queue.is_empty()
            && self.truth_pending.is_empty()
            && self.inbound.is_empty()
            && self.rx_fifo.is_empty()
    }

    // ---- the wire ----

    /// Bits the line can have carried by `now_us`.
    fn line_bits(&self, now_us: u64) -> u64 {
        let bits = u128::from(now_us) * u128::from(self.baud) / 1_000_000;
        u64::try_from(bits).unwrap_or(u64::MAX)
    }

    /// The first bit boundary at or after `us`: where a byte written to an idle line then
    /// starts (a whole bit of the line's clock, never before it was written, so no answer
    /// leaves sooner than its command's and its own bytes allow).
    fn bit_at_or_after(&self, us: u64) -> u64 {
        let bits = (u128::from(us) * u128::from(self.baud)).div_ceil(1_000_000);
        u64::try_from(bits).unwrap_or(u64::MAX)
    }

    /// Moves bytes on both lines up to `now_us`; `truth` supplies true poses for `EmuTruth`.
    pub fn tick(&mut self, now_us: u64, truth: &TruthHistory) {
        let tx_idle =
            self.truth_queue.is_empty() && self.truth_pending.is_empty() && self.tx_fifo.is_empty();
        let rx_idle = self.inbound.is_empty();
        if tx_idle && rx_idle {
            // Nothing to move: note that both lines were idle up to now (a byte written
            // later starts no earlier than this) instead of doing the bit-clock arithmetic.
            self.tx_idle_us = Some(now_us);
            self.rx_idle_us = Some(now_us);
            return;
        }
        let avail = self.line_bits(now_us);
        self.tick_tx(now_us, avail, truth);
        self.tick_rx(now_us, avail);
    }

    fn tick_tx(&mut self, now_us: u64, avail: u64, truth: &TruthHistory) {
        if let Some(t) = self.tx_idle_us.take() {
            // Idle line: time passed without banking bits.
            self.tx_bits = self.tx_bits.max(self.bit_at_or_after(t));
        }
        let mut starved = false;
        while self.tx_bits.saturating_add(BITS_PER_BYTE) <= avail {
            // A truth frame once started goes out whole; then the robot's bytes, a frame it
            // has begun first of all; truth only on a line the robot leaves free.
            let byte = if let Some(b) = self.truth_queue.pop_front() {
                b
            } else if !self.robot_mid_frame
                && self.truth_pending.len() >= TRUTH_OWED_FIRST
                && self.start_truth_frame()
            {
                // A robot that keeps its FIFO full (a slow line) would starve truth for
                // good: once this many are owed, the oldest goes between two robot frames.
                continue;
            } else if let Some(b) = self.tx_fifo.pop_front() {
                self.stats.tx_robot_bytes += 1;
                self.robot_mid_frame = b != 0;
                self.watch(b, truth);
                b
            } else if !self.robot_mid_frame && self.start_truth_frame() {
                continue;
            } else {
                starved = true;
                break;
            };
            self.tx_bits += BITS_PER_BYTE;
            self.stats.tx_bytes += 1;
            if self.outbound.len() >= OUTBOUND_LIMIT {
                self.outbound.pop_front();
                self.stats.outbound_dropped += 1;
            }
            self.outbound.push(byte, self.tx_bits);
        }
        if self.tx_fifo.is_empty() && self.truth_queue.is_empty() && !self.robot_mid_frame {
            // The line is free and the robot has queued nothing: an owed truth frame starts at
            // the line's position even when less than a byte's time is left before `now_us`,
            // so that a byte the robot writes after this tick neither starts before it was
            // written nor ahead of a truth frame the line had already begun.
            self.start_truth_frame();
        }
        if starved || (self.tx_fifo.is_empty() && self.truth_queue.is_empty()) {
            // Nothing the line may carry now (truth may be waiting for the rest of a robot
            // frame): it idles, banking no bits. Also when less than a byte's time has passed
            // since the last byte: a byte written after this tick (the robot answering a frame
            // mid-step) starts no earlier than now.
            self.tx_idle_us = Some(now_us);
        }
    }

    /// Encodes the oldest owed truth frame into `truth_queue`; false when none is owed.
    fn start_truth_frame(&mut self) -> bool {
        while let Some((msg, signed)) = self.truth_pending.pop_front() {
            let msg = Message::EmuTruth(msg);
            let mut buf = [0u8; MAX_FRAME];
            let encoded = match (&self.truth_key, signed) {
                (Some(key), Some((ts, binding))) => protocol::encode_signed(
                    self.truth_seq,
                    &msg,
                    key,
                    &binding,
                    protocol::sign::TRUTH_LINK,
                    ts,
                    &mut buf,
                ),
                // A keyed station would refuse unsigned truth; an unkeyed one, signed truth.
                (Some(_), None) | (None, Some(_)) => continue,
                (None, None) => encode(self.truth_seq, &msg, &mut buf),
            };
            if let Ok(n) = encoded {
                self.truth_seq = self.truth_seq.wrapping_add(1);
                self.truth_queue.extend(buf.iter().take(n));
                self.stats.truth_frames = self.stats.truth_frames.wrapping_add(1);
                return true;
            }
        }
        false
    }

    fn tick_rx(&mut self, now_us: u64, avail: u64) {
        if let Some(t) = self.rx_idle_us.take() {
            self.rx_bits = self.rx_bits.max(self.bit_at_or_after(t));
        }
        while self.rx_bits.saturating_add(BITS_PER_BYTE) <= avail {
            let Some(b) = self.inbound.pop_front() else {
                break;
            };
            self.rx_bits += BITS_PER_BYTE;
            if self.rx_fifo.len() < RX_FIFO {
                self.rx_fifo.push_back(b);
                self.stats.rx_bytes += 1;
            } else {
                self.stats.rx_overflow += 1;
            }
        }
        if self.inbound.is_empty() {
            self.rx_idle_us = Some(now_us);
        }
    }

    /// Feeds one transmitted robot byte to the frame watcher; owes an `EmuTruth` after a
    /// completed Telemetry frame (sent when the robot leaves the line free).
    fn watch(&mut self, byte: u8, truth: &TruthHistory) {
        if !self.truth_enabled {
            return;
        }
        let (time_ms, signed) = match self.decoder.feed(&[byte]) {
            Feed::Frame {
                frame:
                    protocol::Frame {
                        message: Message::Telemetry(t),
                        signature,
                        ..
                    },
                ..
            } => (t.time_ms, signature.map(|s| (s.timestamp, truth.binding))),
            _ => return,
        };
        let Some(s) = truth.at(time_ms) else { return };
        if self.truth_pending.len() >= TRUTH_BACKLOG {
            self.truth_pending.pop_front();
            self.stats.truth_dropped = self.stats.truth_dropped.wrapping_add(1);
        }
        let msg = EmuTruth {
            time_ms,
            pose: wire_pose(s.pose),
            collisions: s.collisions,
            robot_id: truth.robot_id,
        };
        self.truth_pending.push_back((msg, signed));
    }
}

/// A pose in wire units (mm, mrad), clamped (the arena was checked to fit the wire when it
/// was loaded); the heading in (-pi, pi] fits an i16.
pub fn wire_pose(p: Pose) -> WirePose {
    WirePose {
        x_mm: protocol::units::mm_from_m_clamped(p.x),
        y_mm: protocol::units::mm_from_m_clamped(p.y),
        heading_mrad: (p.heading * 1000.0).round() as i16,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_leave_at_the_line_rate_and_an_idle_line_banks_nothing() {
        let mut u = Uart::new(9600, false).expect("valid baud");
        let h = TruthHistory::default();
        assert_eq!(u.serial_write(&[1u8; 100]), TX_FIFO);
        u.tick(10_000, &h); // 10 ms at 960 B/s: 9 whole bytes (9.6)
        assert_eq!(u.take_outbound().len(), 9);
        u.tick(1_000_000, &h);
        assert_eq!(u.take_outbound().len(), TX_FIFO - 9);
        // Idle for a second; a new burst still goes at 960 B/s.
        u.tick(2_000_000, &h);
        u.serial_write(&[2u8; 64]);
        u.tick(2_010_000, &h);
        assert!(u.take_outbound().len() <= 10);
    }

    #[test]
    fn a_full_receive_fifo_drops_and_counts() {
        let mut u = Uart::new(115_200, false).expect("valid baud");
        let h = TruthHistory::default();
        assert_eq!(u.push_inbound(&[7u8; 300]), 300);
        u.tick(1_000_000, &h);
        assert_eq!(u.stats().rx_overflow, 300 - RX_FIFO as u64);
        let mut buf = [0u8; 512];
        assert_eq!(u.serial_read(&mut buf), RX_FIFO);
        assert!(Uart::new(0, false).is_err());
    }

    #[test]
    fn a_burst_beyond_the_line_buffer_is_dropped_and_the_line_is_clear_soon_after() {
        let mut u = Uart::new(115_200, false).expect("valid baud");
        let h = TruthHistory::default();
        let burst = vec![0x55u8; 1 << 20];
        assert_eq!(u.push_inbound(&burst), LINE_BUFFER);
        assert_eq!(
            u.stats().to_robot_dropped(),
            (burst.len() - LINE_BUFFER) as u64
        );
        // The robot reads every millisecond; the line buffer drains at 11,520 B/s.
        let mut buf = [0u8; RX_FIFO];
        let mut t_us = 0;
        while u.inbound_len() > 0 {
            t_us += 1000;
            u.tick(t_us, &h);
            u.serial_read(&mut buf);
        }
        assert!(t_us <= 400_000, "line clear after {t_us} us");
        assert_eq!(
            u.stats().rx_overflow,
            0,
            "a robot reading every ms loses nothing"
        );
        // The next frame goes through.
        assert_eq!(u.push_inbound(&[1, 2, 3]), 3);
        u.tick(t_us + 1000, &h);
        assert_eq!(u.serial_read(&mut buf), 3);
    }

    #[test]
    fn truth_history_finds_exact_times_or_the_newest() {
        let mut h = TruthHistory::default();
        let pose = Pose {
            x: 0.0,
            y: 0.0,
            heading: 0.0,
        };
        for t in 0..5000u32 {
            h.push(TruthSample {
                time_ms: t,
                pose: Pose {
                    x: f64::from(t),
                    ..pose
                },
                collisions: 0,
            });
        }
        assert_eq!(h.at(4000).map(|s| s.pose.x), Some(4000.0));
        assert_eq!(h.at(10).map(|s| s.pose.x), Some(4999.0));
        // The oldest held (4999 - 4095) and the newest; one older is gone.
        assert_eq!(h.at(904).map(|s| s.pose.x), Some(904.0));
        assert_eq!(h.at(4999).map(|s| s.pose.x), Some(4999.0));
        assert_eq!(h.at(903).map(|s| s.pose.x), Some(4999.0));
        assert_eq!(h.at(5000).map(|s| s.pose.x), Some(4999.0));
        assert_eq!(TruthHistory::default().at(0), None);
    }

    /// Encodes `msg` as one frame.
    fn frame(seq: u16, msg: &Message<'_>) -> Vec<u8> {
        let mut buf = [0u8; MAX_FRAME];
        let n = encode(seq, msg, &mut buf).expect("encodes");
        buf.get(..n).expect("in bounds").to_vec()
    }

    /// The kinds of the frames in `bytes`, in order; panics on anything that is not a whole
    /// good frame (a frame cut by another's bytes fails its COBS or CRC check).
    fn kinds(bytes: &[u8]) -> Vec<protocol::Kind> {
        let mut d = FrameDecoder::new();
        let mut out = Vec::new();
        let mut rest = bytes;
        loop {
            match d.feed(rest) {
                Feed::NeedMore => break,
                Feed::Frame { frame, rest: r } => {
                    out.push(frame.header.kind);
                    rest = r;
                }
                Feed::Error { error, .. } => panic!("a frame was cut: {error:?} after {out:?}"),
            }
        }
        assert_eq!(d.stats().bytes_dropped, 0, "partial frame left: {out:?}");
        out
    }

    /// Ticks the port every simulated millisecond from `*t_us` for `ms` milliseconds,
    /// collecting what it sends.
    fn run(u: &mut Uart, h: &TruthHistory, t_us: &mut u64, ms: u64, out: &mut Vec<u8>) {
        for _ in 0..ms {
            *t_us += 1000;
            u.tick(*t_us, h);
            out.extend(u.take_outbound());
        }
    }

    #[test]
    fn a_truth_frame_waits_for_queued_robot_bytes_and_never_cuts_a_frame() {
        use protocol::{Ack, AckInfo, Kind, Telemetry};
        let mut u = Uart::new(115_200, true).expect("valid baud");
        let mut h = TruthHistory::default();
        let pose = Pose {
            x: 1.0,
            y: 2.0,
            heading: 0.5,
        };
        for time_ms in 0..10 {
            h.push(TruthSample {
                time_ms,
                pose,
                collisions: 0,
            });
        }
        let telemetry = frame(
            1,
            &Message::Telemetry(Telemetry {
                time_ms: 5,
                ..Telemetry::default()
            }),
        );
        let ack = frame(
            2,
            &Message::Ack(Ack {
                cmd_seq: 9,
                info: AckInfo::Done,
            }),
        );
        // The telemetry takes longer than 2 ms on the wire (11.5 bytes a millisecond).
        assert!(telemetry.len() > 24 && telemetry.len() <= TX_FIFO);
        let (mut t_us, mut out) = (0, Vec::new());

        // 1. An ack queued behind a telemetry frame goes out before that frame's truth.
        assert_eq!(u.serial_write(&telemetry), telemetry.len());
        run(&mut u, &h, &mut t_us, 2, &mut out);
        assert_eq!(u.serial_write(&ack), ack.len());
        run(&mut u, &h, &mut t_us, 20, &mut out);
        assert_eq!(kinds(&out), [Kind::Telemetry, Kind::Ack, Kind::EmuTruth]);

        // 2. A robot frame written in two parts with the line idle between them (the FIFO
        // empties mid-frame) is not cut by the truth frame its telemetry is owed.
        out.clear();
        u.serial_write(&telemetry);
        let (head, tail) = ack.split_at(ack.len() / 2);
        u.serial_write(head);
        run(&mut u, &h, &mut t_us, 20, &mut out);
        u.serial_write(tail);
        run(&mut u, &h, &mut t_us, 20, &mut out);
        assert_eq!(kinds(&out), [Kind::Telemetry, Kind::Ack, Kind::EmuTruth]);

        // 3. Robot bytes written while a truth frame is on the wire wait for its end.
        out.clear();
        u.serial_write(&telemetry);
        while out.len() <= telemetry.len() {
            run(&mut u, &h, &mut t_us, 1, &mut out);
        }
        // The truth frame has started (at most 12 bytes a millisecond: it is longer than
        // that), so the ack lands mid-truth.
        u.serial_write(&ack);
        run(&mut u, &h, &mut t_us, 20, &mut out);
        assert_eq!(kinds(&out), [Kind::Telemetry, Kind::EmuTruth, Kind::Ack]);
        assert_eq!(u.stats().truth_frames, 3);
    }

    #[test]
    fn truth_owed_while_the_robot_keeps_the_line_busy_still_goes_between_its_frames() {
        use protocol::{Kind, Telemetry};
        let mut u = Uart::new(115_200, true).expect("valid baud");
        let mut h = TruthHistory::default();
        h.push(TruthSample {
            time_ms: 0,
            pose: Pose {
                x: 0.0,
                y: 0.0,
                heading: 0.0,
            },
            collisions: 0,
        });
        let telemetry = frame(1, &Message::Telemetry(Telemetry::default()));
        let (mut t_us, mut out) = (0, Vec::new());
        // The robot refills its FIFO every millisecond: the line is never free for truth, so
        // truth goes between robot frames once TRUTH_OWED_FIRST are owed, and none is lost.
        let owed = TRUTH_BACKLOG + 3;
        let mut pending: Vec<u8> = telemetry.repeat(owed);
        while !pending.is_empty() {
            let n = u.serial_write(&pending);
            pending.drain(..n);
            run(&mut u, &h, &mut t_us, 1, &mut out);
        }
        run(&mut u, &h, &mut t_us, 200, &mut out);
        let k = kinds(&out);
        assert_eq!(k.iter().filter(|&&k| k == Kind::Telemetry).count(), owed);
        assert_eq!(u.stats().truth_dropped, 0);
        assert_eq!(u.stats().truth_frames as usize, owed);
        // Numbered as sent: 0, 1, 2, ... with no gap a station would count as lost.
        let mut d = FrameDecoder::new();
        let mut seqs = Vec::new();
        let mut rest = out.as_slice();
        while let Feed::Frame { frame, rest: r } = d.feed(rest) {
            if frame.header.kind == Kind::EmuTruth {
                seqs.push(frame.header.seq);
            }
            rest = r;
        }
        assert_eq!(seqs, (0..owed as u16).collect::<Vec<_>>());
        // Never more than TRUTH_OWED_FIRST telemetry frames ahead of their truth.
        let mut ahead = 0usize;
        for k in &k {
            match k {
                Kind::Telemetry => ahead += 1,
                Kind::EmuTruth => ahead -= 1,
                _ => {}
            }
            assert!(ahead <= TRUTH_OWED_FIRST, "{k:?}");
        }
    }
}
