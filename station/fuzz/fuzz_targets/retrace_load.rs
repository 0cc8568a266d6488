//! The retrace reader (`station retrace`, `station replay --retrace`) on arbitrary bytes: the
//! loader, then the firmware's own code played over the hardware trace it found. Bytes that
//! are no recording are played as a trace themselves, so the fuzzer reaches the playback
//! without first building CRC'd records and frames. Invariants: no panic; every offset the
//! loader keeps lies inside the file; the work is in proportion to the trace (issue 31: one
//! 8-byte entry claimed 2^32 - 1 passes): at most two control periods of passes, 160,000 for
//! the Khepera's 80 ms, per byte of trace.
#![no_main]

use libfuzzer_sys::fuzz_target;
use station::retrace::load::{load, Loaded};
use station::retrace::run::retrace;

/// The most passes a trace may make between two control cycles (two of the longest period).
const PASSES_PER_CYCLE: u64 = 160_000;

fuzz_target!(|data: &[u8]| {
    let loaded = match load(data) {
        Ok(l) => {
            for &(at, file_offset) in &l.trace_map {
                assert!(at <= l.trace.len() && file_offset < data.len() as u64);
            }
            assert!(l.frames.iter().all(|f| f.file_offset < data.len() as u64));
            l
        }
        // A recording spanning an hour, whose trace is these bytes.
        Err(_) => Loaded {
            trace: data.to_vec(),
            trace_map: vec![(0, 0)],
            span_us: 3_600_000_000,
            ..Loaded::default()
        },
    };
    if loaded.trace.is_empty() {
        return;
    }
    // With the recorded parameters and with one changed, as `--param` does.
    let changed = station::retrace::parse_param("odo_wheel_distance_mm=40").ok();
    for params in [None, changed] {
        if let Ok(run) = retrace(&loaded, params.as_slice(), None) {
            let bound = (loaded.trace.len() as u64 + 1) * (PASSES_PER_CYCLE + 1);
            assert!(run.steps <= bound, "{} passes from {} bytes", run.steps, loaded.trace.len());
            assert!(run.cycles <= run.steps);
        }
    }
});
