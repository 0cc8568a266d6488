//! How fast the robot's clock runs against ours, and so how often to send heartbeats.
//!
//! Layer: pure state of the link machine. The robot times its link timeout (1.5 s) and its
//! manual failsafe on its own clock; an emulator serving faster than real time
//! (`robot-emulator --speed 10`) runs that clock ten times faster, and a station that sends a
//! heartbeat every 250 ms of its own time would be silent for 2.5 s of the robot's and lose the
//! session. So the station reads the robot's clock from every frame of its session that
//! carries it (telemetry, truth, heartbeats; never from what it read before the robot's
//! `HelloReply`, which may be a backlog seconds old: `LinkMachine`), measures its rate, and
//! sends its heartbeats every 250 ms of the *robot's* time (at most every
//! `MIN_HEARTBEAT_MS`). The first estimate comes `FIRST_SPAN_MS` into a session, well before
//! a fast robot's timeout (150 ms of ours at ten times real time), and is refined as the span
//! grows; later measurements span `SPAN_MS` at least. A robot whose clock is within
//! `TOLERANCE` of ours (a real one) keeps the protocol's 250 ms. Cannot fail.

use protocol::timing::HEARTBEAT_PERIOD_MS;

/// Shortest span of our clock the first rate of a session is measured over, ms: rough (a paced
/// port delivers frames up to 32 ms late), but an overestimate only sends more heartbeats.
pub const FIRST_SPAN_MS: u64 = 30;
/// Shortest span of a later measurement, ms (the arrival jitter is then a few per cent).
pub const SPAN_MS: u64 = 1_000;
/// Longest span before the measurement starts afresh, so a changed speed is followed.
pub const RESTART_MS: u64 = 5_000;
/// Rates up to this factor count as real time.
pub const TOLERANCE: f64 = 1.2;
/// Heartbeats never come closer than this, ms (the robot's 1.5 s timeout then holds up to
/// 150 times real time).
pub const MIN_HEARTBEAT_MS: u64 = 10;

/// The robot's clock rate, measured from the times its frames carry.
#[derive(Clone, Debug, Default)]
pub struct RobotClock {
    /// (robot ms, our ms) where the current measurement started.
    anchor: Option<(u32, u64)>,
    /// Robot ms per our ms, once measured.
    rate: Option<f64>,
    /// A measurement has ended: the next one spans `SPAN_MS`.
    settled: bool,
}

impl RobotClock {
    /// Forgets everything (a new session: maybe another robot, or another speed).
    pub fn reset(&mut self) {
        *self = RobotClock::default();
    }

    /// A frame stamped `robot_ms` (the robot's clock, wrapping) arrived at our `now_ms`.
    pub fn observe(&mut self, robot_ms: u32, now_ms: u64) {
        let Some((r0, t0)) = self.anchor else {
            self.anchor = Some((robot_ms, now_ms));
            return;
        };
        let span = now_ms.saturating_sub(t0);
        if span < if self.settled { SPAN_MS } else { FIRST_SPAN_MS } {
            return;
        }
        // A robot that restarted has a clock behind the anchor: start over.
        let advanced = robot_ms.wrapping_sub(r0);
        if advanced > u32::MAX / 2 {
            self.reset();
            self.anchor = Some((robot_ms, now_ms));
            return;
        }
        self.rate = Some(f64::from(advanced) / span as f64);
        if span >= RESTART_MS {
            self.anchor = Some((robot_ms, now_ms));
            self.settled = true;
        }
    }

    /// Robot ms per our ms, once measured.
    pub fn rate(&self) -> Option<f64> {
        self.rate
    }

    /// Whether the robot's clock is measured and runs at ours (within `TOLERANCE` either way):
    /// a real robot's does. Predictions that turn the robot's times into ours
    /// (`line_phase`) hold only then; an emulator at ten times real time puts its bursts ten
    /// times closer than its stamps say.
    pub fn runs_at_our_rate(&self) -> bool {
        self.rate
            .is_some_and(|r| (1.0 / TOLERANCE..=TOLERANCE).contains(&r))
    }

    /// Our ms between two heartbeats: 250 ms of the robot's time.
    pub fn heartbeat_period_ms(&self) -> u64 {
        let period = u64::from(HEARTBEAT_PERIOD_MS);
        match self.rate {
            Some(r) if r > TOLERANCE => ((period as f64 / r) as u64).max(MIN_HEARTBEAT_MS),
            _ => period,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_real_time_robot_keeps_the_protocols_heartbeat() {
        let mut c = RobotClock::default();
        assert_eq!(c.heartbeat_period_ms(), 250);
        for t in (0..3_000u64).step_by(100) {
            // Arrival jitter of a few per cent.
            c.observe((t + t % 7) as u32, t + 30);
        }
        assert_eq!(c.heartbeat_period_ms(), 250);
        assert!(c.runs_at_our_rate());
    }

    #[test]
    fn a_robot_ten_times_faster_gets_heartbeats_ten_times_as_often() {
        let mut c = RobotClock::default();
        c.observe(0, 0);
        assert_eq!(c.heartbeat_period_ms(), 250, "not measured from one frame");
        // Two batches of a paced port, 32 ms apart, one of them late: a rough first estimate.
        c.observe(600, 32);
        let early = c.heartbeat_period_ms();
        assert!((10..=40).contains(&early), "{early} ms");
        c.observe(10_000, 1_000);
        assert_eq!(c.heartbeat_period_ms(), 25);
        assert!(!c.runs_at_our_rate());
        // As fast as the machine allows: capped.
        c.reset();
        c.observe(0, 0);
        c.observe(1_000_000, 1_000);
        assert_eq!(c.heartbeat_period_ms(), MIN_HEARTBEAT_MS);
    }

    #[test]
    fn a_changed_speed_is_followed_and_a_restarted_robot_measured_afresh() {
        let mut c = RobotClock::default();
        c.observe(0, 0);
        c.observe(50_000, 5_000);
        assert_eq!(c.heartbeat_period_ms(), 25);
        // Back to real time: the next measurement starts where the last one ended and spans a
        // second (a short one would be as rough as a session's first).
        c.observe(50_100, 5_100);
        assert_eq!(c.heartbeat_period_ms(), 25);
        c.observe(51_000, 6_000);
        assert_eq!(c.heartbeat_period_ms(), 250);
        // The robot restarted: its clock went back; no rate until measured again.
        c.observe(10, 7_000);
        assert_eq!(c.rate(), None);
        assert_eq!(c.heartbeat_period_ms(), 250);
        // Wrapping of the robot's u32 clock is not a restart.
        let mut w = RobotClock::default();
        w.observe(u32::MAX - 500, 0);
        w.observe(9_499, 1_000);
        assert_eq!(w.heartbeat_period_ms(), 25);
    }
}
