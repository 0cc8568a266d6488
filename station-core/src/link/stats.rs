//! Link statistics: what an operator reads first (MAVProxy's `link` view, and more).
//!
//! Layer: counters and small windows fed by the link state machine with the time passed in;
//! no I/O, no clock. Loss comes from the robot's sequence numbers (`protocol::SeqTracker`),
//! with the emulator's `EmuTruth` frames on a tracker of their own because the emulator numbers
//! them with a separate counter. Round-trip times are sampled only from commands answered
//! after their first send (Karn's rule: a retried command's ack cannot be matched to a send).
//! Cannot fail; every counter saturates or is 64-bit.

use std::collections::VecDeque;

use protocol::{DecoderStats, SeqTracker};
use serde::Serialize;

/// Round-trip samples kept for the percentiles (microseconds: the goal, 8.4-9.6 ms, is
/// finer than a whole-millisecond figure can show).
const RTT_WINDOW: usize = 256;
/// Window of the rate figures, ms.
const RATE_WINDOW_MS: u64 = 1000;

/// A snapshot of the link statistics (serialised as is by `station stats --json`).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct LinkStats {
    /// Connection state name: closed, handshaking, connected, refused.
    pub state: String,
    /// Milliseconds since the link task started.
    pub uptime_ms: u64,
    /// Milliseconds in the current session (0 when not connected).
    pub session_ms: u64,
    pub frames_in: u64,
    pub frames_out: u64,
    pub bytes_in: u64,
    pub bytes_out: u64,
    pub bytes_in_per_s: f64,
    pub bytes_out_per_s: f64,
    pub telemetry_frames: u64,
    /// Telemetry frames received in the last second.
    pub telemetry_hz: f64,
    /// The robot's frames other than EmuTruth, by sequence number.
    pub robot_seq: SeqStats,
    /// The emulator's EmuTruth frames, by their own sequence number.
    pub truth_seq: SeqStats,
    pub decoder: DecoderCounts,
    pub commands: CommandCounts,
    pub rtt_ms: RttSummary,
    /// Times the port was opened.
    pub port_opens: u32,
    /// Completed handshakes.
    pub handshakes: u32,
    /// Sessions ended by 1.5 s of silence.
    pub link_timeouts: u32,
    /// Handshakes renewed before the sequence counter could wrap (PROTOCOL.md §7).
    pub renewals: u32,
    /// Link authentication (PROTOCOL.md §13).
    pub auth: AuthCounts,
}

/// Frames the authentication layer verified and refused, by reason.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct AuthCounts {
    /// This station signs and verifies (it has a key).
    pub keyed: bool,
    pub verified: u32,
    /// Bad MAC: another key, or a forgery.
    pub bad_signature: u32,
    /// Timestamp not above the last accepted: a replay or a duplicate.
    pub stale_timestamp: u32,
    /// Unsigned frames while keyed.
    pub unsigned: u32,
    /// Signed frames while not keyed.
    pub unexpected_signature: u32,
    /// Our own frames reflected back, or more robot-side links than windows.
    pub other: u32,
}

impl AuthCounts {
    pub fn new(keyed: bool, a: &protocol::AuthStats) -> Self {
        AuthCounts {
            keyed,
            verified: a.verified,
            bad_signature: a.bad_signature,
            stale_timestamp: a.stale_timestamp,
            unsigned: a.unsigned,
            unexpected_signature: a.unexpected_signature,
            other: a.wrong_direction.saturating_add(a.too_many_links),
        }
    }

    /// Every refused frame together.
    pub fn refused(&self) -> u64 {
        [
            self.bad_signature,
            self.stale_timestamp,
            self.unsigned,
            self.unexpected_signature,
            self.other,
        ]
        .iter()
        .map(|&n| u64::from(n))
        .sum()
    }
}

/// Sequence-number accounting of one stream.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct SeqStats {
    pub received: u64,
    pub lost: u64,
    pub duplicates: u64,
    pub late: u64,
    /// lost / (received + lost), percent.
    pub loss_percent: f64,
}

impl From<&SeqTracker> for SeqStats {
    fn from(t: &SeqTracker) -> Self {
        let total = t.received + t.lost;
        SeqStats {
            received: t.received,
            lost: t.lost,
            duplicates: t.duplicates,
            late: t.late,
            loss_percent: if total == 0 {
                0.0
            } else {
                t.lost as f64 * 100.0 / total as f64
            },
        }
    }
}

