//! Soak: telemetry at the robot's maximum rate (50 Hz) for a long simulated time, consumed by
//! the station's link machine and its whole UI state (`App::update`), in lockstep with the
//! emulator's simulation on simulated time (as `noisy_link.rs` does, with a clean line).
//!
//! Every retained structure must stay within its cap however long the run: the charts'
//! history, the believed and true tracks, the log, the statistics history, the link's
//! pending commands. The regular test runs 3 simulated minutes (enough to fill the charts'
//! history several times over); the ignored one runs `SOAK_MINUTES` (default 60) and prints
//! the process's resident set every 5 simulated minutes, as JSON with `SOAK_JSON=path`:
//!   cargo test -p station --test soak -- --ignored --nocapture
#![allow(clippy::unwrap_used, clippy::panic)]

use emulator::sim::{Sim, SimConfig};
use protocol::{Command, Mode};
use station::action::Action;
use station::app::history::{Series, HISTORY, TRACK};
use station::app::log::LOG_LINES;
use station::app::{App, AppOptions};
use station::link::{LinkEvent, LinkMachine, MachineConfig};

struct Soak {
    sim: Sim,
    link: LinkMachine,
    app: App,
    now_ms: u64,
    telemetry: u64,
    next_id: u64,
    /// The rate and mode commands went out.
    started: bool,
}

impl Soak {
    fn new() -> Soak {
        let arena =
            emulator::builtin::load(emulator::builtin::MICRO_RATO_99, &Default::default()).unwrap();
        let mut cfg = SimConfig::new(&robot_firmware::MICRO_RATO);
        cfg.seed = 5;
        let mut link = LinkMachine::new(MachineConfig {
            station: "soak".into(),
            nonce_seed: 5,
        });
        link.port_opened(0, "sim");
        Soak {
            sim: Sim::new(arena, cfg).unwrap(),
            link,
            app: App::new(AppOptions {
                port_label: "soak".into(),
                arena: None,
                ..AppOptions::default()
            }),
            now_ms: 0,
            telemetry: 0,
            next_id: 1 << 40,
            started: false,
        }
    }

    fn step(&mut self) {
        self.sim.step();
        self.now_ms = self.sim.now_us() / 1000;
        let now = self.now_ms;
        let mut raw = Vec::new();
        emulator::link::Device::take_outbound(&mut self.sim, &mut raw);
        if !raw.is_empty() {
            self.link.receive(now, &raw);
        }
        self.link.poll(now);
        for ev in self.link.take_events() {
            if matches!(ev, LinkEvent::Telemetry(_)) {
                self.telemetry += 1;
            }
            self.app.update(Action::Link(ev));
        }
        if now.is_multiple_of(50) {
            self.app.update(Action::Tick { now_ms: now });
        }
        for (id, c) in self.app.take_outbox() {
            self.link.submit(now, id, c);
        }
        if !self.started && self.link.connected() {
            self.started = true;
            // Maximum telemetry rate, and a robot that keeps moving so the tracks grow.
            for c in [
                Command::SetTelemetryRate { hz: 50 },
                Command::SetMode(Mode::Manual),
            ] {
                self.next_id += 1;
                self.link.submit(now, self.next_id, c);
            }
        }
        if self.started && now.is_multiple_of(100) {
            // Circles of 0.2 m radius in the open, teleop repeated as the TUI does.
            self.next_id += 1;
            let teleop = Command::Teleop {
                v_mm_s: 100,
                w_mrad_s: 500,
            };
            self.link.submit(now, self.next_id, teleop);
        }
        let out = self.link.take_output();
        if !out.is_empty() {
            self.sim.uart_mut().push_inbound(&out);
        }
    }

    /// The retained structures and their caps.
    fn sizes(&self) -> Vec<(&'static str, usize, usize)> {
        let a = &self.app;
        vec![
            (
                "history",
                a.history.series(Series::SpeedLeft).len(),
                HISTORY,
            ),
            ("believed_track", a.believed.len(), TRACK),
            ("true_track", a.true_track.len(), TRACK),
            ("log", a.log.len(), LOG_LINES),
            ("rx_rate_history", a.rx_rate_history.len(), 120),
        ]
    }
}

/// Resident set size of this process, KiB (Linux `/proc/self/statm`).
fn rss_kib() -> Option<u64> {
    let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: u64 = statm.split_whitespace().nth(1)?.parse().ok()?;
    Some(pages * 4)
}

fn run(minutes: u64, sample_every_min: u64) -> (Soak, Vec<serde_json::Value>) {
    let mut s = Soak::new();
    let mut samples = Vec::new();
    let wall = std::time::Instant::now();
    let total = minutes * 60_000;
    while s.now_ms < total {
        s.step();
        if s.now_ms.is_multiple_of(sample_every_min * 60_000) {
            let sizes: serde_json::Map<String, serde_json::Value> = s
                .sizes()
                .into_iter()
                .map(|(n, len, _)| (n.to_string(), len.into()))
                .collect();
            let sample = serde_json::json!({
                "sim_min": s.now_ms / 60_000,
                "wall_s": wall.elapsed().as_secs_f64(),
                "rss_kib": rss_kib(),
                "telemetry": s.telemetry,
                "sizes": sizes,
            });
            println!("{sample}");
            samples.push(sample);
        }
    }
    (s, samples)
}

fn check_bounded(s: &mut Soak) {
    for (name, len, cap) in s.sizes() {
        assert!(len <= cap, "{name} holds {len}, over its cap {cap}");
    }
    let stats = s.link.stats(s.now_ms);
    // Teleops supersede each other: at most the newest is ever pending.
    assert!(stats.commands.in_flight + stats.commands.queued <= 1);
    assert_eq!(stats.robot_seq.lost, 0, "a clean line loses nothing");
}

#[test]
fn three_minutes_at_50_hz_keep_every_buffer_within_its_cap() {
    let (mut s, _) = run(3, 1);
    println!("{} telemetry frames in 3 simulated minutes", s.telemetry);
    assert!(
        s.telemetry > 8_000,
        "50 Hz for 3 minutes: {} frames",
        s.telemetry
    );
    // The charts' history filled up and stayed at its cap: the cap is what bounds it.
    assert_eq!(s.app.history.series(Series::SpeedLeft).len(), HISTORY);
    check_bounded(&mut s);
}

#[test]
#[ignore = "a simulated hour (about 70 s in a debug build): run for the RSS figures"]
fn an_hour_at_50_hz_keeps_memory_flat() {
    let minutes = std::env::var("SOAK_MINUTES")
        .ok()
        .and_then(|m| m.parse().ok())
        .unwrap_or(60);
    let (mut s, samples) = run(minutes, 5);
    check_bounded(&mut s);
    let rss: Vec<u64> = samples
        .iter()
        .filter_map(|v| v["rss_kib"].as_u64())
        .collect();
    let json = serde_json::json!({
        "simulated_minutes": minutes,
        "telemetry_frames": s.telemetry,
        "samples": samples,
    });
    if let Ok(path) = std::env::var("SOAK_JSON") {
        std::fs::write(path, serde_json::to_string_pretty(&json).unwrap()).unwrap();
    }
    // After the first sample every buffer is full: the rest of the hour must not grow.
    if let (Some(first), Some(last)) = (rss.get(1), rss.last()) {
        println!("RSS {first} KiB at 10 min, {last} KiB at the end");
        assert!(
            *last <= first + 4096,
            "RSS grew from {first} KiB to {last} KiB"
        );
    }
}
