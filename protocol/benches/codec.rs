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

    // Link authentication (PROTOCOL.md §13): the same frame signed, and received with its
    // signature verified (MAC and replay window).
    let key = LinkKey::new(&[0x5a; 32]);
    let mut signed = [0u8; MAX_FRAME];
    let ts = 0x1f92_d63c_e000;
    let binding = Binding::new(0x2a5c_7e19, 1);
    let sn =
        encode_signed(1, &msg, &key, &binding, sign::ROBOT_LINK, ts, &mut signed).expect("fits");
    eprintln!("signed telemetry frame on the wire: {sn} bytes");
    let mut g = c.benchmark_group("signed_telemetry");
    g.throughput(Throughput::Elements(1));
    g.bench_function("encode_and_sign", |b| {
        let mut auth = LinkAuth::new(Some(key.clone()), sign::ROBOT_LINK);
        let mut out = [0u8; MAX_FRAME];
        b.iter(|| auth.encode(black_box(7), black_box(&msg), 0, &mut out))
    });
    g.bench_function("decode_and_verify", |b| {
        let mut dec = FrameDecoder::new();
        let mut auth = LinkAuth::new(Some(key.clone()), sign::STATION_LINK);
        auth.bind(binding);
        b.iter(|| match dec.feed(black_box(&signed[..sn])) {
            Feed::Frame { frame, .. } => {
                // The same frame again is stale: the verdict costs the MAC either way, and
                // resetting the window keeps each iteration a first sighting.
                auth.reset_replay(0);
                auth.verify(&frame)
            }
            _ => unreachable!("a valid frame"),
        })
    });
    g.bench_function("hmac_only", |b| {
        let covered = &signed[..sn - 12];
        b.iter(|| key.mac(&binding, black_box(covered)))
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
