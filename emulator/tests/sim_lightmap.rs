//! Seed 000 §6.1 in the emulator: light-source mapping with and without local correction
//! (emulator/src/scenario/lightmap.rs). Paper (one real run each, 75 x 60 cm box, one
//! source): without correction the source was recognised 5 times; with correction the run
//! was stopped after 24 recognitions.
//!
//! Seeded runs; tolerances: without correction the source is lost after 2..=12 recognitions
//! on every seed and 3..=9 on average (the paper's 5 is one sample of a random process);
//! with correction every seed reaches 24, where the paper stopped. Run with `--nocapture`
//! for the table.
#![allow(clippy::unwrap_used, clippy::panic)]

use emulator::scenario::lightmap::{run_light_map, LightMapOptions};

const SEEDS: [u64; 6] = [1, 2, 3, 4, 5, 6];

#[test]
fn local_correction_keeps_the_source_recognised() {
    println!("seed | without: recognitions ended | with: recognitions ended");
    let mut without = Vec::new();
    for seed in SEEDS {
        let a = run_light_map(&LightMapOptions::new(seed, false)).unwrap();
        let mut o = LightMapOptions::new(seed, true);
        o.limit = 24;
        let b = run_light_map(&o).unwrap();
        println!(
            "{seed:>4} | {:>21} {:>5} | {:>18} {:>5}",
            a.recognitions, a.ended, b.recognitions, b.ended
        );
        for v in a.visits.iter().chain(&b.visits).take(3) {
            println!("       {}", serde_json::to_string(v).unwrap());
        }
        assert!(
            (2..=12).contains(&a.recognitions) && a.ended == "lost",
            "seed {seed} without correction: {a:?}"
        );
        assert_eq!(b.recognitions, 24, "seed {seed} with correction: {b:?}");
        assert_eq!(b.ended, "limit");
        without.push(f64::from(a.recognitions));
    }
    let mean = without.iter().sum::<f64>() / without.len() as f64;
    println!("without correction: mean {mean:.1} recognitions (paper 5); with: all 24 (paper 24)");
    assert!((3.0..=9.0).contains(&mean), "{mean}");
}

#[test]
fn the_same_seed_gives_the_same_run() {
    let o = LightMapOptions {
        limit: 3,
        ..LightMapOptions::new(7, true)
    };
    assert_eq!(run_light_map(&o).unwrap(), run_light_map(&o).unwrap());
}
