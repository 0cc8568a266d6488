//! Supervised grid-line correction with a sampled PPD (seed 003 §2.5, "SPPS").
//!
//! Layer: a state machine above odometry, stepped once per control cycle with the encoder
//! counts and whether the floor sensor reported a line (a pulse: the caller turns a latched
//! sensor level into events, see [`super::LineEdge`]). Per cycle it moves every PPD sample and
//! the plain odometry pose. On a line event (§2.5.2-2.5.3):
//!
//! 1. each sample's sensor path over the cycle is matched to the nearest line band of either
//!    family (the PPD is intersected with every line x = k g and y = k g);
//! 2. samples are weighted by how far they miss their band (a Gaussian of width
//!    `line_sigma_m`), and the weight is summed per line: the line holding the most PPD mass
//!    wins, even if another line is nearer the odometry pose (Fig 2-17);
//! 3. the winning line's samples are moved onto it and resampled (systematic resampling,
//!    seeded), and the others dropped: the PPD is cut by the line and stays bounded (§2.6.4:
//!    "the PPD size can be reduced ... the average size of the PPD stays constant");
//! 4. the corrected pose is the mean of the cut: a position on the line and the heading that
//!    the surviving (V_L, V_R) hypotheses imply, i.e. the heading correction of §2.5.3.
//!
//! Between events the corrected pose is the mean of the samples. Survivors are roughened
//! (small Gaussian jitter of bias and heading) so the set never collapses onto one hypothesis
//! and can follow a bias that changes between trajectory segments.
//!
//! Invariants: N samples always; all weights equal between events (every accepted event
//! resamples); no heap, no clock, no I/O; a seeded [`XorShift32`] makes runs reproducible.
//! What can fail: an event whose best line is further than `gate_m` from the PPD is rejected
//! (returned as [`LineOutcome::Rejected`], state unchanged) - a double detection or a robot
//! already lost (§2.7: past the maximum odometry error there is no recovery). No panics.

use super::grid::{Axis, GridGeometry, GridLine};
use super::ppd::{self, Sample};
use crate::behaviour::XorShift32;
use crate::odometry::{integrate, wrap_angle, OdometryParams, Point, Pose};

/// Parameters of the line correction; defaults are the Khepera on a 10 cm grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SppsParams {
    /// Odometry (wheel distance, mm per pulse) shared with [`crate::odometry`].
    pub odometry: OdometryParams,
    /// The floor grid.
    pub grid: GridGeometry,
    /// Floor sensor distance ahead of the axle centre, metres (the emulator's is at the centre).
    pub sensor_offset_m: f32,
    /// Standard deviation of each wheel's relative speed error. seed 003 §2.3.3, Eq 2-7:
    /// dV = 1 % of 100 mm/s, sigma = dV/2 = 0.5 %.
    pub bias_sigma: f32,
    /// Width of the line likelihood, metres: how far a sample may miss its band and still
    /// count. Covers the sample spacing of a finite PPD; seed 003 gives no value.
    pub line_sigma_m: f32,
    /// An event whose best line is further than this from its samples is rejected, metres.
    pub gate_m: f32,
    /// Bias jitter added to every survivor of a cut (relative, 1 sigma).
    pub roughen_bias: f32,
    /// Heading jitter added to every survivor of a cut, radians (1 sigma).
    pub roughen_heading_rad: f32,
}

impl Default for SppsParams {
    fn default() -> Self {
        Self {
            odometry: OdometryParams::default(),
            grid: GridGeometry::default(),
            sensor_offset_m: 0.0,
            // seed 003 Eq 2-7: sigma = dV/2 with dV = 1 %
            bias_sigma: 0.005,
            line_sigma_m: 0.003,
            // 3 cm: beyond this the sample set no longer brackets the robot; a pulse that far
            // from every sample is more likely a double detection than a line.
            gate_m: 0.03,
            // A tenth of the prior per cut: enough to keep diversity over hundreds of cuts.
            roughen_bias: 0.0005,
            // 0.1 deg: the heading a 1 % bias drifts over ~5 mm of travel.
            roughen_heading_rad: 0.0017,
        }
    }
}

/// Result of one accepted line event.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineCorrection {
    /// The line the PPD was cut with.
    pub line: GridLine,
    /// Corrected pose after the cut.
    pub pose: Pose,
    /// How far the corrected position moved at this event, metres.
    pub moved_m: f32,
    /// Heading change at this event, radians.
    pub turned_rad: f32,
    /// Fraction of the PPD's weight that lay on the winning line (1 = unambiguous).
    pub support: f32,
}

