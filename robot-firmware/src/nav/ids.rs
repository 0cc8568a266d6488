//! Index storage: the caller-provided arrays that hold region ids, parents and heap slots.
//!
//! Layer: the lowest of `nav`; everything above is generic over [`IdStore`], so the firmware
//! keeps region ids in 16 bits or a bit-packed array ([`PackedIds`]) while the station uses
//! `[u32]` in vectors, and both run the very same code. Every store's largest value
//! ([`IdStore::NONE`]) is reserved as the "no id" marker, so a store of `n`-bit values holds ids
//! `0 ..= 2^n - 2`. Invariant: nothing here panics; a read past the end yields `NONE` and a
//! write past the end is ignored. Callers check lengths up front (and report a typed error), so
//! those fallbacks are never relied on for correct results.

/// A fixed-length array of small unsigned values (region ids, parents, heap slots).
pub trait IdStore {
    /// The largest storable value, reserved as the "no id" marker.
    const NONE: u32;
    /// Number of entries.
    fn len(&self) -> usize;
    /// Whether the store has no entries.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Entry `i`, or `NONE` when `i` is out of range.
    fn get(&self, i: usize) -> u32;
    /// Stores `v` at `i`; out-of-range `i` is ignored, `v > NONE` stores `NONE`.
    fn set(&mut self, i: usize, v: u32);
    /// Sets every entry to `v`.
    fn fill(&mut self, v: u32) {
        for i in 0..self.len() {
            self.set(i, v);
        }
    }
}

macro_rules! slice_store {
    ($t:ty) => {
        impl IdStore for [$t] {
            const NONE: u32 = <$t>::MAX as u32;
            #[inline]
            fn len(&self) -> usize {
                <[$t]>::len(self)
            }
            #[inline]
            fn get(&self, i: usize) -> u32 {
                <[$t]>::get(self, i).map_or(Self::NONE, |&v| u32::from(v))
            }
            #[inline]
            fn set(&mut self, i: usize, v: u32) {
                if let Some(slot) = <[$t]>::get_mut(self, i) {
                    *slot = <$t>::try_from(v).unwrap_or(<$t>::MAX);
                }
            }
            fn fill(&mut self, v: u32) {
                <[$t]>::fill(self, <$t>::try_from(v).unwrap_or(<$t>::MAX));
            }
        }
    };
}

slice_store!(u8);
slice_store!(u16);
slice_store!(u32);

/// Bytes needed to hold `len` values of `bits` bits each, plus the 3 bytes of slack that let a
/// read always fetch a whole 32-bit window (usable in array lengths: it is a `const fn`).
pub const fn packed_bytes(bits: u32, len: usize) -> usize {
    // Saturating, so an absurd `len` gives an unsatisfiable size rather than an overflow.
    len.saturating_mul(bits as usize)
        .div_ceil(8)
        .saturating_add(3)
}

/// A bit-packed [`IdStore`] of `BITS`-bit values (1 ..= 24) over caller bytes.
///
/// Exists for the firmware's per-cell region map: 9 bits per cell keep a 64 x 64 map of up to 510
/// regions in 4.6 KB instead of 8 KB for `[u16]` (see `fixed.rs` for the budget).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PackedIds<const BITS: u32, S> {
    len: usize,
    bytes: S,
}

impl<const BITS: u32, S> PackedIds<BITS, S> {
    /// Used by the fixed firmware instance, whose sizes are checked at compile time.
    pub(crate) const fn from_raw(len: usize, bytes: S) -> Self {
        PackedIds { len, bytes }
    }
}

impl<const BITS: u32, S: AsRef<[u8]>> PackedIds<BITS, S> {
    const MASK: u32 = if BITS >= 32 {
        u32::MAX
    } else {
        (1u32 << BITS) - 1
    };

    /// A store of `len` values over `bytes`; `None` if `BITS` is outside 1 ..= 24 or `bytes` is
    /// shorter than [`packed_bytes`]`(BITS, len)`.
    pub fn new(len: usize, bytes: S) -> Option<Self> {
        let ok = (1..=24).contains(&BITS) && bytes.as_ref().len() >= packed_bytes(BITS, len);
        ok.then_some(Self { len, bytes })
    }

