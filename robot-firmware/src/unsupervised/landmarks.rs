//! Significant classes become landmarks; a landmark met again resets the odometry (§3.2.3,
//! §3.6, §3.7.7-3.7.8, §3.15.1-2).
//!
//! Every control step the caller hands in one label per class stream and its odometric
//! position. [`LandmarkStore::step`]:
//! 1. keeps per-class statistics and, when a class's run starts, asks whether it is
//!    *significant*: seen at least `min_activations` times before (not noise), at most
//!    `max_share` of its stream's activations (not everywhere), runs of mean length at most
//!    `max_mean_run` samples (a point, not a region). The thesis found its limits
//!    "empirically" and does not print them: they are [`LandmarkParams`];
//! 2. a significant class becomes the kernel of a pending landmark; `CONTEXT` steps later the
//!    `WINDOW` labels of every stream around it are known (15 before, 15 after) and it is
//!    compared with the stored landmarks that have the same kernel: d_lev is the largest over
//!    the streams of the weighted Levenshtein distance (substitution = prototype distance,
//!    insertion/deletion = `indel_cost`) divided by `WINDOW * indel_cost` (the share of the
//!    window that differs; §3.7.7: a landmark is the same only if every stream is similar),
//!    then by `lev_scale`; d_dist is the distance of the kernel-time position to the stored one in
//!    robot diameters. Candidates farther than one diameter are ignored (§3.15.2); the best
//!    candidate with D = sqrt(d_lev^2 + d_dist^2) < `match_threshold` is a match and the caller
//!    moves its position towards the stored one: all the way (stored - kernel-time position,
//!    the thesis's reset) or by the gain that the landmark's stored variance and its own give
//!    ([`super::fusion`]). No match: a new landmark, stored with the caller's variance.
//!
//! Fixed capacity `MAX_LANDMARKS`; a full store still matches but creates nothing more.

use super::levenshtein::{weighted, EditCosts};
use super::{CONTEXT, MAX_CLASSES, MAX_LANDMARKS, STREAMS, WINDOW};

/// Where the substitution costs come from: the classifiers' prototype distances.
pub trait PrototypeMetric {
    /// Distance of classes `a` and `b` of stream `stream` in input space.
    fn distance(&self, stream: usize, a: u8, b: u8) -> f32;
}

/// Tunable limits the thesis leaves open (all are choices, named in docs/reproductions.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LandmarkParams {
    /// A class must have started this many runs before it can be a kernel.
    pub min_activations: u16,
    /// Largest share of its stream's runs a significant class may have.
    pub max_share: f32,
    /// Largest mean run length (samples) of a significant class.
    pub max_mean_run: f32,
    /// Steps the classifiers settle before any landmark is made (exploration phase, §3.14.2).
    pub warmup_steps: u32,
    /// Fewest steps between two kernels (near-simultaneous kernels make one landmark, §3.15.1).
    pub min_kernel_gap: u32,
    /// Insertion/deletion cost of the Levenshtein distance.
    pub indel_cost: f32,
    /// Share of a stream's window (its distance / (`WINDOW` x `indel_cost`)) that counts as
    /// much as one diameter of position difference.
    pub lev_scale: f32,
    /// D must be below this to match.
    pub match_threshold: f32,
    /// Robot diameter, metres (unit of d_dist; candidates beyond one are ignored).
    pub diameter_m: f32,
}

impl Default for LandmarkParams {
    fn default() -> Self {
        Self {
            min_activations: 3,
            max_share: 0.05,
            max_mean_run: 4.0,
            warmup_steps: 600,
            min_kernel_gap: 5,
            indel_cost: 1.0,
            lev_scale: 0.5,
            match_threshold: 1.0,
            diameter_m: 0.055,
        }
    }
}

/// One stored landmark: the kernel, its context in every stream, and the position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Landmark {
    /// Stream of the significant class.
    pub stream: u8,
    /// The significant class.
    pub class: u8,
    /// `WINDOW` labels of each stream centred on the kernel.
    pub labels: [[u8; WINDOW]; STREAMS],
    /// Odometric position when it was made, metres.
    pub x: f32,
    /// See `x`.
    pub y: f32,
    /// Odometric heading when it was made, radians (§3.6: a landmark holds "the estimated
    /// robot position, time, direction"; a match resets the pose, heading included).
    pub heading: f32,
    /// Variance (per axis, metres squared) of the position when it was made: the robot's
    /// own estimate of how far off it was then ([`super::fusion`]). A landmark keeps the
    /// position it was made with (the thesis; learning from later matches measured no
    /// better, docs/reproductions.md).
    pub var: f32,
    /// Times it was matched.
    pub matches: u16,
}

