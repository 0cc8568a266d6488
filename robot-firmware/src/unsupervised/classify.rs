//! Online classifiers tuned by one vigilance (§3.4): growing K-means, ART-1 and simplified
//! Fuzzy ART. Each turns an input vector (components in [0, 1], length <= `MAX_DIM`) into a
//! class label and grows a new class when no existing one is close enough. A classifier with
//! `MAX_CLASSES` classes stops growing and answers with the best existing class, so memory is
//! fixed; [`Classifier::full`] says when that happened.
//!
//! [`Classifier::prototype_distance`] is the Euclidean distance of two classes' prototypes in
//! input space: the substitution cost of the weighted Levenshtein distance (§3.7.6).

use super::{MAX_CLASSES, MAX_DIM};

/// Common interface of the three classifiers.
pub trait Classifier {
    /// Classify `x` (and learn from it). `None` when `x` is empty or longer than `MAX_DIM`.
    fn classify(&mut self, x: &[f32]) -> Option<u8>;
    /// Euclidean distance between the prototypes of classes `a` and `b` in input space
    /// (`f32::INFINITY` for a class that does not exist).
    fn prototype_distance(&self, a: u8, b: u8) -> f32;
    /// Classes in use.
    fn len(&self) -> usize;
    /// True when no class exists yet.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// True once the class capacity is exhausted (the classifier no longer grows).
    fn full(&self) -> bool {
        self.len() >= MAX_CLASSES
    }
}

fn dim_ok(x: &[f32], dim: usize) -> bool {
    !x.is_empty() && x.len() <= MAX_DIM && (dim == 0 || x.len() == dim)
}

fn euclid(a: &[f32], b: &[f32]) -> f32 {
    let s: f32 = a.iter().zip(b).map(|(p, q)| (p - q) * (p - q)).sum();
    libm::sqrtf(s)
}

/// Growing K-means (§3.4.1): nearest centre wins; a centre farther than `vigilance`
/// (Euclidean) recruits a new centre at the input; a winner moves to the running mean of its
/// members (the online form of Eq. 3-5).
#[derive(Clone, Debug)]
pub struct GrowingKMeans {
    vigilance: f32,
    dim: usize,
    used: usize,
    centre: [[f32; MAX_DIM]; MAX_CLASSES],
    members: [u32; MAX_CLASSES],
}

impl GrowingKMeans {
    /// An empty classifier; `vigilance` is the largest member-to-centre distance.
    pub fn new(vigilance: f32) -> Self {
        Self {
            vigilance,
            dim: 0,
            used: 0,
            centre: [[0.0; MAX_DIM]; MAX_CLASSES],
            members: [0; MAX_CLASSES],
        }
    }
}

impl Classifier for GrowingKMeans {
    fn classify(&mut self, x: &[f32]) -> Option<u8> {
        if !dim_ok(x, self.dim) {
            return None;
        }
        self.dim = x.len();
        let d = self.dim;
        let mut best: Option<(usize, f32)> = None;
        for j in 0..self.used {
            let e = euclid(&self.centre[j][..d], x);
            if best.is_none_or(|(_, b)| e < b) {
                best = Some((j, e));
            }
        }
        let j = match best {
            Some((j, e)) if e <= self.vigilance || self.used >= MAX_CLASSES => j,
            _ => {
                let j = self.used;
                self.used += 1;
                j
            }
        };
        self.members[j] = self.members[j].saturating_add(1);
        let n = self.members[j] as f32;
        for (c, v) in self.centre[j][..d].iter_mut().zip(x) {
            *c += (v - *c) / n;
        }
        Some(j as u8)
    }

    fn prototype_distance(&self, a: u8, b: u8) -> f32 {
        let (a, b) = (a as usize, b as usize);
        if a >= self.used || b >= self.used {
            return f32::INFINITY;
        }
        euclid(&self.centre[a][..self.dim], &self.centre[b][..self.dim])
    }

    fn len(&self) -> usize {
        self.used
    }
}

/// ART-1 (§3.4.2, Carpenter & Grossberg 1987) on binarised inputs (component >= 0.5 is 1):
/// choice |I^W|/(alpha+|W|), resonance |I^W|/|I| >= vigilance, fast learning W <- I^W.
#[derive(Clone, Debug)]
pub struct Art1 {
    vigilance: f32,
    dim: usize,
    used: usize,
    w: [u32; MAX_CLASSES],
}

