//! Station performance: telemetry decode throughput, replay throughput, frame render time,
//! export time.
//!
//! - `decode/link_machine`: telemetry frames per second through the station's own receive
//!   path (`LinkMachine::receive`: COBS, CRC, postcard, sequence accounting, events), fed in
//!   64-byte reads as a serial port delivers them; `decode/link_machine_and_app` adds
//!   `App::update` for each event (history, tracks), which is what the TUI does per frame.
//! - `replay/summary_60s_50hz`: `station replay --json` of a minute at 50 Hz (telemetry and
//!   truth), records to summary.
//! - `render/dashboard_120x40`, `render/dashboard_200x60`, `render/map_200x60`: one whole
//!   frame into a `TestBackend`, with the state of a robot that has been driving for 60 s at
//!   50 Hz on the built-in arena (full chart history and tracks).
//! - `export/csv_60s_50hz`, `export/mcap_60s_50hz`: formatting into memory.
//! - `ten_minutes/{summary,csv,mcap,mcap_json}`: issue 15's figures, each whole command's work on ten
//!   minutes at 50 Hz (about 30,000 telemetry and 30,000 truth frames) from the file's bytes:
//!   parsing the recording (every record's CRC) and then the summary, or the export written
//!   through a `BufWriter` as `station export` writes its file (here into memory). Target:
//!   each at most 0.1 s. `mcap` is the default encoding (protobuf for the topics of every
//!   frame), `mcap_json` the `--mcap-encoding json` one. `PERF_TEN_MINUTES=summary` (or `csv`,
//!   `mcap`, `mcap_json`, `none`) runs only that piece once, for `perf stat -e task-clock` or
//!   callgrind against `none`.
//!
//! `cargo bench -p station --bench perf` prints a one-shot summary (stderr), then runs the
//! criterion groups with 10 samples and short measurement times (2-core machines). Without
//! `--bench` (`cargo test --all-targets`) it only prints the one-shot summary, as a smoke test.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{Criterion, Throughput};
use protocol::{encode, Message, MAX_FRAME};
use ratatui::backend::TestBackend;
use ratatui::Terminal;
use station::action::Action;
use station::app::arena::ArenaOverlay;
use station::app::{App, AppOptions, View};
use station::export::mcap::Encoding;
use station::link::machine::{LinkMachine, MachineConfig};
use station::record::synth::{demo, telemetry};
use station::record::Recording;
use station::replay::summary::summarize;
use station::replay::ReplayFeed;

/// Telemetry frames in one decode batch.
const BATCH: usize = 1000;

fn telemetry_bytes() -> Vec<u8> {
    let mut out = Vec::new();
    let mut buf = [0u8; MAX_FRAME];
    for i in 0..BATCH {
        let n = encode(
            i as u16,
            &Message::Telemetry(telemetry(i as u32, 50)),
            &mut buf,
        )
        .unwrap();
        out.extend_from_slice(&buf[..n]);
    }
    out
}

fn machine() -> LinkMachine {
    let mut m = LinkMachine::new(MachineConfig {
        station: "bench".into(),
        nonce_seed: 1,
    });
    m.port_opened(0, "bench");
    let _ = m.take_output();
    let _ = m.take_events();
    m
}

fn decode(m: &mut LinkMachine, bytes: &[u8]) -> usize {
    for chunk in bytes.chunks(64) {
        m.receive(1, chunk);
    }
    m.take_events().len()
}

fn decode_into_app(m: &mut LinkMachine, app: &mut App, bytes: &[u8]) -> usize {
    let mut n = 0;
    for chunk in bytes.chunks(64) {
        m.receive(1, chunk);
        for ev in m.take_events() {
            app.update(Action::Link(ev));
            n += 1;
        }
    }
    n
}

/// An app after `seconds` of a robot at `hz`, on the built-in arena.
fn driven_app(seconds: u32, hz: u32, size: (u16, u16)) -> App {
    let rec = Recording::parse_strict(&demo(seconds, hz)).unwrap();
    let arena = emulator::builtin::load(emulator::builtin::MICRO_RATO_99, &Default::default())
        .ok()
        .map(|a| ArenaOverlay::from_arena(&a));
    let mut app = App::new(AppOptions {
        port_label: "bench".into(),
        arena,
        ..AppOptions::default()
    });
    app.update(Action::Resize {
        width: size.0,
        height: size.1,
    });
    let mut feed = ReplayFeed::new("bench");
    let mut actions = Vec::new();
    feed.advance_to(&rec.records, rec.duration_us(), &mut actions);
    for a in actions {
        app.update(a.into());
    }
    app
}

fn draw(term: &mut Terminal<TestBackend>, app: &App) {
    term.draw(|f| station::ui::render(app, f)).unwrap();
}

fn time_per<T>(n: u32, mut f: impl FnMut() -> T) -> Duration {
    let t0 = Instant::now();
    for _ in 0..n {
        black_box(f());
    }
    t0.elapsed() / n
}

/// Issue 15's commands on a recording's bytes: parse, then summarise or export.
/// What each returns is printed beside its time: records (summary), rows (csv), bytes (mcap).
type Work = fn(&[u8]) -> usize;

