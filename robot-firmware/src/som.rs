//! Adaptive sensor calibration with a 1-D Kohonen variant (seed 000 §5.1).
//!
//! Layer: pure learning and lookup under the behaviours; it turns a vector of raw sensor
//! values into one symbolic number (angle to a light, distance to a landmark). A chain of `N`
//! neurons, each `V_i = (w_i, phi_i)`: `M` sensor weights and an output value (Eq 17).
//! Training on examples `(s_1..s_M, o)` (Eq 16) finds the best match over all `M + 1`
//! components with the L1 norm (Eq 18) and moves every neuron towards the example,
//! `V_i += lambda(t, |i - bm|) (V_ex - V_i)` (Eq 19 as corrected in the digest: the printed
//! `+ lambda V_bm` is a typo), with a triangular neighbourhood whose width and rate decay
//! linearly over the training ([`Schedule`]). Recall finds the best match on the `M` sensor
//! components only and returns its `phi` (Eqs 20-21).
//!
//! Invariants: fixed size `N * (M + 1)` numbers (f32, or [`Centi`]: hundredths in a u16, half
//! the memory, for the robot), no heap, no clock; randomness (initial weights,
//! presentation order) from a caller-seeded [`XorShift32`]. What can fail: a network with no
//! neurons has no best match (`None`); empty example sets train nothing. Non-finite inputs give
//! an arbitrary (but in-range) best match, never a panic. Units are the caller's: the L1 norm
//! adds the output component to the sensor components as they are, so the output's scale sets
//! how much it steers training (seed 000 trains on raw degrees and sensor counts).

use protocol::object::{encode_light, LightView, ObjectError, LIGHT_INPUTS, LIGHT_NEURONS};

use crate::behaviour::XorShift32;

/// One training example: `M` sensor values and the output they should map to (Eq 16).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Example<const M: usize> {
    /// Sensor values, e.g. rescaled light readings.
    pub inputs: [f32; M],
    /// Wanted output, e.g. the angle to the light in degrees.
    pub output: f32,
}

/// How width and rate decay over the training epochs (linearly, seed 000 §5.1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Schedule {
    /// Passes over the example set ("cycles" in the paper).
    pub epochs: u32,
    /// Neighbourhood half-width at the first epoch, neurons.
    pub width_start: f32,
    /// Neighbourhood half-width at the last epoch, neurons.
    pub width_end: f32,
    /// Learning rate at the first epoch.
    pub rate_start: f32,
    /// Learning rate at the last epoch.
    pub rate_end: f32,
}

impl Schedule {
    /// seed 000 §5.3, light sensors: 20 cycles, width 10 -> 1, rate 0.6 -> 0.1.
    pub const LIGHT: Schedule = Schedule {
        epochs: 20,
        width_start: 10.0,
        width_end: 1.0,
        rate_start: 0.6,
        rate_end: 0.1,
    };

    /// seed 000 §5.5, linear camera: 3 cycles, width 10 -> 1, rate 0.8 -> 0.1.
    pub const CAMERA: Schedule = Schedule {
        epochs: 3,
        width_start: 10.0,
        width_end: 1.0,
        rate_start: 0.8,
        rate_end: 0.1,
    };

    /// (width, rate) during `epoch` (0-based): linear from start to end over the epochs.
    pub fn at(&self, epoch: u32) -> (f32, f32) {
        let t = if self.epochs > 1 {
            (epoch.min(self.epochs - 1)) as f32 / (self.epochs - 1) as f32
        } else {
            0.0
        };
        // (1 - t) a + t b: exact at both ends.
        (
            (1.0 - t) * self.width_start + t * self.width_end,
            (1.0 - t) * self.rate_start + t * self.rate_end,
        )
    }
}

/// Triangular neighbourhood: `rate * (1 - d / width)` for `d < width`, else 0; a width below
/// 1 is taken as 1 (only the best match learns).
pub fn neighbourhood(rate: f32, width: f32, distance: usize) -> f32 {
    let w = width.max(1.0);
    let d = distance as f32;
    if d >= w {
        0.0
    } else {
        rate * (1.0 - d / w)
    }
}