/// What one step did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Event {
    /// A new landmark was stored at this index.
    Created(u16),
    /// Landmark `index` matched: move the position by (dx, dy) metres and turn the heading
    /// by `dheading` (the stored pose minus the pose at the kernel).
    Matched {
        /// The landmark.
        index: u16,
        /// Correction, metres.
        dx: f32,
        /// Correction, metres.
        dy: f32,
        /// Heading correction, radians, in (-pi, pi].
        dheading: f32,
        /// Its D.
        d: f32,
        /// The landmark's position variance (per axis, m^2) before this match.
        var: f32,
    },
    /// No match and the store is full.
    Full,
}

/// Why resolved kernels did not match (for reports and tuning views).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MatchStats {
    /// Kernels resolved.
    pub kernels: u32,
    /// ... with no stored landmark of the same kernel.
    pub unknown_kernel: u32,
    /// ... whose same-kernel landmarks were all more than one diameter away (ignored).
    pub too_far: u32,
    /// ... with near candidates, none below the threshold.
    pub dissimilar: u32,
    /// Sum of the best near candidate's scaled d_lev (mean = sum / near).
    pub lev_sum: f32,
    /// Kernels that had a near candidate.
    pub near: u32,
}

#[derive(Clone, Copy, Debug, Default)]
struct Pending {
    stream: u8,
    class: u8,
    due: u32,
    x: f32,
    y: f32,
    heading: f32,
    var: f32,
}

const PENDING: usize = 4;

#[derive(Clone, Copy, Debug, Default)]
struct ClassStats {
    runs: u16,
    samples: u32,
}

/// The landmark memory and the statistics that choose kernels.
#[derive(Clone, Debug)]
pub struct LandmarkStore {
    params: LandmarkParams,
    step: u32,
    history: [[u8; STREAMS]; WINDOW],
    last: [Option<u8>; STREAMS],
    stats: [[ClassStats; MAX_CLASSES]; STREAMS],
    stream_runs: [u32; STREAMS],
    pending: [Option<Pending>; PENDING],
    last_kernel: Option<u32>,
    landmarks: [Landmark; MAX_LANDMARKS],
    used: usize,
    stats_m: MatchStats,
}

struct StreamCosts<'a, M: PrototypeMetric> {
    metric: &'a M,
    stream: usize,
    indel: f32,
}

impl<M: PrototypeMetric> EditCosts<u8> for StreamCosts<'_, M> {
    fn delete(&self, _: &u8) -> f32 {
        self.indel
    }
    fn insert(&self, _: &u8) -> f32 {
        self.indel
    }
    fn replace(&self, a: &u8, b: &u8) -> f32 {
        if a == b {
            0.0
        } else {
            // Never dearer than delete + insert; unknown classes cost that much.
            self.metric
                .distance(self.stream, *a, *b)
                .min(2.0 * self.indel)
        }
    }
}

impl LandmarkStore {
    /// An empty store.
    pub fn new(params: LandmarkParams) -> Self {
        let empty = Landmark {
            stream: 0,
            class: 0,
            labels: [[0; WINDOW]; STREAMS],
            x: 0.0,
            y: 0.0,
            heading: 0.0,
            var: 0.0,
            matches: 0,
        };
        Self {
            params,
            step: 0,
            history: [[0; STREAMS]; WINDOW],
            last: [None; STREAMS],
            stats: [[ClassStats::default(); MAX_CLASSES]; STREAMS],
            stream_runs: [0; STREAMS],
            pending: [None; PENDING],
            last_kernel: None,
            landmarks: [empty; MAX_LANDMARKS],
            used: 0,
            stats_m: MatchStats::default(),
        }
    }

    /// The stored landmarks.
    pub fn landmarks(&self) -> &[Landmark] {
        &self.landmarks[..self.used]
    }

    /// Why kernels matched or not.
    pub fn match_stats(&self) -> MatchStats {
        self.stats_m
    }

    /// The parameters in use.
    pub fn params(&self) -> &LandmarkParams {
        &self.params
    }

    /// How many classes of each stream are significant now (could make a landmark's
    /// kernel); a class seen everywhere, such as the thesis's right-angle corner (§3.15.4),
    /// is not.
    pub fn significant_classes(&self) -> [usize; STREAMS] {
        let mut out = [0; STREAMS];
        for (s, o) in out.iter_mut().enumerate() {
            *o = (0..MAX_CLASSES).filter(|&c| self.significant(s, c)).count();
        }
        out
    }

