//! Map upload goodput over a simulated 115200-baud line, as a share of the line rate.
//!
//! The station's I/O-free link machine (`LinkMachine`) and transfer engine (`TransferEngine`)
//! run in lockstep, millisecond by millisecond, with the emulator's simulation (`Sim`: the real
//! firmware and its UART at 115200 baud, 10 bits a byte) through the emulator's fault injector
//! in both directions, as `tests/noisy_link.rs` does. Every clock is the simulation's, so the
//! figure is the protocol's and not this machine's load.
//!
//! Each seed: a fresh robot, a handshake, a settling time of about a second (its phase against
//! the robot's telemetry varies with the seed), or none, then one upload of a 64 x 64 map (1,060 bytes, distinct per
//! seed). Goodput = object bytes / (submission to the engine's `Finished`), reported as a
//! percentage of the line rate (11,520 B/s) over all seeds: median, p10, p90. Conditions:
//! a clean line, and 1 % and 5 % of bytes dropped both ways, each upload begun after the
//! line settled (the TUI's case: the station has measured the line's loss); and a clean line
//! and 1 % with the upload begun as the handshake completes (the command line's case:
//! `station upload-map` uploads at once, before anything is known of the line).
//!
//! `cargo bench -p station --bench transfer_goodput -- --json [--seeds N]` prints the JSON
//! report (default 200 seeds); without `--json` a table. Under `cargo test --all-targets` it
//! runs 3 seeds as a smoke test.
#![allow(clippy::unwrap_used, clippy::panic)]

use emulator::fault::{FaultConfig, FaultInjector};
use emulator::sim::{Sim, SimConfig};
use protocol::transfer::SenderStats;
use protocol::ObjectKind;
use robot_firmware::nav::{grid_bytes, Cell, Geometry, Grid};
use robot_firmware::transfer::{encode_map_object, MAP_OBJECT_MAX};
use station::link::{LinkMachine, MachineConfig, TransferOut};
use station::transfer::{EngineOut, JobOutcome, JobSpec, TransferEngine, TransferEvent};

const BAUD: u32 = 115_200;
/// Bytes per second the line carries (8N1: 10 bits a byte).
const LINE_RATE: f64 = BAUD as f64 / 10.0;
/// Simulated time an upload may take before the run counts it as failed, ms.
const GIVE_UP_MS: u64 = 60_000;

/// One upload's result.
struct Run {
    ok: bool,
    elapsed_ms: u64,
    /// Chunk data bytes the station put on the wire (retransmissions included).
    chunk_bytes: u64,
    /// The sender's counts when it finished.
    stats: SenderStats,
    /// The chunk size the upload started with, bytes (0: it never started).
    first_chunk: u32,
}

/// A 64 x 64 map of mixed cells, distinct for each seed.
fn map_bytes(seed: u64) -> Vec<u8> {
    let (w, h) = (64usize, 64usize);
    let mut g = Grid::new(64, 64, Geometry::SEED_004, vec![0; grid_bytes(w, h)]).unwrap();
    let mut x = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    for i in 0..w * h {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        let c = [Cell::Free, Cell::Obstacle, Cell::Unknown][(x % 3) as usize];
        g.set(i % w, i / w, c).unwrap();
    }
    let mut bytes = vec![0; MAP_OBJECT_MAX];
    let n = encode_map_object(&g, None, None, &mut bytes).unwrap();
    bytes.truncate(n);
    bytes
}

/// When an upload begins.
#[derive(Clone, Copy)]
enum Start {
    /// Past the handshake's traffic, at a phase that varies with the seed.
    Settled,
    /// As the handshake completes.
    AtConnect,
}