/// Rescales `values` linearly so the smallest becomes `lo` and the largest `hi` (seed 000
/// §5.3: min -> 50, max -> 500, preferred there to normalisation because of the sensors'
/// uneven layout). All-equal values map to the middle.
pub fn rescale<const M: usize>(values: [f32; M], lo: f32, hi: f32) -> [f32; M] {
    let min = values.iter().copied().fold(f32::INFINITY, f32::min);
    let max = values.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    let span = max - min;
    values.map(|v| {
        if span > 0.0 {
            lo + (v - min) / span * (hi - lo)
        } else {
            (lo + hi) / 2.0
        }
    })
}

/// How a neuron's numbers are stored. Arithmetic is always f32; storage may be narrower.
pub trait Store: Copy + Default + PartialEq + core::fmt::Debug {
    /// The stored value.
    fn get(self) -> f32;
    /// Stores `v` (rounded and clamped to what the type holds; NaN stores as the smallest).
    fn put(v: f32) -> Self;
}

impl Store for f32 {
    fn get(self) -> f32 {
        self
    }
    fn put(v: f32) -> Self {
        v
    }
}

/// Hundredths in a u16: 0.00 ..= 655.35. Holds §5.3's rescaled readings (50..500) and angles
/// (0..180 deg) at half the memory of f32; a training step smaller than 0.005 is lost, which
/// stops a neuron within 0.05 of its target at the final rate 0.1.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Centi(pub u16);

impl Store for Centi {
    fn get(self) -> f32 {
        f32::from(self.0) / 100.0
    }
    fn put(v: f32) -> Self {
        // `as` saturates and maps NaN to 0.
        Centi(libm::roundf(v * 100.0) as u16)
    }
}

/// A 1-D chain of `N` neurons over `M` sensor inputs and one output, stored as `W`.
#[derive(Clone, Debug, PartialEq)]
pub struct Som<const N: usize, const M: usize, W: Store = f32> {
    weights: [[W; M]; N],
    outputs: [W; N],
}

/// The light-angle network of seed 000 §5.3: 60 neurons, 6 front sensors, in hundredths
/// (840 bytes: the robot's RAM is tight, §1.1 aside).
pub type LightSom = Som<60, 6, Centi>;

// The network's wire form, one place for the robot (upload, download) and the station (files).
impl LightSom {
    /// Encodes the network as a LightCalibration object (PROTOCOL.md §12) into `out`.
    pub fn encode_object(&self, out: &mut [u8]) -> Result<usize, ObjectError> {
        let neurons = (0..LIGHT_NEURONS).map(|i| {
            self.stored(i)
                .map_or(([0; LIGHT_INPUTS], 0), |(w, o)| (w.map(|c| c.0), o.0))
        });
        encode_light(neurons, out)
    }

    /// Replaces every neuron with a parsed object's, in place (no second network on the
    /// stack: the robot's RAM is tight).
    pub fn load_object(&mut self, view: &LightView<'_>) {
        for (i, (w, o)) in view.neurons().enumerate() {
            self.set_stored(i, w.map(Centi), Centi(o));
        }
    }
}

impl<const N: usize, const M: usize, W: Store> Som<N, M, W> {
    /// A network with the given neurons (e.g. restored from flash or a file).
    pub fn from_neurons(weights: [[f32; M]; N], outputs: [f32; N]) -> Self {
        Self {
            weights: weights.map(|w| w.map(W::put)),
            outputs: outputs.map(W::put),
        }
    }