    fn significant(&self, stream: usize, class: usize) -> bool {
        let s = self.stats[stream][class];
        let p = &self.params;
        s.runs >= p.min_activations
            && (s.runs as f32) <= p.max_share * self.stream_runs[stream] as f32
            && (s.samples as f32) <= p.max_mean_run * s.runs as f32
    }

    /// One control step: `labels` (one per stream, each < `MAX_CLASSES`), the odometric
    /// pose (x, y in metres, heading in radians) and its position variance (per axis, m^2;
    /// 0 if unknown). Returns what happened to the landmark store, if anything.
    pub fn step<M: PrototypeMetric>(
        &mut self,
        labels: [u8; STREAMS],
        (x, y, heading): (f32, f32, f32),
        var: f32,
        metric: &M,
    ) -> Option<Event> {
        self.step = self.step.wrapping_add(1);
        self.history.copy_within(1.., 0);
        self.history[WINDOW - 1] = labels;
        let mut kernel: Option<(usize, u8)> = None;
        for (s, &l) in labels.iter().enumerate() {
            let c = (l as usize).min(MAX_CLASSES - 1);
            let st = &mut self.stats[s][c];
            st.samples = st.samples.saturating_add(1);
            if self.last[s] != Some(l) {
                // A run starts: judge significance on the history before this run.
                if kernel.is_none() && self.significant(s, c) {
                    kernel = Some((s, l));
                }
                let st = &mut self.stats[s][c];
                st.runs = st.runs.saturating_add(1);
                self.stream_runs[s] = self.stream_runs[s].saturating_add(1);
                self.last[s] = Some(l);
            }
        }
        if let Some((s, c)) = kernel {
            let gap_ok = self
                .last_kernel
                .is_none_or(|k| self.step.wrapping_sub(k) >= self.params.min_kernel_gap);
            if self.step > self.params.warmup_steps && gap_ok {
                if let Some(slot) = self.pending.iter_mut().find(|p| p.is_none()) {
                    *slot = Some(Pending {
                        stream: s as u8,
                        class: c,
                        due: self.step.wrapping_add(CONTEXT as u32),
                        x,
                        y,
                        heading,
                        var,
                    });
                    self.last_kernel = Some(self.step);
                }
            }
        }
        let due = self
            .pending
            .iter()
            .position(|p| p.is_some_and(|p| p.due == self.step))?;
        let p = self.pending[due].take()?;
        Some(self.resolve(p, metric))
    }

    /// The last `WINDOW` labels of every stream, oldest first (at a resolution: the window
    /// around the kernel just resolved).
    pub fn window(&self) -> [[u8; WINDOW]; STREAMS] {
        let mut window = [[0u8; WINDOW]; STREAMS];
        for (k, row) in self.history.iter().enumerate() {
            for (w, &l) in window.iter_mut().zip(row) {
                w[k] = l;
            }
        }
        window
    }

    /// The weighted Levenshtein distance of `window` to landmark `lm`, per stream, in label
    /// costs (not normalised).
    pub fn stream_distances<M: PrototypeMetric>(
        &self,
        window: &[[u8; WINDOW]; STREAMS],
        lm: &Landmark,
        metric: &M,
    ) -> [f32; STREAMS] {
        let mut out = [0.0; STREAMS];
        for (s, ((ours, theirs), o)) in window.iter().zip(&lm.labels).zip(&mut out).enumerate() {
            let costs = StreamCosts {
                metric,
                stream: s,
                indel: self.params.indel_cost,
            };
            *o = weighted(ours, theirs, &costs).unwrap_or(f32::INFINITY);
        }
        out
    }

