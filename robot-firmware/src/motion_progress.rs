//! Motion progress: how long the mode in force has gone without getting nearer its target,
//! and when that is long enough to give up (the robot's side is `robot::progress`).
//!
//! Layer: pure, no clock (the time is passed in). Defaults, from the robot's speed and its way of moving (settable: `stuck_limit_s`,
//! `stuck_progress_m`). Guided motion (compass robots, seed 004): going round a wall end of the
//! labyrinth (walls on a 1.25 m grid) at the avoidance speed (nominal 25, 0.07 m/s at average
//! battery, seed 004 §4's table) takes 2 x 1.25 m / 0.07 m/s = 36 s without getting nearer,
//! and a detour round a U of such walls three times that: 120 s. Measured on 30 generated
//! Micro-Rato labyrinths (`robot-emulator bench --task goto --profile micro-rato --kind
//! micro-rato --arenas generated:30`): 40 s gave up on 4 go-tos that arrived after 75-160 s
//! (20 -> 16 arrivals); 120 s keeps all 20 and ends the 4 that ran into the 300 s timeout. The drift behaviour (encoder robots, seed 000 §4.4-4.5) escapes a dead end by
//! turning away from the goal, with 180° turns that escalate: in Fig. 17's two successive dead
//! ends the project's Khepera arrives after 2-8 minutes (`emulator/tests/paper_000_fig17.rs`),
//! so 600 s. 0.1 m of progress is more than dead-reckoning jitter from cycle to cycle and less
//! than a waypoint's pass radius.
//! Cannot fail or panic.

use protocol::{Mode, Progress};

use crate::profile::Profile;

/// Period of `Progress` messages, ms.
pub const REPORT_PERIOD_MS: u32 = 1000;

/// Giving-up limits (parameters `stuck_limit_s`, `stuck_progress_m`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProgressParams {
    /// A target mode without progress for this long gives up, seconds.
    pub stuck_limit_s: f32,
    /// The distance left must shrink by this much to count as progress, metres.
    pub stuck_progress_m: f32,
}

impl Default for ProgressParams {
    fn default() -> Self {
        ProgressParams {
            stuck_limit_s: GUIDED_STUCK_LIMIT_S,
            stuck_progress_m: 0.1,
        }
    }
}

/// Default limits for guided motion (compass robots) and the drift behaviour (encoders).
const GUIDED_STUCK_LIMIT_S: f32 = 120.0;
const DRIFT_STUCK_LIMIT_S: f32 = 600.0;

impl ProgressParams {
    /// The defaults for `profile`'s way of reaching a point (see the module's words).
    pub fn for_profile(profile: &Profile) -> Self {
        let drift = profile.has(protocol::caps::ENCODERS);
        ProgressParams {
            stuck_limit_s: if drift {
                DRIFT_STUCK_LIMIT_S
            } else {
                GUIDED_STUCK_LIMIT_S
            },
            ..ProgressParams::default()
        }
    }
}

/// Progress through the mode in force.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MotionProgress {
    pub params: ProgressParams,
    /// When the mode was entered, ms.
    since_ms: u32,
    /// The smallest distance left so far (`None` until measured), metres.
    best_m: Option<f32>,
    /// When `best_m` last shrank by `stuck_progress_m` (or the mode began), ms.
    progress_ms: u32,
    /// The last distance left measured, metres.
    left_m: Option<f32>,
    next_report_ms: u32,
}

impl MotionProgress {
    pub fn new(params: ProgressParams) -> Self {
        MotionProgress {
            params,
            ..MotionProgress::default()
        }
    }

    /// A mode (re)starts at `now_ms`: time and progress count from here; the first report
    /// goes at once.
    pub fn restart(&mut self, now_ms: u32) {
        *self = MotionProgress {
            params: self.params,
            since_ms: now_ms,
            progress_ms: now_ms,
            next_report_ms: now_ms,
            ..MotionProgress::default()
        };
    }

    /// Takes this cycle's distance left; returns the time without progress, ms.
    pub fn observe(&mut self, now_ms: u32, left_m: Option<f32>) -> u32 {
        self.left_m = left_m;
        if let Some(d) = left_m {
            let better = self
                .best_m
                .is_none_or(|b| d <= b - self.params.stuck_progress_m);
            if better {
                self.best_m = Some(d);
                self.progress_ms = now_ms;
            }
        } else {
            // No target, nothing to be stuck on.
            self.progress_ms = now_ms;
        }
        now_ms.wrapping_sub(self.progress_ms)
    }

