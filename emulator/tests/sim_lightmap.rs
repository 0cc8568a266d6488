//! Seed 000 §6.1 in the emulator: light-source mapping with and without local correction
//! (emulator/src/scenarios/lightmap.rs). Paper (one real run each, 75 x 60 cm box, one
//! source): without correction the source was recognised 5 times; with correction the run
//! was stopped after 24 recognitions.
//!
//! Seeds 1-10, the emulator's default noise, the simulated wheels 53.3 mm apart. Measured on
//! this firmware: without correction the source is lost on every seed after 3-19
//! recognitions (mean 8.4, median 7.5; the paper's 5 is one sample of this spread); with
//! correction 9 of 10 seeds still recognise it when the harness stops them at 30
//! recognitions (its own limit, `LightMapOptions::limit`, not a result) and seed 10 loses it
//! after 28. Asserted: without correction every seed loses the source, after 1-25
//! recognitions, mean 4-14; with correction every seed recognises it at least the paper's 24
//! times and more often than without. Run with `--nocapture` for the table.
#![allow(clippy::unwrap_used, clippy::panic)]

use emulator::scenarios::lightmap::{run_light_map, LightMapOptions};

const SEEDS: std::ops::RangeInclusive<u64> = 1..=10;

#[test]
fn local_correction_keeps_the_source_recognised() {
    println!("seed | without: recognitions ended | with: recognitions ended");
    let mut without = Vec::new();
    let mut at_limit = 0;
    for seed in SEEDS {
        let a = run_light_map(&LightMapOptions::new(seed, false)).unwrap();
        let b = run_light_map(&LightMapOptions::new(seed, true)).unwrap();
        println!(
            "{seed:>4} | {:>21} {:>5} | {:>18} {:>5}",
            a.recognitions, a.ended, b.recognitions, b.ended
        );
        assert!(
            (1..=25).contains(&a.recognitions) && a.ended == "lost",
            "seed {seed} without correction: {a:?}"
        );
        assert!(
            b.recognitions >= 24 && b.recognitions > a.recognitions,
            "seed {seed} with correction: {b:?}"
        );
        at_limit += u32::from(b.ended == "limit");
        without.push(f64::from(a.recognitions));
    }
    without.sort_by(f64::total_cmp);
    let mean = without.iter().sum::<f64>() / without.len() as f64;
    println!(
        "without correction: {:.0}-{:.0} recognitions, mean {mean:.1} (paper 5); with: {at_limit} \
         of {} still recognised at the {}-recognition stop (paper: stopped at 24)",
        without[0],
        without[without.len() - 1],
        SEEDS.count(),
        LightMapOptions::new(0, true).limit
    );
    assert!((4.0..=14.0).contains(&mean), "{mean}");
}

#[test]
fn the_same_seed_gives_the_same_run() {
    let o = LightMapOptions {
        limit: 3,
        ..LightMapOptions::new(7, true)
    };
    assert_eq!(run_light_map(&o).unwrap(), run_light_map(&o).unwrap());
}