/// One upload on a fresh robot over a line that drops `drop_rate` of its bytes both ways.
fn run(seed: u64, drop_rate: f64, start: Start) -> Run {
    let arena =
        emulator::builtin::load(emulator::builtin::MICRO_RATO_99, &Default::default()).unwrap();
    let mut cfg = SimConfig::new(&robot_firmware::MICRO_RATO);
    cfg.seed = seed;
    let mut sim = Sim::new(arena, cfg).unwrap();
    let noise = FaultConfig {
        drop_rate,
        flip_rate: 0.0,
        stall: None,
    };
    let mut to_robot = FaultInjector::new(noise, seed, 1);
    let mut from_robot = FaultInjector::new(noise, seed, 2);
    let mut link = LinkMachine::new(MachineConfig {
        station: "goodput".into(),
        nonce_seed: seed,
    });
    link.port_opened(0, "sim");
    let mut engine = TransferEngine::new();
    let bytes = map_bytes(seed);
    let mut wire = Vec::new();
    let mut connected_at = None;
    let mut started = None;
    let mut chunk_bytes = 0u64;
    let mut stats = SenderStats::default();
    let mut first_chunk = 0;
    // GOODPUT_TRACE=<seed>: that seed's link events and frames out, on stderr.
    let trace = std::env::var("GOODPUT_TRACE").is_ok_and(|t| t == seed.to_string());
    loop {
        sim.step();
        let now = sim.now_us() / 1000;
        let t_s = now as f64 / 1000.0;
        let raw = sim.uart_mut().take_outbound();
        wire.clear();
        from_robot.apply(&raw, t_s, &mut wire);
        if !wire.is_empty() {
            link.receive(now, &wire);
        }
        link.poll(now);
        if connected_at.is_none() && link.connected() {
            connected_at = Some(now);
        }
        // Settle past the handshake's traffic, at a phase that varies with the seed.
        let settle = match start {
            // About a second of telemetry: enough for the station to call a clean line
            // clean (the engine's CLEAN_EVIDENCE_FRAMES).
            Start::Settled => 1000 + seed % 97,
            // The engine has seen the session begin (the loop below, last millisecond).
            Start::AtConnect => 1,
        };
        if let (Some(c), None) = (connected_at, started) {
            if now >= c + settle {
                engine.submit(JobSpec::Upload {
                    object: ObjectKind::Map,
                    bytes: bytes.clone(),
                });
                started = Some(now);
            }
        }
        engine.poll(now);
        loop {
            let mut busy = false;
            for ev in link.take_events() {
                busy = true;
                if trace {
                    eprintln!("{now} ev {ev:?}");
                }
                engine.on_link_event(now, &ev);
            }
            for o in engine.take_output() {
                busy = true;
                match o {
                    EngineOut::Frame(f) => {
                        if trace {
                            eprintln!("{now} out {f:?}");
                        }
                        if let TransferOut::Chunk { data, .. } = &f {
                            chunk_bytes += data.len() as u64;
                        }
                        link.send_transfer(now, &f);
                    }
                    EngineOut::Command { id, command } => link.submit(now, id, command),
                }
            }
            if let Some(s) = engine.upload_stats() {
                stats = s;
            }
            if first_chunk == 0 {
                first_chunk = engine.upload_chunk().unwrap_or(0);
            }
            for ev in engine.take_events() {
                if let TransferEvent::Finished(r) = ev {
                    let ok = matches!(r.outcome, JobOutcome::Complete);
                    return Run {
                        ok,
                        elapsed_ms: r.elapsed_ms,
                        chunk_bytes,
                        stats,
                        first_chunk,
                    };
                }
            }
            if !busy {
                break;
            }
        }
        let out = link.take_output();
        wire.clear();
        to_robot.apply(&out, t_s, &mut wire);
        if !wire.is_empty() {
            sim.uart_mut().push_inbound(&wire);
        }
        if started.is_some_and(|s| now > s + GIVE_UP_MS) || (started.is_none() && now > 10_000) {
            return Run {
                ok: false,
                elapsed_ms: GIVE_UP_MS,
                chunk_bytes,
                stats,
                first_chunk,
            };
        }
    }
}

/// The `q` quantile (nearest rank) of sorted values.
fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let i = ((sorted.len() - 1) as f64 * q).round() as usize;
    sorted[i.min(sorted.len() - 1)]
}

/// The five slowest uploads: seed, time and the sender's counts (where a tail comes from).
fn slowest(runs: &[Run]) -> serde_json::Value {
    let mut by_time: Vec<(u64, &Run)> = (1..).zip(runs).collect();
    by_time.sort_by_key(|(_, r)| std::cmp::Reverse(r.elapsed_ms));
    by_time
        .iter()
        .take(5)
        .map(|(seed, r)| {
            let s = &r.stats;
            serde_json::json!({
                "seed": seed, "elapsed_ms": r.elapsed_ms, "chunks": s.chunks,
                "resent_chunks": s.resent, "units_found_lost": s.lost_units,
                "probes": s.probes, "timer_expiries": s.timeouts,
                "first_chunk": r.first_chunk,
            })
        })
        .collect()
}

/// How the uploads started: per first chunk size, how many and their median time, ms (the
/// first upload on a fresh link starts before the station has measured the line's loss).
fn first_chunks(runs: &[Run]) -> serde_json::Value {
    let mut by: std::collections::BTreeMap<u32, Vec<f64>> = Default::default();
    for r in runs {
        by.entry(r.first_chunk)
            .or_default()
            .push(r.elapsed_ms as f64);
    }
    by.into_iter()
        .map(|(c, mut ms)| {
            ms.sort_by(f64::total_cmp);
            serde_json::json!({"chunk": c, "uploads": ms.len(), "median_ms": quantile(&ms, 0.5),
                               "max_ms": quantile(&ms, 1.0)})
        })
        .collect()
}

