//! An indexed binary min-heap in caller storage: A*'s open set (seed 004 §6).
//!
//! Layer: private helper of `astar.rs`. `heap[0 .. len]` holds region ids in heap order;
//! `pos[id]` is the id's slot, or [`UNSEEN`]/[`CLOSED`] markers. The key of id `v` is
//! `(f[v], v)`: unique per id, so the pop order is a total order and does not depend on the
//! order of pushes - the reason plans are identical however neighbours are enumerated.
//! Decrease-key keeps the heap at most one entry per region, so it never outgrows `R` slots.
//! Invariant: callers ensure `heap`, `pos` and `f` hold at least `R` entries and `R <= NONE - 1`
//! (so slot numbers never collide with the markers); out-of-range reads then cannot happen,
//! and if they did they would read `NONE`/`u32::MAX` rather than panic.

use super::ids::IdStore;

/// `pos` marker: never pushed in this search.
pub(crate) const fn unseen<I: IdStore + ?Sized>() -> u32 {
    I::NONE
}

/// `pos` marker: popped (its cost is final).
pub(crate) const fn closed<I: IdStore + ?Sized>() -> u32 {
    I::NONE.wrapping_sub(1)
}

/// The open set: borrowed heap and position stores plus the current length.
pub(crate) struct OpenSet<'s, I: IdStore + ?Sized> {
    heap: &'s mut I,
    pos: &'s mut I,
    len: usize,
}

#[inline]
fn key(f: &[u32], id: u32) -> u64 {
    (u64::from(f.get(id as usize).copied().unwrap_or(u32::MAX)) << 32) | u64::from(id)
}

impl<'s, I: IdStore + ?Sized> OpenSet<'s, I> {
    /// An empty open set with every id unseen.
    pub(crate) fn new(heap: &'s mut I, pos: &'s mut I) -> Self {
        pos.fill(unseen::<I>());
        OpenSet { heap, pos, len: 0 }
    }

    /// `pos` entry of `id`: a slot, `unseen` or `closed`.
    #[inline]
    pub(crate) fn state(&self, id: u32) -> u32 {
        self.pos.get(id as usize)
    }

    /// Adds `id` (unseen) with key `f[id]`.
    pub(crate) fn push(&mut self, f: &[u32], id: u32) {
        let slot = self.len;
        self.len += 1;
        self.place(slot, id);
        self.sift_up(f, slot);
    }

    /// Restores heap order after `f[id]` decreased.
    pub(crate) fn decreased(&mut self, f: &[u32], id: u32) {
        let slot = self.pos.get(id as usize) as usize;
        if slot < self.len {
            self.sift_up(f, slot);
        }
    }

    /// Removes and returns the id with the smallest key, marking it closed.
    pub(crate) fn pop(&mut self, f: &[u32]) -> Option<u32> {
        if self.len == 0 {
            return None;
        }
        let top = self.heap.get(0);
        self.len -= 1;
        if self.len > 0 {
            let last = self.heap.get(self.len);
            self.place(0, last);
            self.sift_down(f, 0);
        }
        self.pos.set(top as usize, closed::<I>());
        Some(top)
    }

    #[inline]
    fn place(&mut self, slot: usize, id: u32) {
        self.heap.set(slot, id);
        self.pos.set(id as usize, slot as u32);
    }

    fn sift_up(&mut self, f: &[u32], mut slot: usize) {
        let id = self.heap.get(slot);
        let k = key(f, id);
        while slot > 0 {
            let parent = (slot - 1) / 2;
            let pid = self.heap.get(parent);
            if key(f, pid) <= k {
                break;
            }
            self.place(slot, pid);
            slot = parent;
        }
        self.place(slot, id);
    }

    fn sift_down(&mut self, f: &[u32], mut slot: usize) {
        let id = self.heap.get(slot);
        let k = key(f, id);
        loop {
            let left = 2 * slot + 1;
            if left >= self.len {
                break;
            }
            let right = left + 1;
            let mut child = left;
            let mut ck = key(f, self.heap.get(left));
            if right < self.len {
                let rk = key(f, self.heap.get(right));
                if rk < ck {
                    child = right;
                    ck = rk;
                }
            }
            if k <= ck {
                break;
            }
            let cid = self.heap.get(child);
            self.place(slot, cid);
            slot = child;
        }
        self.place(slot, id);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pops_in_key_order_with_ties_broken_by_id() {
        let mut f = [5u32, 3, 5, 1, 9, 3];
        let (mut heap, mut pos) = ([0u16; 6], [0u16; 6]);
        let mut open = OpenSet::new(&mut heap[..], &mut pos[..]);
        for id in [4u32, 2, 0, 5, 1, 3] {
            open.push(&f, id);
        }
        f[4] = 2;
        open.decreased(&f, 4);
        let mut order = [0u32; 6];
        for slot in &mut order {
            *slot = open.pop(&f).expect("six entries");
        }
        assert_eq!(order, [3, 4, 1, 5, 0, 2]);
        assert_eq!(open.pop(&f), None);
        assert_eq!(open.state(2), closed::<[u16]>());
    }
}