/// What a line event did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LineOutcome {
    /// The PPD was cut with a line and the pose corrected.
    Corrected(LineCorrection),
    /// No line lay within `gate_m` of the PPD; nothing changed.
    Rejected {
        /// Weighted mean distance of the best line's samples from it, metres.
        distance_m: f32,
    },
}

/// Line-event counters, for telemetry.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct SppsCounters {
    /// Cycles stepped.
    pub cycles: u32,
    /// Line events accepted.
    pub corrections: u32,
    /// Line events rejected by the gate.
    pub rejected: u32,
}

/// Most distinct lines one event's samples may fall on; more are ignored (a PPD spanning
/// eight lines is already lost).
const MAX_LINES: usize = 8;

/// The supervised passive positioning system with `N` PPD samples.
#[derive(Clone, Debug)]
pub struct Spps<const N: usize> {
    params: SppsParams,
    samples: [Sample; N],
    rng: XorShift32,
    corrected: Pose,
    uncorrected: Pose,
    counters: SppsCounters,
}

/// The firmware's instance: 64 samples (1.3 KB of samples).
pub type Spps64 = Spps<64>;

impl<const N: usize> Spps<N> {
    /// Starts at a known `pose` (§2.5.1: the initial position and direction must be known)
    /// with biases drawn from the prior.
    pub fn new(params: SppsParams, pose: Pose, seed: u32) -> Self {
        let mut s = Self {
            params,
            samples: [Sample::default(); N],
            rng: XorShift32::new(seed),
            corrected: pose,
            uncorrected: pose,
            counters: SppsCounters::default(),
        };
        s.reset(pose);
        s
    }

    /// Re-seeds the PPD at a known pose (e.g. a global fix); the plain odometry pose is reset
    /// too, so both tracks restart together.
    pub fn reset(&mut self, pose: Pose) {
        let pose = Pose::new(pose.x, pose.y, pose.heading);
        ppd::seed_prior(
            &mut self.samples,
            pose,
            self.params.bias_sigma,
            &mut self.rng,
        );
        self.corrected = pose;
        self.uncorrected = pose;
    }

    /// Re-seeds the PPD as the thesis's sweep of each wheel over `±dv` (App 5.3), for drawing
    /// the model's banana; see [`ppd::seed_lattice`].
    pub fn reset_lattice(&mut self, pose: Pose, dv: f32) {
        ppd::seed_lattice(&mut self.samples, pose, dv);
        self.corrected = pose;
        self.uncorrected = pose;
    }

    /// One control cycle: encoder counts since the last cycle, and whether a line pulse was
    /// seen during it. Returns what the line event did, if there was one.
    pub fn step(&mut self, n_l: i32, n_r: i32, line: bool) -> Option<LineOutcome> {
        let p = self.params;
        self.counters.cycles = self.counters.cycles.wrapping_add(1);
        self.uncorrected = integrate(self.uncorrected, n_l, n_r, &p.odometry);
        if !line {
            for s in self.samples.iter_mut() {
                s.step(n_l, n_r, &p.odometry);
            }
            self.corrected = ppd::mean_pose(&self.samples).unwrap_or(self.corrected);
            return None;
        }
        // Each sample's sensor path over this cycle, and the band it is nearest to.
        let mut hits = [Hit::default(); N];
        for (s, hit) in self.samples.iter_mut().zip(hits.iter_mut()) {
            let before = s.sensor(p.sensor_offset_m);
            s.step(n_l, n_r, &p.odometry);
            let sw = p.grid.swept(before, s.sensor(p.sensor_offset_m));
            *hit = Hit {
                line: sw.line,
                shift_m: sw.shift_m,
                weight: 0.0,
            };
        }
        let before = ppd::mean_pose(&self.samples).unwrap_or(self.corrected);
        let outcome = self.cut(&mut hits, before);
        self.corrected = match outcome {
            LineOutcome::Corrected(c) => c.pose,
            LineOutcome::Rejected { .. } => before,
        };
        Some(outcome)
    }

