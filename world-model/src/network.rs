//! The cell network (§4.2.2-4.2.3): cells holding situations, symmetric edges weighted by
//! confidence, the spatial index, and the primitive changes (insert, move, connect, the
//! winner-change confidence update, removal). The learning rules that drive them live in
//! [`crate::model`].

use serde::Serialize;

use crate::index::Grid;
use crate::situation::Weights;

/// One cell: a situation with its statistics and its edges.
#[derive(Clone, Debug, Serialize)]
pub struct Cell {
    /// The situation `[lights, touches, x, y]`, unweighted.
    pub s: Vec<f64>,
    /// Accumulated classification error d_total (eq. 4), halved at each statistical
    /// insertion next to it (as in Fritzke's growing cell structures: otherwise the oldest
    /// cell would always be the runner).
    pub d_total: f64,
    /// Updates u (times this cell won).
    pub updates: u32,
    /// Neighbours and the confidence a(., .) of each edge (> 0; an edge at <= 0 is removed).
    pub edges: Vec<(u32, f64)>,
    #[serde(skip)]
    key: (i64, i64),
}

/// The network: cells in slots (ids stay valid until the cell is removed), a free list, the
/// spatial index and the distance weights.
#[derive(Clone, Debug)]
pub struct Network {
    slots: Vec<Option<Cell>>,
    free: Vec<u32>,
    grid: Grid,
    weights: Weights,
    live: usize,
    max_cells: usize,
    /// Insertions refused because the network was full.
    pub refused: u64,
}

impl Network {
    /// An empty network.
    pub fn new(weights: Weights, g_search: f64, max_cells: usize) -> Self {
        Network {
            slots: Vec::new(),
            free: Vec::new(),
            grid: Grid::new(g_search),
            weights,
            live: 0,
            max_cells,
            refused: 0,
        }
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.live
    }

    /// True when there are no cells.
    pub fn is_empty(&self) -> bool {
        self.live == 0
    }

    /// The cell `id`, if it exists.
    pub fn cell(&self, id: u32) -> Option<&Cell> {
        self.slots.get(id as usize).and_then(|c| c.as_ref())
    }

    /// All cells with their ids.
    pub fn cells(&self) -> impl Iterator<Item = (u32, &Cell)> {
        self.slots
            .iter()
            .enumerate()
            .filter_map(|(i, c)| c.as_ref().map(|c| (i as u32, c)))
    }

