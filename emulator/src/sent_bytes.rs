//! The bytes a UART has put on the wire, each with the moment its last bit left.
//!
//! Layer: a queue inside `uart`, no I/O. The serving loop runs the robot's millisecond step as
//! soon as the wall clock reaches it, and the step moves the line on to the step's end: bytes
//! completing up to a millisecond in the future. Handing those to the station at once would
//! make the emulator answer faster than its baud rate allows; holding them all to the next
//! step made it up to a millisecond slower (issue 15: a minimal client's round trip p50
//! 3.9 ms for 2.1-2.4 ms of bytes). So each byte keeps its completion time on the line's bit
//! clock and the host takes only those complete by its own clock (`take_until`).
//!
//! The times are stored as runs (a byte completing `BITS_PER_BYTE` after the one before
//! belongs to its run): on a busy line a frame is one run, so the queue costs a few words
//! beside its bytes. Invariant: `runs` counts exactly the bytes in `bytes`, in order. Cannot
//! fail.

use std::collections::VecDeque;

/// Bits on the wire per byte: start + 8 data + stop (8N1); the spacing of a run.
pub const BITS_PER_BYTE: u64 = 10;

/// Sent bytes with their completion times (bit-clock positions).
#[derive(Debug, Default)]
pub struct SentBytes {
    bytes: VecDeque<u8>,
    /// (bit position at which the run's first byte completed, bytes in the run).
    runs: VecDeque<(u64, u64)>,
}

impl SentBytes {
    /// Bytes held.
    pub fn len(&self) -> usize {
        self.bytes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }

    /// A byte whose last bit left at bit position `done_bits`.
    pub fn push(&mut self, byte: u8, done_bits: u64) {
        self.bytes.push_back(byte);
        match self.runs.back_mut() {
            Some((first, n)) if *first + *n * BITS_PER_BYTE == done_bits => *n += 1,
            _ => self.runs.push_back((done_bits, 1)),
        }
    }

    /// Forgets the `n` oldest bytes' times (their bytes are taken by the caller).
    fn drop_times(&mut self, mut n: u64) {
        while n > 0 {
            let Some((first, len)) = self.runs.front_mut() else {
                return;
            };
            let k = n.min(*len);
            *first += k * BITS_PER_BYTE;
            *len -= k;
            n -= k;
            if *len == 0 {
                self.runs.pop_front();
            }
        }
    }

    /// Drops the oldest byte (the host never took it); returns whether there was one.
    pub fn pop_front(&mut self) -> bool {
        let had = self.bytes.pop_front().is_some();
        if had {
            self.drop_times(1);
        }
        had
    }

    /// Moves up to `buf.len()` of the oldest bytes into `buf`, whenever they completed.
    pub fn take_into(&mut self, buf: &mut [u8]) -> usize {
        let n = buf.len().min(self.bytes.len());
        for (slot, b) in buf.iter_mut().zip(self.bytes.drain(..n)) {
            *slot = b;
        }
        self.drop_times(n as u64);
        n
    }

    /// How many of the oldest bytes had completed by bit position `bits`.
    pub fn complete_by(&self, bits: u64) -> usize {
        let mut count = 0u64;
        for &(first, len) in &self.runs {
            if first > bits {
                break;
            }
            let k = ((bits - first) / BITS_PER_BYTE + 1).min(len);
            count += k;
            if k < len {
                break;
            }
        }
        usize::try_from(count).unwrap_or(usize::MAX)
    }

    /// Moves into `buf` the oldest bytes complete by bit position `bits` (at most its length).
    pub fn take_until(&mut self, bits: u64, buf: &mut [u8]) -> usize {
        let n = self.complete_by(bits).min(buf.len());
        self.take_into(buf.get_mut(..n).unwrap_or(&mut []))
    }

    /// The bit position at which the first byte equal to `value` completes, if one is held:
    /// with `value` 0, when the station can first decode a whole frame.
    pub fn done_bits_of_first(&self, value: u8) -> Option<u64> {
        let mut index = u64::try_from(self.bytes.iter().position(|&b| b == value)?).ok()?;
        for &(first, len) in &self.runs {
            if index < len {
                return Some(first + index * BITS_PER_BYTE);
            }
            index -= len;
        }
        None
    }

    /// Every byte, oldest first, whenever it completed.
    pub fn take_all(&mut self) -> Vec<u8> {
        self.runs.clear();
        self.bytes.drain(..).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_are_taken_only_once_complete_and_in_order() {
        let mut s = SentBytes::default();
        // A frame of three bytes back to back from bit 100, then one after a gap.
        for (i, b) in [1u8, 2, 0].into_iter().enumerate() {
            s.push(b, 100 + 10 * i as u64);
        }
        s.push(7, 500);
        assert_eq!(s.complete_by(99), 0);
        assert_eq!(s.complete_by(100), 1);
        assert_eq!(s.complete_by(115), 2);
        assert_eq!(s.complete_by(499), 3);
        assert_eq!(s.complete_by(10_000), 4);
        assert_eq!(s.done_bits_of_first(0), Some(120));
        assert_eq!(s.done_bits_of_first(7), Some(500));
        assert_eq!(s.done_bits_of_first(9), None);
        let mut buf = [0u8; 8];
        assert_eq!(s.take_until(115, &mut buf), 2);
        assert_eq!(buf[..2], [1, 2]);
        // The times follow the bytes taken.
        assert_eq!(s.done_bits_of_first(0), Some(120));
        assert_eq!(s.complete_by(120), 1);
        assert!(s.pop_front());
        assert_eq!(s.take_until(499, &mut buf), 0);
        assert_eq!(s.take_all(), vec![7]);
        assert!(s.is_empty() && !s.pop_front());
    }

    #[test]
    fn a_small_buffer_takes_part_of_what_is_complete() {
        let mut s = SentBytes::default();
        for i in 0..10u64 {
            s.push(i as u8 + 1, 10 * (i + 1));
        }
        let mut buf = [0u8; 4];
        assert_eq!(s.take_until(1_000, &mut buf), 4);
        assert_eq!(s.complete_by(1_000), 6);
        assert_eq!(s.len(), 6);
        assert_eq!(s.done_bits_of_first(5), Some(50));
    }
}