    /// Steps 2-4 of the module doc on this cycle's `hits`.
    fn cut(&mut self, hits: &mut [Hit; N], before: Pose) -> LineOutcome {
        let p = self.params;
        // Likelihoods relative to the best sample, so at least one is 1 (no underflow to 0).
        let best = hits
            .iter()
            .map(|h| libm::fabsf(h.shift_m))
            .fold(f32::INFINITY, f32::min);
        let two_var = 2.0 * p.line_sigma_m * p.line_sigma_m;
        for h in hits.iter_mut() {
            let d = libm::fabsf(h.shift_m);
            h.weight = libm::expf(-(d * d - best * best) / two_var);
        }
        let Some((line, mass, total)) = winning_line(hits) else {
            return LineOutcome::Rejected {
                distance_m: f32::INFINITY,
            };
        };
        let mut miss = 0.0;
        for h in hits.iter().filter(|h| h.line == line) {
            miss += h.weight * libm::fabsf(h.shift_m);
        }
        let distance_m = miss / mass;
        // `!(a <= b)` also rejects NaN distances.
        if !(distance_m <= p.gate_m) {
            self.counters.rejected = self.counters.rejected.wrapping_add(1);
            return LineOutcome::Rejected { distance_m };
        }
        self.resample_onto(line, hits, mass);
        self.counters.corrections = self.counters.corrections.wrapping_add(1);
        let pose = ppd::mean_pose(&self.samples).unwrap_or(before);
        LineOutcome::Corrected(LineCorrection {
            line,
            pose,
            moved_m: pose.point().distance_to(before.point()),
            turned_rad: wrap_angle(pose.heading - before.heading),
            support: mass / total,
        })
    }

    /// Systematic resampling of the samples on `line` by weight; each copy is moved onto the
    /// line and roughened.
    fn resample_onto(&mut self, line: GridLine, hits: &[Hit; N], mass: f32) {
        let p = self.params;
        let old = self.samples;
        let step = mass / N as f32;
        // One uniform offset for all N pointers: low variance, deterministic given the seed.
        let mut target = step * ((self.rng.next_u32() >> 8) as f32 / 16_777_216.0);
        let mut cum = 0.0f32;
        let mut src = 0usize;
        let limit = p.bias_sigma * 10.0;
        for slot in self.samples.iter_mut() {
            // Advance to the sample whose cumulative weight covers `target`; rounding can
            // leave the last pointer past the end, so fall back to the last one on the line.
            while src < N {
                let w = if hits[src].line == line {
                    hits[src].weight
                } else {
                    0.0
                };
                if w > 0.0 && cum + w > target {
                    break;
                }
                cum += w;
                src += 1;
            }
            let pick = if src < N { src } else { last_on(line, hits) };
            let (Some(&s), Some(h)) = (old.get(pick), hits.get(pick)) else {
                continue;
            };
            let mut s = s;
            match line.axis {
                Axis::X => s.pose.x += h.shift_m,
                Axis::Y => s.pose.y += h.shift_m,
            }
            s.bias_left = (s.bias_left + p.roughen_bias * ppd::gauss(&mut self.rng))
                .clamp(-limit, limit);
            s.bias_right = (s.bias_right + p.roughen_bias * ppd::gauss(&mut self.rng))
                .clamp(-limit, limit);
            s.pose.heading = wrap_angle(
                s.pose.heading + p.roughen_heading_rad * ppd::gauss(&mut self.rng),
            );
            *slot = s;
            target += step;
        }
    }

    /// Corrected pose: the PPD's mean, or the cut's mean right after a line event.
    pub fn pose(&self) -> Pose {
        self.corrected
    }

    /// Plain odometry from the same counts, never corrected (the "uncorrected" track of
    /// seed 003 Fig 2-25).
    pub fn uncorrected(&self) -> Pose {
        self.uncorrected
    }

    /// The PPD samples, for drawing; all have equal weight.
    pub fn samples(&self) -> &[Sample; N] {
        &self.samples
    }

    /// Root-mean-square radius of the PPD, metres.
    pub fn size_m(&self) -> f32 {
        ppd::rms_size(&self.samples)
    }

    /// Mean wheel biases of the PPD (left, right): what the cuts have learnt.
    pub fn mean_bias(&self) -> (f32, f32) {
        let n = N.max(1) as f32;
        let l: f32 = self.samples.iter().map(|s| s.bias_left).sum();
        let r: f32 = self.samples.iter().map(|s| s.bias_right).sum();
        (l / n, r / n)
    }

    /// Event counters.
    pub fn counters(&self) -> SppsCounters {
        self.counters
    }

    /// Parameters in use.
    pub fn params(&self) -> &SppsParams {
        &self.params
    }

    /// Where the floor sensor of the corrected pose is, metres.
    pub fn sensor(&self) -> Point {
        ppd::sensor_point(self.corrected, self.params.sensor_offset_m)
    }
}

