//! An indexed binary min-heap in caller storage: A*'s open set (seed 004 §6).
//!
//! Layer: private helper of `astar.rs`. `heap[0 .. len]` holds region ids in heap order and
//! `keys[slot]` the f of the id in that slot (kept by slot, not by id, so comparisons read
//! adjacent memory instead of jumping through an id-indexed array); `pos[id]` is the id's slot,
//! or the [`unseen`]/[`closed`] markers. The order is on `(f, id)`: unique per id, so the pop
//! order is a total order and does not depend on the order of pushes - the reason plans are
//! identical however neighbours are enumerated. Decrease-key keeps at most one entry per
//! region, so the heap never outgrows `R` slots.
//!
//! Invariant: callers ensure `heap`, `pos` and `keys` hold at least `R` entries and
//! `R <= NONE - 1` (so slot numbers never collide with the markers); out-of-range accesses then
//! cannot happen, and if they did they would read `NONE`/`u32::MAX` rather than panic.

use super::ids::IdStore;

/// `pos` marker: never pushed in this search.
pub(crate) const fn unseen<I: IdStore + ?Sized>() -> u32 {
    I::NONE
}

/// `pos` marker: popped (its cost is final).
pub(crate) const fn closed<I: IdStore + ?Sized>() -> u32 {
    I::NONE.wrapping_sub(1)
}

/// The open set: borrowed heap, position and key stores plus the current length.
pub(crate) struct OpenSet<'s, I: IdStore + ?Sized> {
    heap: &'s mut I,
    pos: &'s mut I,
    keys: &'s mut [u32],
    len: usize,
}

#[inline]
fn order(f: u32, id: u32) -> u64 {
    (u64::from(f) << 32) | u64::from(id)
}

impl<'s, I: IdStore + ?Sized> OpenSet<'s, I> {
    /// An empty open set with every id unseen.
    pub(crate) fn new(heap: &'s mut I, pos: &'s mut I, keys: &'s mut [u32]) -> Self {
        pos.fill(unseen::<I>());
        OpenSet {
            heap,
            pos,
            keys,
            len: 0,
        }
    }

    /// `pos` entry of `id`: a slot, `unseen` or `closed`.
    #[inline]
    pub(crate) fn state(&self, id: u32) -> u32 {
        self.pos.get(id as usize)
    }

    /// f of an open id (`u32::MAX` if it is not open).
    #[inline]
    pub(crate) fn f(&self, id: u32) -> u32 {
        let slot = self.pos.get(id as usize) as usize;
        match self.keys.get(slot) {
            Some(&f) if slot < self.len => f,
            _ => u32::MAX,
        }
    }

    /// Adds `id` (unseen) with f `f`.
    pub(crate) fn push(&mut self, id: u32, f: u32) {
        let slot = self.len;
        self.len += 1;
        self.sift_up(slot, id, f);
    }

    /// Lowers the f of the open `id` to `f`.
    pub(crate) fn decrease(&mut self, id: u32, f: u32) {
        let slot = self.pos.get(id as usize) as usize;
        if slot < self.len {
            self.sift_up(slot, id, f);
        }
    }

    /// Removes the entry with the least `(f, id)`, marks it closed and returns `(id, f)`.
    pub(crate) fn pop(&mut self) -> Option<(u32, u32)> {
        if self.len == 0 {
            return None;
        }
        let top = (self.heap.get(0), self.key(0));
        self.len -= 1;
        if self.len > 0 {
            let (id, f) = (self.heap.get(self.len), self.key(self.len));
            self.sift_down(0, id, f);
        }
        self.pos.set(top.0 as usize, closed::<I>());
        Some(top)
    }

    #[inline]
    fn key(&self, slot: usize) -> u32 {
        self.keys.get(slot).copied().unwrap_or(u32::MAX)
    }

    #[inline]
    fn place(&mut self, slot: usize, id: u32, f: u32) {
        self.heap.set(slot, id);
        if let Some(k) = self.keys.get_mut(slot) {
            *k = f;
        }
        self.pos.set(id as usize, slot as u32);
    }

    fn sift_up(&mut self, mut slot: usize, id: u32, f: u32) {
        let k = order(f, id);
        while slot > 0 {
            let parent = (slot - 1) / 2;
            let (pid, pf) = (self.heap.get(parent), self.key(parent));
            if order(pf, pid) <= k {
                break;
            }
            self.place(slot, pid, pf);
            slot = parent;
        }
        self.place(slot, id, f);
    }

    fn sift_down(&mut self, mut slot: usize, id: u32, f: u32) {
        let k = order(f, id);
        loop {
            let left = 2 * slot + 1;
            if left >= self.len {
                break;
            }
            let (mut child, mut cid, mut cf) = (left, self.heap.get(left), self.key(left));
            let right = left + 1;
            if right < self.len {
                let (rid, rf) = (self.heap.get(right), self.key(right));
                if order(rf, rid) < order(cf, cid) {
                    (child, cid, cf) = (right, rid, rf);
                }
            }
            if k <= order(cf, cid) {
                break;
            }
            self.place(slot, cid, cf);
            slot = child;
        }
        self.place(slot, id, f);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pops_in_key_order_with_ties_broken_by_id() {
        let f = [5u32, 3, 5, 1, 9, 3];
        let (mut heap, mut pos, mut keys) = ([0u16; 6], [0u16; 6], [0u32; 6]);
        let mut open = OpenSet::new(&mut heap[..], &mut pos[..], &mut keys);
        for id in [4u32, 2, 0, 5, 1, 3] {
            open.push(id, f[id as usize]);
        }
        open.decrease(4, 2);
        assert_eq!(open.f(4), 2);
        let mut order = [0u32; 6];
        for slot in &mut order {
            *slot = open.pop().expect("six entries").0;
        }
        assert_eq!(order, [3, 4, 1, 5, 0, 2]);
        assert_eq!(open.pop(), None);
        assert_eq!(open.state(2), closed::<[u16]>());
        assert_eq!(open.f(2), u32::MAX);
    }
}
