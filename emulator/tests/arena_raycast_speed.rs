//! Ray-cast throughput on real arenas: the emulator needs ~10,000x real time with 8 IR sensors
//! at 12.5 Hz, i.e. 10^6 rays per second. Timing on a shared machine is noisy, so this is
//! ignored by default; run it with
//! `cargo test --release -p emulator --test arena_raycast_speed -- --ignored --nocapture`.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::Path;
use std::time::Instant;

use emulator::arena::{load, LoadOptions};
use emulator::geometry::{Point, SegmentSet, Vector};

/// Rays per second over `n` random free poses x 8 directions, and the hit count as a checksum.
fn rays_per_second(
    arena: &emulator::arena::Arena,
    set: &SegmentSet,
    range: f64,
    n: usize,
) -> (f64, usize) {
    let mut seed = 12345u64;
    let mut rnd = move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let b = arena.bounds;
    let mut poses = Vec::with_capacity(n);
    while poses.len() < n {
        let p = Point::new(b.min.x + rnd() * b.width(), b.min.y + rnd() * b.height());
        if !arena.is_solid(p) {
            poses.push((p, rnd() * std::f64::consts::TAU));
        }
    }
    let dirs: Vec<f64> = (0..8)
        .map(|i| i as f64 * std::f64::consts::TAU / 8.0)
        .collect();
    let t0 = Instant::now();
    let mut hits = 0;
    for (p, h) in &poses {
        for d in &dirs {
            let a = h + d;
            hits += usize::from(
                set.ray_cast(*p, Vector::new(a.cos(), a.sin()), range)
                    .is_some(),
            );
        }
    }
    ((n * 8) as f64 / t0.elapsed().as_secs_f64(), hits)
}

#[test]
#[ignore = "timing; run in release by hand"]
fn ray_casts_reach_a_million_per_second_on_real_arenas() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/arenas");
    for file in [
        "ciberrato/wallsMicRato99.xml",
        "ciberrato/Ciber2005_FinalLab.xml",
        "micromouse/japan2016hef.txt",
    ] {
        let arena = load(&dir.join(file), &LoadOptions::default()).unwrap();
        let indexed = arena.segment_set();
        let flat = SegmentSet::unindexed(arena.segments());
        for range in [0.3, f64::INFINITY] {
            let (fast, h1) = rays_per_second(&arena, &indexed, range, 200_000);
            let (slow, h2) = rays_per_second(&arena, &flat, range, 200_000);
            assert_eq!(h1, h2, "index and flat scan disagree");
            println!(
                "{file}: {} segments (indexed: {}), range {range}: {:.2e} rays/s indexed, {:.2e} flat",
                indexed.len(),
                indexed.is_indexed(),
                fast,
                slow
            );
            if range.is_finite() {
                assert!(fast > 1e6, "{file}: {fast:.2e} rays/s is below 10^6");
            }
        }
    }
}