/// One sample's relation to this cycle's line event.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Hit {
    line: GridLine,
    shift_m: f32,
    weight: f32,
}

impl Default for Hit {
    fn default() -> Self {
        Self {
            line: GridLine {
                axis: Axis::X,
                index: 0,
            },
            shift_m: 0.0,
            weight: 0.0,
        }
    }
}

/// The line holding the most weight: (line, its weight, all weight). `None` if no weight.
fn winning_line(hits: &[Hit]) -> Option<(GridLine, f32, f32)> {
    let mut lines = [(Hit::default().line, 0.0f32); MAX_LINES];
    let mut used = 0usize;
    let mut total = 0.0f32;
    for h in hits {
        total += h.weight;
        if let Some(slot) = lines[..used].iter_mut().find(|(l, _)| *l == h.line) {
            slot.1 += h.weight;
        } else if let Some(slot) = lines.get_mut(used) {
            *slot = (h.line, h.weight);
            used += 1;
        }
    }
    let (line, mass) = lines[..used]
        .iter()
        .copied()
        .fold(None, |best: Option<(GridLine, f32)>, c| match best {
            Some(b) if b.1 >= c.1 => Some(b),
            _ => Some(c),
        })?;
    (mass > 0.0).then_some((line, mass, total))
}

fn last_on(line: GridLine, hits: &[Hit]) -> usize {
    hits.iter()
        .rposition(|h| h.line == line && h.weight > 0.0)
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> SppsParams {
        SppsParams::default()
    }

    #[test]
    fn without_lines_the_ppd_mean_tracks_odometry_and_grows() {
        let mut s = Spps64::new(params(), Pose::new(0.05, 0.05, 0.0), 3);
        for _ in 0..100 {
            assert!(s.step(100, 100, false).is_none());
        }
        // 0.8 m straight: uncorrected is exact; the PPD mean is near it, the PPD has spread.
        let u = s.uncorrected();
        assert!((u.x - 0.85).abs() < 1e-4 && (u.y - 0.05).abs() < 1e-6, "{u:?}");
        assert!(s.pose().point().distance_to(u.point()) < 0.03, "{:?}", s.pose());
        assert!(s.size_m() > 0.01 && s.size_m() < 0.2, "{}", s.size_m());
    }

    #[test]
    fn a_line_event_puts_the_pose_on_the_line_and_shrinks_the_ppd() {
        let mut s = Spps64::new(params(), Pose::new(0.05, 0.02, 0.3), 5);
        // Drive about 0.5 m so the PPD has grown, then report a line.
        for _ in 0..60 {
            s.step(80, 80, false);
        }
        let size = s.size_m();
        let out = s.step(10, 10, true);
        let Some(LineOutcome::Corrected(c)) = out else {
            panic!("{out:?}");
        };
        let on = match c.line.axis {
            Axis::X => c.pose.x,
            Axis::Y => c.pose.y,
        };
        // Mean of sensor paths touching a 1 cm band: within the band plus one cycle's travel.
        assert!((on - s.params().grid.coordinate(c.line)).abs() < 0.006, "{c:?}");
        assert!(s.size_m() < size, "{} -> {}", size, s.size_m());
        assert_eq!(s.counters().corrections, 1);
    }

    #[test]
    fn a_pulse_far_from_every_line_is_rejected_and_changes_nothing() {
        let p = SppsParams {
            gate_m: 0.01,
            ..params()
        };
        // Mid-square, freshly reset: every sample is 4 cm from any band.
        let mut s = Spps64::new(p, Pose::new(0.05, 0.05, 0.0), 9);
        let out = s.step(0, 0, true);
        assert!(matches!(out, Some(LineOutcome::Rejected { distance_m }) if distance_m > 0.03));
        assert_eq!(s.pose(), Pose::new(0.05, 0.05, 0.0));
        assert_eq!(s.counters().rejected, 1);
    }

    #[test]
    fn runs_are_reproducible_for_a_seed() {
        let run = |seed| {
            let mut s = Spps64::new(params(), Pose::new(0.01, 0.05, 0.2), seed);
            for k in 0..300 {
                s.step(100 + k % 7, 100 - k % 5, k % 13 == 0);
            }
            s.pose()
        };
        assert_eq!(run(1), run(1));
    }

    #[test]
    fn zero_samples_do_not_panic() {
        let mut s = Spps::<0>::new(params(), Pose::default(), 1);
        s.step(10, 10, false);
        s.step(10, 10, true);
        assert_eq!(s.size_m(), 0.0);
    }
}
