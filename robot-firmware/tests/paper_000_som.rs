//! Seed 000 (Löffler et al. 2001) §5.3 reproduced on the host: the 1-D Kohonen variant maps
//! six ambient-light readings to the angle of a light source.
//!
//! The sensor model is this file's own, built from what the paper says and nothing from the
//! emulator (emulator/tests/sim_som.rs repeats the experiment on the emulator's model):
//! - six front receivers S0..S5 on the rim of the 55 mm body at +90, +45, +10, -10, -45,
//!   -90 deg (seed 000 §1.1, §4.1);
//! - each sees the lamp through a raised-cosine acceptance `max(0, (cos phi + 1/2) / 1.5)`
//!   around its axis (full on axis, zero beyond 120 deg where the body shades it) and an
//!   inverse-square fall-off that stays finite at the lamp: `b = I acc / (1 + (d / 20 mm)^2)`;
//! - the reading is inverted, `500 / (1 + b)`: about 500 in the dark, falling as the light
//!   gets closer (§5.2, Fig 19); 10-bit, with 2 counts of Gaussian noise ("noise plays a
//!   significantly lesser role here", §5.2);
//! - the lamp's strength `I` makes the six readings average 200 facing the lamp 1 cm away:
//!   the paper's "optimal distance" threshold T2 (§6.1), where it calibrates;
//! - the angle labels come from odometry while the robot turns (§5.3), which the paper does
//!   not qualify; we give them 2 deg (1 sigma) of white error, our assumption for +-1 pulse,
//!   slip when turning on the spot and the skew between reading six sensors and the encoders
//!   within an 80 ms cycle. It is the one free parameter. The RESULT is the exact-label
//!   figure: the chain reaches the floor of 60 neurons over 180 deg (3 deg apart: 0.75 deg
//!   mean), below the paper's 1.52 deg; the 2 deg run only shows how much label error the
//!   paper's figure implies. The emulated calibration measures its own label error from the
//!   truth and finds far less (emulator/tests/sim_calibrate.rs).
//!
//! Training (§5.3): the robot 1 cm from the lamp turned through 180 deg, one example per
//! degree; values rescaled min -> 50, max -> 500; 60 neurons, 20 epochs, width 10 -> 1, rate
//! 0.6 -> 0.1; errors measured on the training rotation, as Fig 23 does. Paper: mean 1.52 deg,
//! max 6.52 deg; at 4 cm much worse (a plot only). Run with `--nocapture` for the tables.
#![allow(clippy::unwrap_used, clippy::panic)]

use robot_firmware::behaviour::XorShift32;
use robot_firmware::localize::ppd::gauss;
use robot_firmware::som::{rescale, Example, LightSom, Schedule};

const BODY_R_MM: f64 = 27.5; // seed 000 §1.1: 55 mm diameter
const SENSOR_DEG: [f64; 6] = [90.0, 45.0, 10.0, -10.0, -45.0, -90.0]; // seed 000 §4.1
const DARK: f64 = 500.0; // seed 000 §4.1: about 500 is dark
const D0_MM: f64 = 20.0; // near-field size of the lamp
const ACCEPT_C: f64 = 0.5; // raised-cosine offset: zero response beyond 120 deg
const NOISE: f64 = 2.0; // counts, 1 sigma
const T2: f64 = 200.0; // seed 000 §6.1: optimal distance threshold
const LABEL_SIGMA_DEG: f64 = 2.0; // odometry angle error, our assumption (see above)
const SEEDS: u32 = 8;

/// Noise-free readings of S0..S5 with the lamp `gap_mm` from the body's rim at `bearing_deg`
/// (robot frame, counter-clockwise from straight ahead), lamp strength `i`.
fn clean(gap_mm: f64, bearing_deg: f64, i: f64) -> [f64; 6] {
    let b = bearing_deg.to_radians();
    let lamp = (
        (BODY_R_MM + gap_mm) * b.cos(),
        (BODY_R_MM + gap_mm) * b.sin(),
    );
    SENSOR_DEG.map(|deg| {
        let (s, c) = deg.to_radians().sin_cos();
        let v = (lamp.0 - BODY_R_MM * c, lamp.1 - BODY_R_MM * s);
        let d = v.0.hypot(v.1);
        let cos_phi = (v.0 * c + v.1 * s) / d;
        let accept = ((cos_phi + ACCEPT_C) / (1.0 + ACCEPT_C)).max(0.0);
        DARK / (1.0 + i * accept / (1.0 + (d / D0_MM).powi(2)))
    })
}

