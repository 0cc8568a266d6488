//! A byte ring buffer with the counts the measures report: its fullest and what it dropped.
//! One sits between each UART interrupt and the main loop (the station's receive FIFO is
//! 256 bytes: at 115200 baud, 22 ms of line, more than the longest pass of the main loop).

/// `N` bytes of FIFO.
pub struct Fifo<const N: usize> {
    buf: [u8; N],
    head: usize,
    len: usize,
    max: usize,
    pushed: u32,
    dropped: u32,
}

impl<const N: usize> Default for Fifo<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Fifo<N> {
    pub const fn new() -> Self {
        Fifo {
            buf: [0; N],
            head: 0,
            len: 0,
            max: 0,
            pushed: 0,
            dropped: 0,
        }
    }

    /// Appends `b`; false (and counted) when full.
    pub fn push(&mut self, b: u8) -> bool {
        if self.len == N {
            self.dropped = self.dropped.wrapping_add(1);
            return false;
        }
        if let Some(slot) = self.buf.get_mut((self.head + self.len) % N) {
            *slot = b;
        }
        self.len += 1;
        self.max = self.max.max(self.len);
        self.pushed = self.pushed.wrapping_add(1);
        true
    }

    /// Takes the oldest byte.
    pub fn pop(&mut self) -> Option<u8> {
        if self.len == 0 {
            return None;
        }
        let b = self.buf.get(self.head).copied();
        self.head = (self.head + 1) % N;
        self.len -= 1;
        b
    }

    /// Moves up to `out.len()` bytes out; returns how many.
    pub fn pop_into(&mut self, out: &mut [u8]) -> usize {
        let mut n = 0;
        for slot in out.iter_mut() {
            match self.pop() {
                Some(b) => *slot = b,
                None => break,
            }
            n += 1;
        }
        n
    }

    /// Appends as many of `bytes` as fit; returns how many (the rest is not counted dropped:
    /// the caller keeps it).
    pub fn push_some(&mut self, bytes: &[u8]) -> usize {
        let room = N - self.len;
        let n = bytes.len().min(room);
        for &b in bytes.get(..n).unwrap_or_default() {
            self.push(b);
        }
        n
    }

    // The image's interrupt handlers ask; the host build has none.
    #[cfg_attr(not(target_os = "none"), allow(dead_code))]
    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The fullest it has been.
    pub fn max(&self) -> usize {
        self.max
    }

    /// Bytes taken in, and bytes refused full.
    pub fn pushed(&self) -> u32 {
        self.pushed
    }

    pub fn dropped(&self) -> u32 {
        self.dropped
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn it_keeps_order_wraps_and_counts_what_it_refused() {
        let mut f = Fifo::<4>::new();
        for b in 1..=6 {
            f.push(b);
        }
        assert_eq!((f.max(), f.dropped(), f.pushed()), (4, 2, 4));
        let mut out = [0; 3];
        assert_eq!(f.pop_into(&mut out), 3);
        assert_eq!(out, [1, 2, 3]);
        assert_eq!(f.push_some(&[7, 8, 9, 10]), 3);
        let mut out = [0; 8];
        assert_eq!(f.pop_into(&mut out), 4);
        assert_eq!(&out[..4], &[4, 7, 8, 9]);
        assert!(f.is_empty() && f.pop().is_none());
    }
}