fn ten_minutes() -> [(&'static str, Work); 4] {
    [
        ("summary", |bytes| {
            let rec = Recording::parse_strict(bytes).unwrap();
            black_box(summarize(&rec));
            rec.records.len()
        }),
        ("csv", |bytes| {
            let rec = Recording::parse_strict(bytes).unwrap();
            let mut out = std::io::BufWriter::new(Vec::with_capacity(16 << 20));
            station::export::csv::write(&rec, &mut out).unwrap()
        }),
        ("mcap", |bytes| mcap(bytes, Encoding::Protobuf)),
        ("mcap_json", |bytes| mcap(bytes, Encoding::Json)),
    ]
}

/// `station export --mcap` of a recording's bytes into memory, in `enc`; the file's bytes.
fn mcap(bytes: &[u8], enc: Encoding) -> usize {
    let rec = Recording::parse_strict(bytes).unwrap();
    let mut out = std::io::BufWriter::new(Vec::with_capacity(64 << 20));
    station::export::mcap::write(&rec, enc, &mut out, std::path::Path::new("bench.mcap")).unwrap();
    out.into_inner().unwrap().len()
}

/// One-shot figures, printed even without `--bench`.
fn summary() {
    let bytes = telemetry_bytes();
    let mut m = machine();
    let per_batch = time_per(20, || decode(&mut m, &bytes));
    eprintln!(
        "decode: {:.0} telemetry frames/s through LinkMachine ({:.2} us per frame)",
        BATCH as f64 / per_batch.as_secs_f64(),
        per_batch.as_secs_f64() * 1e6 / BATCH as f64
    );
    let mut app = App::new(AppOptions::default());
    let per_batch = time_per(20, || decode_into_app(&mut m, &mut app, &bytes));
    eprintln!(
        "decode+app: {:.0} telemetry frames/s",
        BATCH as f64 / per_batch.as_secs_f64()
    );
    let rec = Recording::parse_strict(&demo(60, 50)).unwrap();
    let t = time_per(3, || summarize(&rec));
    eprintln!(
        "replay summary of 60 s at 50 Hz: {:.1} ms ({:.0}x real time)",
        t.as_secs_f64() * 1e3,
        60.0 / t.as_secs_f64()
    );
    let ten = demo(600, 50);
    for (name, f) in ten_minutes() {
        let mut n = 0;
        let t = time_per(3, || n = f(&ten));
        eprintln!(
            "ten minutes at 50 Hz, {name}: {:.1} ms ({n})",
            t.as_secs_f64() * 1e3
        );
    }
    for (w, h, view) in [
        (120, 40, View::Dashboard),
        (200, 60, View::Dashboard),
        (200, 60, View::Map),
    ] {
        let mut app = driven_app(60, 50, (w, h));
        app.update(Action::ShowView(view));
        let mut term = Terminal::new(TestBackend::new(w, h)).unwrap();
        let t = time_per(20, || draw(&mut term, &app));
        eprintln!(
            "render {view:?} at {w}x{h}: {:.2} ms per frame",
            t.as_secs_f64() * 1e3
        );
    }
}

fn main() {
    // `PERF_TEN_MINUTES=summary|csv|mcap|mcap_json|none`: only that piece, once, after building the
    // recording, so that `perf stat` or `valgrind --tool=callgrind` can count its CPU time or
    // instructions against `none` on a machine too loaded for wall-clock timings.
    if let Ok(which) = std::env::var("PERF_TEN_MINUTES") {
        let ten = demo(600, 50);
        for (name, f) in ten_minutes() {
            if name == which {
                eprintln!("{name}: {}", f(&ten));
            }
        }
        return;
    }
    summary();
    if !std::env::args().any(|a| a == "--bench") {
        return;
    }
    let mut c = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2))
        .configure_from_args();

    let bytes = telemetry_bytes();
    let mut g = c.benchmark_group("decode");
    g.throughput(Throughput::Elements(BATCH as u64));
    let mut m = machine();
    g.bench_function("link_machine", |b| b.iter(|| decode(&mut m, &bytes)));
    let mut app = App::new(AppOptions::default());
    g.bench_function("link_machine_and_app", |b| {
        b.iter(|| decode_into_app(&mut m, &mut app, &bytes))
    });
    g.finish();

    let rec = Recording::parse_strict(&demo(60, 50)).unwrap();
    let mut g = c.benchmark_group("replay");
    g.throughput(Throughput::Elements(rec.records.len() as u64));
    g.bench_function("summary_60s_50hz", |b| b.iter(|| summarize(&rec)));
    g.finish();

    let mut g = c.benchmark_group("render");
    for (name, w, h, view) in [
        ("dashboard_120x40", 120, 40, View::Dashboard),
        ("dashboard_200x60", 200, 60, View::Dashboard),
        ("map_200x60", 200, 60, View::Map),
    ] {
        let mut app = driven_app(60, 50, (w, h));
        app.update(Action::ShowView(view));
        let mut term = Terminal::new(TestBackend::new(w, h)).unwrap();
        g.bench_function(name, |b| b.iter(|| draw(&mut term, &app)));
    }
    g.finish();

    let mut g = c.benchmark_group("export");
    g.bench_function("csv_60s_50hz", |b| {
        b.iter(|| {
            let mut out = Vec::with_capacity(4 << 20);
            station::export::csv::write(&rec, &mut out).unwrap()
        })
    });
    g.bench_function("mcap_60s_50hz", |b| {
        b.iter(|| {
            let out = Vec::with_capacity(16 << 20);
            station::export::mcap::write(
                &rec,
                Encoding::Protobuf,
                out,
                std::path::Path::new("bench.mcap"),
            )
            .unwrap()
        })
    });
    g.finish();

    let ten = demo(600, 50);
    let mut g = c.benchmark_group("ten_minutes");
    for (name, f) in ten_minutes() {
        g.bench_function(name, |b| b.iter(|| f(&ten)));
    }
    g.finish();
    c.final_summary();
}
