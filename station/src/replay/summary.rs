//! `station replay FILE --json`: what a recording holds, without a terminal.
//!
//! Layer: pure, over a parsed `Recording`: it runs the same `ReplayFeed` the TUI uses, at
//! once, and counts what comes out (frames by kind both ways, telemetry rate, sessions and
//! gaps, decoding errors, loss, commands and their outcomes). A gap is the time from losing a
//! session to the next one (or the end), with the reason the link gave. Cannot fail.

use std::collections::BTreeMap;

use serde::Serialize;

use super::ReplayFeed;
use crate::action::Action;
use crate::link::stats::{CommandCounts, DecoderCounts, RttSummary, SeqStats};
use crate::link::{Connection, LinkEvent};
use crate::record::live::PeerRecord;
use crate::record::{Meta, Recording, VERSION};

/// Everything `station replay --json` prints.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    pub format_version: u16,
    pub meta: Meta,
    pub file_bytes: u64,
    pub records: usize,
    pub duration_s: f64,
    /// The end record's reason; `None` for an unfinished (`.partial`) recording.
    pub end: Option<String>,
    /// Where reading stopped early, and why.
    pub damage: Option<Damage>,
    pub bytes_from_robot: u64,
    pub bytes_to_robot: u64,
    /// Good frames by message kind.
    pub frames_from_robot: BTreeMap<String, u64>,
    pub frames_to_robot: BTreeMap<String, u64>,
    pub telemetry: TelemetrySummary,
    pub robot: Option<PeerRecord>,
    /// Handshakes completed.
    pub sessions: u32,
    pub gaps: Vec<Gap>,
    /// Bad frames from the robot, by kind of error (PROTOCOL.md §11).
    pub errors: DecoderCounts,
    /// Bad frames in the station's own bytes (a station bug if ever non-zero).
    pub outgoing_errors: u32,
    pub loss: SeqStats,
    pub commands: CommandCounts,
    pub rtt_ms: RttSummary,
    pub robot_log_lines: u64,
    pub robot_events: u64,
}

/// Damage found in the file.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Damage {
    pub offset: u64,
    pub error: String,
}

#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct TelemetrySummary {
    pub frames: u64,
    /// Frames over the time a session was up, Hz.
    pub mean_hz: f64,
    /// Time a session was up, s.
    pub connected_s: f64,
    /// Most frames in any one-second window (aligned to whole seconds), Hz.
    pub max_hz: u64,
    pub first_s: Option<f64>,
    pub last_s: Option<f64>,
}

/// A time without a session.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Gap {
    pub start_s: f64,
    /// `None`: the recording ended before a new session.
    pub end_s: Option<f64>,
    pub duration_s: f64,
    pub reason: String,
}

/// Replays the whole recording at once and counts.
pub fn summarize(rec: &Recording) -> Summary {
    let mut feed = ReplayFeed::new(&rec.meta.port);
    let mut c = Counter::default();
    let mut actions = Vec::new();
    let duration = rec.duration_us();
    // One second of recording at a time keeps the action buffer small.
    let mut t = 0u64;
    loop {
        t = t.saturating_add(1_000_000).min(duration);
        feed.advance_to(&rec.records, t, &mut actions);
        for a in actions.drain(..) {
            c.action(a);
        }
        if t >= duration {
            break;
        }
    }
    c.finish(duration);
    let stats = feed.stats();
    let (fin, fout) = feed.frame_counts();
    let names = |counts: &[u64; super::KINDS]| -> BTreeMap<String, u64> {
        protocol::Kind::ALL
            .iter()
            .zip(counts.iter())
            .filter(|(_, &n)| n > 0)
            .map(|(k, &n)| (format!("{k:?}"), n))
            .collect()
    };
    let telemetry = c.telemetry();
    Summary {
        format_version: VERSION,
        meta: rec.meta.clone(),
        file_bytes: rec.file_len,
        records: rec.records.len(),
        duration_s: duration as f64 / 1e6,
        end: rec.end.clone(),
        damage: rec.damage.as_ref().map(|d| Damage {
            offset: d.offset(),
            error: d.to_string(),
        }),
        bytes_from_robot: stats.bytes_in,
        bytes_to_robot: stats.bytes_out,
        frames_from_robot: names(fin),
        frames_to_robot: names(fout),
        telemetry,
        robot: c.robot,
        sessions: stats.handshakes,
        gaps: c.gaps,
        errors: stats.decoder,
        outgoing_errors: feed.outgoing_errors(),
        loss: stats.robot_seq,
        commands: stats.commands,
        rtt_ms: stats.rtt_ms,
        robot_log_lines: c.logs,
        robot_events: c.events,
    }
}