/// ART's small choice constant (avoids dividing by zero; §3.4.3 quotes about 1e-7).
pub const ART_ALPHA: f32 = 1e-6;

impl Art1 {
    /// An empty network. Binary inputs fit one `u32` each, so `x.len()` <= 32 here.
    pub fn new(vigilance: f32) -> Self {
        Self {
            vigilance,
            dim: 0,
            used: 0,
            w: [0; MAX_CLASSES],
        }
    }
}

impl Classifier for Art1 {
    fn classify(&mut self, x: &[f32]) -> Option<u8> {
        if !dim_ok(x, self.dim) || x.len() > 32 {
            return None;
        }
        self.dim = x.len();
        let input = x
            .iter()
            .enumerate()
            .fold(0u32, |m, (i, &v)| if v >= 0.5 { m | (1 << i) } else { m });
        let norm_i = input.count_ones() as f32;
        let mut disabled = 0u64;
        loop {
            let mut win: Option<(usize, f32)> = None;
            for j in (0..self.used).filter(|j| disabled & (1 << j) == 0) {
                let t = (input & self.w[j]).count_ones() as f32
                    / (ART_ALPHA + self.w[j].count_ones() as f32);
                if win.is_none_or(|(_, b)| t > b) {
                    win = Some((j, t));
                }
            }
            let Some((j, _)) = win else { break };
            // An empty input matches only an empty prototype (it would erase any other).
            let resonates = if norm_i == 0.0 {
                self.w[j] == 0
            } else {
                (input & self.w[j]).count_ones() as f32 / norm_i >= self.vigilance
            };
            if resonates {
                self.w[j] &= input;
                return Some(j as u8);
            }
            disabled |= 1 << j;
        }
        if self.used < MAX_CLASSES {
            self.w[self.used] = input;
            self.used += 1;
            return Some((self.used - 1) as u8);
        }
        // Full: the class sharing most bits, without learning.
        (0..self.used)
            .max_by_key(|&j| (input & self.w[j]).count_ones())
            .map(|j| j as u8)
    }

    fn prototype_distance(&self, a: u8, b: u8) -> f32 {
        let (a, b) = (a as usize, b as usize);
        if a >= self.used || b >= self.used {
            return f32::INFINITY;
        }
        libm::sqrtf((self.w[a] ^ self.w[b]).count_ones() as f32)
    }

    fn len(&self) -> usize {
        self.used
    }
}

/// Simplified Fuzzy ART (§3.4.3, Kasuba 1993): complement coding I = (a, 1-a); choice
/// T_j = |I^W_j|/(alpha+|W_j|) (Eq. 3-8), ^ = min (Eq. 3-6); resonance |I^W_j|/d >= vigilance
/// (Eq. 3-9); learning W <- beta(I^W) + (1-beta)W (Eq. 3-10). Nodes are searched in falling
/// T order until one resonates; a new node starts at W = I (the thesis's appendix listing,
/// i.e. W = 1 followed by one fast-learning step).
#[derive(Clone, Debug)]
pub struct FuzzyArt {
    vigilance: f32,
    beta: f32,
    dim: usize,
    used: usize,
    w: [[f32; 2 * MAX_DIM]; MAX_CLASSES],
}

impl FuzzyArt {
    /// An empty network with learning rate `beta` in (0, 1] (1 = fast learning).
    pub fn new(vigilance: f32, beta: f32) -> Self {
        Self {
            vigilance,
            beta,
            dim: 0,
            used: 0,
            w: [[0.0; 2 * MAX_DIM]; MAX_CLASSES],
        }
    }

    fn code(x: &[f32], out: &mut [f32; 2 * MAX_DIM]) {
        let d = x.len();
        for (i, &v) in x.iter().enumerate() {
            let v = v.clamp(0.0, 1.0);
            out[i] = v;
            out[d + i] = 1.0 - v;
        }
    }

    /// |I ^ W_j| and |W_j|.
    fn and_norms(&self, i: &[f32], j: usize) -> (f32, f32) {
        let w = &self.w[j][..i.len()];
        let and = i.iter().zip(w).map(|(a, b)| a.min(*b)).sum();
        (and, w.iter().sum())
    }

