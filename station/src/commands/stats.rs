//! `station stats`: watch one or several links for a while and print their statistics, with
//! the round trip of a harmless probe (a parameter read) sent every 250 ms.

use std::process::ExitCode;
use std::time::Duration;

use anyhow::{bail, Context as _};
use serde_json::json;
use tokio::time::Instant;

use super::args::RequiredPort;
use super::connect::connect;
use super::send::RoundTrips;
use crate::link::api::{command_text, refusal_text};
use crate::link::robot_ids::duplicates;
use crate::link::{CommandOutcome, LinkEvent, LinkStats, PeerInfo};

/// The round-trip probe of `station stats`: reading a parameter, which changes nothing.
const PROBE: protocol::Command = protocol::Command::GetParam {
    id: protocol::ParamId(0),
};
/// Time between two probes, ms: a few a second, a small share of the link.
const PROBE_PERIOD_MS: u64 = 250;

/// What `station stats` measured on one port.
struct Watched {
    port: String,
    peer: PeerInfo,
    stats: LinkStats,
    round_trip: Option<RoundTrips>,
    probe_failures: Vec<String>,
}

impl Watched {
    fn json(&self) -> serde_json::Value {
        json!({"port": self.port, "peer": self.peer, "stats": self.stats,
               "round_trip": self.round_trip, "probe": command_text(&PROBE),
               "probe_failures": self.probe_failures})
    }
}

