//! When the robot's line towards the station is next quiet: the phase of its periodic burst
//! (a telemetry frame, and the emulator's truth frame after it), read from the robot's own
//! clock, so that a command that may wait (a teleop *repeat*) goes out right after a burst and
//! its answer never queues behind one.
//!
//! Layer: pure state of the link machine, times passed in (ours in µs, the robot's in the
//! wrapping milliseconds its frames carry). At 50 Hz telemetry the robot's transmitter is busy
//! 7.2 ms of every 20 ms at 115 200 baud (62 B of telemetry, 21 B of truth): a command written
//! at a random moment finds its answer behind that a third of the time, which was the TUI's
//! round-trip p99 (issue 15). The station cannot time the burst by when it reads it: the paced
//! port (`link::paced`) reads a busy port once per 32 ms slot, so a frame is read up to a slot
//! after it arrived. But every telemetry frame carries the robot's time, and the time between
//! the robot stamping a frame and the station having it is never less than the line's own
//! delay: the smallest `receipt - robot time` over a window (as NTP filters its offsets) is
//! the delay of a frame read the moment it arrived, late reads only ever being later. One such
//! minimum per frame kind (telemetry, truth) gives when each frame of the next burst will have
//! arrived (`robot time + period + lag`); the burst ends with the latest. The period is the
//! median of the last `STEPS` steps between telemetry times: a frame the robot skipped, or the
//! odd step of a rate change (the robot sends at once on `SetTelemetryRate`), is one step of
//! eight; a minimum over a window kept such a 3 ms step for seconds.
//!
//! `quiet_at` answers for a command asked at `now`: at once when no burst is known (no
//! telemetry, too few frames yet, a silent robot) or when the next burst ends more than
//! `MAX_HOLD_US` away (slow telemetry: the line is idle most of the time and a burst that
//! near would already be held for); else `MARGIN_US` after the next burst ends, or at once
//! when the last one ended just now. Estimates err late, never early, so a command goes
//! later into the quiet gap than it could, not into the burst. Cannot fail.

/// A command goes this long after the predicted end of a burst.
pub const MARGIN_US: u64 = 500;
/// A command asked for within this long after `MARGIN_US` past a burst's end goes at once:
/// the gap after a burst (12.8 ms at 50 Hz, 115 200 baud) has room for its round trip.
pub const NOW_WINDOW_US: u64 = 2_000;
/// Longest a command is held for the next burst's end. Above the longest burst a line at
/// 115 200 baud carries in one period (7.2 ms at 50 Hz) plus a round trip, so that a command
/// that is not held has the line to itself until its answer is back.
pub const MAX_HOLD_US: u64 = 25_000;
/// Each half of the windowed minimum, µs: the estimate follows a robot's clock drifting
/// against ours (50 ppm is 0.2 ms in 4 s) and forgets a stale frame kind.
pub const WINDOW_US: u64 = 2_000_000;
/// Telemetry frames of a session before a burst is predicted: the first few may all have been
/// read late (a paced read samples a 20 ms period at 4 ms spacings, so five see every phase).
pub const MIN_FRAMES: u32 = 8;
/// Steps between telemetry times the period is the median of.
pub const STEPS: usize = 8;
/// A telemetry stream silent for this many periods is not predicted any more.
const STALE_PERIODS: u64 = 3;

/// The robot's periodic frames that make up its burst.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Periodic {
    /// The robot's telemetry: stamped when the robot queued it, the start of a burst.
    Telemetry,
    /// The emulator's `EmuTruth`: stamped with the telemetry's time, sent after it.
    Truth,
}

/// The minimum of the values of the last one to two `WINDOW_US`.
#[derive(Clone, Copy, Debug, Default)]
struct WindowMin {
    current: Option<i64>,
    previous: Option<i64>,
    since_us: u64,
}

impl WindowMin {
    fn push(&mut self, v: i64, now_us: u64) {
        let age = now_us.saturating_sub(self.since_us);
        if age >= WINDOW_US || self.current.is_none() {
            self.previous = if age < 2 * WINDOW_US {
                self.current
            } else {
                None
            };
            self.current = None;
            self.since_us = now_us;
        }
        self.current = Some(self.current.map_or(v, |c| c.min(v)));
    }

    fn get(&self, now_us: u64) -> Option<i64> {
        let age = now_us.saturating_sub(self.since_us);
        if age >= 2 * WINDOW_US {
            return None;
        }
        let previous = if age < WINDOW_US { self.previous } else { None };
        match (self.current, previous) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }
}

/// The last telemetry frame: its robot time (ms, unwrapped) and the raw value it carried.
#[derive(Clone, Copy, Debug)]
struct Last {
    robot_ms: i64,
    raw: u32,
    at_us: u64,
}

