//! Seed 000 §5.3 on the emulator's own light sensor model: the firmware's 1-D Kohonen variant
//! (`robot_firmware::som`) trained on readings from `emulator::sensors::light::AmbientLight`
//! (cardioid acceptance, inverse-square fall-off, calibrated to T2 = 200 at about 1 cm, 1.5
//! counts of noise: `Noise::default().light_counts`).
//!
//! Same protocol as robot-firmware/tests/paper_000_som.rs: the Khepera 1 cm from the reference
//! lamp turned through 180 deg, one example per degree, the six front readings rescaled
//! min -> 50, max -> 500; 60 neurons, 20 epochs, width 10 -> 1, rate 0.6 -> 0.1; errors on the
//! training rotation and on one 4 cm away. Paper: mean 1.52 deg, max 6.52 deg; worse at 4 cm.
//! The result is the exact-label run; the 2 deg one is a sensitivity check (the label noise
//! paper_000_som.rs assumes; the emulated calibration has far less, sim_calibrate.rs).
//! Run with `--nocapture` for the table.
#![allow(clippy::unwrap_used, clippy::panic)]

use emulator::arena::{Light, Pose};
use emulator::geometry::{Point, SegmentSet};
use emulator::rng::SimRng;
use emulator::sensors::light::AmbientLight;
use emulator::sensors::Noise;
use robot_firmware::behaviour::XorShift32;
use robot_firmware::localize::ppd::gauss;
use robot_firmware::som::{rescale, Example, LightSom, Schedule};
use robot_firmware::KHEPERA;

const SEEDS: u32 = 8;

/// One rotation with the lamp `gap_m` from the rim: the robot at the origin turns so the lamp
/// sweeps from its right (angle 0) to its left (180); labels get `label_sigma` deg of error.
fn rotation(gap_m: f64, label_sigma: f64, seed: u32) -> Vec<Example<6>> {
    let radius = f64::from(KHEPERA.body_diameter_m) / 2.0;
    let lamp = Light {
        position: Point::new(radius + gap_m, 0.0),
        height_m: 0.0,
        intensity: 1.0,
    };
    let noise = Noise::default().light_counts;
    let mut sensor = AmbientLight::new(&KHEPERA, noise, SimRng::new(u64::from(seed), 11));
    let mut rng = XorShift32::new(seed);
    (0..=180)
        .map(|a| {
            // Lamp at bearing (a - 90) deg in the robot frame: heading = -(a - 90) deg.
            let heading = -(f64::from(a) - 90.0).to_radians();
            let r = sensor.read(
                &SegmentSet::default(),
                &[lamp],
                Pose {
                    x: 0.0,
                    y: 0.0,
                    heading,
                },
            );
            let front: [f32; 6] = core::array::from_fn(|k| f32::from(r[k]));
            Example {
                inputs: rescale(front, 50.0, 500.0),
                output: (f64::from(a) + label_sigma * f64::from(gauss(&mut rng))) as f32,
            }
        })
        .collect()
}

fn errors(som: &LightSom, set: &[Example<6>]) -> (f64, f64) {
    let e: Vec<f64> = set
        .iter()
        .map(|ex| f64::from((som.recall(&ex.inputs).unwrap() - ex.output).abs()))
        .collect();
    (
        e.iter().sum::<f64>() / e.len() as f64,
        e.iter().copied().fold(0.0, f64::max),
    )
}

fn experiment(label_sigma: f64) -> (f64, f64, f64) {
    println!("\n§5.3 on the emulator's light model, label sigma {label_sigma} deg");
    println!("seed | 1 cm mean   max | 4 cm mean   max");
    let mut acc = (0.0, 0.0, 0.0);
    for seed in 1..=SEEDS {
        let train = rotation(0.010, label_sigma, seed);
        let mut rng = XorShift32::new(seed + 50);
        let mut som = LightSom::random(&mut rng, (50.0, 500.0), (0.0, 180.0));
        som.train(&train, &Schedule::LIGHT, &mut rng);
        let (mean, max) = errors(&som, &train);
        let (fmean, fmax) = errors(&som, &rotation(0.040, label_sigma, seed + 100));
        println!("{seed:>4} | {mean:>9.2} {max:>5.2} | {fmean:>9.2} {fmax:>5.1}");
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
fn the_som_learns_light_angle_from_the_emulators_sensors() {
    // Exact angle labels: the chain reaches the floor of 60 neurons 3 deg apart (0.75 deg),
    // like the paper's own "expected" figure, and never errs by more than the paper's max.
    let (mean, max, _) = experiment(0.0);
    assert!((0.6..=1.52).contains(&mean), "{mean}");
    assert!(max < 6.52, "{max}");
}

#[test]
fn with_2_deg_of_assumed_label_noise_the_errors_are_the_papers() {
    // 2 deg of ASSUMED label error, as in paper_000_som.rs; same tolerances: mean ±25 % of 1.52 deg,
    // max ±35 % of 6.52 deg.
    let (mean, max, far) = experiment(2.0);
    assert!((1.14..=1.90).contains(&mean), "{mean}");
    assert!((4.24..=8.80).contains(&max), "{max}");
    // The emulator's cardioid receivers keep the rescaled pattern nearly distance-invariant,
    // so 4 cm is worse, but not by the large factor the paper reports (see the report).
    assert!(far > mean, "{far} vs {mean}");
}