/// The mean of one sender count over the runs.
fn mean(runs: &[Run], f: impl Fn(&SenderStats) -> u32) -> f64 {
    runs.iter().map(|r| f64::from(f(&r.stats))).sum::<f64>() / runs.len().max(1) as f64
}

fn condition(name: &str, drop_rate: f64, start: Start, seeds: u64) -> serde_json::Value {
    let len = map_bytes(0).len() as f64;
    let runs: Vec<Run> = (1..=seeds).map(|s| run(s, drop_rate, start)).collect();
    let ok = runs.iter().filter(|r| r.ok).count();
    let failed: Vec<u64> = (1..=seeds)
        .zip(&runs)
        .filter(|(_, r)| !r.ok)
        .map(|(s, _)| s)
        .collect();
    // A failed upload counts as zero goodput, so it can only pull the figures down.
    let mut pct: Vec<f64> = runs
        .iter()
        .map(|r| {
            if r.ok {
                len / (r.elapsed_ms.max(1) as f64 / 1000.0) / LINE_RATE * 100.0
            } else {
                0.0
            }
        })
        .collect();
    pct.sort_by(f64::total_cmp);
    let mut ms: Vec<f64> = runs.iter().map(|r| r.elapsed_ms as f64).collect();
    ms.sort_by(f64::total_cmp);
    let sent: f64 = runs.iter().map(|r| r.chunk_bytes as f64).sum::<f64>() / runs.len() as f64;
    serde_json::json!({
        "condition": name,
        "drop_rate": drop_rate,
        "seeds": seeds,
        "object_bytes": len,
        "completed": ok,
        "failed_seeds": failed,
        "goodput_pct_of_line_rate": {
            "median": quantile(&pct, 0.5), "p10": quantile(&pct, 0.1), "p90": quantile(&pct, 0.9),
        },
        "goodput_b_per_s_median": quantile(&pct, 0.5) * LINE_RATE / 100.0,
        "elapsed_ms": {"median": quantile(&ms, 0.5), "p10": quantile(&ms, 0.1),
                       "p90": quantile(&ms, 0.9), "max": quantile(&ms, 1.0)},
        "chunk_bytes_sent_per_object_byte": sent / len,
        "first_chunk": first_chunks(&runs),
        "slowest": slowest(&runs),
        "per_upload_mean": {
            "chunks": mean(&runs, |s| s.chunks),
            "resent_chunks": mean(&runs, |s| s.resent),
            "units_found_lost": mean(&runs, |s| s.lost_units),
            "probes": mean(&runs, |s| s.probes),
            "timer_expiries": mean(&runs, |s| s.timeouts),
        },
    })
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let bench = args.iter().any(|a| a == "--bench");
    let json = args.iter().any(|a| a == "--json");
    let seeds = args
        .iter()
        .position(|a| a == "--seeds")
        .and_then(|i| args.get(i + 1))
        .and_then(|s| s.parse().ok())
        .unwrap_or(if bench { 200 } else { 3 });
    let report = serde_json::json!({
        "baud": BAUD,
        "line_rate_b_per_s": LINE_RATE,
        "conditions": [
            condition("clean", 0.0, Start::Settled, seeds),
            condition("drop_1pct", 0.01, Start::Settled, seeds),
            condition("drop_5pct", 0.05, Start::Settled, seeds),
            condition("clean_at_connect", 0.0, Start::AtConnect, seeds),
            condition("drop_1pct_at_connect", 0.01, Start::AtConnect, seeds),
        ],
    });
    if json {
        println!("{}", serde_json::to_string_pretty(&report).unwrap());
        return;
    }
    for c in report["conditions"].as_array().unwrap() {
        let g = &c["goodput_pct_of_line_rate"];
        println!(
            "{:<20} {}/{} complete; goodput % of line rate: median {:.1}, p10 {:.1}, p90 {:.1}; \
             median {:.0} ms; {:.2} chunk bytes sent per object byte; per upload {}",
            c["condition"].as_str().unwrap(),
            c["completed"],
            c["seeds"],
            g["median"].as_f64().unwrap(),
            g["p10"].as_f64().unwrap(),
            g["p90"].as_f64().unwrap(),
            c["elapsed_ms"]["median"].as_f64().unwrap(),
            c["chunk_bytes_sent_per_object_byte"].as_f64().unwrap(),
            c["per_upload_mean"],
        );
    }
}
