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

use emulator::scenarios::unsupervised_places::{run, ArenaKind, PlacesOptions, PlacesReport};

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

/// Paper: about 150 landmarks. Ours (seeds 1-10, the thesis's 5 cm IR): 48-245, median 120
/// (86-189, median about 130 with the real Khepera's 3.3 cm IR; 106-286 before the
/// compass heading: the estimate a kernel is stored with decides match or new). Tolerance:
/// the median within 75-300 (a factor of two; the thesis gives one arena, one run).
#[test]
fn unstructured_landmark_count_median_within_a_factor_of_two_of_150() {
    let r = reports(ArenaKind::Unstructured);
    let m = median(r.iter().map(|r| r.landmarks as f64).collect());
    assert!((75.0..=300.0).contains(&m), "median landmarks {m}");
}

/// Paper: plain odometry drifts (Fig. 3-34's reference). Ours: plain odometry's peak error
/// 7.3-22 diameters on every seed (wheel-bias heading drift). Asserted: more than 5
/// diameters on every seed, ten times the corrected error's bound.
#[test]
fn plain_odometry_drifts_more_than_five_diameters() {
    for r in reports(ArenaKind::Unstructured) {
        assert!(r.plain_peak > 5.0, "seed {}: {}", r.seed, r.plain_peak);
    }
}

/// Paper: corrected error peak about 1/3 diameter, bound about 1/2 (Fig. 3-34).
/// Ours (seeds 1-10, 1200 s): compass + landmarks peak 0.20-0.38 diameters (median 0.30),
/// mean 0.08-0.20; 23-121 matches a run (3.3 cm IR: 0.18-0.36, 29-226 matches). Before (heading from the wheels, reset to the
/// stored position): 3.6-33 (2.1-25 with the 3.3 cm IR). Asserted: at least one match and peak <= 1/2 on every seed.
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
/// distance; the landmarks hold the error. Ours: compass alone peak 0.37-1.22 diameters
/// (median about 0.76; 0.20-0.35 after 1200 s), compass + landmarks 0.25-0.47 (median about
/// 0.32); plain odometry 19-25. Asserted: compass + landmarks <= 1/2 on every seed; its
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
/// heading): the matched landmark's own error averages 0.24-0.48 diameters a run with the
/// reset (corrected peak 0.49-1.54) and 0.10-0.19 with the variance-weighted gain (peak
/// 0.20-0.38). Asserted: the weighted gain gives the lower mean landmark error on at least 8
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
/// Ours: 23-121 matches a run (median 52); judged with the truth, the matched kernel
/// lies on average 0.09-0.17 diameters from the landmark's true place, 10 of 634 more than
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
/// (Fig. 3-36, 3-37). Ours (1200 s): landmarks 5-82 (median 27.5) against 48-245 (120)
/// unstructured, matches 0-46 a run (median 8.5) against 23-121 (median 52).
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
/// (§3.15.4, Fig. 3-37: "After a certain time, the odometry error exceeds the limit of one
/// robot diameter due to missing landmarks. No further corrections can be proceeded because
/// rediscovered 'good' landmarks, with an assumed distance of more than one robot diameter,
/// are pronounced as unlikely and therefore ignored"). The thesis's mechanism is the drift
/// outrunning few corrections; it adds that the few landmarks are less reliable (negative
/// peaks) and that whether an arena fails "depends ... also of the sensor and odometry
/// quality of the robot". It prints no noise figure of its simulator's odometry.
/// Ours: NOT reproduced. Per seed (1-10, 1200 s, thesis 5 cm IR; thesis: > 1, lost):
/// peak 0.22 0.34 0.15 0.63 0.20 0.22 0.45 0.24 0.36 0.29 diameters, never lost; matches
/// 46 20 39 16 7 3 6 10 7 0; longest time without a match 397 944 255 539 460 857 913 573
/// 770 1200 s (unstructured 92-252 s: the thesis's "less correction events" holds); yet the
/// corrected error grows by at most 0.00-0.17 diameters between two matches, because the
/// compass-heading odometry drifts about 0.15-0.45 in 1200 s (0.22-1.08 in 7200 s). Wrong
/// identifications (kernel more than 1/2 from the landmark's true place): 1 of 154 matches
/// (unstructured 10 of 634); landmarks made at most 0.13-0.51 off; no revisit ignored by the
/// gate. 7200 s: peak 0.15-0.82, 21 wrong of 1,627 matches. With the thesis's reset (gain 1)
/// 0.25-0.86 (unstructured 0.49-1.54: the reset loses the unstructured arena first). With
/// the heading from the wheels both arenas are lost (structured 8.8-31, unstructured 3.6-33).
/// The contrast needs an odometry that drifts about one diameter in 400-450 s: with the
/// gaps above and a drift linear in the time since the last match, 8-9 structured seeds
/// pass one diameter while every unstructured one stays below it (3-4 above 1/2). Ours
/// drifts one diameter in hours with the compass, in about 15 s with the wheels' heading.
/// Over 7200 s the arenas' longest gaps overlap (unstructured 156-3150 s, structured
/// 397-6573 s), so no drift rate would keep the contrast in long runs.
/// Asserted (with --ignored): peak > 1 on at least 8 of 10.
#[test]
#[ignore = "not reproduced: the compass-heading odometry drifts too slowly to outrun even the structured arena's few corrections (docs/reproductions.md)"]
fn structured_arena_gets_lost() {
    let lost = reports(ArenaKind::Structured)
        .iter()
        .filter(|r| r.corrected_peak > 1.0)
        .count();
    assert!(lost >= 8, "lost in {lost} of 10");
}

