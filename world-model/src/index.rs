//! The spatial index behind the winner search (§4.2.2: "the search area is limited by the
//! geometric distance g_search ... by applying adequate data-structures"): a hash grid of
//! square buckets `g_search` wide, so a search touches at most 9 buckets whatever the
//! network's size.

use std::collections::HashMap;

/// Cell ids per grid bucket.
#[derive(Clone, Debug, Default)]
pub struct Grid {
    pitch: f64,
    buckets: HashMap<(i64, i64), Vec<u32>>,
}

impl Grid {
    /// An empty grid of `pitch`-metre buckets.
    pub fn new(pitch: f64) -> Self {
        Grid {
            pitch,
            buckets: HashMap::new(),
        }
    }

    /// The bucket a position falls in. Positions far outside any arena saturate (the cast is
    /// saturating), which keeps them findable without overflow.
    pub fn key(&self, x: f64, y: f64) -> (i64, i64) {
        (
            (x / self.pitch).floor() as i64,
            (y / self.pitch).floor() as i64,
        )
    }

    /// Add `id` at `key`.
    pub fn insert(&mut self, key: (i64, i64), id: u32) {
        self.buckets.entry(key).or_default().push(id);
    }

    /// Remove `id` from `key`'s bucket.
    pub fn remove(&mut self, key: (i64, i64), id: u32) {
        if let Some(v) = self.buckets.get_mut(&key) {
            v.retain(|&c| c != id);
            if v.is_empty() {
                self.buckets.remove(&key);
            }
        }
    }

    /// Ids in the buckets that can hold a point within `r` of `(x, y)` (a superset: callers
    /// check the distance).
    pub fn near(&self, x: f64, y: f64, r: f64, out: &mut Vec<u32>) {
        out.clear();
        let (x0, y0) = self.key(x - r, y - r);
        let (x1, y1) = self.key(x + r, y + r);
        // Bounded: with r <= pitch this is at most 3 x 3 buckets; a larger r (a caller's
        // choice) still visits only as many buckets as the area spans, capped below.
        let span = (x1.saturating_sub(x0)).saturating_add(1) as i128
            * (y1.saturating_sub(y0)).saturating_add(1) as i128;
        if span > self.buckets.len() as i128 {
            for v in self.buckets.values() {
                out.extend_from_slice(v);
            }
            // A HashMap's order varies from run to run; the candidates' must not (a winner
            // search keeps the first of equals).
            out.sort_unstable();
            return;
        }
        for bx in x0..=x1 {
            for by in y0..=y1 {
                if let Some(v) = self.buckets.get(&(bx, by)) {
                    out.extend_from_slice(v);
                }
            }
        }
    }
}