    /// "k randomly initialised neurons" (§5.1): weights uniform in `inputs`, outputs uniform
    /// in `output`, each a `(low, high)` range.
    pub fn random(rng: &mut XorShift32, inputs: (f32, f32), output: (f32, f32)) -> Self {
        let mut u = |(lo, hi): (f32, f32)| {
            let f = (rng.next_u32() >> 8) as f32 / 16_777_216.0;
            lo + f * (hi - lo)
        };
        let mut weights = [[W::default(); M]; N];
        let mut outputs = [W::default(); N];
        for (w, o) in weights.iter_mut().zip(outputs.iter_mut()) {
            for v in w.iter_mut() {
                *v = W::put(u(inputs));
            }
            *o = W::put(u(output));
        }
        Self { weights, outputs }
    }

    /// Neuron `i` as stored (for a network's object, PROTOCOL.md §12).
    pub fn stored(&self, i: usize) -> Option<([W; M], W)> {
        Some((*self.weights.get(i)?, *self.outputs.get(i)?))
    }

    /// Replaces neuron `i` as stored; false if there is no neuron `i`.
    pub fn set_stored(&mut self, i: usize, weights: [W; M], output: W) -> bool {
        match (self.weights.get_mut(i), self.outputs.get_mut(i)) {
            (Some(w), Some(o)) => {
                (*w, *o) = (weights, output);
                true
            }
            _ => false,
        }
    }

    /// Neuron `i`'s sensor weights and output value.
    pub fn neuron(&self, i: usize) -> Option<([f32; M], f32)> {
        let w = self.weights.get(i)?;
        Some((w.map(W::get), self.outputs.get(i)?.get()))
    }

    /// Eq 18: the neuron nearest to the whole example (L1 over sensors and output).
    pub fn best_match_training(&self, ex: &Example<M>) -> Option<usize> {
        self.argmin(|i| {
            l1(&self.weights[i], &ex.inputs) + (self.outputs[i].get() - ex.output).abs()
        })
    }

    /// Eq 21: the neuron nearest to the sensor values alone (L1).
    pub fn best_match(&self, inputs: &[f32; M]) -> Option<usize> {
        self.argmin(|i| l1(&self.weights[i], inputs))
    }

    /// Eqs 20-21: the output of the best match on the sensor values.
    pub fn recall(&self, inputs: &[f32; M]) -> Option<f32> {
        self.best_match(inputs)
            .and_then(|i| self.outputs.get(i).map(|o| o.get()))
    }

    /// One training step (Eqs 18-19 with the digest's fix): every neuron moves towards the
    /// example by the neighbourhood factor of its chain distance to the best match. Returns
    /// the best match.
    pub fn train_step(&mut self, ex: &Example<M>, rate: f32, width: f32) -> Option<usize> {
        let bm = self.best_match_training(ex)?;
        for (i, (w, o)) in self
            .weights
            .iter_mut()
            .zip(self.outputs.iter_mut())
            .enumerate()
        {
            let l = neighbourhood(rate, width, i.abs_diff(bm));
            if l == 0.0 {
                continue;
            }
            for (wj, sj) in w.iter_mut().zip(ex.inputs.iter()) {
                let v = wj.get();
                *wj = W::put(v + l * (sj - v));
            }
            let v = o.get();
            *o = W::put(v + l * (ex.output - v));
        }
        Some(bm)
    }

    /// Trains on `examples` for `schedule.epochs` passes. Each pass presents every example
    /// once in a pseudo-random order (a random start and a random stride coprime to the
    /// count: a permutation without storage), so an ordered recording (a rotation) does not
    /// drag the chain one way.
    pub fn train(&mut self, examples: &[Example<M>], schedule: &Schedule, rng: &mut XorShift32) {
        let n = examples.len();
        if n == 0 {
            return;
        }
        for epoch in 0..schedule.epochs {
            let (width, rate) = schedule.at(epoch);
            let (start, stride) = permutation(n, rng);
            for k in 0..n {
                let idx = (start + k * stride) % n;
                if let Some(ex) = examples.get(idx) {
                    self.train_step(ex, rate, width);
                }
            }
        }
    }

