//! How the robot could get lost (§3.15.4), each mechanism measured against the truth (report
//! only; the robot never sees it):
//! - drift outrunning few corrections: the time between matches and how much the corrected
//!   error grows in it; when the error first passes one diameter and whether any match
//!   follows (beyond it the one-diameter gate ignores the right landmark);
//! - wrong identifications (perceptual aliasing): matches whose kernel lies more than half a
//!   diameter (the thesis's least distance between two identical landmarks, §3.15.2) from
//!   the matched landmark's true place, their offsets and what they did to the error; pairs
//!   of landmarks with the same kernel stored within the gate of each other but apart in
//!   truth (a kernel at one can match the other); landmark count and spacing;
//! - landmarks made at wrong poses: each landmark's stored position against the true one
//!   when it was made.

use robot_firmware::unsupervised::landmarks::Landmark;
use serde::Serialize;

use super::{PlacesReport, DIAMETER_M};

/// A wrong identification: the kernel is farther than this from the matched landmark's true
/// place, diameters (§3.15.2: identical landmarks closer than about half a diameter cannot
/// be told apart).
pub const WRONG_OFFSET: f64 = 0.5;

/// See the module docs. Distances in robot diameters, times in simulated seconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct LossDiagnosis {
    /// Matches (odometry corrections).
    pub matches: u32,
    /// ... of those, wrong identifications (offset > [`WRONG_OFFSET`]).
    pub wrong_matches: u32,
    /// Their mean and largest offset from the matched landmark's true place.
    pub wrong_offset_mean: f64,
    /// See `wrong_offset_mean`.
    pub wrong_offset_max: f64,
    /// Mean change of the error at a wrong match (after - before; > 0 made it worse).
    pub wrong_error_change_mean: f64,
    /// Mean offset over all matches.
    pub offset_mean: f64,
    /// Mean and longest time without a match: from the start to the first match, between
    /// matches, and from the last match to the end.
    pub gap_mean_s: f64,
    /// See `gap_mean_s`.
    pub gap_max_s: f64,
    /// Mean and largest growth of the corrected error between one match and the next
    /// (err_before of a match - err_after of the one before).
    pub drift_between_mean: f64,
    /// See `drift_between_mean`.
    pub drift_between_max: f64,
    /// Mean corrected error just before and just after a match.
    pub err_before_mean: f64,
    /// See `err_before_mean`.
    pub err_after_mean: f64,
    /// Landmarks stored.
    pub landmarks: usize,
    /// Mean true distance from each landmark to its nearest other landmark.
    pub spacing_mean: f64,
    /// Mean true distance from each landmark to its nearest landmark with the same kernel
    /// (over the landmarks that have one).
    pub same_kernel_spacing_mean: f64,
    /// Pairs of same-kernel landmarks stored within one diameter of each other (the gate)
    /// but more than [`WRONG_OFFSET`] apart in truth: places the robot can confuse.
    pub alias_pairs: u32,
    /// Mean and largest error of a landmark's stored position when it was made.
    pub made_err_mean: f64,
    /// See `made_err_mean`.
    pub made_err_max: f64,
    /// First time the corrected error passes one diameter, and matches after it (sampled
    /// every `series_every_s`); `None`: never lost.
    pub lost_at_s: Option<f64>,
    /// See `lost_at_s`.
    pub matches_after_lost: u32,
}