    /// Every edge once (`a < b`) with its confidence.
    pub fn edges(&self) -> impl Iterator<Item = (u32, u32, f64)> + '_ {
        self.cells().flat_map(|(a, c)| {
            c.edges
                .iter()
                .filter(move |(b, _)| a < *b)
                .map(move |&(b, w)| (a, b, w))
        })
    }

    /// Position (x, y) of a situation.
    pub fn pos_of(s: &[f64]) -> (f64, f64) {
        let n = s.len();
        (s[n - 2], s[n - 1])
    }

    /// Position of cell `id` (the origin for a missing id).
    pub fn position(&self, id: u32) -> (f64, f64) {
        self.cell(id).map_or((0.0, 0.0), |c| Self::pos_of(&c.s))
    }

    /// Weighted situation distance.
    pub fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        self.weights.distance(a, b)
    }

    /// Weighted distance over the first `n` components only (e.g. the sensor part).
    pub fn distance_part(&self, a: &[f64], b: &[f64], n: usize) -> f64 {
        self.weights.distance_prefix(a, b, n)
    }

    /// The cell nearest to situation `s` (eq. 1) among those within `r` metres of `at`.
    pub fn winner(
        &self,
        s: &[f64],
        at: (f64, f64),
        r: f64,
        scratch: &mut Vec<u32>,
    ) -> Option<(u32, f64)> {
        self.grid.near(at.0, at.1, r, scratch);
        let mut best: Option<(u32, f64)> = None;
        for &id in scratch.iter() {
            let Some(c) = self.cell(id) else { continue };
            let (x, y) = Self::pos_of(&c.s);
            if (x - at.0).hypot(y - at.1) > r {
                continue;
            }
            let d = self.weights.distance(&c.s, s);
            if best.is_none_or(|(_, bd)| d < bd) {
                best = Some((id, d));
            }
        }
        best
    }

    /// The cell geometrically nearest to `at` within `r` (eq. 9).
    pub fn nearest(&self, at: (f64, f64), r: f64, scratch: &mut Vec<u32>) -> Option<(u32, f64)> {
        self.grid.near(at.0, at.1, r, scratch);
        let mut best: Option<(u32, f64)> = None;
        for &id in scratch.iter() {
            let Some(c) = self.cell(id) else { continue };
            let (x, y) = Self::pos_of(&c.s);
            let g = (x - at.0).hypot(y - at.1);
            if g <= r && best.is_none_or(|(_, bg)| g < bg) {
                best = Some((id, g));
            }
        }
        best
    }

    /// Insert a cell holding `s`; `None` (and a refusal counted) when the network is full.
    pub fn insert(&mut self, s: Vec<f64>, d_total: f64) -> Option<u32> {
        if self.live >= self.max_cells {
            self.refused += 1;
            return None;
        }
        let (x, y) = Self::pos_of(&s);
        let key = self.grid.key(x, y);
        let cell = Cell {
            s,
            d_total,
            updates: 0,
            edges: Vec::new(),
            key,
        };
        let id = match self.free.pop() {
            Some(id) => {
                self.slots[id as usize] = Some(cell);
                id
            }
            None => {
                self.slots.push(Some(cell));
                (self.slots.len() - 1) as u32
            }
        };
        self.grid.insert(key, id);
        self.live += 1;
        Some(id)
    }

    /// Remove cell `id` and its edges.
    pub fn remove(&mut self, id: u32) {
        let Some(cell) = self.slots.get_mut(id as usize).and_then(|c| c.take()) else {
            return;
        };
        self.grid.remove(cell.key, id);
        for (n, _) in &cell.edges {
            if let Some(nc) = self.slots.get_mut(*n as usize).and_then(|c| c.as_mut()) {
                nc.edges.retain(|(m, _)| *m != id);
            }
        }
        self.free.push(id);
        self.live -= 1;
    }

    /// Move cell `id` a fraction `eps` of the way to `s` (the standard SOM/GCS move: the
    /// thesis's printed eqs. 2-3 subtract a scalar, which cannot be meant literally).
    pub fn move_toward(&mut self, id: u32, s: &[f64], eps: f64) {
        let Some(c) = self.slots.get_mut(id as usize).and_then(|c| c.as_mut()) else {
            return;
        };
        for (v, t) in c.s.iter_mut().zip(s) {
            *v += eps * (t - *v);
        }
        let (x, y) = Self::pos_of(&c.s);
        let key = self.grid.key(x, y);
        if key != c.key {
            let old = c.key;
            c.key = key;
            self.grid.remove(old, id);
            self.grid.insert(key, id);
        }
    }

    /// Mutable statistics of a cell.
    pub fn cell_mut(&mut self, id: u32) -> Option<&mut Cell> {
        self.slots.get_mut(id as usize).and_then(|c| c.as_mut())
    }

    /// Set the edge `a`-`b` to confidence `w` (created if missing; removed if `w <= 0`).
    pub fn set_edge(&mut self, a: u32, b: u32, w: f64) {
        if a == b || self.cell(a).is_none() || self.cell(b).is_none() {
            return;
        }
        for (x, y) in [(a, b), (b, a)] {
            if let Some(c) = self.cell_mut(x) {
                c.edges.retain(|(n, _)| *n != y);
                if w > 0.0 {
                    c.edges.push((y, w));
                }
            }
        }
    }

    /// The winner changed from `old` to `new` (eqs. 7-8): a(new, old) = 1, new's m other
    /// edges each lose a_red / m, edges at <= 0 vanish, and a neighbour left with no edge at
    /// all is removed. Says what it did (nothing when the two are one cell or either is
    /// gone).
    pub fn winner_changed(&mut self, new: u32, old: u32, a_red: f64) -> WinnerChange {
        let mut change = WinnerChange::default();
        if new == old || self.cell(old).is_none() {
            return change;
        }
        let Some(cell) = self.cell(new) else {
            return change;
        };
        change.joined = true;
        change.created = !cell.edges.iter().any(|e| e.0 == old);
        let others: Vec<(u32, f64)> = cell
            .edges
            .iter()
            .copied()
            .filter(|(n, _)| *n != old)
            .collect();
        let m = others.len();
        change.worn = m;
        for (n, w) in others {
            let w = w - a_red / m as f64;
            self.set_edge(new, n, w);
            if w <= 0.0 && self.cell(n).is_some_and(|c| c.edges.is_empty()) {
                self.remove(n);
                change.removed.push(n);
            }
        }
        self.set_edge(new, old, 1.0);
        change
    }
}

