//! The revisit diagnosis, accumulated over a run from the truth (report only; the robot never
//! sees it).

use robot_firmware::unsupervised::landmarks::{Event, LandmarkStore};
use robot_firmware::unsupervised::STREAMS;

use super::report::RevisitDiagnosis;
use super::{Classifiers, DIAMETER_M};
use crate::arena::Pose;

/// Accumulates [`RevisitDiagnosis`].
#[derive(Default)]
pub(super) struct Diagnoser {
    d: RevisitDiagnosis,
    lev: [f64; STREAMS],
    lev_same: [f64; STREAMS],
    odo: f64,
    imp: [f64; STREAMS],
    off: f64,
}

impl Diagnoser {
    /// A kernel resolved as `e`; it happened at true pose `kt`, corrected position `ko`.
    pub(super) fn resolved(
        &mut self,
        e: Event,
        kt: Pose,
        ko: [f32; 2],
        store: &LandmarkStore,
        cls: &Classifiers,
        lm_truth: &mut Vec<Pose>,
    ) {
        let lms = store.landmarks();
        let (me, matched) = match e {
            Event::Created(i) => (Some(usize::from(i)), false),
            Event::Matched { .. } => (None, true),
            Event::Full => (None, false),
        };
        // The kernel: the created landmark's, or re-read from the store's statistics of a
        // match (the matched landmark has the same kernel).
        let kernel = match e {
            Event::Created(i) => lms.get(usize::from(i)).map(|l| (l.stream, l.class)),
            Event::Matched { index, .. } => {
                lms.get(usize::from(index)).map(|l| (l.stream, l.class))
            }
            Event::Full => None,
        };
        self.d.kernels += 1;
        if let Event::Matched { index, .. } = e {
            if let Some(t) = lm_truth.get(usize::from(index)) {
                let off = (t.x - kt.x).hypot(t.y - kt.y) / DIAMETER_M;
                self.d.matches += 1;
                self.off += off;
                if off > 0.5 {
                    self.d.match_offset_over_half += 1;
                }
            }
        }
        let limit = 0.5 * DIAMETER_M;
        let nearest = lms
            .iter()
            .enumerate()
            .filter(|(i, _)| Some(*i) != me && *i < lm_truth.len())
            .map(|(i, l)| (i, l, (lm_truth[i].x - kt.x).hypot(lm_truth[i].y - kt.y)))
            .filter(|(_, _, d)| *d < limit)
            .min_by(|a, b| a.2.total_cmp(&b.2));
        if let Some((i, l, _)) = nearest {
            self.d.near_any_landmark += 1;
            if kernel == Some((l.stream, l.class)) {
                self.d.revisits += 1;
                if matched {
                    self.d.revisits_matched += 1;
                }
                let odo = f64::from((l.x - ko[0]).hypot(l.y - ko[1])) / DIAMETER_M;
                self.odo += odo;
                if odo > 1.0 {
                    self.d.revisits_too_far += 1;
                }
                let dh = (lm_truth[i].heading - kt.heading + std::f64::consts::PI)
                    .rem_euclid(std::f64::consts::TAU)
                    - std::f64::consts::PI;
                let lev = store.stream_distances(&store.window(), l, cls);
                let same = dh.abs() < std::f64::consts::FRAC_PI_4;
                if same {
                    self.d.revisits_same_direction += 1;
                }
                for ((all, same_dir), v) in self.lev.iter_mut().zip(&mut self.lev_same).zip(lev) {
                    *all += f64::from(v);
                    if same {
                        *same_dir += f64::from(v);
                    }
                }
            }
        }
        for (i, l) in lms.iter().enumerate() {
            if Some(i) == me || i >= lm_truth.len() || kernel != Some((l.stream, l.class)) {
                continue;
            }
            let odo = f64::from((l.x - ko[0]).hypot(l.y - ko[1])) / DIAMETER_M;
            let tru = (lm_truth[i].x - kt.x).hypot(lm_truth[i].y - kt.y) / DIAMETER_M;
            if odo <= 1.0 && tru > 1.0 {
                self.d.impostors += 1;
                let lev = store.stream_distances(&store.window(), l, cls);
                for (a, v) in self.imp.iter_mut().zip(lev) {
                    *a += f64::from(v);
                }
            }
        }
        if let Some(i) = me {
            if lm_truth.len() == i {
                lm_truth.push(kt);
            }
        }
    }

    pub(super) fn finish(mut self) -> RevisitDiagnosis {
        let n = f64::from(self.d.revisits.max(1));
        let m = f64::from(self.d.revisits_same_direction.max(1));
        self.d.revisit_lev = self.lev.map(|v| (v / n) as f32);
        self.d.revisit_lev_same_direction = self.lev_same.map(|v| (v / m) as f32);
        self.d.revisit_odo_dist = (self.odo / n) as f32;
        let k = f64::from(self.d.impostors.max(1));
        self.d.impostor_lev = self.imp.map(|v| (v / k) as f32);
        self.d.match_offset_mean = (self.off / f64::from(self.d.matches.max(1))) as f32;
        self.d
    }
}