/// The phase of the robot's burst; see the module's note.
#[derive(Clone, Debug, Default)]
pub struct LinePhase {
    last: Option<Last>,
    frames: u32,
    /// The last `STEPS` steps between telemetry times, robot ms (a ring; 0 = none yet).
    steps_ms: [u32; STEPS],
    next_step: usize,
    /// `receipt µs - robot time µs`, per `Periodic` kind.
    lag_us: [WindowMin; 2],
}

impl LinePhase {
    /// Forgets everything (a new session: maybe another robot, or a restarted one).
    pub fn reset(&mut self) {
        *self = LinePhase::default();
    }

    /// A frame of `kind` stamped `robot_ms` was read at our `now_us`.
    pub fn observe(&mut self, kind: Periodic, robot_ms: u32, now_us: u64) {
        let robot_ms = match (kind, self.last) {
            (Periodic::Telemetry, None) => i64::from(robot_ms),
            (Periodic::Telemetry, Some(last)) => {
                let step = robot_ms.wrapping_sub(last.raw);
                if step > u32::MAX / 2 {
                    // The robot's clock went back: it restarted.
                    self.reset();
                    return self.observe(kind, robot_ms, now_us);
                }
                if step > 0 {
                    if let Some(slot) = self.steps_ms.get_mut(self.next_step) {
                        *slot = step;
                    }
                    self.next_step = (self.next_step + 1) % STEPS;
                }
                last.robot_ms + i64::from(step)
            }
            // A truth frame carries its telemetry's time: near the last one, either side.
            (Periodic::Truth, Some(last)) => {
                last.robot_ms + i64::from(robot_ms.wrapping_sub(last.raw) as i32)
            }
            (Periodic::Truth, None) => return,
        };
        if kind == Periodic::Telemetry {
            self.last = Some(Last {
                robot_ms,
                raw: robot_ms as u32,
                at_us: now_us,
            });
            self.frames = self.frames.saturating_add(1);
        }
        let lag = i64::try_from(now_us)
            .unwrap_or(i64::MAX)
            .saturating_sub(robot_ms.saturating_mul(1000));
        let slot = match kind {
            Periodic::Telemetry => 0,
            Periodic::Truth => 1,
        };
        if let Some(w) = self.lag_us.get_mut(slot) {
            w.push(lag, now_us);
        }
    }

    /// The telemetry period, µs, once three steps are measured: their median.
    pub fn period_us(&self) -> Option<u64> {
        // Unmeasured slots are 0 and sort first: the median is of the measured ones.
        let mut steps = self.steps_ms;
        steps.sort_unstable();
        let unmeasured = steps.iter().take_while(|&&s| s == 0).count();
        let measured = steps.get(unmeasured..)?;
        if measured.len() < 3 {
            return None;
        }
        measured
            .get(measured.len() / 2)
            .map(|&p| u64::from(p) * 1000)
    }

    /// When a command asked for at `now_us` that may wait for a quiet line should go: `now_us`
    /// or a moment at most `MAX_HOLD_US` later.
    pub fn quiet_at(&self, now_us: u64) -> u64 {
        self.next_quiet(now_us).unwrap_or(now_us)
    }