/// What [`Network::winner_changed`] did.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct WinnerChange {
    /// The two cells were joined to confidence 1 (false: nothing was done).
    pub joined: bool,
    /// The edge between them was new (false: an existing one was refreshed).
    pub created: bool,
    /// The new winner's other edges, each worn by a_red / m.
    pub worn: usize,
    /// Cells removed because they lost their last edge.
    pub removed: Vec<u32>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Params;

    fn net(cap: usize) -> Network {
        Network::new(Weights::new(&Params::default()), 0.8, cap)
    }

    fn at(net: &mut Network, x: f64, y: f64) -> Option<u32> {
        let mut s = vec![0.0; 48];
        s.extend([x, y]);
        net.insert(s, 0.0)
    }

    /// Eqs. 7-8: the new winner's edge to the old one is set to 1, its m other edges lose
    /// a_red / m each; an edge reaching 0 goes, and a cell left with no edge goes with it.
    #[test]
    fn a_winner_change_confirms_one_edge_and_wears_the_others() {
        let mut n = net(10);
        let [a, b, c, d] = [0.0, 0.3, 0.6, 0.9].map(|x| at(&mut n, x, 0.0).expect("room"));
        n.set_edge(b, c, 0.5);
        n.set_edge(b, d, 0.05);
        n.set_edge(c, d, 0.5);
        let change = n.winner_changed(b, a, 0.2);
        assert!(change.removed.is_empty());
        assert_eq!(
            (change.joined, change.created, change.worn),
            (true, true, 2)
        );
        let conf = |n: &Network, x: u32, y: u32| {
            n.cell(x)
                .and_then(|c| c.edges.iter().find(|e| e.0 == y).map(|e| e.1))
        };
        assert_eq!(conf(&n, b, a), Some(1.0));
        assert_eq!(conf(&n, a, b), Some(1.0), "edges are symmetric");
        assert!((conf(&n, b, c).expect("kept") - 0.4).abs() < 1e-12);
        assert_eq!(conf(&n, b, d), None, "0.05 - 0.1 <= 0: gone");
        // d keeps its edge to c, so it stays; a cell that loses its only edge is removed.
        assert!(n.cell(d).is_some());
        let e = at(&mut n, 1.2, 0.0).expect("room");
        n.set_edge(b, e, 0.01);
        let change = n.winner_changed(b, a, 0.2);
        assert_eq!(change.removed, vec![e]);
        assert_eq!(
            (change.created, change.worn),
            (false, 2),
            "b-a refreshed; c and e worn"
        );
        assert_eq!(n.winner_changed(b, b, 0.2), WinnerChange::default());
        assert!(n.cell(e).is_none() && n.len() == 4);
    }

    /// The cap bounds memory: a full network refuses and counts.
    #[test]
    fn a_full_network_refuses_insertions() {
        let mut n = net(2);
        assert!(at(&mut n, 0.0, 0.0).is_some() && at(&mut n, 1.0, 0.0).is_some());
        assert_eq!(at(&mut n, 2.0, 0.0), None);
        assert_eq!((n.len(), n.refused), (2, 1));
    }

    /// The winner search sees only cells within the radius, through the index, also after
    /// cells moved between buckets.
    #[test]
    fn the_search_is_limited_to_g_search_and_follows_moved_cells() {
        let mut n = net(10);
        let a = at(&mut n, 0.0, 0.0).expect("room");
        let far = at(&mut n, 5.0, 5.0).expect("room");
        let mut q = vec![0.0; 48];
        q.extend([4.9, 4.9]);
        let mut scratch = Vec::new();
        assert_eq!(
            n.winner(&q, (4.9, 4.9), 0.8, &mut scratch).map(|w| w.0),
            Some(far)
        );
        // Move a next to the query: it must be found in its new bucket.
        n.move_toward(a, &q, 1.0);
        assert_eq!(
            n.nearest((4.9, 4.9), 0.05, &mut scratch).map(|w| w.0),
            Some(a)
        );
        assert_eq!(n.winner(&q, (0.0, 0.0), 0.8, &mut scratch), None);
    }
}