    /// Search for a resonating node at `vigilance` among nodes not in `disabled`, in
    /// descending choice order. Returns the node and its match value.
    fn search(&self, i: &[f32], vigilance: f32, disabled: &mut u64) -> Option<(usize, f32)> {
        let d = (i.len() / 2) as f32;
        loop {
            let mut win: Option<(usize, f32, f32)> = None;
            for j in (0..self.used).filter(|j| *disabled & (1 << j) == 0) {
                let (and, wn) = self.and_norms(i, j);
                let t = and / (ART_ALPHA + wn);
                if win.is_none_or(|(_, b, _)| t > b) {
                    win = Some((j, t, and / d));
                }
            }
            let (j, _, m) = win?;
            if m >= vigilance {
                return Some((j, m));
            }
            *disabled |= 1 << j;
        }
    }

    fn learn(&mut self, i: &[f32], j: usize) {
        let b = self.beta;
        for (w, a) in self.w[j][..i.len()].iter_mut().zip(i) {
            *w = b * a.min(*w) + (1.0 - b) * *w;
        }
    }

    fn create(&mut self, i: &[f32]) -> Option<usize> {
        if self.used >= MAX_CLASSES {
            return None;
        }
        self.w[self.used][..i.len()].copy_from_slice(i);
        self.used += 1;
        Some(self.used - 1)
    }

    /// The node with the highest choice value, without learning.
    fn best(&self, i: &[f32]) -> Option<usize> {
        let mut win: Option<(usize, f32)> = None;
        for j in 0..self.used {
            let (and, wn) = self.and_norms(i, j);
            let t = and / (ART_ALPHA + wn);
            if win.is_none_or(|(_, b)| t > b) {
                win = Some((j, t));
            }
        }
        win.map(|(j, _)| j)
    }
}

impl Classifier for FuzzyArt {
    fn classify(&mut self, x: &[f32]) -> Option<u8> {
        if !dim_ok(x, self.dim) {
            return None;
        }
        self.dim = x.len();
        let mut buf = [0.0; 2 * MAX_DIM];
        Self::code(x, &mut buf);
        let i = &buf[..2 * x.len()];
        let mut disabled = 0u64;
        let j = match self.search(i, self.vigilance, &mut disabled) {
            Some((j, _)) => {
                self.learn(i, j);
                j
            }
            None => match self.create(i) {
                Some(j) => j,
                None => self.best(i)?,
            },
        };
        Some(j as u8)
    }

    /// Distance between the centres of the two categories' boxes: W = (u, 1 - v) stands for
    /// the box [u, v], centre (u + v) / 2.
    fn prototype_distance(&self, a: u8, b: u8) -> f32 {
        let (a, b) = (a as usize, b as usize);
        if a >= self.used || b >= self.used {
            return f32::INFINITY;
        }
        let d = self.dim;
        let centre = |w: &[f32; 2 * MAX_DIM], k: usize| (w[k] + 1.0 - w[d + k]) / 2.0;
        let s: f32 = (0..d)
            .map(|k| {
                let e = centre(&self.w[a], k) - centre(&self.w[b], k);
                e * e
            })
            .sum();
        libm::sqrtf(s)
    }

    fn len(&self) -> usize {
        self.used
    }
}

/// Simplified Fuzzy ARTMAP, the supervised form of [`FuzzyArt`] in the thesis's appendix 5.4
/// (Kasuba 1993): each node carries a category; a resonating node of the wrong category raises
/// the vigilance to its match + epsilon ("match tracking") and the search goes on. Kept for
/// the thesis's demonstration; the robot uses the unsupervised [`FuzzyArt`].
#[derive(Clone, Debug)]
pub struct FuzzyArtmap {
    art: FuzzyArt,
    category: [u8; MAX_CLASSES],
    epsilon: f32,
}

impl FuzzyArtmap {
    /// Fast learning (beta = 1) as in the listing; `epsilon` is its 0.0001.
    pub fn new(vigilance: f32, epsilon: f32) -> Self {
        Self {
            art: FuzzyArt::new(vigilance, 1.0),
            category: [0; MAX_CLASSES],
            epsilon,
        }
    }

    /// Learn that `x` belongs to `category`. False if `x` is malformed or the net is full.
    pub fn train(&mut self, x: &[f32], category: u8) -> bool {
        if !dim_ok(x, self.art.dim) {
            return false;
        }
        self.art.dim = x.len();
        let mut buf = [0.0; 2 * MAX_DIM];
        FuzzyArt::code(x, &mut buf);
        let i = &buf[..2 * x.len()];
        let mut vigilance = self.art.vigilance;
        let mut disabled = 0u64;
        while let Some((j, m)) = self.art.search(i, vigilance, &mut disabled) {
            if self.category[j] == category {
                self.art.learn(i, j);
                return true;
            }
            vigilance = m + self.epsilon;
            disabled |= 1 << j;
        }
        match self.art.create(i) {
            Some(j) => {
                self.category[j] = category;
                true
            }
            None => false,
        }
    }