/// `station stats`: one port as before; several watched at once, each reported on its own
/// (a port that fails does not stop the others), with robots that state the same id named.
pub async fn stats(
    ports: &crate::commands::args::StatsPorts,
    seconds: f64,
    json: bool,
    timeout: f64,
) -> anyhow::Result<ExitCode> {
    let each = ports.each();
    if let [one] = each.as_slice() {
        let w = watch(one, seconds, timeout).await?;
        if json {
            println!("{}", crate::json_text::pretty(&w.json())?);
        } else {
            print_watched(&w);
        }
        return Ok(ExitCode::SUCCESS);
    }
    crate::commands::args::distinct_ports(each.iter().map(|p| p.port.as_path()))
        .map_err(anyhow::Error::msg)?;
    let tasks: Vec<_> = each
        .into_iter()
        .map(|p| tokio::spawn(async move { (p.port.clone(), watch(&p, seconds, timeout).await) }))
        .collect();
    let mut results = Vec::new();
    for t in tasks {
        results.push(t.await.context("a port's watch ended abnormally")?);
    }
    let ids: Vec<(String, Option<u8>)> = results
        .iter()
        .map(|(p, r)| {
            (
                p.display().to_string(),
                r.as_ref().ok().map(|w| w.peer.robot_id),
            )
        })
        .collect();
    let dups = duplicates(ids.iter().map(|(p, id)| (p.as_str(), *id)));
    let failed = results.iter().any(|(_, r)| r.is_err());
    if json {
        let links: Vec<serde_json::Value> = results
            .iter()
            .map(|(p, r)| match r {
                Ok(w) => w.json(),
                Err(e) => json!({"port": p.display().to_string(), "error": format!("{e:#}")}),
            })
            .collect();
        let v = json!({"links": links, "duplicate_robot_ids": dups});
        println!("{}", crate::json_text::pretty(&v)?);
    } else {
        for (i, (p, r)) in results.iter().enumerate() {
            if i > 0 {
                println!();
            }
            match r {
                Ok(w) => print_watched(w),
                Err(e) => {
                    println!("port        {}", p.display());
                    println!(
                        "error       {}",
                        crate::terminal_text::printable_text(&format!("{e:#}"))
                    );
                }
            }
        }
    }
    for d in &dups {
        eprintln!(
            "station: warning: {}",
            crate::terminal_text::printable_text(&d.warning())
        );
    }
    for (p, r) in &results {
        if let Err(e) = r {
            eprintln!("station: {}: {e:#}", p.display());
        }
    }
    Ok(if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

/// Watches one port for `seconds`, probing the round trip.
async fn watch(port: &RequiredPort, seconds: f64, timeout: f64) -> anyhow::Result<Watched> {
    let (mut link, peer) = connect(port, timeout).await?;
    let deadline = Instant::now() + Duration::from_secs_f64(seconds);
    let mut last: Option<LinkStats> = None;
    // The round trip is measured, not waited for: a harmless probe (reading a parameter
    // changes nothing on the robot) goes out every PROBE_PERIOD_MS while the link is watched,
    // at whatever moment of the robot's telemetry cycle it falls (unlike `send --repeat`,
    // which picks the quiet moment), so it is the round trip a command meets.
    let mut probes: Vec<u64> = Vec::new();
    let mut probe_failures: Vec<String> = Vec::new();
    let mut next_probe = Instant::now();
    loop {
        let wake = next_probe.min(deadline);
        match tokio::time::timeout_at(wake, link.events.recv()).await {
            Ok(Some(LinkEvent::Stats(s))) => last = Some(*s),
            Ok(Some(_)) => {}
            Ok(None) => break,
            Err(_) if Instant::now() >= deadline => break,
            Err(_) => {
                next_probe += Duration::from_millis(PROBE_PERIOD_MS);
                let sent = Instant::now();
                match link.handle.call(PROBE).await {
                    CommandOutcome::Acked { .. } => probes.push(sent.elapsed().as_micros() as u64),
                    other => probe_failures.push(match other {
                        CommandOutcome::Nacked { reason, .. } => refusal_text(&PROBE, reason),
                        CommandOutcome::Failed(why) => why.to_string(),
                        CommandOutcome::Acked { .. } => String::new(),
                    }),
                }
            }
        }
    }
    let round_trip = RoundTrips::of(probes);
    link.handle.shutdown();
    let _ = tokio::time::timeout(Duration::from_secs(1), link.task).await;
    let Some(stats) = last else {
        bail!("no statistics were published in {seconds} s");
    };
    Ok(Watched {
        port: port.port.display().to_string(),
        peer,
        stats,
        round_trip,
        probe_failures,
    })
}

/// The port and the robot on it, as its HelloReply states, the first lines of a report.
pub fn print_robot(port: &str, peer: &PeerInfo) {
    println!("port        {}", crate::terminal_text::printable(port));
    println!(
        "robot       {} {} {:?}, robot id {}",
        crate::terminal_text::printable(&peer.firmware),
        crate::terminal_text::printable(&peer.firmware_version),
        peer.profile,
        peer.robot_id
    );
}

fn print_watched(w: &Watched) {
    let (peer, s, round_trip) = (&w.peer, &w.stats, &w.round_trip);
    let probe = command_text(&PROBE);
    print_robot(&w.port, peer);
    println!(
        "state       {} for {:.1} s",
        s.state,
        s.session_ms as f64 / 1000.0
    );
    println!(
        "frames      in {} out {}  bytes in {} ({:.0}/s) out {} ({:.0}/s)",
        s.frames_in, s.frames_out, s.bytes_in, s.bytes_in_per_s, s.bytes_out, s.bytes_out_per_s
    );
    println!(
        "telemetry   {:.1} Hz ({} frames)",
        s.telemetry_hz, s.telemetry_frames
    );
    println!(
        "loss        robot {} ({:.2}%)  truth {}  duplicates {}",
        s.robot_seq.lost, s.robot_seq.loss_percent, s.truth_seq.lost, s.robot_seq.duplicates
    );
    println!(
        "errors      CRC {}  bad frames {}  dropped bytes {}",
        s.decoder.crc_errors,
        s.decoder.errors(),
        s.decoder.bytes_dropped
    );
    if s.auth.keyed || s.auth.refused() > 0 {
        let a = &s.auth;
        println!(
            "auth        {}; verified {}  bad signature {}  stale {}  unsigned {}  \
             unexpected signature {}",
            if a.keyed { "signed" } else { "no key" },
            a.verified,
            a.bad_signature,
            a.stale_timestamp,
            a.unsigned,
            a.unexpected_signature
        );
    }
    println!(
        "commands    {} ok, {} refused, {} failed, {} superseded",
        s.commands.acked, s.commands.nacked, s.commands.failed, s.commands.superseded
    );
    match round_trip {
        Some(r) => println!(
            "round trip  p50 {:.2} ms, p99 {:.2} ms, max {:.2} ms over {} probes ({probe}, \
             every {PROBE_PERIOD_MS} ms)",
            r.p50_us as f64 / 1000.0,
            r.p99_us as f64 / 1000.0,
            r.max_us as f64 / 1000.0,
            r.samples
        ),
        None => println!("round trip  no answer to any probe ({probe})"),
    }
    if let Some(why) = w.probe_failures.first() {
        println!(
            "probes      {} unanswered or refused: {}",
            w.probe_failures.len(),
            crate::terminal_text::printable_text(why)
        );
    }
}
