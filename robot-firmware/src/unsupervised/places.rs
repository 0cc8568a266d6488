//! Places: sequences of landmarks recognised by first-order Markov chains (§3.10-3.11).
//!
//! Each place is an ergodic N x N transition matrix over landmarks, every row starting uniform
//! (1/N). A new landmark sequence S is scored against every place: log P(S|M_k) = sum of
//! log a_{s_i, s_i+1}; the best place w is accepted when
//! log P(S|M_w) - log P(S|M_new) > log T (T about 0.008, §3.11.3), and then learns S: each
//! transition's cell gains 10/N and its row is renormalised to sum 1. Otherwise S founds a new
//! place. M_new is read as the matrix a new place would have after learning S (uniform plus
//! S's transitions), the only reading under which a sequence no place has seen is not
//! accepted by a place that never saw its rows (the thesis does not spell it out).
//!
//! Storage is sparse and fixed: a place keeps up to `MAX_TRANSITIONS` seen cells with their
//! probabilities and per-cell update counts; an unseen cell of row i is
//! (1/N) / (1 + 10/N)^k_i, k_i the updates row i has had. A full place stops learning new
//! cells (they keep the row's base probability).

use super::{MAX_PLACES, MAX_SEQUENCE, MAX_TRANSITIONS};

/// One step of a Markov chain: s' = s T (§3.11.2).
pub fn propagate<const N: usize>(s: &[f32; N], t: &[[f32; N]; N]) -> [f32; N] {
    let mut out = [0.0; N];
    for (i, si) in s.iter().enumerate() {
        for (o, tij) in out.iter_mut().zip(&t[i]) {
            *o += si * tij;
        }
    }
    out
}

/// The thesis's acceptance threshold T (§3.11.3).
pub const THRESHOLD_T: f32 = 0.008;

/// Place parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaceParams {
    /// N, the matrix size: the number of landmarks the robot can hold.
    pub n: u32,
    /// T of the acceptance rule.
    pub threshold: f32,
    /// Landmarks per sequence (the thesis: "about 5 are discovered for each pass").
    pub sequence_len: usize,
}

impl Default for PlaceParams {
    fn default() -> Self {
        Self {
            n: super::MAX_LANDMARKS as u32,
            threshold: THRESHOLD_T,
            sequence_len: 5,
        }
    }
}

#[derive(Clone, Copy, Debug, Default)]
struct Cell {
    from: u16,
    to: u16,
    p: f32,
}

/// One place's sparse Markov matrix.
#[derive(Clone, Copy, Debug)]
pub struct Place {
    cells: [Cell; MAX_TRANSITIONS],
    used: usize,
    /// Updates per row, counted over the cells (rows are landmarks).
    updates: [(u16, u16); MAX_TRANSITIONS],
    rows: usize,
    /// Sequences learnt.
    pub visits: u32,
}

impl Place {
    const EMPTY: Place = Place {
        cells: [Cell {
            from: 0,
            to: 0,
            p: 0.0,
        }; MAX_TRANSITIONS],
        used: 0,
        updates: [(0, 0); MAX_TRANSITIONS],
        rows: 0,
        visits: 0,
    };

    fn row_updates(&self, row: u16) -> u16 {
        self.updates[..self.rows]
            .iter()
            .find(|(r, _)| *r == row)
            .map_or(0, |(_, k)| *k)
    }

    /// a_ij of this place with matrix size `n`.
    pub fn probability(&self, i: u16, j: u16, n: u32) -> f32 {
        if let Some(c) = self.cells[..self.used]
            .iter()
            .find(|c| c.from == i && c.to == j)
        {
            return c.p;
        }
        let n = n as f32;
        let k = self.row_updates(i) as i32;
        (1.0 / n) / libm::powf(1.0 + 10.0 / n, k as f32)
    }

    /// log P(seq | this place).
    pub fn log_likelihood(&self, seq: &[u16], n: u32) -> f32 {
        seq.windows(2)
            .map(|w| libm::logf(self.probability(w[0], w[1], n)))
            .sum()
    }

    /// Learn one transition: +10/N, then renormalise the row (§3.11.3).
    fn learn(&mut self, i: u16, j: u16, n: u32) {
        let nf = n as f32;
        let inc = 10.0 / nf;
        let current = self.probability(i, j, n);
        if !self.cells[..self.used]
            .iter()
            .any(|c| c.from == i && c.to == j)
        {
            if self.used >= MAX_TRANSITIONS {
                return; // Full: the cell keeps its base probability.
            }
            self.cells[self.used] = Cell {
                from: i,
                to: j,
                p: current,
            };
            self.used += 1;
        }
        // The row sums to 1 before; after the increment to 1 + 10/N.
        let scale = 1.0 / (1.0 + inc);
        for c in self.cells[..self.used].iter_mut().filter(|c| c.from == i) {
            if c.to == j {
                c.p += inc;
            }
            c.p *= scale;
        }
        match self.updates[..self.rows].iter_mut().find(|(r, _)| *r == i) {
            Some((_, k)) => *k = k.saturating_add(1),
            None if self.rows < MAX_TRANSITIONS => {
                self.updates[self.rows] = (i, 1);
                self.rows += 1;
            }
            None => {}
        }
    }