    fn argmin(&self, cost: impl Fn(usize) -> f32) -> Option<usize> {
        let mut best: Option<(usize, f32)> = None;
        for i in 0..N {
            let c = cost(i);
            match best {
                // Keep the best unless the candidate is smaller; a NaN best is always replaced
                // and a NaN candidate never replaces.
                Some((_, b)) if !b.is_nan() && (c >= b || c.is_nan()) => {}
                _ => best = Some((i, c)),
            }
        }
        best.map(|(i, _)| i)
    }
}

/// Online training (seed 000 §5.3 on the robot itself): examples arrive one at a time, in
/// the order the robot meets them, and are not kept. Presented in that order, a rotation would
/// drag the chain along with it while the neighbourhood is wide; a small reservoir of `B`
/// recent examples, from which a random one is trained as each new one arrives, breaks the
/// order at the cost of `B` examples of memory. The schedule advances by epoch (one turn of
/// the robot), so the paper's width and rate decay is kept.
/// Held examples are stored as `W`, like the network.
#[derive(Clone, Debug, PartialEq)]
pub struct OnlineTrainer<const M: usize, const B: usize, W: Store = f32> {
    /// Width and rate decay over the epochs.
    pub schedule: &'static Schedule,
    epoch: u16,
    held_inputs: [[W; M]; B],
    held_outputs: [W; B],
    len: u8,
    trained: u32,
}

impl<const M: usize, const B: usize, W: Store> OnlineTrainer<M, B, W> {
    /// A trainer at epoch 0 with an empty reservoir. `B` is at most 255.
    pub fn new(schedule: &'static Schedule) -> Self {
        Self {
            schedule,
            epoch: 0,
            held_inputs: [[W::default(); M]; B],
            held_outputs: [W::default(); B],
            len: 0,
            trained: 0,
        }
    }

    fn held(&self, k: usize) -> Option<Example<M>> {
        Some(Example {
            inputs: self.held_inputs.get(k)?.map(W::get),
            output: self.held_outputs.get(k)?.get(),
        })
    }

    fn hold(&mut self, k: usize, ex: &Example<M>) {
        if let (Some(i), Some(o)) = (self.held_inputs.get_mut(k), self.held_outputs.get_mut(k)) {
            *i = ex.inputs.map(W::put);
            *o = W::put(ex.output);
        }
    }

    /// The epoch examples are trained in now.
    pub fn epoch(&self) -> u32 {
        u32::from(self.epoch)
    }

    /// Training steps taken so far.
    pub fn trained(&self) -> u32 {
        self.trained
    }

    /// Whether every epoch of the schedule has passed.
    pub fn finished(&self) -> bool {
        self.epoch() >= self.schedule.epochs
    }

    /// Takes `ex`; trains `som` on a random held one (or on `ex` itself when `B` is 0).
    /// Does nothing once the schedule is finished.
    pub fn offer<const N: usize>(
        &mut self,
        som: &mut Som<N, M, W>,
        ex: Example<M>,
        rng: &mut XorShift32,
    ) {
        if self.finished() {
            return;
        }
        let (width, rate) = self.schedule.at(self.epoch());
        let len = usize::from(self.len);
        let chosen = if len < B {
            self.hold(len, &ex);
            self.len = self.len.saturating_add(1);
            return;
        } else if B == 0 {
            ex
        } else {
            let k = rng.next_u32() as usize % B;
            let old = self.held(k).unwrap_or(ex);
            self.hold(k, &ex);
            old
        };
        if som.train_step(&chosen, rate, width).is_some() {
            self.trained = self.trained.saturating_add(1);
        }
    }

    /// Ends the epoch; after the last one the held examples are trained at the final rate
    /// and width, so none is lost.
    pub fn next_epoch<const N: usize>(&mut self, som: &mut Som<N, M, W>) {
        if self.finished() {
            return;
        }
        self.epoch = self.epoch.saturating_add(1);
        if self.finished() {
            let last = self.schedule.epochs.saturating_sub(1);
            let (width, rate) = self.schedule.at(last);
            for k in 0..usize::from(self.len) {
                if let Some(ex) = self.held(k) {
                    if som.train_step(&ex, rate, width).is_some() {
                        self.trained = self.trained.saturating_add(1);
                    }
                }
            }
            self.len = 0;
        }
    }
}

