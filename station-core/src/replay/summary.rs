//! `station replay FILE --json`: what a recording holds, without a terminal.
//!
//! Layer: pure, over a parsed `Recording`: it runs the same `ReplayFeed` the TUI uses, at
//! once, and counts what comes out (frames by kind both ways, telemetry rate, sessions and
//! gaps, decoding errors, loss, commands and their outcomes). A gap is the robot's silence
//! around a lost session: from its last frame before the loss to its first frame after, once a
//! session is back (or to the end), with the reason the link gave. The work is linear in the
//! records, whatever times they carry. Cannot fail.

use std::collections::BTreeMap;

use serde::Serialize;

use super::ReplayFeed;
use crate::link::stats::{CommandCounts, DecoderCounts, RttSummary, SeqStats};
use crate::link::{Connection, LinkEvent};
use crate::record::live::PeerRecord;
use crate::record::{Meta, Recording};
use crate::replay::ReplayEvent;

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

/// A time without a session, measured by the robot's frames: from the last frame of the lost
/// session to the robot's first frame after it (not from the link timeout to the handshake).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Gap {
    /// The last frame before the session was lost.
    pub start_s: f64,
    /// The robot's first frame after `start_s`, once a new session came; `None`: the
    /// recording ended before a new session.
    pub end_s: Option<f64>,
    pub duration_s: f64,
    pub reason: String,
}

/// Replays the whole recording at once and counts.
pub fn summarize(rec: &Recording) -> Summary {
    replay(rec).0
}

