//! Seed 003 chapter 3 (Mächler 1998, §3.15): unsupervised landmarks correct the odometry of a
//! simulated Khepera in an arena of about 15 x 15 robot diameters.
//!
//! Paper: unstructured arena, about 150 landmarks (§3.15.1); the absolute position error stays
//! bounded, peak about 1/3 robot diameter, bound about 1/2 (§3.15.2, Fig. 3-34); a structured
//! arena (right-angle corners) gives worse classes and the error passes one diameter: the
//! robot gets lost (§3.15.4, Fig. 3-37).
//! Project: `robot-emulator run --task unsupervised-places`, seeds 1-10, 1200 simulated s
//! (7200 s for the comparison with the compass alone), default noise; every figure in robot
//! diameters. Three estimates against the truth: plain odometry, wheels plus compass heading,
//! compass plus landmarks (the corrected one: matches weighted by the variances,
//! `robot_firmware::unsupervised::fusion`). What each test asserts and what it measured is in
//! its own comment; the structured arena's "passes one diameter" is NOT reproduced with the
//! compass in the odometry (its test is ignored with the reason and fails with `--ignored`).
#![allow(clippy::unwrap_used, clippy::panic)]

use std::sync::OnceLock;

use emulator::unsupervised_places::{run, ArenaKind, PlacesOptions, PlacesReport};

const SEEDS: std::ops::RangeInclusive<u64> = 1..=10;

/// The runs of one configuration, printed once.
fn runs(what: &str, make: impl Fn(u64) -> PlacesOptions) -> Vec<PlacesReport> {
    let runs: Vec<PlacesReport> = SEEDS.map(|seed| run(&make(seed))).collect();
    for r in &runs {
        eprintln!(
            "{what} {:?} seed {:>2}: {:>3} landmarks, {:>4} matches, {:>2} places; peak/mean \
             error plain {:.2}/{:.2}, compass {:.2}/{:.2}, compass + landmarks {:.2}/{:.2} \
             diameters",
            r.arena,
            r.seed,
            r.landmarks,
            r.matches,
            r.places,
            r.plain_peak,
            r.plain_mean,
            r.compass_peak,
            r.compass_mean,
            r.corrected_peak,
            r.corrected_mean
        );
    }
    runs
}

/// The default scenario, 1200 s.
fn reports(kind: ArenaKind) -> &'static [PlacesReport] {
    static UNSTRUCTURED: OnceLock<Vec<PlacesReport>> = OnceLock::new();
    static STRUCTURED: OnceLock<Vec<PlacesReport>> = OnceLock::new();
    let cell = match kind {
        ArenaKind::Unstructured => &UNSTRUCTURED,
        ArenaKind::Structured => &STRUCTURED,
    };
    cell.get_or_init(|| runs("default", |seed| PlacesOptions::new(kind, seed)))
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

/// Paper: about 150 landmarks. Ours (seeds 1-10): 86-189, median about 130 (106-286 before the
/// compass heading: the estimate a kernel is stored with decides match or new). Tolerance:
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
/// Ours (seeds 1-10, 1200 s): compass + landmarks peak 0.18-0.36 diameters (median about
/// 0.27), mean 0.08-0.16; 29-226 matches a run. Before (heading from the wheels, reset to the
/// stored position): 2.1-25. Asserted: at least one match and peak <= 1/2 on every seed.
#[test]
fn unstructured_corrected_error_stays_below_half_a_diameter() {
    for r in reports(ArenaKind::Unstructured) {
        assert!(r.matches > 0, "seed {}: no match", r.seed);
        assert!(
            r.corrected_peak <= 0.5,
            "seed {}: corrected peak {:.2} diameters (plain {:.2}, compass {:.2})",
            r.seed,
            r.corrected_peak,
            r.plain_peak,
            r.compass_peak
        );
    }
}

/// Unstructured, 7200 s: what the landmarks add to the compass. The compass alone leaves a
/// sideways random walk (2 degrees of noise a reading), which grows as the square root of the
/// distance; the landmarks hold the error. Ours: compass alone peak 0.28-1.10 diameters
/// (median about 0.6; 0.15-0.49 after 1200 s), compass + landmarks 0.23-0.39 (median about
/// 0.30); plain odometry 18-32. Asserted: compass + landmarks <= 1/2 on every seed; its
/// median peak below the compass alone's; the compass alone past 1/2 on at least 3 seeds.
#[test]
fn landmarks_hold_the_error_the_compass_alone_lets_grow() {
    static LONG: OnceLock<Vec<PlacesReport>> = OnceLock::new();
    let r = LONG.get_or_init(|| {
        runs("7200 s", |seed| {
            let mut o = PlacesOptions::new(ArenaKind::Unstructured, seed);
            o.duration_s = 7200.0;
            o
        })
    });
    for r in r {
        assert!(
            r.corrected_peak <= 0.5,
            "seed {}: corrected peak {:.2} (compass {:.2})",
            r.seed,
            r.corrected_peak,
            r.compass_peak
        );
    }
    let corrected = median(r.iter().map(|r| r.corrected_peak).collect());
    let compass = median(r.iter().map(|r| r.compass_peak).collect());
    assert!(
        corrected < compass,
        "medians: landmarks {corrected:.2}, compass {compass:.2}"
    );
    let grown = r.iter().filter(|r| r.compass_peak > 0.5).count();
    assert!(grown >= 3, "the compass alone passed 1/2 on {grown} seeds");
}