fn l1<const M: usize, W: Store>(a: &[W; M], b: &[f32; M]) -> f32 {
    a.iter()
        .zip(b.iter())
        .map(|(x, y)| (x.get() - y).abs())
        .sum()
}

/// A random start and a stride coprime to `n` (so `start + k stride mod n` visits all).
fn permutation(n: usize, rng: &mut XorShift32) -> (usize, usize) {
    let start = rng.next_u32() as usize % n;
    let mut stride = 1 + rng.next_u32() as usize % n;
    while gcd(stride, n) != 1 {
        stride = stride % n + 1;
    }
    (start, stride)
}

fn gcd(mut a: usize, mut b: usize) -> usize {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn training_moves_every_neuron_towards_the_example_by_its_neighbourhood() {
        // Five neurons, one input: best match is neuron 2 (L1 over input AND output).
        let mut som = Som::<5, 1>::from_neurons(
            [[0.0], [10.0], [20.0], [30.0], [40.0]],
            [0.0, 1.0, 2.0, 3.0, 4.0],
        );
        let ex = Example {
            inputs: [22.0],
            output: 6.0,
        };
        assert_eq!(som.best_match_training(&ex), Some(2));
        // rate 0.5, width 2: lambda = 0.5 at d = 0, 0.25 at d = 1, 0 at d >= 2.
        assert_eq!(som.train_step(&ex, 0.5, 2.0), Some(2));
        let got: [(f32, f32); 5] = core::array::from_fn(|i| {
            let (w, o) = som.neuron(i).unwrap();
            (w[0], o)
        });
        assert_eq!(
            got,
            [
                (0.0, 0.0),
                (13.0, 2.25),
                (21.0, 4.0),
                (28.0, 3.75),
                (40.0, 4.0)
            ]
        );
    }

    #[test]
    fn the_printed_eq_19_would_not_converge_and_the_fixed_one_does() {
        // Printed: V_i += lambda V_bm grows without bound; fixed: V_i -> V_ex.
        let mut som = Som::<1, 1>::from_neurons([[1.0]], [1.0]);
        let ex = Example {
            inputs: [5.0],
            output: 3.0,
        };
        for _ in 0..50 {
            som.train_step(&ex, 0.5, 1.0);
        }
        let (w, o) = som.neuron(0).unwrap();
        assert!((w[0] - 5.0).abs() < 1e-4 && (o - 3.0).abs() < 1e-4);
    }

    #[test]
    fn best_match_in_training_uses_the_output_and_in_recall_ignores_it() {
        let som = Som::<2, 1>::from_neurons([[10.0], [12.0]], [100.0, 0.0]);
        let ex = Example {
            inputs: [10.0],
            output: 0.0,
        };
        // Training: |10-10| + |100-0| = 100 vs |12-10| + 0 = 2.
        assert_eq!(som.best_match_training(&ex), Some(1));
        // Recall: sensors only.
        assert_eq!(som.best_match(&[10.0]), Some(0));
        assert_eq!(som.recall(&[10.0]), Some(100.0));
    }

    #[test]
    fn the_triangular_neighbourhood_shrinks_with_width() {
        assert_eq!(neighbourhood(0.6, 10.0, 0), 0.6);
        assert!((neighbourhood(0.6, 10.0, 5) - 0.3).abs() < 1e-6);
        assert_eq!(neighbourhood(0.6, 10.0, 10), 0.0);
        // Width 1 (the end of training): only the best match.
        assert_eq!(neighbourhood(0.1, 1.0, 0), 0.1);
        assert_eq!(neighbourhood(0.1, 1.0, 1), 0.0);
        assert_eq!(neighbourhood(0.1, 0.0, 0), 0.1);
    }

    #[test]
    fn schedules_decay_linearly_from_start_to_end() {
        let s = Schedule::LIGHT;
        assert_eq!(s.at(0), (10.0, 0.6));
        assert_eq!(s.at(19), (1.0, 0.1));
        let (w, r) = s.at(10);
        assert!(
            (w - (10.0 - 9.0 * 10.0 / 19.0)).abs() < 1e-5
                && (r - (0.6 - 0.5 * 10.0 / 19.0)).abs() < 1e-6
        );
        assert_eq!(Schedule { epochs: 1, ..s }.at(0), (10.0, 0.6));
    }

    #[test]
    fn rescale_maps_min_to_50_and_max_to_500() {
        assert_eq!(
            rescale([300.0, 100.0, 200.0], 50.0, 500.0),
            [500.0, 50.0, 275.0]
        );
        assert_eq!(rescale([7.0, 7.0], 50.0, 500.0), [275.0, 275.0]);
    }

    #[test]
    fn permutations_visit_every_example_once() {
        let mut rng = XorShift32::new(3);
        for n in [1usize, 2, 12, 181, 360] {
            let (start, stride) = permutation(n, &mut rng);
            let mut seen = [false; 360];
            for k in 0..n {
                seen[(start + k * stride) % n] = true;
            }
            assert!(seen[..n].iter().all(|&s| s), "n = {n}");
        }
    }

    #[test]
    fn a_chain_learns_a_1d_map_and_recalls_it() {
        // Learn y = 2x on x in 0..100 with 20 neurons.
        let mut rng = XorShift32::new(9);
        let mut som = Som::<20, 1>::random(&mut rng, (0.0, 100.0), (0.0, 200.0));
        let ex: [Example<1>; 101] = core::array::from_fn(|i| Example {
            inputs: [i as f32],
            output: 2.0 * i as f32,
        });
        som.train(&ex, &Schedule::LIGHT, &mut rng);
        for x in [3.0f32, 37.0, 50.0, 96.0] {
            let y = som.recall(&[x]).unwrap();
            assert!((y - 2.0 * x).abs() < 12.0, "{x} -> {y}");
        }
    }

    #[test]
    fn the_online_trainer_learns_an_ordered_stream_and_follows_the_schedule() {
        // y = 2x presented in order, forwards then backwards, 20 epochs: the reservoir keeps
        // the ordered stream from dragging the chain.
        let mut rng = XorShift32::new(5);
        let mut som = Som::<20, 1>::random(&mut rng, (0.0, 100.0), (0.0, 200.0));
        let mut t = OnlineTrainer::<1, 8>::new(&Schedule::LIGHT);
        for epoch in 0..20u32 {
            assert_eq!(t.epoch(), epoch);
            for k in 0..=100u32 {
                let x = if epoch % 2 == 0 { k } else { 100 - k } as f32;
                let ex = Example {
                    inputs: [x],
                    output: 2.0 * x,
                };
                t.offer(&mut som, ex, &mut rng);
            }
            t.next_epoch(&mut som);
        }
        assert!(t.finished());
        // Every example trained once: the first 8 went into the reservoir and were flushed.
        assert_eq!(t.trained(), 20 * 101);
        for x in [3.0f32, 37.0, 50.0, 96.0] {
            let y = som.recall(&[x]).unwrap();
            assert!((y - 2.0 * x).abs() < 12.0, "{x} -> {y}");
        }
        // A finished trainer changes nothing.
        let before = som.clone();
        let ex = Example {
            inputs: [0.0],
            output: 500.0,
        };
        t.offer(&mut som, ex, &mut rng);
        assert_eq!(som, before);
    }

    #[test]
    fn an_empty_network_has_no_best_match_and_nan_does_not_panic() {
        let som = Som::<0, 2>::from_neurons([], []);
        assert_eq!(som.recall(&[1.0, 2.0]), None);
        let som = Som::<2, 1>::from_neurons([[1.0], [2.0]], [5.0, 6.0]);
        assert!(som.recall(&[f32::NAN]).is_some());
    }
}
