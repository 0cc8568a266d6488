//! Motion progress: what the mode in force is doing (for the station's status line) and
//! giving up when a mode with a target makes none.
//!
//! Layer: part of the control cycle. Every cycle `Core::track_progress` measures the distance
//! left to the mode's target (GoTo: the point; ExecutePlan: along the waypoints still ahead,
//! or to the goal light on the final approach; Explore: to the goal light) and remembers when
//! it last shrank by `stuck_progress_m`. A GoTo or ExecutePlan that has not progressed for
//! `stuck_limit_s` ends: a `NoProgress` event (value: the milliseconds without progress), the
//! motors stopped, mode Idle. Reactive motion can oscillate at a wall for minutes (guided
//! motion turns away, the heading correction turns back); this is what ends it. Explore is
//! reported but never given up: its wall following may lead away from the light for long, by
//! design, and it breaks its own loops (seed 004 §5 timeouts, planning).
//!
//! About once a second while a mode other than Idle runs, `Message::Progress` (PROTOCOL.md §6
//! kind 14) carries the waypoint k of n, distance left, time in mode and time without
//! progress; telemetry stays small.
//!
//! Defaults, from the robot's speed and its way of moving (settable: `stuck_limit_s`,
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

use protocol::{EventCode, Mode, Progress};

use super::{Core, Kit, Slot};
use crate::hal::MotorCommand;
use crate::odometry::Point;
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

impl<K: Kit> Core<K> {
    /// The distance left to the mode's target, metres; `None` for a mode without one.
    pub(super) fn distance_left(&self) -> Option<f32> {
        let here = self.pose().point();
        match self.mode {
            // A go-to on the map (compass robots): along its route, which may lead away from
            // the point for long (round a wall); else straight to it.
            Mode::GoTo => self
                .planned_route_left()
                .or_else(|| self.goal.map(|g| here.distance_to(g))),
            Mode::ExecutePlan => self.plan_distance_left(here),
            Mode::Explore => Some(here.distance_to(self.dead.params.beacon)),
            _ => None,
        }
    }

    /// The planned go-to's route length, metres (its cells times the map's cell).
    fn planned_route_left(&self) -> Option<f32> {
        let cells = self.explorer.get()?.planned().route_cells()?;
        let cell_m = self.objects.nav().grid().geometry().cell_size_m();
        Some(cells as f32 * cell_m)
    }

    /// Along the plan: to the next waypoint, then leg by leg to the last; on the final
    /// approach, to the goal light.
    fn plan_distance_left(&self, here: Point) -> Option<f32> {
        let exec = self.exec?;
        if exec.approaching {
            return Some(here.distance_to(self.dead.params.beacon));
        }
        let mut at = here;
        let mut total = 0.0;
        for i in exec.next..exec.count {
            let p = self.waypoint(i)?;
            total += at.distance_to(p);
            at = p;
        }
        Some(total)
    }

    /// (waypoint being driven to, 1-based; count) for the report, (0, 0) outside a plan.
    pub(super) fn plan_position(&self) -> (u16, u16) {
        match self.exec {
            Some(e) if self.mode == Mode::ExecutePlan => (
                e.next.saturating_add(1).min(e.count.saturating_add(1)),
                e.count,
            ),
            _ => (0, 0),
        }
    }

    /// Measures progress; a target mode stuck for its limit gives up: `NoProgress`, Idle,
    /// motors stopped. Returns the command to use instead of the mode's, if it gave up.
    pub(super) fn track_progress(&mut self) -> Option<MotorCommand> {
        let now = self.cycle_ms;
        let left = self.distance_left();
        let stuck_ms = self.progress.observe(now, left);
        if self.arrived || !self.progress.stuck(self.mode, now) {
            return None;
        }
        let value = i32::try_from(stuck_ms).unwrap_or(i32::MAX);
        self.push_event(EventCode::NoProgress, value);
        if self.mode == Mode::ExecutePlan {
            self.exec = None;
        }
        self.enter(Mode::Idle);
        Some(MotorCommand::STOP)
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
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
    fn a_go_to_against_a_wall_gives_up_at_its_limit_and_stops_the_motors() {
        use crate::robot::follow::tests::{robot_on_open_map, run};
        use crate::scripted::ScriptedHal;
        use protocol::{Command, PointMm};
        // Issue 16: go-to oscillated at a wall for minutes with no word. Every IR sensor sees
        // the wall: guided motion turns away, and gets no nearer.
        let mut robot = robot_on_open_map(None, 0.0);
        let mut hal = ScriptedHal {
            compass: Some(0.0),
            ir: [900; 8],
            ..ScriptedHal::default()
        };
        let goal = PointMm {
            x_mm: 4000,
            y_mm: 4000,
        };
        let _ = robot.core.apply(Command::GoTo(goal), 0);
        assert_eq!(robot.core.mode, Mode::GoTo);
        let limit_ms = 120_000;
        let events = run(&mut robot, &mut hal, 2600);
        let gave_up: std::vec::Vec<_> = events
            .iter()
            .filter(|e| e.0 == EventCode::NoProgress)
            .collect();
        assert_eq!(gave_up.len(), 1, "{events:?}");
        let (_, stuck_ms, motor, at_ms) = *gave_up[0];
        assert!(stuck_ms >= limit_ms, "{stuck_ms}");
        assert!(
            (120_000..=121_000).contains(&at_ms),
            "gave up at {at_ms} ms"
        );
        assert_eq!(motor, MotorCommand::STOP);
        assert_eq!(robot.core.mode, Mode::Idle);
        assert_eq!(hal.motors, MotorCommand::STOP);
    }

    #[test]
    fn a_progress_report_says_where_the_plan_is() {
        use crate::robot::follow::tests::robot_on_open_map;
        use protocol::{Command, PointMm};
        let mut robot = robot_on_open_map(
            Some(PointMm {
                x_mm: 4000,
                y_mm: 4000,
            }),
            0.0,
        );
        let core = &mut robot.core;
        let _ = core.apply(
            Command::Plan {
                from: None,
                to: None,
            },
            0,
        );
        let (plan_id, view) = core.objects.plan().unwrap();
        let n = view.waypoint_count();
        let _ = core.apply(Command::ExecutePlan { plan_id }, 0);
        core.track_progress();
        let r = core.progress.report(core.mode, 0, core.plan_position());
        assert_eq!((r.mode, r.waypoint, r.waypoints), (Mode::ExecutePlan, 1, n));
        // From (0.5, 0.5) through the waypoints to (4, 4): at least the straight line.
        let left = r.distance_left_mm.unwrap();
        assert!((4949..6000).contains(&left), "{left}");
        assert_eq!(r.give_up_ms, 120_000);
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