    fn resolve<M: PrototypeMetric>(&mut self, p: Pending, metric: &M) -> Event {
        let window = self.window();
        let prm = self.params;
        // Each stream's distance as a share of its window (§3.7.7: a landmark is the same
        // only if *all* class streams are similar enough, so the worst stream counts).
        let norm = WINDOW as f32 * prm.indel_cost * prm.lev_scale;
        let mut best: Option<(usize, f32)> = None;
        let (mut same_kernel, mut near) = (false, false);
        let mut best_lev = f32::INFINITY;
        self.stats_m.kernels += 1;
        for (i, lm) in self.landmarks[..self.used].iter().enumerate() {
            if lm.stream != p.stream || lm.class != p.class {
                continue;
            }
            same_kernel = true;
            let dd = libm::hypotf(lm.x - p.x, lm.y - p.y) / prm.diameter_m;
            if dd > 1.0 {
                continue; // §3.15.2: too far to be the same place.
            }
            near = true;
            let per = self.stream_distances(&window, lm, metric);
            let lev = per.iter().fold(0.0f32, |a, &b| a.max(b)) / norm;
            best_lev = best_lev.min(lev);
            let d = libm::hypotf(lev, dd);
            if d < prm.match_threshold && best.is_none_or(|(_, b)| d < b) {
                best = Some((i, d));
            }
        }
        if near {
            self.stats_m.near += 1;
            self.stats_m.lev_sum += best_lev;
        }
        if best.is_none() {
            let m = &mut self.stats_m;
            match (same_kernel, near) {
                (false, _) => m.unknown_kernel += 1,
                (true, false) => m.too_far += 1,
                (true, true) => m.dissimilar += 1,
            }
        }
        if let Some((i, d)) = best {
            let lm = &mut self.landmarks[i];
            lm.matches = lm.matches.saturating_add(1);
            return Event::Matched {
                index: i as u16,
                dx: lm.x - p.x,
                dy: lm.y - p.y,
                dheading: wrap_pi(lm.heading - p.heading),
                d,
                var: lm.var,
            };
        }
        if self.used >= MAX_LANDMARKS {
            return Event::Full;
        }
        self.landmarks[self.used] = Landmark {
            stream: p.stream,
            class: p.class,
            labels: window,
            x: p.x,
            y: p.y,
            heading: p.heading,
            var: p.var,
            matches: 0,
        };
        self.used += 1;
        Event::Created((self.used - 1) as u16)
    }
}

/// `a` folded into (-pi, pi].
fn wrap_pi(a: f32) -> f32 {
    use core::f32::consts::{PI, TAU};
    let r = a - TAU * libm::floorf((a + PI) / TAU);
    if r <= -PI {
        r + TAU
    } else {
        r
    }
}

/// Bytes of one stored landmark and of the whole store (for the memory budget in docs/reproductions.md).
pub const LANDMARK_BYTES: usize = core::mem::size_of::<Landmark>();
/// See [`LANDMARK_BYTES`].
pub const STORE_BYTES: usize = core::mem::size_of::<LandmarkStore>();

#[cfg(test)]
mod tests {
    use super::*;

    struct Same;
    impl PrototypeMetric for Same {
        fn distance(&self, _: usize, a: u8, b: u8) -> f32 {
            if a == b {
                0.0
            } else {
                1.0
            }
        }
    }

    fn params() -> LandmarkParams {
        LandmarkParams {
            min_activations: 2,
            max_share: 0.3,
            max_mean_run: 3.0,
            warmup_steps: 0,
            ..LandmarkParams::default()
        }
    }

    /// A lap of 60 steps: background class 0 with a one-step blip of class 9 at step 20 of
    /// stream 0 (a rare, short event: significant once seen twice).
    fn lap(store: &mut LandmarkStore, x0: f32, out: &mut [Option<Event>; 4], n: &mut usize) {
        lap_with(store, x0, |_| 2, out, n);
    }

    /// [`lap`] with stream 2's label at step k given by `s2`.
    fn lap_with(
        store: &mut LandmarkStore,
        x0: f32,
        s2: impl Fn(u32) -> u8,
        out: &mut [Option<Event>; 4],
        n: &mut usize,
    ) {
        for k in 0..60u32 {
            let l0 = if k == 20 { 9 } else { (k / 10) as u8 };
            let x = x0 + k as f32 * 0.001;
            if let Some(e) = store.step([l0, 1, s2(k)], (x, 0.0, 0.0), 0.0, &Same) {
                if *n < out.len() {
                    out[*n] = Some(e);
                }
                *n += 1;
            }
        }
    }

    #[test]
    fn a_rare_short_class_becomes_a_landmark_and_is_matched_with_a_correction() {
        let mut store = LandmarkStore::new(params());
        let mut ev = [None; 4];
        let mut n = 0;
        // Laps 1 and 2: the blip is not yet significant (needs 2 earlier runs).
        lap(&mut store, 0.0, &mut ev, &mut n);
        lap(&mut store, 0.0, &mut ev, &mut n);
        assert_eq!(n, 0, "{ev:?}");
        // Lap 3 makes the landmark at x = 0.020.
        lap(&mut store, 0.0, &mut ev, &mut n);
        assert_eq!(ev[0], Some(Event::Created(0)));
        assert!((store.landmarks()[0].x - 0.020).abs() < 1e-6);
        // Lap 4, odometry drifted 2 cm (< 1 diameter): matched, correction -2 cm.
        lap(&mut store, 0.02, &mut ev, &mut n);
        match ev[1] {
            Some(Event::Matched {
                index: 0, dx, dy, ..
            }) => {
                assert!((dx + 0.02).abs() < 1e-5 && dy.abs() < 1e-6, "{dx} {dy}");
            }
            e => panic!("{e:?}"),
        }
        // Lap 5 drifted 7 cm (> 1 diameter): ignored, a new landmark instead.
        lap(&mut store, 0.07, &mut ev, &mut n);
        assert_eq!(ev[2], Some(Event::Created(1)));
    }