/// The frame decoder's error counters (PROTOCOL.md §11).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct DecoderCounts {
    pub frames_ok: u32,
    pub crc_errors: u32,
    pub bad_cobs: u32,
    pub too_short: u32,
    pub oversize: u32,
    pub bad_version: u32,
    pub unknown_kind: u32,
    pub undecodable: u32,
    /// Bytes that belonged to no good frame.
    pub bytes_dropped: u64,
}

impl From<&DecoderStats> for DecoderCounts {
    fn from(d: &DecoderStats) -> Self {
        DecoderCounts {
            frames_ok: d.frames_ok,
            crc_errors: d.bad_crc,
            bad_cobs: d.bad_cobs,
            too_short: d.too_short,
            oversize: d.oversize,
            bad_version: d.bad_version,
            unknown_kind: d.unknown_kind,
            undecodable: d.undecodable,
            bytes_dropped: d.bytes_dropped,
        }
    }
}

impl DecoderCounts {
    /// Every kind of bad frame together.
    pub fn errors(&self) -> u64 {
        [
            self.crc_errors,
            self.bad_cobs,
            self.too_short,
            self.oversize,
            self.bad_version,
            self.unknown_kind,
            self.undecodable,
        ]
        .iter()
        .map(|&n| u64::from(n))
        .sum()
    }
}

/// Command bookkeeping.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct CommandCounts {
    pub submitted: u64,
    pub acked: u64,
    pub nacked: u64,
    /// Unanswered: timed out, link lost, not connected (each logged with its reason).
    pub failed: u64,
    /// Replaced by a newer teleop before an answer: normal at 10 Hz, so not a failure.
    pub superseded: u64,
    /// Sends beyond the first (retries).
    pub resends: u64,
    pub in_flight: u32,
    pub queued: u32,
    /// Acks or Nacks naming no command in flight (late answers to retried or dropped ones).
    pub unmatched_replies: u64,
}

/// Round-trip time percentiles over the last `RTT_WINDOW` first-send acks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct RttSummary {
    pub samples: u32,
    pub p50: Option<f64>,
    pub p99: Option<f64>,
    pub max: Option<f64>,
}

/// Collects the figures; owned by the link state machine.
#[derive(Debug, Default)]
pub struct StatsCollector {
    pub frames_in: u64,
    pub frames_out: u64,
    pub bytes_in: u64,
    pub bytes_out: u64,
    pub telemetry_frames: u64,
    pub robot_seq: SeqTracker,
    pub truth_seq: SeqTracker,
    pub commands: CommandCounts,
    pub port_opens: u32,
    pub handshakes: u32,
    pub link_timeouts: u32,
    pub renewals: u32,
    telemetry_times: VecDeque<u64>,
    /// Round trips, µs.
    rtt: VecDeque<u64>,
    byte_marks: VecDeque<(u64, u64, u64)>,
}

impl StatsCollector {
    /// Records a telemetry frame at `now_ms`.
    pub fn telemetry(&mut self, now_ms: u64) {
        self.telemetry_frames += 1;
        self.telemetry_times.push_back(now_ms);
        self.prune(now_ms);
    }

    /// Records a round-trip sample timed in whole milliseconds.
    pub fn rtt_sample(&mut self, ms: u64) {
        self.rtt_sample_us(ms.saturating_mul(1000));
    }

    /// Records a round-trip sample in microseconds.
    pub fn rtt_sample_us(&mut self, us: u64) {
        if self.rtt.len() == RTT_WINDOW {
            self.rtt.pop_front();
        }
        self.rtt.push_back(us);
    }

    fn prune(&mut self, now_ms: u64) {
        while self
            .telemetry_times
            .front()
            .is_some_and(|&t| now_ms.saturating_sub(t) >= RATE_WINDOW_MS)
        {
            self.telemetry_times.pop_front();
        }
        while self.byte_marks.len() > 1
            && self
                .byte_marks
                .get(1)
                .is_some_and(|&(t, _, _)| now_ms.saturating_sub(t) >= RATE_WINDOW_MS)
        {
            self.byte_marks.pop_front();
        }
    }

