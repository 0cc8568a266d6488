//! `station status`: the robot's state once (mode, pose, sensors, the running task's progress,
//! the link's statistics), as text or as one JSON object whose parts are `station watch`'s
//! lines (`station_core::watch`) and `station stats`'s figures.

use std::process::ExitCode;
use std::time::Duration;

use clap::Args;
use serde_json::{json, Value};
use tokio::time::Instant;

use super::args::{parse_seconds, RequiredPort};
use super::connect::connect;
use crate::link::{LinkEvent, LinkStats, PeerInfo};
use crate::watch::Lines;

/// Arguments of `station status`.
#[derive(Debug, Args, Clone)]
pub struct StatusArgs {
    #[command(flatten)]
    pub port: RequiredPort,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// Seconds to wait for the handshake.
    #[arg(long, default_value_t = 5.0, value_parser = parse_seconds,
          allow_negative_numbers = true)]
    pub timeout: f64,
}

/// Longest wait after the handshake for what the snapshot holds: a telemetry frame (at 1 Hz
/// or more), the link's statistics (every 250 ms) and a task's progress (every second).
const COLLECT_FOR: Duration = Duration::from_millis(1500);

/// What the snapshot holds.
struct Snapshot {
    port: String,
    peer: PeerInfo,
    /// A watch line's object without its `kind`.
    telemetry: Option<Value>,
    progress: Option<Value>,
    stats: Option<LinkStats>,
}

impl Snapshot {
    fn json(&self) -> Value {
        json!({"port": self.port, "peer": self.peer, "telemetry": self.telemetry,
               "progress": self.progress, "stats": self.stats})
    }
}

/// A line's object without its `kind` (the snapshot's key says it).
fn without_kind(mut v: Value) -> Value {
    if let Some(m) = v.as_object_mut() {
        m.remove("kind");
    }
    v
}

/// Runs `station status`.
pub async fn run(args: &StatusArgs) -> anyhow::Result<ExitCode> {
    let started = Instant::now();
    let (mut link, peer) = connect(&args.port, args.timeout).await?;
    let until = Instant::now() + COLLECT_FOR;
    let mut lines = Lines::new(Some(peer.capabilities));
    let mut snap = Snapshot {
        port: args.port.port.display().to_string(),
        peer: peer.clone(),
        telemetry: None,
        progress: None,
        stats: None,
    };
    let mut idle = false;
    loop {
        let have_telemetry = snap.telemetry.is_some() || peer.telemetry_hz == 0;
        let have_progress = snap.progress.is_some() || idle;
        if have_telemetry && have_progress && snap.stats.is_some() {
            break;
        }
        let ev = match tokio::time::timeout_at(until, link.events.recv()).await {
            Ok(Some(ev)) => ev,
            Ok(None) | Err(_) => break,
        };
        let t_us = started.elapsed().as_micros() as u64;
        match &ev {
            LinkEvent::Stats(s) => snap.stats = Some((**s).clone()),
            LinkEvent::Telemetry(t) => {
                // Idle runs no task: no progress report comes.
                idle = t.mode == protocol::Mode::Idle;
                if let Some(l) = lines.line(t_us, &ev) {
                    snap.telemetry = Some(without_kind(l.value()));
                }
            }
            LinkEvent::Progress(_) => {
                if let Some(l) = lines.line(t_us, &ev) {
                    snap.progress = Some(without_kind(l.value()));
                }
            }
            _ => {}
        }
    }
    link.handle.shutdown();
    let _ = tokio::time::timeout(Duration::from_secs(1), link.task).await;
    // A report of a mode telemetry no longer shows is over.
    let mode = |v: &Option<Value>| v.as_ref().map(|v| v["mode"].clone());
    if snap.telemetry.is_some() && mode(&snap.telemetry) != mode(&snap.progress) {
        snap.progress = None;
    }
    if args.json {
        println!("{}", crate::json_text::pretty(&snap.json())?);
    } else {
        print_snapshot(&snap);
    }
    Ok(ExitCode::SUCCESS)
}

fn print_snapshot(s: &Snapshot) {
    let text =
        |v: &Value| crate::terminal_text::printable_text(v.as_str().unwrap_or("?")).into_owned();
    let num = |v: &Value| v.as_f64();
    let peer = &s.peer;
    super::stats::print_robot(&s.port, peer);
    match &s.telemetry {
        Some(t) => {
            let task = s
                .progress
                .as_ref()
                .and_then(|p| p["text"].as_str())
                .map_or(String::new(), |p| format!(": {p}"));
            println!("mode        {}{task}", text(&t["mode"]));
            if let (Some(x), Some(y), Some(h)) =
                (num(&t["x_m"]), num(&t["y_m"]), num(&t["heading_rad"]))
            {
                println!(
                    "pose        x {x:.3} m, y {y:.3} m, heading {:.1} deg (sigma {:.3} m, {:.1} deg)",
                    h.to_degrees(),
                    num(&t["sigma_xy_m"]).unwrap_or(0.0),
                    num(&t["sigma_heading_rad"]).unwrap_or(0.0).to_degrees()
                );
            }
            if let Some(v) = num(&t["battery_v"]) {
                println!("battery     {v:.2} V");
            }
            let set: Vec<&str> = ["on_goal", "on_line", "contact", "failsafe", "goal_reached"]
                .into_iter()
                .filter(|k| t[*k].as_bool() == Some(true))
                .collect();
            println!(
                "flags       {}",
                if set.is_empty() {
                    "none".to_string()
                } else {
                    set.join(", ")
                }
            );
            println!(
                "robot time  {:.3} s",
                num(&t["robot_time_s"]).unwrap_or(0.0)
            );
        }
        None if peer.telemetry_hz == 0 => println!(
            "telemetry   off (the robot sends none; `station send --port P rate 10` starts it)"
        ),
        None => println!(
            "telemetry   none received in {:.1} s",
            COLLECT_FOR.as_secs_f64()
        ),
    }
    if let Some(st) = &s.stats {
        println!(
            "link        {} for {:.1} s, telemetry {} Hz, lost {} ({:.2}%), CRC errors {}, \
             commands {} ok {} refused {} failed",
            st.state,
            st.session_ms as f64 / 1000.0,
            peer.telemetry_hz,
            st.robot_seq.lost,
            st.robot_seq.loss_percent,
            st.decoder.crc_errors,
            st.commands.acked,
            st.commands.nacked,
            st.commands.failed
        );
    }
}