    /// §3.7.7: a landmark is the same only if *every* class stream is similar. Here streams 0
    /// and 1 repeat exactly and stream 2 differs in 20 of its 31 labels: no match. (Summing
    /// the streams' distances over all 93 labels, as before, called it the same landmark.)
    #[test]
    fn one_dissimilar_stream_prevents_a_match() {
        let mut store = LandmarkStore::new(LandmarkParams {
            lev_scale: 0.5,
            ..params()
        });
        let mut ev = [None; 4];
        let mut n = 0;
        for _ in 0..3 {
            lap(&mut store, 0.0, &mut ev, &mut n);
        }
        assert_eq!(ev[0], Some(Event::Created(0)));
        // Stream 2 runs class 3 through steps 10..30 (one long run: never a kernel itself).
        let odd = |k: u32| if (10..30).contains(&k) { 3 } else { 2 };
        lap_with(&mut store, 0.02, odd, &mut ev, &mut n);
        assert_eq!(ev[1], Some(Event::Created(1)), "{ev:?}");
        // The same lap with stream 2 as stored matches again.
        lap(&mut store, 0.02, &mut ev, &mut n);
        assert!(
            matches!(ev[2], Some(Event::Matched { index: 0, .. })),
            "{ev:?}"
        );
    }

    /// A match turns the heading by the stored heading minus the heading at the kernel.
    #[test]
    fn a_match_carries_the_stored_heading() {
        let mut store = LandmarkStore::new(params());
        let mut seen = None;
        for lap_no in 0..4 {
            // Heading 0.1 rad when the landmark is made (lap 3), 0.4 rad when it is met again.
            let h = if lap_no < 3 { 0.1 } else { 0.4 };
            for k in 0..60u32 {
                let l0 = if k == 20 { 9 } else { (k / 10) as u8 };
                if let Some(Event::Matched { dheading, .. }) =
                    store.step([l0, 1, 2], (k as f32 * 0.001, 0.0, h), 0.0, &Same)
                {
                    seen = Some(dheading);
                }
            }
        }
        assert_eq!(store.landmarks()[0].heading, 0.1);
        let d = seen.expect("matched");
        assert!((d + 0.3).abs() < 1e-5, "{d}");
    }

    /// A landmark keeps the variance of the estimate that made it, and a match hands it to
    /// the caller (who weighs the correction by it, `super::super::fusion`).
    #[test]
    fn a_landmark_keeps_the_variance_it_was_made_with() {
        let mut store = LandmarkStore::new(params());
        let mut seen = None;
        for lap_no in 0..4 {
            let var = if lap_no < 3 { 2e-4 } else { 5e-5 };
            for k in 0..60u32 {
                let l0 = if k == 20 { 9 } else { (k / 10) as u8 };
                if let Some(Event::Matched { var, .. }) =
                    store.step([l0, 1, 2], (k as f32 * 0.001, 0.0, 0.0), var, &Same)
                {
                    seen = Some(var);
                }
            }
        }
        assert_eq!(store.landmarks()[0].var, 2e-4);
        assert_eq!(seen, Some(2e-4));
    }

    #[test]
    fn frequent_or_long_classes_are_not_significant() {
        let mut store = LandmarkStore::new(params());
        // Class 5 alternates every step (far too frequent); class 7 of stream 1 runs long.
        for k in 0..400u32 {
            let a = if k % 2 == 0 { 5 } else { 6 };
            let b = if (k / 50) % 2 == 0 { 7 } else { 8 };
            assert_eq!(store.step([a, b, 0], (0.0, 0.0, 0.0), 0.0, &Same), None);
        }
        assert!(store.landmarks().is_empty());
    }

    #[test]
    fn store_size_is_stated() {
        // docs/reproductions.md states these numbers; the test keeps them honest.
        let (one, all) = (LANDMARK_BYTES, STORE_BYTES);
        assert!(one <= 116, "{one}");
        assert!(all <= 40 * 1024, "{all}");
    }
}