#[derive(Default)]
struct Counter {
    now_ms: u64,
    telemetry: u64,
    first_ms: Option<u64>,
    last_ms: u64,
    second: u64,
    in_second: u64,
    max_hz: u64,
    logs: u64,
    events: u64,
    robot: Option<PeerRecord>,
    connected: bool,
    since_ms: u64,
    connected_ms: u64,
    gap: Option<(u64, String)>,
    gaps: Vec<Gap>,
}

impl Counter {
    fn action(&mut self, a: Action) {
        match a {
            Action::Tick { now_ms } => self.now_ms = now_ms,
            Action::Link(LinkEvent::Telemetry(_)) => {
                self.telemetry += 1;
                self.first_ms.get_or_insert(self.now_ms);
                self.last_ms = self.now_ms;
                let s = self.now_ms / 1000;
                if s != self.second {
                    self.second = s;
                    self.in_second = 0;
                }
                self.in_second += 1;
                self.max_hz = self.max_hz.max(self.in_second);
            }
            Action::Link(LinkEvent::Log { .. }) => self.logs += 1,
            Action::Link(LinkEvent::Robot(_)) => self.events += 1,
            Action::Link(LinkEvent::Connection(c)) => self.connection(c),
            _ => {}
        }
    }

    fn connection(&mut self, c: Connection) {
        match c {
            Connection::Connected(p) => {
                if self.robot.is_none() {
                    self.robot = Some(PeerRecord::from(&p));
                }
                if let Some((start, reason)) = self.gap.take() {
                    self.gaps.push(gap(start, Some(self.now_ms), reason));
                }
                if !self.connected {
                    self.since_ms = self.now_ms;
                }
                self.connected = true;
            }
            other => {
                let reason = match &other {
                    Connection::Closed { reason } => reason.clone(),
                    Connection::Refused { message } => message.clone(),
                    _ => "no frames for 1.5 s (link timeout)".into(),
                };
                if self.connected {
                    self.connected_ms += self.now_ms.saturating_sub(self.since_ms);
                    self.gap = Some((self.now_ms, reason));
                } else if let Some((_, r)) = &mut self.gap {
                    // A closed port says more than the handshaking that follows it.
                    if !matches!(other, Connection::Handshaking { .. }) {
                        *r = reason;
                    }
                }
                self.connected = false;
            }
        }
    }

    fn finish(&mut self, duration_us: u64) {
        if self.connected {
            self.connected_ms += (duration_us / 1000).saturating_sub(self.since_ms);
        }
        if let Some((start, reason)) = self.gap.take() {
            let mut g = gap(start, None, reason);
            g.duration_s = (duration_us / 1000).saturating_sub(start) as f64 / 1000.0;
            self.gaps.push(g);
        }
    }

    fn telemetry(&self) -> TelemetrySummary {
        let connected_s = self.connected_ms as f64 / 1000.0;
        TelemetrySummary {
            frames: self.telemetry,
            mean_hz: if connected_s > 0.0 {
                self.telemetry as f64 / connected_s
            } else {
                0.0
            },
            connected_s,
            max_hz: self.max_hz,
            first_s: self.first_ms.map(|f| f as f64 / 1000.0),
            last_s: self.first_ms.map(|_| self.last_ms as f64 / 1000.0),
        }
    }
}

fn gap(start_ms: u64, end_ms: Option<u64>, reason: String) -> Gap {
    Gap {
        start_s: start_ms as f64 / 1000.0,
        end_s: end_ms.map(|e| e as f64 / 1000.0),
        duration_s: end_ms.map_or(0.0, |e| e.saturating_sub(start_ms) as f64 / 1000.0),
        reason,
    }
}