    /// A snapshot. `state`, `uptime_ms` and `session_ms` come from the caller.
    pub fn snapshot(
        &mut self,
        now_ms: u64,
        state: &str,
        session_ms: u64,
        decoder: &DecoderStats,
    ) -> LinkStats {
        self.byte_marks
            .push_back((now_ms, self.bytes_in, self.bytes_out));
        self.prune(now_ms);
        let (bytes_in_per_s, bytes_out_per_s) = match (self.byte_marks.front(), now_ms) {
            (Some(&(t0, i0, o0)), now) if now > t0 => {
                let dt = (now - t0) as f64 / 1000.0;
                (
                    (self.bytes_in - i0) as f64 / dt,
                    (self.bytes_out - o0) as f64 / dt,
                )
            }
            _ => (0.0, 0.0),
        };
        LinkStats {
            state: state.to_string(),
            uptime_ms: now_ms,
            session_ms,
            frames_in: self.frames_in,
            frames_out: self.frames_out,
            bytes_in: self.bytes_in,
            bytes_out: self.bytes_out,
            bytes_in_per_s,
            bytes_out_per_s,
            telemetry_frames: self.telemetry_frames,
            telemetry_hz: self.telemetry_times.len() as f64 * 1000.0 / RATE_WINDOW_MS as f64,
            robot_seq: SeqStats::from(&self.robot_seq),
            truth_seq: SeqStats::from(&self.truth_seq),
            decoder: DecoderCounts::from(decoder),
            commands: self.commands,
            rtt_ms: rtt_summary(&self.rtt),
            port_opens: self.port_opens,
            handshakes: self.handshakes,
            link_timeouts: self.link_timeouts,
            renewals: self.renewals,
            auth: AuthCounts::default(),
        }
    }
}

/// Percentiles in milliseconds of samples in microseconds.
fn rtt_summary(samples_us: &VecDeque<u64>) -> RttSummary {
    let mut v: Vec<u64> = samples_us.iter().copied().collect();
    v.sort_unstable();
    let ms = |us: u64| us as f64 / 1000.0;
    RttSummary {
        samples: u32::try_from(v.len()).unwrap_or(u32::MAX),
        p50: percentile(&v, 0.50).map(ms),
        p99: percentile(&v, 0.99).map(ms),
        max: v.last().map(|&m| ms(m)),
    }
}

/// Nearest-rank percentile of sorted samples.
fn percentile(sorted: &[u64], q: f64) -> Option<u64> {
    if sorted.is_empty() {
        return None;
    }
    let rank = (q * sorted.len() as f64).ceil() as usize;
    sorted.get(rank.clamp(1, sorted.len()) - 1).copied()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_use_the_nearest_rank() {
        let v: Vec<u64> = (1..=100).collect();
        assert_eq!(percentile(&v, 0.5), Some(50));
        assert_eq!(percentile(&v, 0.99), Some(99));
        assert_eq!(percentile(&[7], 0.99), Some(7));
        assert_eq!(percentile(&[], 0.5), None);
    }

    #[test]
    fn telemetry_rate_counts_the_last_second_only() {
        let mut s = StatsCollector::default();
        for i in 0..30 {
            s.telemetry(i * 100);
        }
        let snap = s.snapshot(2950, "connected", 0, &DecoderStats::default());
        assert_eq!(snap.telemetry_hz, 10.0);
        assert_eq!(snap.telemetry_frames, 30);
    }

    #[test]
    fn rtt_window_keeps_the_newest_samples() {
        let mut s = StatsCollector::default();
        for ms in 0..(RTT_WINDOW as u64 + 10) {
            s.rtt_sample(ms);
        }
        let snap = s.snapshot(0, "connected", 0, &DecoderStats::default());
        assert_eq!(snap.rtt_ms.samples as usize, RTT_WINDOW);
        assert_eq!(snap.rtt_ms.max, Some((RTT_WINDOW + 9) as f64));
    }

    #[test]
    fn round_trips_keep_their_microseconds() {
        let mut s = StatsCollector::default();
        for us in [2_140, 2_860, 8_390] {
            s.rtt_sample_us(us);
        }
        let snap = s.snapshot(0, "connected", 0, &DecoderStats::default());
        assert_eq!(snap.rtt_ms.p50, Some(2.86));
        assert_eq!(snap.rtt_ms.p99, Some(8.39));
    }
}