    /// Changes the number of entries (contents are unspecified until written); `false` if the
    /// bytes are too few, in which case nothing changes.
    pub fn resize(&mut self, len: usize) -> bool {
        let ok = self.bytes.as_ref().len() >= packed_bytes(BITS, len);
        if ok {
            self.len = len;
        }
        ok
    }

    /// Largest number of entries the bytes can hold.
    pub fn capacity(&self) -> usize {
        self.bytes
            .as_ref()
            .len()
            .saturating_sub(3)
            .saturating_mul(8)
            / BITS.max(1) as usize
    }

    /// The packed bytes (little-endian bit order, entry `i` at bit `i * BITS`).
    pub fn as_bytes(&self) -> &[u8] {
        self.bytes.as_ref()
    }

    fn window(&self, byte: usize) -> u32 {
        let b = self.bytes.as_ref();
        let at = |k: usize| u32::from(b.get(byte + k).copied().unwrap_or(0));
        at(0) | at(1) << 8 | at(2) << 16 | at(3) << 24
    }
}

impl<const BITS: u32, S: AsMut<[u8]>> PackedIds<BITS, S> {
    /// The bytes as scratch for another use (the grid planner's labels when the squares did
    /// not fit, `fixed.rs`); the ids read afterwards are meaningless until the next segmentation.
    pub(crate) fn bytes_mut(&mut self) -> &mut [u8] {
        self.bytes.as_mut()
    }
}

impl<const BITS: u32, S: AsRef<[u8]> + AsMut<[u8]>> IdStore for PackedIds<BITS, S> {
    const NONE: u32 = Self::MASK;

    fn len(&self) -> usize {
        self.len
    }

    #[inline]
    fn get(&self, i: usize) -> u32 {
        if i >= self.len {
            return Self::NONE;
        }
        let bit = i * BITS as usize;
        // BITS <= 24 and shift <= 7, so the value lies inside one 32-bit window.
        (self.window(bit / 8) >> (bit % 8)) & Self::MASK
    }

    fn set(&mut self, i: usize, v: u32) {
        if i >= self.len {
            return;
        }
        let bit = i * BITS as usize;
        let (byte, shift) = (bit / 8, bit % 8);
        let w = (self.window(byte) & !(Self::MASK << shift)) | (v.min(Self::MASK) << shift);
        let bytes = self.bytes.as_mut();
        for (k, b) in w.to_le_bytes().iter().enumerate() {
            if let Some(slot) = bytes.get_mut(byte + k) {
                *slot = *b;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slice_stores_read_none_past_the_end_and_ignore_writes_there() {
        let mut a = [0u16; 4];
        let s: &mut [u16] = &mut a;
        // The trait's methods, not the slice's inherent `get`.
        IdStore::set(s, 9, 3);
        assert_eq!(IdStore::get(s, 9), u32::from(u16::MAX));
        IdStore::set(s, 1, 70_000);
        assert_eq!(IdStore::get(s, 1), <[u16] as IdStore>::NONE);
    }

    #[test]
    fn packed_store_round_trips_every_value_at_every_position() {
        let mut bytes = [0u8; packed_bytes(9, 40)];
        let mut p = PackedIds::<9, _>::new(40, &mut bytes[..]).expect("enough bytes");
        for i in 0..40 {
            p.set(i, (i as u32 * 37) % 512);
        }
        for i in 0..40 {
            assert_eq!(p.get(i), (i as u32 * 37) % 512, "entry {i}");
        }
        p.fill(PackedIds::<9, &mut [u8]>::NONE);
        assert!((0..40).all(|i| p.get(i) == 511));
        assert_eq!(p.get(40), 511);
    }

    #[test]
    fn packed_store_rejects_too_few_bytes_and_bad_widths() {
        assert!(PackedIds::<9, _>::new(40, [0u8; 10]).is_none());
        assert!(PackedIds::<25, _>::new(1, [0u8; 64]).is_none());
        assert!(PackedIds::<0, _>::new(1, [0u8; 64]).is_none());
    }
}