/// The summary as text for a person.
pub fn text(file: &str, s: &Summary) -> String {
    let mut out = String::new();
    let mut line = |k: &str, v: String| {
        out.push_str(&format!("{k:<12}{v}\n"));
    };
    line(
        "recording",
        format!(
            "{file} (format {}, {} bytes, {} records, {})",
            s.format_version,
            s.file_bytes,
            s.records,
            match &s.end {
                Some(r) => format!("ended: {r}"),
                None => "unfinished: no end record".into(),
            }
        ),
    );
    if let Some(d) = &s.damage {
        line("DAMAGED", format!("{}; read up to there", d.error));
    }
    line(
        "recorded",
        format!(
            "{} on {} by {}",
            utc(s.meta.created_unix_ms),
            s.meta.port,
            s.meta.writer
        ),
    );
    if let Some(r) = &s.robot {
        line(
            "robot",
            format!("{} {} {:?}", r.firmware, r.firmware_version, r.profile),
        );
    }
    line("duration", format!("{:.1} s", s.duration_s));
    line(
        "bytes",
        format!(
            "from robot {}, to robot {}",
            s.bytes_from_robot, s.bytes_to_robot
        ),
    );
    let kinds = |m: &BTreeMap<String, u64>| {
        m.iter()
            .map(|(k, n)| format!("{k} {n}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    line("frames in", kinds(&s.frames_from_robot));
    line("frames out", kinds(&s.frames_to_robot));
    line(
        "telemetry",
        format!(
            "{} frames, {:.1} Hz mean over {:.1} s connected, {} Hz max",
            s.telemetry.frames, s.telemetry.mean_hz, s.telemetry.connected_s, s.telemetry.max_hz
        ),
    );
    let gaps = s
        .gaps
        .iter()
        .map(|g| match g.end_s {
            Some(e) => format!(
                "{:.1}-{:.1} s ({:.1} s, {})",
                g.start_s, e, g.duration_s, g.reason
            ),
            None => format!("{:.1} s to the end ({})", g.start_s, g.reason),
        })
        .collect::<Vec<_>>();
    line(
        "sessions",
        format!(
            "{}; {} gap(s){}{}",
            s.sessions,
            gaps.len(),
            if gaps.is_empty() { "" } else { ": " },
            gaps.join("; ")
        ),
    );
    line(
        "errors",
        if s.errors.errors() == 0 {
            "none".into()
        } else {
            format!(
                "CRC {}, bad frames {}, dropped bytes {}",
                s.errors.crc_errors,
                s.errors.errors(),
                s.errors.bytes_dropped
            )
        },
    );
    line(
        "loss",
        format!("{} frames ({:.2} %)", s.loss.lost, s.loss.loss_percent),
    );
    line(
        "commands",
        format!(
            "{} sent, {} acked, {} refused, {} failed, {} resends{}",
            s.commands.submitted,
            s.commands.acked,
            s.commands.nacked,
            s.commands.failed,
            s.commands.resends,
            s.rtt_ms
                .p50
                .map(|p| format!("; rtt p50 {p:.0} ms"))
                .unwrap_or_default()
        ),
    );
    line(
        "robot said",
        format!("{} log lines, {} events", s.robot_log_lines, s.robot_events),
    );
    out
}

/// `YYYY-MM-DD HH:MM:SS UTC` for milliseconds since the Unix epoch (0: unknown).
pub fn utc(unix_ms: u64) -> String {
    if unix_ms == 0 {
        return "an unknown time".into();
    }
    let secs = unix_ms / 1000;
    let (days, rem) = (secs / 86_400, secs % 86_400);
    // Howard Hinnant's civil_from_days.
    let z = days as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02}:{:02} UTC",
        rem / 3600,
        (rem / 60) % 60,
        rem % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utc_dates_are_civil() {
        assert_eq!(utc(0), "an unknown time");
        assert_eq!(utc(951_782_400_000), "2000-02-29 00:00:00 UTC");
        assert_eq!(utc(1_700_000_000_000), "2023-11-14 22:13:20 UTC");
    }
}