/// Why the thesis's reset (all the way to the stored position) random-walks: a landmark made
/// late carries the error of its moment, and a reset to it hands that error on to the
/// landmarks made next. Judged with the truth, over every match of seeds 1-10 (1200 s, compass
/// heading): the matched landmark's own error averages 0.20-0.89 diameters a run with the
/// reset (corrected peak 0.52-1.66) and 0.08-0.18 with the variance-weighted gain (peak
/// 0.18-0.36). Asserted: the weighted gain gives the lower mean landmark error on at least 8
/// of 10 seeds, and the reset passes 1/2 on at least 5.
#[test]
fn resetting_all_the_way_walks_the_error_through_late_landmarks() {
    let reset = runs("thesis reset", |seed| {
        let mut o = PlacesOptions::new(ArenaKind::Unstructured, seed);
        o.fusion = None;
        o
    });
    let weighted = reports(ArenaKind::Unstructured);
    let lm_err = |r: &PlacesReport| {
        r.match_log.iter().map(|m| m.landmark_err).sum::<f64>() / r.match_log.len().max(1) as f64
    };
    let better = reset
        .iter()
        .zip(weighted)
        .filter(|(a, b)| lm_err(b) < lm_err(a))
        .count();
    assert!(better >= 8, "weighted gain better on {better} of 10");
    let over = reset.iter().filter(|r| r.corrected_peak > 0.5).count();
    assert!(over >= 5, "the reset passed 1/2 on {over} of 10");
}

/// Paper: "Every time the robot rediscovers a landmark on a plausible position, it corrects
/// its odometry" (§3.15.1), mostly right, sometimes wrong (Fig. 3-34's negative peaks).
/// Ours: 29-226 matches a run (median about 78); judged with the truth, the matched kernel
/// lies on average 0.04-0.12 diameters from the landmark's true place, 1 of 1,014 more than
/// 1/2 away (wrong identifications are not what moves the error).
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

/// Paper: the structured arena gives fewer usable landmarks and fewer corrections
/// (Fig. 3-36, 3-37). Ours (1200 s): median landmarks about 32 against about 130
/// unstructured, matches 1-46 a run (median about 17) against 29-226 (median about 78).
/// Asserted: fewer landmarks and fewer matches (medians) than the unstructured arena.
#[test]
fn structured_arena_gives_fewer_landmarks_and_corrections() {
    let s = reports(ArenaKind::Structured);
    let u = reports(ArenaKind::Unstructured);
    let ms = median(s.iter().map(|r| r.landmarks as f64).collect());
    let mu = median(u.iter().map(|r| r.landmarks as f64).collect());
    assert!(ms < mu, "landmarks: structured {ms} vs unstructured {mu}");
    let ms = median(s.iter().map(|r| f64::from(r.matches)).collect());
    let mu = median(u.iter().map(|r| f64::from(r.matches)).collect());
    assert!(ms < mu, "matches: structured {ms} vs unstructured {mu}");
}

/// Paper: in the structured arena the error passes one diameter and the robot is lost
/// (Fig. 3-37). Ours: NOT reproduced with the compass in the odometry: the compass alone
/// drifts by 0.16-0.39 diameters in 1200 s (0.39-1.11 in 7200 s), too slowly to outrun even the
/// structured arena's few corrections: compass + landmarks peaks 0.16-0.44 (1200 s) and
/// 0.25-0.70 (7200 s). The loss needs an odometry that drifts past one diameter between
/// corrections: with the heading from the wheels the structured arena is lost on every seed
/// (peak 6.8-38, `structured_arena_is_lost_when_the_heading_drifts`), but so is the
/// unstructured one (2.1-25). Asserted (with --ignored): peak > 1 on at least 8 of 10.
#[test]
#[ignore = "not reproduced: with the compass heading the drift is too slow to get lost (README)"]
fn structured_arena_gets_lost() {
    let lost = reports(ArenaKind::Structured)
        .iter()
        .filter(|r| r.corrected_peak > 1.0)
        .count();
    assert!(lost >= 8, "lost in {lost} of 10");
}

/// The thesis's mechanism of the loss, with the heading from the wheels (compass only at
/// matches, each match a reset to the stored position): the odometry is more than a
/// diameter off before a landmark is met again and the one-diameter gate then ignores every
/// landmark. Ours: peak 6.8-38 diameters. Asserted: past one diameter on at least 8 of 10.
#[test]
fn structured_arena_is_lost_when_the_heading_drifts() {
    let s = runs("wheel heading", |seed| {
        let mut o = PlacesOptions::new(ArenaKind::Structured, seed);
        o.compass_heading = false;
        o.fusion = None;
        o
    });
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
