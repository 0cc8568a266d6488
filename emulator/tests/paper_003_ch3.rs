//! Seed 003 chapter 3 (Mächler 1998, §3.15): unsupervised landmarks correct the odometry of a
//! simulated Khepera in an arena of about 15 x 15 robot diameters.
//!
//! Paper: unstructured arena, about 150 landmarks (§3.15.1); the absolute position error stays
//! bounded, peak about 1/3 robot diameter, bound about 1/2 (§3.15.2, Fig. 3-34); a structured
//! arena (right-angle corners) gives worse classes and the error passes one diameter: the
//! robot gets lost (§3.15.4, Fig. 3-37).
//! Project: `robot-emulator run --task unsupervised-places`, seeds 1-10, 1200 simulated s,
//! default noise; every figure in robot diameters. What each test asserts and what it measured
//! is in its own comment; the bounded-error claim is NOT reproduced (its test is ignored with
//! the reason and fails when run with `--ignored`).
#![allow(clippy::unwrap_used, clippy::panic)]

use std::sync::OnceLock;

use emulator::unsupervised_places::{run, ArenaKind, PlacesOptions, PlacesReport};

const SEEDS: std::ops::RangeInclusive<u64> = 1..=10;

fn reports(kind: ArenaKind) -> &'static [PlacesReport] {
    static UNSTRUCTURED: OnceLock<Vec<PlacesReport>> = OnceLock::new();
    static STRUCTURED: OnceLock<Vec<PlacesReport>> = OnceLock::new();
    let cell = match kind {
        ArenaKind::Unstructured => &UNSTRUCTURED,
        ArenaKind::Structured => &STRUCTURED,
    };
    cell.get_or_init(|| {
        let runs: Vec<PlacesReport> = SEEDS
            .map(|seed| run(&PlacesOptions::new(kind, seed)))
            .collect();
        for r in &runs {
            eprintln!(
                "{:?} seed {:>2}: {:>3} landmarks, {:>4} matches, {:>2} places; peak/mean error \
                 corrected {:.2}/{:.2}, plain {:.2}/{:.2}, compass-heading {:.2}/{:.2} diameters",
                r.arena,
                r.seed,
                r.landmarks,
                r.matches,
                r.places,
                r.corrected_peak,
                r.corrected_mean,
                r.plain_peak,
                r.plain_mean,
                r.compass_peak,
                r.compass_mean
            );
        }
        runs
    })
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    }
}

/// Paper: about 150 landmarks. Ours (seeds 1-10): 106-286, median about 177. Tolerance:
/// the median within 75-300 (a factor of two; the thesis gives one arena, one run).
#[test]
fn unstructured_landmark_count_is_near_150() {
    let r = reports(ArenaKind::Unstructured);
    let m = median(r.iter().map(|r| r.landmarks as f64).collect());
    assert!((75.0..=300.0).contains(&m), "median landmarks {m}");
}

/// Paper: plain odometry drifts (Fig. 3-34's reference). Ours: plain odometry's peak error
/// 6.6-28 diameters on every seed (wheel-bias heading drift). Asserted: > 1/2 diameter on
/// every seed.
#[test]
fn plain_odometry_drifts_past_half_a_diameter() {
    for r in reports(ArenaKind::Unstructured) {
        assert!(r.plain_peak > 0.5, "seed {}: {}", r.seed, r.plain_peak);
    }
}

/// Paper: corrected error peak about 1/3 diameter, bound about 1/2 (Fig. 3-34).
/// Ours: NOT reproduced. Landmarks are now met again (6-129 matches a run, the matched
/// kernel on average 0.07-0.17 diameters from the landmark's true place, none over 1/2), but
/// the corrected peak is 2.1-25 diameters (median 11.6; plain 6.6-28, median 18.5): with the
/// thesis's wheel bias (sigma 0.5 %) the odometry is a diameter off within about 0.9 m of
/// travel, before the robot is back at a landmark, so landmarks are stored already drifted
/// and most revisits lie beyond the one-diameter gate; with perfect wheels the matches alone
/// still walk the error to 0.6-3.5 diameters (README). Asserted (when run with --ignored):
/// peak <= 1/2 on every seed and at least one match per run.
#[test]
#[ignore = "not reproduced: drift outruns revisits, matches random-walk the error (README)"]
fn unstructured_corrected_error_stays_below_half_a_diameter() {
    for r in reports(ArenaKind::Unstructured) {
        assert!(r.matches > 0, "seed {}: no match", r.seed);
        assert!(
            r.corrected_peak <= 0.5,
            "seed {}: corrected peak {:.2} diameters (plain {:.2})",
            r.seed,
            r.corrected_peak,
            r.plain_peak
        );
    }
}

/// Paper: "Every time the robot rediscovers a landmark on a plausible position, it corrects
/// its odometry" (§3.15.1), mostly right, sometimes wrong (Fig. 3-34's negative peaks).
/// Ours: 6-129 matches a run (median 41); judged with the truth, the matched kernel lies on
/// average 0.07-0.17 diameters from the landmark's true place and none more than 1/2 away.
/// Before the landmark comparison took the worst stream's share of its window (§3.7.7) it
/// matched 0-1 times a run. Asserted: a median of at least 10 matches a run, and at most 5 %
/// of all matches more than half a diameter from the true place.
#[test]
fn unstructured_landmarks_are_met_again_at_the_right_place() {
    let r = reports(ArenaKind::Unstructured);
    let m = median(r.iter().map(|r| f64::from(r.matches)).collect());
    assert!(m >= 10.0, "median matches {m}");
    let all: u32 = r.iter().map(|r| r.revisit.matches).sum();
    let off: u32 = r.iter().map(|r| r.revisit.match_offset_over_half).sum();
    assert!(
        f64::from(off) <= 0.05 * f64::from(all),
        "{off} of {all} matches more than half a diameter off"
    );
}

/// Paper: the structured arena gives fewer usable landmarks and the error passes one
/// diameter (Fig. 3-36, 3-37). Ours: median landmarks about 43 against about 177 unstructured,
/// 0-14 matches a run against 6-129; corrected peak 6.8-38 diameters. Asserted: fewer landmarks (median) than the unstructured
/// arena, and the corrected error passes one diameter on at least 8 of 10 seeds. Caveat: with
/// the unstructured claim unreproduced, "lost" here holds for the same reason as there.
#[test]
fn structured_arena_gets_lost() {
    let s = reports(ArenaKind::Structured);
    let u = reports(ArenaKind::Unstructured);
    let ms = median(s.iter().map(|r| r.landmarks as f64).collect());
    let mu = median(u.iter().map(|r| r.landmarks as f64).collect());
    assert!(ms < mu, "structured {ms} vs unstructured {mu}");
    let lost = s.iter().filter(|r| r.corrected_peak > 1.0).count();
    assert!(lost >= 8, "lost in {lost} of 10");
}

/// The report is a function of the seed (the landmark store and classifiers are
/// deterministic), and every run stays within the store's stated capacity.
#[test]
fn runs_are_repeatable_and_bounded() {
    let mut o = PlacesOptions::new(ArenaKind::Unstructured, 3);
    o.duration_s = 120.0;
    let (mut a, mut b) = (run(&o), run(&o));
    a.wall_s = 0.0;
    b.wall_s = 0.0;
    assert_eq!(a, b);
    for r in reports(ArenaKind::Unstructured) {
        assert!(r.landmarks <= r.landmark_capacity);
        assert!(r.distance_m > 10.0, "seed {} barely moved", r.seed);
    }
}
