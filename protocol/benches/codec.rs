//! Encode and decode of one full telemetry frame, in ns per frame.

#![allow(clippy::unwrap_used, clippy::panic)]

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use protocol::*;
use std::hint::black_box;

fn telemetry() -> Telemetry {
    Telemetry {
        time_ms: 123_456,
        mode: Mode::Explore,
        pose: Pose {
            x_mm: 2500,
            y_mm: -1200,
            heading_mrad: 1571,
        },
        sigma: PoseSigma {
            xy_mm: 40,
            heading_mrad: 35,
        },
        wheels: Wheels {
            speed_mm_s: [180, 220],
            encoders: [40_000, 41_000],
        },
        ir: Packed10x8::new([12, 40, 300, 900, 1023, 80, 3, 0]),
        light: Packed10x8::new([480, 470, 460, 200, 210, 490, 500, 500]),
        compass_ddeg: 900,
        flags: flags::HAS_MAP,
        line_events: 17,
        beacon: Beacon {
            bearing_ddeg: -450,
            strength: 200,
        },
        battery_mv: 7400,
        behaviour: BehaviourOut {
            active: behaviours::AVOID,
            motor_mm_s: [180, 220],
        },
        cycle: CycleTiming {
            period_us: 80_000,
            busy_us: 350,
            overruns: 0,
        },
    }
}

fn codec(c: &mut Criterion) {
    let msg = Message::Telemetry(telemetry());
    let mut wire = [0u8; MAX_FRAME];
    let n = encode(1, &msg, &mut wire).expect("fits");
    eprintln!("telemetry frame on the wire: {n} bytes");

    let mut g = c.benchmark_group("telemetry");
    g.throughput(Throughput::Elements(1));
    g.bench_function("encode", |b| {
        let mut out = [0u8; MAX_FRAME];
        b.iter(|| encode(black_box(7), black_box(&msg), &mut out))
    });
    g.bench_function("decode", |b| {
        let mut dec = FrameDecoder::new();
        b.iter(|| match dec.feed(black_box(&wire[..n])) {
            Feed::Frame { frame, .. } => frame.header.seq,
            _ => unreachable!("a valid frame"),
        })
    });
    g.finish();

    // Decode throughput over a long stream of frames, in bytes.
    let stream: Vec<u8> = (0..1000).flat_map(|_| wire[..n].iter().copied()).collect();
    let mut g = c.benchmark_group("stream");
    g.throughput(Throughput::Bytes(stream.len() as u64));
    g.bench_function("decode_1000_telemetry_frames", |b| {
        let mut dec = FrameDecoder::new();
        b.iter(|| {
            let mut input = black_box(&stream[..]);
            let mut frames = 0u32;
            loop {
                match dec.feed(input) {
                    Feed::NeedMore => break,
                    Feed::Frame { rest, .. } => {
                        frames += 1;
                        input = rest;
                    }
                    Feed::Error { rest, .. } => input = rest,
                }
            }
            frames
        })
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(50).measurement_time(std::time::Duration::from_secs(2));
    targets = codec
}
criterion_main!(benches);
