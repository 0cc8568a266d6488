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
//!   is sent next, on the same wire and out of the same bit budget, so the total never
//!   exceeds the baud rate. The robot's FIFO waits meanwhile.
//!
//! Invariants: bytes leave in order, frames are never interleaved; an idle line does not bank
//! time (a burst after silence still goes at the line rate); host-side queues are bounded
//! (inbound: `push_inbound` takes what fits; outbound: the oldest bytes are dropped and
//! counted if the host never takes them). Nothing here panics. What can fail: [`Uart::new`]
//! with a baud rate of 0 or above 10 Mbaud.

use std::collections::VecDeque;

use protocol::{encode, EmuTruth, Feed, FrameDecoder, Message, Pose as WirePose, MAX_FRAME};
use thiserror::Error;

use crate::arena::Pose;

/// Default line rate.
pub const DEFAULT_BAUD: u32 = 115_200;
/// Bits on the wire per byte: start + 8 data + stop (8N1).
pub const BITS_PER_BYTE: u64 = 10;
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
    truth_queue: VecDeque<u8>,
    outbound: VecDeque<u8>,
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
            outbound: VecDeque::new(),
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
        self.outbound.drain(..).collect()
    }

    /// Host: moves up to `buf.len()` transmitted bytes into `buf`; returns how many.
    pub fn take_outbound_into(&mut self, buf: &mut [u8]) -> usize {
        let n = buf.len().min(self.outbound.len());
        for (slot, b) in buf.iter_mut().zip(self.outbound.drain(..n)) {
            *slot = b;
        }
        n
    }

    /// Host: transmitted bytes waiting to be taken.
    pub fn outbound_len(&self) -> usize {
        self.outbound.len()
    }

    /// Whether no byte is on its way in either direction (nothing to send, nothing arriving,
    /// nothing received that the robot has not read): stepping then moves no byte.
    pub fn idle(&self) -> bool {
        self.tx_fifo.is_empty()
            && self.truth_queue.is_empty()
            && self.inbound.is_empty()
            && self.rx_fifo.is_empty()
    }

    // ---- the wire ----

    /// Bits the line can have carried by `now_us`.
    fn line_bits(&self, now_us: u64) -> u64 {
        let bits = u128::from(now_us) * u128::from(self.baud) / 1_000_000;
        u64::try_from(bits).unwrap_or(u64::MAX)
    }

    /// Moves bytes on both lines up to `now_us`; `truth` supplies true poses for `EmuTruth`.
    pub fn tick(&mut self, now_us: u64, truth: &TruthHistory) {
        let tx_idle = self.truth_queue.is_empty() && self.tx_fifo.is_empty();
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
            self.tx_bits = self.tx_bits.max(self.line_bits(t));
        }
        while self.tx_bits.saturating_add(BITS_PER_BYTE) <= avail {
            let byte = if let Some(b) = self.truth_queue.pop_front() {
                b
            } else if let Some(b) = self.tx_fifo.pop_front() {
                self.stats.tx_robot_bytes += 1;
                self.watch(b, truth);
                b
            } else {
                break;
            };
            self.tx_bits += BITS_PER_BYTE;
            self.stats.tx_bytes += 1;
            if self.outbound.len() >= OUTBOUND_LIMIT {
                self.outbound.pop_front();
                self.stats.outbound_dropped += 1;
            }
            self.outbound.push_back(byte);
        }
        if self.truth_queue.is_empty() && self.tx_fifo.is_empty() {
            self.tx_idle_us = Some(now_us);
        }
    }

    fn tick_rx(&mut self, now_us: u64, avail: u64) {
        if let Some(t) = self.rx_idle_us.take() {
            self.rx_bits = self.rx_bits.max(self.line_bits(t));
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

    /// Feeds one transmitted robot byte to the frame watcher; queues `EmuTruth` after a
    /// completed Telemetry frame.
    fn watch(&mut self, byte: u8, truth: &TruthHistory) {
        if !self.truth_enabled {
            return;
        }
        let (time_ms, timestamp) = match self.decoder.feed(&[byte]) {
            Feed::Frame {
                frame:
                    protocol::Frame {
                        message: Message::Telemetry(t),
                        signature,
                        ..
                    },
                ..
            } => (t.time_ms, signature.map(|s| s.timestamp)),
            _ => return,
        };
        let Some(s) = truth.at(time_ms) else { return };
        let msg = Message::EmuTruth(EmuTruth {
            time_ms,
            pose: wire_pose(s.pose),
            collisions: s.collisions,
            robot_id: truth.robot_id,
        });
        let mut buf = [0u8; MAX_FRAME];
        let encoded = match (&self.truth_key, timestamp) {
            (Some(key), Some(ts)) => protocol::encode_signed(
                self.truth_seq,
                &msg,
                key,
                protocol::sign::TRUTH_LINK,
                ts,
                &mut buf,
            ),
            // A keyed station would refuse unsigned truth; an unkeyed one, signed truth.
            (Some(_), None) | (None, Some(_)) => return,
            (None, None) => encode(self.truth_seq, &msg, &mut buf),
        };
        if let Ok(n) = encoded {
            self.truth_seq = self.truth_seq.wrapping_add(1);
            self.truth_queue.extend(buf.iter().take(n));
            self.stats.truth_frames = self.stats.truth_frames.wrapping_add(1);
        }
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
}