/// Lamp strength whose six readings, facing the lamp 1 cm away, average T2 (bisection).
fn calibrated_strength() -> f64 {
    let avg = |i: f64| clean(10.0, 0.0, i).iter().sum::<f64>() / 6.0;
    let (mut lo, mut hi) = (0.0, 1e6);
    for _ in 0..100 {
        let mid = (lo + hi) / 2.0;
        if avg(mid) > T2 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// One rotation through 180 deg at `gap_mm`, one example per degree: noisy 10-bit readings
/// rescaled as §5.3 says; output = labelled angle in degrees, 0 (light on the right) .. 180.
fn rotation(gap_mm: f64, i: f64, label_sigma: f64, rng: &mut XorShift32) -> Vec<Example<6>> {
    (0..=180)
        .map(|a| {
            let raw = clean(gap_mm, f64::from(a) - 90.0, i).map(|v| {
                (v + NOISE * f64::from(gauss(rng)))
                    .round()
                    .clamp(0.0, 1023.0) as f32
            });
            Example {
                inputs: rescale(raw, 50.0, 500.0),
                output: (f64::from(a) + label_sigma * f64::from(gauss(rng))) as f32,
            }
        })
        .collect()
}

/// (mean, max) absolute recall error in degrees over `set`, and where the max is.
fn errors(som: &LightSom, set: &[Example<6>]) -> (f64, f64, f32) {
    let mut sum = 0.0;
    let mut worst = (0.0, 0.0);
    for ex in set {
        let e = f64::from((som.recall(&ex.inputs).unwrap() - ex.output).abs());
        sum += e;
        if e > worst.0 {
            worst = (e, ex.output);
        }
    }
    (sum / set.len() as f64, worst.0, worst.1)
}

/// Trains `SEEDS` networks at 1 cm and tests them at 1 cm (training set) and 4 cm; prints the
/// table and returns the seed-averaged (mean, max, 4 cm mean).
fn experiment(label_sigma: f64) -> (f64, f64, f64) {
    let i = calibrated_strength();
    println!("\n§5.3 light -> angle, own model, label sigma {label_sigma} deg, lamp {i:.1}");
    println!("seed | 1 cm mean   max (at deg) | 4 cm mean   max");
    let mut acc = (0.0, 0.0, 0.0);
    for seed in 1..=SEEDS {
        let mut rng = XorShift32::new(seed);
        let train = rotation(10.0, i, label_sigma, &mut rng);
        let mut som = LightSom::random(&mut rng, (50.0, 500.0), (0.0, 180.0));
        som.train(&train, &Schedule::LIGHT, &mut rng);
        let (mean, max, at) = errors(&som, &train);
        let far = rotation(40.0, i, label_sigma, &mut rng);
        let (fmean, fmax, _) = errors(&som, &far);
        println!("{seed:>4} | {mean:>9.2} {max:>5.2} ({at:>5.1}) | {fmean:>9.2} {fmax:>5.1}");
        acc = (acc.0 + mean, acc.1 + max, acc.2 + fmean);
    }
    let n = f64::from(SEEDS);
    let out = (acc.0 / n, acc.1 / n, acc.2 / n);
    println!(
        "average: mean {:.2} deg (paper 1.52), max {:.2} deg (paper 6.52), 4 cm mean {:.2} deg",
        out.0, out.1, out.2
    );
    out
}

#[test]
fn the_model_is_inverted_and_calibrated_to_t2_at_one_centimetre() {
    let i = calibrated_strength();
    let near = clean(10.0, 0.0, i);
    assert!((near.iter().sum::<f64>() / 6.0 - T2).abs() < 0.01);
    // Brighter (lower) when closer for the four sensors that face a lamp straight ahead (the
    // two side ones are shaded by the body when it is close); above T3 = 490 ("area left",
    // §6.1) a metre away (Fig 19).
    let far = clean(1000.0, 0.0, i);
    assert!(
        near[1..5].iter().zip(&far[1..5]).all(|(n, f)| n < f),
        "{near:?}"
    );
    assert!(far.iter().all(|&v| v > 490.0), "{far:?}");
    // The sensor facing the lamp is the brightest.
    let side = clean(10.0, 45.0, i);
    let brightest = (0..6).min_by(|&a, &b| side[a].total_cmp(&side[b])).unwrap();
    assert_eq!(brightest, 1);
}

#[test]
fn with_2_deg_of_assumed_label_noise_the_errors_land_on_the_papers_and_are_worse_at_four_cm() {
    let (mean, max, far) = experiment(LABEL_SIGMA_DEG);
    // Tolerances: the mean within ±25 % of 1.52 deg (it depends on our one free parameter,
    // the label error); the max within ±35 % of 6.52 deg (a single worst example out of 181,
    // so it scatters: 5.1-5.8 deg over our seeds); at 4 cm at least three times the mean at
    // 1 cm ("a large distance sensitivity", Fig 23, shown only as a plot).
    assert!((1.14..=1.90).contains(&mean), "{mean}");
    assert!((4.24..=8.80).contains(&max), "{max}");
    assert!(far > 3.0 * mean, "{far} vs {mean}");
}

#[test]
fn the_result_with_exact_angle_labels_is_the_chains_spacing_floor_below_the_papers_error() {
    // 60 neurons 3 deg apart: a perfect chain errs 0.75 deg on average.
    let (mean, max, far) = experiment(0.0);
    assert!((0.6..=1.1).contains(&mean), "{mean}");
    assert!(max < 6.52, "{max}");
    assert!(far > 3.0 * mean, "{far} vs {mean}");
}