impl LossDiagnosis {
    /// The diagnosis of a finished run; `stored` are the landmarks as the store holds them
    /// (their kernels), `r.landmark_truth` their true places.
    pub fn of(r: &PlacesReport, stored: &[Landmark]) -> Self {
        let mut d = LossDiagnosis {
            matches: r.match_log.len() as u32,
            landmarks: stored.len(),
            ..LossDiagnosis::default()
        };
        let n = r.match_log.len().max(1) as f64;
        let wrong: Vec<_> = r
            .match_log
            .iter()
            .filter(|m| m.offset > WRONG_OFFSET)
            .collect();
        d.wrong_matches = wrong.len() as u32;
        let nw = wrong.len().max(1) as f64;
        d.wrong_offset_mean = wrong.iter().map(|m| m.offset).sum::<f64>() / nw;
        d.wrong_offset_max = wrong.iter().map(|m| m.offset).fold(0.0, f64::max);
        d.wrong_error_change_mean = wrong
            .iter()
            .map(|m| m.err_after - m.err_before)
            .sum::<f64>()
            / nw;
        d.offset_mean = r.match_log.iter().map(|m| m.offset).sum::<f64>() / n;
        d.err_before_mean = r.match_log.iter().map(|m| m.err_before).sum::<f64>() / n;
        d.err_after_mean = r.match_log.iter().map(|m| m.err_after).sum::<f64>() / n;

        let mut times = vec![0.0];
        times.extend(r.match_log.iter().map(|m| m.t_s));
        times.push(r.duration_s);
        let gaps: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
        d.gap_mean_s = gaps.iter().sum::<f64>() / gaps.len() as f64;
        d.gap_max_s = gaps.iter().copied().fold(0.0, f64::max);
        let drift: Vec<f64> = r
            .match_log
            .windows(2)
            .map(|w| w[1].err_before - w[0].err_after)
            .collect();
        d.drift_between_mean = drift.iter().sum::<f64>() / drift.len().max(1) as f64;
        d.drift_between_max = drift.iter().copied().fold(0.0, f64::max);

        let truth = &r.landmark_truth;
        let k = stored.len().min(truth.len());
        let dist = |i: usize, j: usize| {
            (truth[i][0] - truth[j][0]).hypot(truth[i][1] - truth[j][1]) / DIAMETER_M
        };
        let (mut nn_sum, mut nn_n, mut same_sum, mut same_n) = (0.0, 0, 0.0, 0);
        for i in 0..k {
            let mut nn = f64::INFINITY;
            let mut same = f64::INFINITY;
            for j in (0..k).filter(|&j| j != i) {
                let t = dist(i, j);
                nn = nn.min(t);
                let (a, b) = (&stored[i], &stored[j]);
                if (a.stream, a.class) == (b.stream, b.class) {
                    same = same.min(t);
                    let odo = f64::from((a.x - b.x).hypot(a.y - b.y)) / DIAMETER_M;
                    if j > i && odo <= 1.0 && t > WRONG_OFFSET {
                        d.alias_pairs += 1;
                    }
                }
            }
            if nn.is_finite() {
                nn_sum += nn;
                nn_n += 1;
            }
            if same.is_finite() {
                same_sum += same;
                same_n += 1;
            }
            let made = (f64::from(stored[i].x) - truth[i][0])
                .hypot(f64::from(stored[i].y) - truth[i][1])
                / DIAMETER_M;
            d.made_err_mean += made / k as f64;
            d.made_err_max = d.made_err_max.max(made);
        }
        d.spacing_mean = nn_sum / f64::from(nn_n.max(1));
        d.same_kernel_spacing_mean = same_sum / f64::from(same_n.max(1));

        d.lost_at_s = r
            .series
            .iter()
            .find(|p| p.corrected_err > 1.0)
            .map(|p| p.t_s);
        if let Some(t) = d.lost_at_s {
            d.matches_after_lost = r.match_log.iter().filter(|m| m.t_s > t).count() as u32;
        }
        d
    }
}

#[cfg(test)]
mod tests {
    use super::super::{run, ArenaKind, MatchRecord, PlacesOptions};
    use super::*;

    fn record(t_s: f64, offset: f64, err_before: f64, err_after: f64) -> MatchRecord {
        MatchRecord {
            t_s,
            landmark: 0,
            d: 0.5,
            correction: 0.0,
            gain: 1.0,
            landmark_sigma: 0.0,
            landmark_err: 0.0,
            offset,
            err_before,
            err_after,
            from: [0.0; 2],
            to: [0.0; 2],
        }
    }

    /// Gaps count from the start and to the end, drift is the error's growth between one
    /// match and the next, a match more than half a diameter off is wrong, and the robot is
    /// lost from the first sample past one diameter.
    #[test]
    fn gaps_drift_wrong_matches_and_loss_from_a_known_run() {
        let mut o = PlacesOptions::new(ArenaKind::Structured, 1);
        o.duration_s = 100.0;
        o.series_every_s = 10.0;
        let mut r = run(&o);
        r.match_log = vec![
            record(10.0, 0.1, 0.3, 0.1),
            record(40.0, 0.7, 0.5, 0.8),
            record(90.0, 0.2, 1.3, 1.2),
        ];
        for p in &mut r.series {
            p.corrected_err = if p.t_s >= 60.0 { 1.1 } else { 0.2 };
        }
        let d = LossDiagnosis::of(&r, &[]);
        assert_eq!((d.matches, d.wrong_matches), (3, 1));
        assert!((d.wrong_offset_max - 0.7).abs() < 1e-9);
        assert!((d.wrong_error_change_mean - 0.3).abs() < 1e-9);
        // Gaps 10, 30, 50, 10 s.
        assert!((d.gap_max_s - 50.0).abs() < 1e-9 && (d.gap_mean_s - 25.0).abs() < 1e-9);
        // Growth 0.5 - 0.1 and 1.3 - 0.8.
        assert!((d.drift_between_max - 0.5).abs() < 1e-9, "{d:?}");
        assert_eq!((d.lost_at_s, d.matches_after_lost), (Some(60.0), 1));
    }
}