    /// The category of the node with the highest choice value.
    pub fn predict(&self, x: &[f32]) -> Option<u8> {
        if !dim_ok(x, self.art.dim) {
            return None;
        }
        let mut buf = [0.0; 2 * MAX_DIM];
        FuzzyArt::code(x, &mut buf);
        self.art.best(&buf[..2 * x.len()]).map(|j| self.category[j])
    }

    /// Nodes in use.
    pub fn nodes(&self) -> usize {
        self.art.used
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The thesis's demonstration (appendix 5.4): vigilance 0.4; (0.3,0.3), (0.7,0.7) are
    /// "inside" (0), (0.1,0.1), (0.9,0.9), (0.1,0.8) "outside" (1). After one pass every
    /// training point is recalled with its category.
    #[test]
    fn thesis_fuzzy_artmap_demo() {
        let samples: [([f32; 2], u8); 5] = [
            ([0.3, 0.3], 0),
            ([0.7, 0.7], 0),
            ([0.1, 0.1], 1),
            ([0.9, 0.9], 1),
            ([0.1, 0.8], 1),
        ];
        let mut net = FuzzyArtmap::new(0.4, 0.0001);
        for (x, c) in samples {
            assert!(net.train(&x, c));
        }
        for (x, c) in samples {
            assert_eq!(net.predict(&x), Some(c), "{x:?}");
        }
        // (0.9,0.9) resonates with the inside node at 0.4 and needs match tracking: 3 nodes.
        assert_eq!(net.nodes(), 3);
    }

    #[test]
    fn fuzzy_art_groups_by_vigilance() {
        // Unsupervised at the same vigilance, (0.1,0.1) still resonates with the inside node
        // (match exactly 0.4): that is why the demo needs the supervised form.
        let mut art = FuzzyArt::new(0.4, 1.0);
        assert_eq!(art.classify(&[0.3, 0.3]), Some(0));
        assert_eq!(art.classify(&[0.7, 0.7]), Some(0));
        assert_eq!(art.classify(&[0.1, 0.1]), Some(0));
        // A high vigilance separates them.
        let mut art = FuzzyArt::new(0.9, 1.0);
        assert_eq!(art.classify(&[0.3, 0.3]), Some(0));
        assert_eq!(art.classify(&[0.7, 0.7]), Some(1));
        assert_eq!(art.classify(&[0.31, 0.3]), Some(0));
        assert!(art.prototype_distance(0, 1) > 0.5);
    }

    #[test]
    fn kmeans_grows_only_past_vigilance() {
        let mut k = GrowingKMeans::new(0.2);
        assert_eq!(k.classify(&[0.0, 0.0]), Some(0));
        assert_eq!(k.classify(&[0.1, 0.0]), Some(0));
        assert_eq!(k.classify(&[1.0, 1.0]), Some(1));
        assert_eq!(k.len(), 2);
        // The centre moved to the mean of its two members.
        assert!((k.prototype_distance(0, 1) - libm::sqrtf(0.95 * 0.95 + 1.0)).abs() < 1e-5);
        assert_eq!(k.classify(&[0.0; 3]), None, "dimension changed");
    }

    #[test]
    fn art1_binary_resonance() {
        let mut a = Art1::new(0.6);
        assert_eq!(a.classify(&[1.0, 1.0, 0.0, 0.0]), Some(0));
        // |I^W|/|I| = 2/3 >= 0.6: resonance.
        assert_eq!(a.classify(&[1.0, 1.0, 1.0, 0.0]), Some(0));
        assert_eq!(a.classify(&[0.0, 0.0, 1.0, 1.0]), Some(1));
        assert_eq!(
            a.classify(&[0.0; 4]),
            Some(2),
            "empty input gets its own class"
        );
        assert_eq!(a.classify(&[0.0; 4]), Some(2));
    }

    #[test]
    fn full_classifiers_stop_growing() {
        let mut k = GrowingKMeans::new(0.0);
        let mut f = FuzzyArt::new(1.0, 1.0);
        for n in 0..(MAX_CLASSES + 10) {
            let x = [n as f32 / 200.0];
            assert!(k.classify(&x).is_some());
            assert!(f.classify(&x).is_some());
        }
        assert!(k.full() && f.full());
    }
}