    /// The give-up limit, ms (0 for a mode that does not give up).
    fn limit_ms(&self, mode: Mode) -> u32 {
        if gives_up(mode) {
            libm::roundf(self.params.stuck_limit_s * 1000.0) as u32
        } else {
            0
        }
    }

    /// Whether `mode` has made no progress for its limit.
    pub fn stuck(&self, mode: Mode, now_ms: u32) -> bool {
        let limit = self.limit_ms(mode);
        limit > 0 && now_ms.wrapping_sub(self.progress_ms) >= limit
    }

    /// The report for `mode` if one is due at `now_ms`.
    pub fn report_due(&mut self, mode: Mode, now_ms: u32, plan: (u16, u16)) -> Option<Progress> {
        if mode == Mode::Idle || now_ms.wrapping_sub(self.next_report_ms) >= 0x8000_0000 {
            return None;
        }
        self.next_report_ms = now_ms.wrapping_add(REPORT_PERIOD_MS);
        Some(self.report(mode, now_ms, plan))
    }

    /// What `mode` is doing now; `plan` = (waypoint 1-based, count), (0, 0) outside a plan.
    pub fn report(&self, mode: Mode, now_ms: u32, plan: (u16, u16)) -> Progress {
        Progress {
            mode,
            waypoint: plan.0,
            waypoints: plan.1,
            distance_left_mm: self
                .left_m
                .map(|d| libm::roundf(d.max(0.0) * 1000.0) as u32),
            elapsed_ms: now_ms.wrapping_sub(self.since_ms),
            stuck_ms: now_ms.wrapping_sub(self.progress_ms),
            give_up_ms: self.limit_ms(mode),
        }
    }
}

/// The modes that end when they cannot progress: those that drive to a target of the
/// operator's.
pub fn gives_up(mode: Mode) -> bool {
    matches!(mode, Mode::GoTo | Mode::ExecutePlan)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn progress_resets_the_stuck_clock_and_a_target_mode_gives_up_at_its_limit() {
        let mut p = MotionProgress::default();
        p.restart(1000);
        assert_eq!(p.observe(1000, Some(3.0)), 0);
        // Oscillating within 0.1 m of the best is no progress.
        assert_eq!(p.observe(5000, Some(2.95)), 4000);
        assert_eq!(p.observe(6000, Some(3.2)), 5000);
        // 0.1 m nearer is.
        assert_eq!(p.observe(7000, Some(2.9)), 0);
        assert!(!p.stuck(Mode::GoTo, 126_999));
        assert!(p.stuck(Mode::GoTo, 127_000));
        // Explore is reported, never given up.
        assert!(!p.stuck(Mode::Explore, 1_000_000));
        let r = p.report(Mode::GoTo, 127_000, (0, 0));
        assert_eq!(r.distance_left_mm, Some(2900));
        assert_eq!(
            (r.elapsed_ms, r.stuck_ms, r.give_up_ms),
            (126_000, 120_000, 120_000)
        );
    }

    #[test]
    fn the_widest_report_is_the_size_protocol_md_states() {
        let widest = Progress {
            mode: Mode::CalibrateLight,
            waypoint: u16::MAX,
            waypoints: u16::MAX,
            distance_left_mm: Some(u32::MAX),
            elapsed_ms: u32::MAX,
            stuck_ms: u32::MAX,
            give_up_ms: u32::MAX,
        };
        let mut buf = [0u8; protocol::MAX_FRAME];
        let n = protocol::encode(0xFFFF, &protocol::Message::Progress(widest), &mut buf).unwrap();
        assert_eq!(n, 38);
    }

    #[test]
    fn a_khepera_waits_longer_its_drift_behaviour_turns_away_to_leave_dead_ends() {
        let k = ProgressParams::for_profile(&crate::KHEPERA);
        let m = ProgressParams::for_profile(&crate::MICRO_RATO);
        assert_eq!((k.stuck_limit_s, m.stuck_limit_s), (600.0, 120.0));
    }

    #[test]
    fn reports_come_once_a_period_and_not_in_idle() {
        let mut p = MotionProgress::default();
        p.restart(0);
        assert!(p.report_due(Mode::GoTo, 0, (0, 0)).is_some());
        assert!(p.report_due(Mode::GoTo, 999, (0, 0)).is_none());
        assert!(p.report_due(Mode::GoTo, 1000, (0, 0)).is_some());
        assert!(p.report_due(Mode::Idle, 5000, (0, 0)).is_none());
    }
}