    fn next_quiet(&self, now_us: u64) -> Option<u64> {
        let last = self.last?;
        let period = self.period_us()?;
        if self.frames < MIN_FRAMES
            || now_us.saturating_sub(last.at_us) > STALE_PERIODS.saturating_mul(period)
        {
            return None;
        }
        let lag = self.lag_us.iter().filter_map(|w| w.get(now_us)).max()?;
        // The end of the last telemetry's burst, in our µs, and the period, both signed.
        let end0 = last.robot_ms.saturating_mul(1000).saturating_add(lag);
        let p = i64::try_from(period).ok()?;
        let now = i64::try_from(now_us).ok()?;
        let margin = MARGIN_US as i64;
        // The first burst whose end (plus the margin) is not yet past.
        let behind = now - margin - end0;
        let k = if behind <= 0 { 0 } else { (behind + p - 1) / p };
        let release = end0 + k * p + margin;
        let previous = release - p;
        if k > 0 && now - previous <= NOW_WINDOW_US as i64 {
            return None;
        }
        let wait = u64::try_from(release - now).ok()?;
        if wait > MAX_HOLD_US {
            return None;
        }
        Some(now_us + wait)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A robot at 50 Hz whose clock reads `offset_us` behind ours; its telemetry frame ends on
    /// the line `tel_us` after the robot stamps it, the truth frame `truth_us` after.
    struct Line {
        offset_us: u64,
        period_us: u64,
        tel_us: u64,
        truth_us: u64,
    }

    impl Line {
        const AT_50_HZ: Line = Line {
            offset_us: 1_234_567,
            period_us: 20_000,
            tel_us: 5_400,
            truth_us: 7_200,
        };

        /// Robot time (ms) of burst `k`.
        fn robot_ms(&self, k: u64) -> u32 {
            (k * self.period_us / 1000) as u32
        }

        /// When burst `k` is over on our clock.
        fn end(&self, k: u64) -> u64 {
            self.offset_us + k * self.period_us + self.truth_us
        }

        /// Burst `k`'s frames, read late by `late(k)` µs (each frame).
        fn feed(&self, p: &mut LinePhase, k: u64, late: u64) {
            let stamp = self.offset_us + k * self.period_us;
            p.observe(
                Periodic::Telemetry,
                self.robot_ms(k),
                stamp + self.tel_us + late,
            );
            p.observe(
                Periodic::Truth,
                self.robot_ms(k),
                stamp + self.truth_us + late,
            );
        }
    }

    /// The slot-paced reads' lateness: the frame is read at the next 32 ms grid time.
    fn paced_late(arrival_us: u64) -> u64 {
        let slot = 32_000;
        (slot - arrival_us % slot) % slot
    }

    #[test]
    fn nothing_is_held_without_a_known_burst() {
        let line = Line::AT_50_HZ;
        let mut p = LinePhase::default();
        assert_eq!(p.quiet_at(5_000), 5_000, "no telemetry at all");
        for k in 0..(u64::from(MIN_FRAMES) - 1) {
            line.feed(&mut p, k, 0);
        }
        let now = line.end(MIN_FRAMES as u64) - 3_000;
        assert_eq!(p.quiet_at(now), now, "too few frames yet");
        line.feed(&mut p, u64::from(MIN_FRAMES) - 1, 0);
        assert!(p.quiet_at(now) > now, "enough frames: held");
        // The robot went silent: after three periods, nothing is held.
        let silent = line.end(u64::from(MIN_FRAMES) - 1) + 4 * line.period_us;
        assert_eq!(p.quiet_at(silent), silent);
    }

    #[test]
    fn with_prompt_reads_a_command_goes_just_after_the_burst_or_at_once_after_it() {
        let line = Line::AT_50_HZ;
        let mut p = LinePhase::default();
        for k in 0..50 {
            line.feed(&mut p, k, 0);
        }
        // Asked during burst 50 (after its telemetry started, before the truth frame ended).
        let start = line.offset_us + 50 * line.period_us;
        for into in [0, 1_000, 5_000, 7_000, 7_400] {
            let at = p.quiet_at(start + into);
            assert_eq!(
                at,
                line.end(50) + MARGIN_US,
                "asked {into} µs into the burst"
            );
        }
        // Just after the margin: at once.
        let just_after = line.end(50) + MARGIN_US + 1_000;
        assert_eq!(p.quiet_at(just_after), just_after);
        // Later in the gap: held to the next burst's end.
        let later = line.end(50) + MARGIN_US + 5_000;
        assert_eq!(p.quiet_at(later), line.end(51) + MARGIN_US);
        assert!(p.quiet_at(later) - later <= MAX_HOLD_US);
    }

    #[test]
    fn late_paced_reads_make_the_estimate_late_never_early_and_never_inside_a_burst() {
        let line = Line::AT_50_HZ;
        let mut p = LinePhase::default();
        // Every frame read on the 32 ms grid, none at once.
        for k in 0..200 {
            let stamp = line.offset_us + k * line.period_us;
            let tel = stamp + line.tel_us;
            let truth = stamp + line.truth_us;
            p.observe(Periodic::Telemetry, line.robot_ms(k), tel + paced_late(tel));
            p.observe(Periodic::Truth, line.robot_ms(k), truth + paced_late(truth));
        }
        // Ask at every 100 µs across two periods: the release is after the burst's true end
        // and before the next burst starts, with room for a 3 ms round trip.
        let base = line.offset_us + 200 * line.period_us;
        for step in 0..400u64 {
            let now = base + step * 100;
            let at = p.quiet_at(now);
            assert!(at >= now && at - now <= MAX_HOLD_US);
            // The burst the release follows, and where in its period the release falls.
            let since_stamp = (at - line.offset_us) % line.period_us;
            assert!(
                since_stamp >= line.truth_us && since_stamp + 3_000 <= line.period_us,
                "asked at +{} µs, released {} µs into a period",
                now - base,
                since_stamp
            );
        }
    }

    #[test]
    fn one_prompt_read_among_late_ones_sharpens_the_estimate() {
        let line = Line::AT_50_HZ;
        let mut p = LinePhase::default();
        for k in 0..20 {
            line.feed(&mut p, k, 9_000 + (k % 4) * 3_000);
        }
        let now = line.end(20) - 2_000;
        let late = p.quiet_at(now);
        assert_eq!(
            late,
            line.end(20) + 9_000 + MARGIN_US,
            "the best of the late reads"
        );
        line.feed(&mut p, 20, 0);
        assert_eq!(p.quiet_at(now), line.end(20) + MARGIN_US);
    }

    #[test]
    fn a_skipped_frame_a_wrapping_clock_and_a_restart_are_followed() {
        let mut p = LinePhase::default();
        // The robot's clock wraps mid-stream; one frame is skipped.
        let first = u32::MAX - 100;
        let mut t_us = 10_000_000u64;
        let mut robot = first;
        for k in 0..20 {
            let step = if k == 10 { 40 } else { 20 };
            robot = robot.wrapping_add(step);
            t_us += u64::from(step) * 1000;
            p.observe(Periodic::Telemetry, robot, t_us + 5_000);
        }
        assert_eq!(p.period_us(), Some(20_000));
        let now = t_us + 5_000 + 10_000;
        assert_eq!(p.quiet_at(now), t_us + 20_000 + 5_000 + MARGIN_US);
        // A restart (the clock goes back to zero): everything is measured afresh.
        p.observe(Periodic::Telemetry, 3, t_us + 30_000);
        assert_eq!(p.period_us(), None);
        assert_eq!(p.quiet_at(t_us + 31_000), t_us + 31_000);
    }

    #[test]
    fn a_rate_change_is_followed_and_its_odd_step_ignored() {
        // 10 Hz, then the rate set to 50 Hz 37 ms after a frame: the robot sends at once
        // (a 37 ms step), then every 20 ms.
        let mut p = LinePhase::default();
        let lag = 1_000_000 + 5_400;
        let mut robot = 0u32;
        for _ in 0..10 {
            robot += 100;
            p.observe(Periodic::Telemetry, robot, u64::from(robot) * 1000 + lag);
        }
        assert_eq!(p.period_us(), Some(100_000));
        robot += 37;
        p.observe(Periodic::Telemetry, robot, u64::from(robot) * 1000 + lag);
        for _ in 0..5 {
            robot += 20;
            p.observe(Periodic::Telemetry, robot, u64::from(robot) * 1000 + lag);
        }
        assert_eq!(p.period_us(), Some(20_000), "five of eight steps at 20 ms");
        // The same the other way: a short step among 50 Hz ones is outvoted at once.
        robot += 3;
        p.observe(Periodic::Telemetry, robot, u64::from(robot) * 1000 + lag);
        assert_eq!(p.period_us(), Some(20_000));
        let now = u64::from(robot) * 1000 + lag + 10_000;
        assert_eq!(p.quiet_at(now), now + 10_000 + MARGIN_US);
    }

    #[test]
    fn a_slow_stream_holds_only_a_command_asked_for_near_its_burst() {
        // 10 Hz: the line is idle 93 % of the time.
        let line = Line {
            period_us: 100_000,
            ..Line::AT_50_HZ
        };
        let mut p = LinePhase::default();
        for k in 0..20 {
            line.feed(&mut p, k, 0);
        }
        let mid_gap = line.end(19) + 40_000;
        assert_eq!(p.quiet_at(mid_gap), mid_gap);
        let start = line.offset_us + 20 * line.period_us;
        assert_eq!(p.quiet_at(start + 1_000), line.end(20) + MARGIN_US);
        // Within MAX_HOLD of the end, before the burst starts: held too (the command could
        // not have its round trip before the burst).
        assert_eq!(p.quiet_at(start - 10_000), line.end(20) + MARGIN_US);
    }

    #[test]
    fn a_truth_stream_that_stops_is_forgotten() {
        let line = Line::AT_50_HZ;
        let mut p = LinePhase::default();
        for k in 0..20 {
            line.feed(&mut p, k, 0);
        }
        // Telemetry alone for two windows: the burst ends with the telemetry frame.
        let mut k = 20;
        while line.offset_us + k * line.period_us < line.end(20) + 2 * WINDOW_US {
            let stamp = line.offset_us + k * line.period_us;
            p.observe(Periodic::Telemetry, line.robot_ms(k), stamp + line.tel_us);
            k += 1;
        }
        let stamp = line.offset_us + k * line.period_us;
        assert_eq!(p.quiet_at(stamp + 1_000), stamp + line.tel_us + MARGIN_US);
    }
}