    fn learn_sequence(&mut self, seq: &[u16], n: u32) {
        for w in seq.windows(2) {
            self.learn(w[0], w[1], n);
        }
        self.visits = self.visits.saturating_add(1);
    }
}

/// Outcome of offering a sequence.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PlaceEvent {
    /// Recognised as place `index` (score = log P(S|M_w) - log P(S|M_new)).
    Recognised {
        /// The place.
        index: u16,
        /// Its normalised log score.
        score: f32,
    },
    /// A new place was made.
    Created(u16),
    /// No place matched and the store is full.
    Full,
}

/// All places, and the sequence being collected.
#[derive(Clone, Debug)]
pub struct Places {
    params: PlaceParams,
    places: [Place; MAX_PLACES],
    used: usize,
    seq: [u16; MAX_SEQUENCE],
    seq_len: usize,
}

impl Places {
    /// No places yet.
    pub fn new(params: PlaceParams) -> Self {
        Self {
            params,
            places: [Place::EMPTY; MAX_PLACES],
            used: 0,
            seq: [0; MAX_SEQUENCE],
            seq_len: 0,
        }
    }

    /// Places made so far.
    pub fn len(&self) -> usize {
        self.used
    }

    /// True when there is no place yet.
    pub fn is_empty(&self) -> bool {
        self.used == 0
    }

    /// The places.
    pub fn places(&self) -> &[Place] {
        &self.places[..self.used]
    }

    /// Feed the next landmark seen (made or matched); every `sequence_len` landmarks the
    /// sequence is classified.
    pub fn push(&mut self, landmark: u16) -> Option<PlaceEvent> {
        if self.seq_len > 0 && self.seq[self.seq_len - 1] == landmark {
            return None; // The same landmark twice in a row is one visit.
        }
        self.seq[self.seq_len] = landmark;
        self.seq_len += 1;
        let len = self.params.sequence_len.clamp(2, MAX_SEQUENCE);
        if self.seq_len < len {
            return None;
        }
        let seq = self.seq;
        self.seq_len = 0;
        Some(self.offer(&seq[..len]))
    }

    /// Classify one landmark sequence (length >= 2) and learn it (§3.11.3).
    pub fn offer(&mut self, seq: &[u16]) -> PlaceEvent {
        let n = self.params.n.max(1);
        let mut fresh = Place::EMPTY;
        fresh.learn_sequence(seq, n);
        let own = fresh.log_likelihood(seq, n);
        let best = self.places[..self.used]
            .iter()
            .enumerate()
            .map(|(k, p)| (k, p.log_likelihood(seq, n)))
            .max_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((w, l)) = best {
            let score = l - own;
            if score > libm::logf(self.params.threshold) {
                self.places[w].learn_sequence(seq, n);
                return PlaceEvent::Recognised {
                    index: w as u16,
                    score,
                };
            }
        }
        if self.used >= MAX_PLACES {
            return PlaceEvent::Full;
        }
        self.places[self.used] = fresh;
        self.used += 1;
        PlaceEvent::Created((self.used - 1) as u16)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thesis_london_example() {
        // §3.11.2, Fig. 3-28.
        let t = [[0.6, 0.3, 0.1], [0.2, 0.5, 0.3], [0.4, 0.1, 0.5]];
        let s1 = propagate(&[0.5, 0.3, 0.2], &t);
        let s2 = propagate(&s1, &t);
        for (a, b) in s1.iter().zip([0.44, 0.32, 0.24]) {
            assert!((a - b).abs() < 1e-6, "{s1:?}");
        }
        for (a, b) in s2.iter().zip([0.424, 0.316, 0.260]) {
            assert!((a - b).abs() < 1e-6, "{s2:?}");
        }
    }

    #[test]
    fn learning_keeps_rows_stochastic() {
        let n = 20;
        let mut p = Place::EMPTY;
        p.learn_sequence(&[1, 2, 3, 1, 2, 4], n);
        for row in 0..n as u16 {
            let sum: f32 = (0..n as u16).map(|j| p.probability(row, j, n)).sum();
            assert!((sum - 1.0).abs() < 1e-4, "row {row}: {sum}");
        }
        // 1 -> 2 was learnt twice: (1/N + 10/N)/(1 + 10/N), then again.
        let once = (1.0 / 20.0 + 0.5) / 1.5;
        let twice = (once + 0.5) / 1.5;
        assert!((p.probability(1, 2, n) - twice).abs() < 1e-5);
    }

    #[test]
    fn a_sequence_seen_again_is_the_same_place_and_a_new_one_is_not() {
        let mut places = Places::new(PlaceParams {
            n: 100,
            ..PlaceParams::default()
        });
        assert_eq!(places.offer(&[1, 2, 3, 4, 5]), PlaceEvent::Created(0));
        // One landmark missing (§3.12: Markov is tolerant to missing elements).
        assert!(matches!(
            places.offer(&[1, 2, 4, 5]),
            PlaceEvent::Recognised { index: 0, .. }
        ));
        assert_eq!(places.offer(&[10, 11, 12, 13, 14]), PlaceEvent::Created(1));
        assert!(matches!(
            places.offer(&[11, 12, 13, 14]),
            PlaceEvent::Recognised { index: 1, .. }
        ));
        assert_eq!(places.len(), 2);
    }
}