/// The summary and the feed's timer runs (its work besides the records).
fn replay(rec: &Recording) -> (Summary, u64) {
    let mut feed = ReplayFeed::new(&rec.meta.port);
    let mut c = Counter::default();
    let mut actions = Vec::new();
    let duration = rec.duration_us();
    // Work follows the records, not the recorded time (a record's time is anything up to a
    // year): one step per record time, and an empty span before a record is crossed in one
    // step that runs the link's timers just before it (a command expires before a late reply,
    // as live). Each step's actions are counted before the next, keeping the buffer small.
    while let Some(t) = rec.records.get(feed.next_index()).map(|r| r.t_us) {
        if t > feed.position_us().saturating_add(1) {
            feed.advance_to(&rec.records, t - 1, &mut actions);
            for a in actions.drain(..) {
                c.action(a);
            }
        }
        let frames = feed.frames_from_robot();
        feed.advance_to(&rec.records, t, &mut actions);
        // Frames first: a frame and a link change in the same microsecond count as the frame
        // coming first (the live station decided on what it had read).
        if feed.frames_from_robot() > frames {
            c.frame(t / 1000);
        }
        for a in actions.drain(..) {
            c.action(a);
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
    let timer_runs = feed.timer_runs();
    let summary = Summary {
        format_version: rec.version,
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
    };
    (summary, timer_runs)
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
    /// When the robot's last good frame arrived.
    last_frame_ms: Option<u64>,
    gap: Option<OpenGap>,
    gaps: Vec<Gap>,
}

/// A gap whose session has not come back yet.
struct OpenGap {
    /// The last frame of the lost session (or the loss itself, if it had none).
    start_ms: u64,
    /// The robot's first frame since then, once one came.
    first_frame_ms: Option<u64>,
    reason: String,
}

impl Counter {
    /// The robot's bytes held at least one good frame at `now_ms`.
    fn frame(&mut self, now_ms: u64) {
        self.last_frame_ms = Some(now_ms);
        if let Some(g) = &mut self.gap {
            g.first_frame_ms.get_or_insert(now_ms);
        }
    }

    fn action(&mut self, a: ReplayEvent) {
        match a {
            ReplayEvent::Tick { now_ms } => self.now_ms = now_ms,
            ReplayEvent::Link(LinkEvent::Telemetry(_)) => {
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
            ReplayEvent::Link(LinkEvent::Log { .. }) => self.logs += 1,
            ReplayEvent::Link(LinkEvent::Robot(_)) => self.events += 1,
            ReplayEvent::Link(LinkEvent::Connection(c)) => self.connection(c),
            _ => {}
        }
    }

    fn connection(&mut self, c: Connection) {
        match c {
            Connection::Connected(p) => {
                if self.robot.is_none() {
                    self.robot = Some(PeerRecord::from(&p));
                }
                if let Some(g) = self.gap.take() {
                    // The outage ends when the robot was heard again, which is usually the
                    // reply that opened this session, but may be bytes held up by a stall.
                    let end = g.first_frame_ms.unwrap_or(self.now_ms);
                    self.gaps.push(gap(g.start_ms, Some(end), g.reason));
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
                    // The robot went silent at its last frame, not when the station noticed
                    // (the link timeout fires 1.5 s later, PROTOCOL.md §4).
                    let start_ms = self.last_frame_ms.unwrap_or(self.now_ms).min(self.now_ms);
                    self.gap = Some(OpenGap {
                        start_ms,
                        first_frame_ms: None,
                        reason,
                    });
                } else if let Some(g) = &mut self.gap {
                    // A closed port says more than the handshaking that follows it.
                    if !matches!(other, Connection::Handshaking { .. }) {
                        g.reason = reason;
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
        if let Some(open) = self.gap.take() {
            let mut g = gap(open.start_ms, None, open.reason);
            g.duration_s = (duration_us / 1000).saturating_sub(open.start_ms) as f64 / 1000.0;
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
            format!(
                "{} {} {:?}{}",
                r.firmware,
                r.firmware_version,
                r.profile,
                r.robot_id
                    .map(|id| format!(", robot id {id}"))
                    .unwrap_or_default()
            ),
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
    use crate::record::synth::{demo_peer, telemetry, Synth};
    use protocol::Message;

    /// 10 Hz telemetry from a robot that falls silent after its frame at 4.31 s (as under
    /// `robot-emulator --stall 5,2`): the live link times out at 5.81 s, the held-up bytes
    /// arrive at 6.34 s, a new session opens at 6.35 s, and telemetry runs to 8 s.
    fn stalled() -> Recording {
        let mut s = Synth::new(&Meta::default());
        s.handshake(demo_peer());
        let mut i = 0;
        let mut telemetry_at = |s: &mut Synth, t_us: u64| {
            s.from_robot(t_us, &Message::Telemetry(telemetry(i, 10)));
            i += 1;
        };
        for k in 0..=43 {
            telemetry_at(&mut s, 10_000 + k * 100_000);
        }
        s.link(
            5_810_000,
            &Connection::Handshaking {
                port: "memory".into(),
            },
        );
        telemetry_at(&mut s, 6_340_000);
        s.handshake_at(6_345_000, demo_peer());
        for k in 64..80 {
            telemetry_at(&mut s, 10_000 + k * 100_000);
        }
        Recording::parse_strict(&s.finish(8_000_000, "done")).unwrap()
    }

    #[test]
    fn a_gap_runs_from_the_last_frame_to_the_first_frame_after() {
        let s = summarize(&stalled());
        assert_eq!(s.sessions, 2);
        assert_eq!(
            s.gaps,
            vec![Gap {
                start_s: 4.31,
                end_s: Some(6.34),
                duration_s: 2.03,
                reason: "no frames for 1.5 s (link timeout)".into(),
            }]
        );
    }

    #[test]
    fn a_gap_to_the_end_starts_at_the_last_frame() {
        let mut s = Synth::new(&Meta::default());
        s.handshake(demo_peer());
        s.from_robot(100_000, &Message::Telemetry(telemetry(0, 10)));
        s.link(
            1_600_000,
            &Connection::Handshaking {
                port: "memory".into(),
            },
        );
        let rec = Recording::parse_strict(&s.finish(3_000_000, "done")).unwrap();
        let g = &summarize(&rec).gaps;
        assert_eq!(g.len(), 1);
        assert_eq!(
            (g[0].start_s, g[0].end_s, g[0].duration_s),
            (0.1, None, 2.9)
        );
    }

    #[test]
    fn the_work_follows_the_records_not_the_recorded_time() {
        // Ten hours between two records: one-second steps ran the timers 36 000 times (and a
        // record near a year, 31.5 million).
        let mut s = Synth::new(&Meta::default());
        s.handshake(demo_peer());
        s.from_robot(1_000_000, &Message::Telemetry(telemetry(0, 10)));
        s.from_robot(36_000_000_000, &Message::Telemetry(telemetry(1, 10)));
        let rec = Recording::parse_strict(&s.finish(36_000_000_001, "done")).unwrap();
        let (sum, runs) = replay(&rec);
        let records = rec.records.len() as u64;
        assert!(
            runs <= 2 * records,
            "{runs} timer runs for {records} records"
        );
        assert_eq!(sum.telemetry.frames, 2);
        assert_eq!(sum.duration_s, 36_000.000001);
    }

    #[test]
    fn utc_dates_are_civil() {
        assert_eq!(utc(0), "an unknown time");
        assert_eq!(utc(951_782_400_000), "2000-02-29 00:00:00 UTC");
        assert_eq!(utc(1_700_000_000_000), "2023-11-14 22:13:20 UTC");
    }
}