/// Paper (§3.15.4): the structured arena has "almost as many classes" but of "worse
/// quality": the right-angle corners make their class no longer significant. Ours
/// (1200 s, all streams): classes 38-54 (median 44.5) against 43-65 (60.5); significant
/// classes at the end 1-7 (median 2) against 3-14 (median 8.5). Asserted: structured median classes
/// at least half the unstructured's, significant ones less than half.
#[test]
fn structured_arena_has_classes_but_few_significant_ones() {
    let sum = |v: [usize; 3]| v.iter().sum::<usize>() as f64;
    let med = |k, f: &dyn Fn(&PlacesReport) -> f64| median(reports(k).iter().map(f).collect());
    let (cs, cu) = (
        med(ArenaKind::Structured, &|r| sum(r.classes)),
        med(ArenaKind::Unstructured, &|r| sum(r.classes)),
    );
    let (ss, su) = (
        med(ArenaKind::Structured, &|r| sum(r.significant_classes)),
        med(ArenaKind::Unstructured, &|r| sum(r.significant_classes)),
    );
    assert!(
        cs >= 0.5 * cu,
        "classes: structured {cs} vs unstructured {cu}"
    );
    assert!(
        ss < 0.5 * su,
        "significant: structured {ss} vs unstructured {su}"
    );
}

/// Which of the ways to get lost the structured arena shows (`report.loss`, judged with
/// the truth; numbers in `structured_arena_gets_lost`): fewer corrections, yes (median
/// longest gap without a match 672 s against 170 s unstructured); wrong identifications and
/// landmarks made at wrong poses, no (at most 5 % of matches wrong over the seeds, every
/// landmark made within one diameter); and the error between corrections never grows to the
/// gate, so no revisit is ignored as too far. Asserted: those four, seeds 1-10.
#[test]
fn structured_arena_has_long_gaps_but_no_loss_mechanism() {
    let s = reports(ArenaKind::Structured);
    let u = reports(ArenaKind::Unstructured);
    let gs = median(s.iter().map(|r| r.loss.gap_max_s).collect());
    let gu = median(u.iter().map(|r| r.loss.gap_max_s).collect());
    assert!(
        gs > 2.0 * gu,
        "longest gap: structured {gs} s vs unstructured {gu} s"
    );
    let matches: u32 = s.iter().map(|r| r.loss.matches).sum();
    let wrong: u32 = s.iter().map(|r| r.loss.wrong_matches).sum();
    assert!(
        f64::from(wrong) <= 0.05 * f64::from(matches),
        "{wrong} of {matches} wrong"
    );
    for r in s {
        assert!(r.loss.made_err_max < 1.0, "seed {}: {:?}", r.seed, r.loss);
        assert!(
            r.loss.drift_between_max < 1.0,
            "seed {}: {:?}",
            r.seed,
            r.loss
        );
        assert_eq!(r.revisit.revisits_too_far, 0, "seed {}", r.seed);
    }
}

/// The thesis's simulated IR sensors reach about 5 cm (§3.2.2) and read 300 at about
/// 2.5 cm (§3.3.1). The scenario used the real Khepera's curve (nothing beyond 3.3 cm)
/// before. Asserted on the scenario's default curve: 300 within 2.3-2.7 cm, a wall at 4 cm
/// well above the floor, nothing from 5 cm.
#[test]
fn the_scenario_ir_sensor_is_the_thesis_five_centimetre_one() {
    let c = PlacesOptions::new(ArenaKind::Structured, 1).ir_curve;
    assert!(c.reading(0.023) > 300 && c.reading(0.027) < 300);
    assert!(c.reading(0.04) >= 30, "{}", c.reading(0.04));
    assert_eq!(c.reading(0.05), 5);
}

/// The thesis's mechanism of the loss, with the heading from the wheels (compass only at
/// matches, each match a reset to the stored position): the odometry is more than a
/// diameter off before a landmark is met again and the one-diameter gate then ignores every
/// landmark. Ours: peak 8.8-31 diameters (unstructured 3.6-33). Asserted: past one diameter on at least 8 of 10.
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
