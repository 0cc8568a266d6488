//! Floor-grid line correction on the robot (seed 003 §2.5-2.7): the PPD corrector, the
//! rejected baseline and plain odometry run side by side, and the survey pilot drives.
//!
//! Layer: the robot's glue around [`crate::localize`]. The control cycle feeds it the encoder
//! counts and the floor sensor's level ([`LineCorr::step`]); while it is active the robot's
//! pose is the corrected one, `Mode::Survey` drives with [`LineCorr::drive`], and the robot
//! sends a `Localization` message at [`REPORT_PERIOD_MS`] ([`LineCorr::report`]). It starts
//! when the robot enters `Mode::Survey` (seeded at the pose the robot then believes) and stays
//! on in every mode until a `SetPose` re-seeds it there.
//!
//! Invariants: fixed size (the 64-sample PPD is most of it); nothing allocates or panics;
//! wire values saturate.

use protocol::{
    EventCode, LineAxis, LineEventInfo, LineVerdict, Localization, NackReason, Pose as WirePose,
    PpdSample, PPD_SAMPLES_SENT,
};

use crate::behaviour::units;
use crate::hal::MotorCommand;
use crate::localize::{
    Axis, GridGeometry, LineEdge, LineOutcome, NearestLine, Spps64, SppsParams, Survey,
    SurveyParams,
};
use crate::odometry::{OdometryParams, Pose};
use crate::profile::Profile;

use super::{Core, Kit};

/// Line correction needs encoders (the PPD moves with their counts) and a floor sensor.
const NEEDS: u32 = protocol::caps::ENCODERS | protocol::caps::LINE_SENSOR;

/// Whether `Mode::Survey` can run on `profile` (which then announces `caps::LINE_CORRECTION`).
pub fn check(profile: &Profile) -> Result<(), NackReason> {
    if profile.has(NEEDS | protocol::caps::LINE_CORRECTION) {
        Ok(())
    } else {
        Err(NackReason::Unsupported)
    }
}

impl<K: Kit<LineCorr = LineCorr>> Core<K> {
    /// The control cycle's line-correction step, after odometry.
    pub(super) fn line_correct(&mut self, n_l: i32, n_r: i32, now_ms: u32) {
        let level = self.sensors.line;
        if let Some(LineOutcome::Corrected(c)) = self.linecorr.step(n_l, n_r, level, now_ms) {
            let mm = libm::roundf(c.moved_m * 1000.0) as i32;
            self.push_event(EventCode::PoseCorrected, mm);
        }
    }

    /// `Mode::Survey`'s motor command.
    pub(super) fn survey_command(&mut self) -> MotorCommand {
        let (ir, n) = self.ir_rays();
        self.linecorr.drive(self.profile, &ir[..n])
    }
}

/// Time between two `Localization` messages, ms (5 Hz: a tenth of a grid square at 100 mm/s,
/// and below the 10 Hz telemetry default).
pub const REPORT_PERIOD_MS: u32 = 200;
/// IR reading above which the survey's avoider takes over (the avoid behaviour's threshold,
/// seed 000 §4.1: about 2 cm from a wall).
const AVOID_IR: u16 = 475;
/// Turn rate of the avoider, rad/s.
const AVOID_RAD_S: f32 = 2.5;
/// A pulse starting within this travel after the previous pulse ENDED is a double detection,
/// metres. The corrector's own refractory travel counts from the cut, at the pulse's start;
/// a long pulse (a line crossed obliquely, or a crossing) can outlast it, and the sensor's
/// echo then comes one read after the pulse (seen in the emulator: seed 2 was lost that way).
/// 2 cm: two cycles at 100 mm/s; a real next line is at least a few cm of travel away except
/// at a crossing, where dropping it costs one line, which the PPD tolerates (§2.7).
const ECHO_GAP_M: f32 = 0.02;

/// The robot's line-correction state.
#[derive(Clone, Debug)]
pub struct LineCorr {
    active: bool,
    spps: Spps64,
    baseline: NearestLine,
    edge: LineEdge,
    /// Travel since the floor sensor's level last fell, metres.
    since_pulse_m: f32,
    /// Pulses dropped as echoes by `ECHO_GAP_M`.
    echoes: u16,
    survey: Survey,
    last: Option<LineEventInfo>,
    lines: u16,
    next_report_ms: u32,
    /// Fractions of a motor unit not yet driven, left and right (the Khepera's 8 mm/s units
    /// are too coarse for the fitter's gentle turns; carrying the remainder dithers them).
    residual: [f32; 2],
}

impl LineCorr {
    /// Inactive, ready to start at `pose` with the robot's odometry constants.
    pub fn new(odometry: OdometryParams, pose: Pose, seed: u32) -> Self {
        let params = SppsParams {
            odometry,
            ..SppsParams::default()
        };
        Self {
            active: false,
            spps: Spps64::new(params, pose, seed),
            baseline: NearestLine::new(odometry, params.grid, params.sensor_offset_m, pose),
            edge: LineEdge::default(),
            since_pulse_m: f32::INFINITY,
            echoes: 0,
            survey: Survey::new(SurveyParams::default(), pose.point(), seed ^ 0x0003_5EED),
            last: None,
            lines: 0,
            next_report_ms: 0,
            residual: [0.0; 2],
        }
    }

    /// Whether the correction runs (and the robot's pose is the corrected one).
    pub fn active(&self) -> bool {
        self.active
    }

    /// Starts the correction at `pose` if it is not running; a running one is kept.
    pub fn start(&mut self, pose: Pose, now_ms: u32) {
        if !self.active {
            self.active = true;
            self.seed(pose);
            self.next_report_ms = now_ms;
        }
        self.survey.restart(self.spps.pose().point());
    }

    /// A pose given by the operator: every estimate restarts there.
    pub fn set_pose(&mut self, pose: Pose) {
        if self.active {
            self.seed(pose);
        }
    }

    fn seed(&mut self, pose: Pose) {
        self.spps.reset(pose);
        let p = *self.spps.params();
        self.baseline = NearestLine::new(p.odometry, p.grid, p.sensor_offset_m, pose);
        self.last = None;
        self.lines = 0;
        self.echoes = 0;
    }

    /// One control cycle: encoder counts since the last one and the floor sensor's level.
    pub fn step(
        &mut self,
        n_l: i32,
        n_r: i32,
        line_level: bool,
        now_ms: u32,
    ) -> Option<LineOutcome> {
        let mut event = self.edge.update(line_level);
        if !self.active {
            return None;
        }
        let mm = self.spps.params().odometry.mm_per_pulse;
        let travel = libm::fabsf(n_l as f32 + n_r as f32) / 2.0 * mm * 1e-3;
        let echo = event && self.since_pulse_m < ECHO_GAP_M;
        if line_level {
            self.since_pulse_m = 0.0;
        } else {
            self.since_pulse_m += travel;
        }
        if echo {
            event = false;
            self.echoes = self.echoes.wrapping_add(1);
        }
        self.baseline.step(n_l, n_r, event);
        let outcome = if echo {
            self.spps.step(n_l, n_r, false);
            LineOutcome::Echo
        } else {
            self.spps.step(n_l, n_r, event)?
        };
        self.lines = self.lines.wrapping_add(1);
        self.last = Some(event_info(outcome, now_ms));
        Some(outcome)
    }

    /// The corrected pose.
    pub fn pose(&self) -> Pose {
        self.spps.pose()
    }

    /// Plain odometry since the correction started.
    pub fn uncorrected(&self) -> Pose {
        self.spps.uncorrected()
    }

    /// The nearest-line baseline.
    pub fn baseline(&self) -> Pose {
        self.baseline.pose()
    }

    /// The corrector, for inspection.
    pub fn spps(&self) -> &Spps64 {
        &self.spps
    }

    /// The grid the correction assumes.
    pub fn grid(&self) -> GridGeometry {
        self.spps.params().grid
    }

    /// The survey's motor command for this cycle: `ir` are the readings with their mounting
    /// directions (radians, left positive).
    pub fn drive(&mut self, profile: &Profile, ir: &[(u16, f32)]) -> MotorCommand {
        let avoid = avoid_turn(ir);
        let s = self.survey.step(self.spps.pose(), avoid);
        let half_base_mm = profile.wheel_distance_m * 500.0;
        let wheels = [
            s.v_mm_s - s.w_rad_s * half_base_mm,
            s.v_mm_s + s.w_rad_s * half_base_mm,
        ];
        let mut out = [0i16; 2];
        for ((o, r), mm_s) in out.iter_mut().zip(self.residual.iter_mut()).zip(wheels) {
            let want = mm_s / profile.motor_unit_mm_s + *r;
            *o = profile.motor_units((libm::roundf(want)) * profile.motor_unit_mm_s);
            // Keep the remainder bounded if the command was clamped.
            *r = (want - f32::from(*o)).clamp(-1.0, 1.0);
        }
        MotorCommand::new(out[0], out[1])
    }

    /// Whether a `Localization` message is due at `now_ms`; if so, schedules the next.
    pub fn report_due(&mut self, now_ms: u32) -> bool {
        if !self.active || now_ms.wrapping_sub(self.next_report_ms) >= 0x8000_0000 {
            return false;
        }
        let next = self.next_report_ms.wrapping_add(REPORT_PERIOD_MS);
        // After a stall, restart the schedule from now rather than send a burst.
        self.next_report_ms = if now_ms.wrapping_sub(next) < 0x8000_0000 {
            now_ms.wrapping_add(REPORT_PERIOD_MS)
        } else {
            next
        };
        true
    }

    /// The `Localization` message for the current state.
    pub fn report(&self, now_ms: u32) -> Localization {
        let c = self.spps.pose();
        let counters = self.spps.counters();
        let (bl, br) = self.spps.mean_bias();
        let mut samples = [PpdSample::default(); PPD_SAMPLES_SENT];
        let all = self.spps.samples();
        let stride = (all.len() / PPD_SAMPLES_SENT).max(1);
        for (out, s) in samples.iter_mut().zip(all.iter().step_by(stride)) {
            *out = PpdSample {
                dx_mm: units((s.pose.x - c.x) * 1000.0),
                dy_mm: units((s.pose.y - c.y) * 1000.0),
                bias: [bias_i8(s.bias_left), bias_i8(s.bias_right)],
            };
        }
        Localization {
            time_ms: now_ms,
            corrected: wire(c),
            uncorrected: wire(self.spps.uncorrected()),
            baseline: wire(self.baseline.pose()),
            ppd_size_mm: sat_u16(self.spps.size_m() * 1000.0),
            // 0.001 % units: 1e-5.
            bias_mean: [units(bl * 1e5), units(br * 1e5)],
            lines: self.lines,
            corrections: counters.corrections as u16,
            rejected: (counters.rejected as u16).wrapping_add(self.echoes),
            last_event: self.last,
            samples,
        }
    }
}

/// The avoider: a turn away from the side that sees more, when a front sensor is close.
fn avoid_turn(ir: &[(u16, f32)]) -> Option<f32> {
    let front = |a: f32| libm::fabsf(a) < core::f32::consts::FRAC_PI_2;
    let near = ir.iter().any(|&(v, a)| front(a) && v > AVOID_IR);
    if !near {
        return None;
    }
    let side: f32 = ir
        .iter()
        .filter(|&&(_, a)| front(a))
        .map(|&(v, a)| f32::from(v) * libm::sinf(a))
        .sum();
    // Obstacle on the left (positive angles) -> turn right; dead ahead -> turn right too.
    Some(if side > 0.0 {
        -AVOID_RAD_S
    } else if side < 0.0 {
        AVOID_RAD_S
    } else {
        -AVOID_RAD_S
    })
}

fn event_info(outcome: LineOutcome, now_ms: u32) -> LineEventInfo {
    let mut e = LineEventInfo {
        time_ms: now_ms,
        ..LineEventInfo::default()
    };
    match outcome {
        LineOutcome::Corrected(c) => {
            e.verdict = LineVerdict::Corrected;
            e.axis = match c.line.axis {
                Axis::X => LineAxis::X,
                Axis::Y => LineAxis::Y,
            };
            e.index = c.line.index.clamp(i32::from(i16::MIN), i32::from(i16::MAX)) as i16;
            e.moved_mm = sat_u16(c.moved_m * 1000.0);
            e.turned_mrad = units(c.turned_rad * 1000.0);
            e.support_pct = libm::roundf(c.support * 100.0).clamp(0.0, 100.0) as u8;
        }
        LineOutcome::Rejected { distance_m } => {
            e.verdict = LineVerdict::Rejected;
            e.moved_mm = sat_u16(distance_m * 1000.0);
        }
        LineOutcome::Echo => e.verdict = LineVerdict::Echo,
    }
    e
}

fn wire(p: Pose) -> WirePose {
    WirePose {
        x_mm: libm::roundf(p.x * 1000.0) as i32,
        y_mm: libm::roundf(p.y * 1000.0) as i32,
        heading_mrad: units(p.heading * 1000.0),
    }
}

/// Relative bias to 0.01 % units, saturating.
fn bias_i8(b: f32) -> i8 {
    libm::roundf(b * 1e4).clamp(-127.0, 127.0) as i8
}

fn sat_u16(v: f32) -> u16 {
    // `as` saturates and maps NaN to 0.
    libm::roundf(v) as u16
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::KHEPERA;

    fn khepera_odometry() -> OdometryParams {
        OdometryParams {
            wheel_distance_mm: KHEPERA.wheel_distance_m * 1000.0,
            mm_per_pulse: KHEPERA.pulse_m * 1000.0,
            ..OdometryParams::default()
        }
    }

    #[test]
    fn inactive_it_reports_nothing_and_follows_no_lines() {
        let mut lc = LineCorr::new(khepera_odometry(), Pose::new(0.05, 0.05, 0.0), 1);
        assert!(lc.step(100, 100, true, 0).is_none());
        assert!(!lc.report_due(0));
        lc.start(Pose::new(0.05, 0.05, 0.0), 0);
        assert!(lc.report_due(0));
        assert!(!lc.report_due(100));
        assert!(lc.report_due(200));
    }

    #[test]
    fn a_line_event_is_reported_with_its_line_and_correction() {
        let start = Pose::new(0.26, 0.05, 0.0);
        let mut lc = LineCorr::new(khepera_odometry(), start, 1);
        lc.start(start, 0);
        // Straight along +x at 10 mm per cycle: the x = 0.3 band starts at 0.295.
        let mut outcome = None;
        let mut level = false;
        for k in 0..6 {
            let x = 0.26 + 0.01 * (k + 1) as f32;
            level = level || (0.295..=0.305).contains(&x);
            if let Some(o) = lc.step(125, 125, level, k * 80) {
                outcome = Some(o);
                break;
            }
        }
        assert!(
            matches!(outcome, Some(LineOutcome::Corrected(_))),
            "{outcome:?}"
        );
        let m = lc.report(500);
        let e = m.last_event.expect("an event");
        assert_eq!(
            (e.verdict, e.axis, e.index),
            (LineVerdict::Corrected, LineAxis::X, 3)
        );
        assert_eq!(m.lines, 1);
        assert_eq!(m.corrections, 1);
        // The corrected pose is on the band the sensor entered (0.295..0.305).
        assert!((295..=305).contains(&m.corrected.x_mm), "{m:?}");
        // The frame fits the wire with room to spare, at the widest values too.
        let mut wide = m;
        wide.samples = [PpdSample {
            dx_mm: i16::MIN,
            dy_mm: i16::MAX,
            bias: [i8::MIN, i8::MAX],
        }; PPD_SAMPLES_SENT];
        let far = WirePose {
            x_mm: i32::MIN,
            y_mm: i32::MIN,
            heading_mrad: i16::MIN,
        };
        wide.corrected = far;
        wide.uncorrected = far;
        wide.baseline = far;
        wide.time_ms = u32::MAX;
        wide.ppd_size_mm = u16::MAX;
        wide.bias_mean = [i16::MIN; 2];
        (wide.lines, wide.corrections, wide.rejected) = (u16::MAX, u16::MAX, u16::MAX);
        wide.last_event = Some(LineEventInfo {
            time_ms: u32::MAX,
            verdict: LineVerdict::Echo,
            axis: LineAxis::Y,
            index: i16::MIN,
            moved_mm: u16::MAX,
            turned_mrad: i16::MIN,
            support_pct: u8::MAX,
        });
        let mut buf = [0u8; protocol::MAX_FRAME];
        let typical =
            protocol::encode(0, &protocol::Message::Localization(m), &mut buf).expect("fits");
        let n =
            protocol::encode(0, &protocol::Message::Localization(wide), &mut buf).expect("fits");
        // Frame sizes on the wire, delimiter included, quoted in PROTOCOL.md.
        assert_eq!((typical, n), (103, 218));
    }

    #[test]
    fn line_correction_fits_the_robots_ram_budget() {
        // The PPD is most of it; the whole robot must stay within 32 KB.
        let lc = core::mem::size_of::<LineCorr>();
        assert!(lc < 1600, "{lc}");
        assert!(core::mem::size_of::<crate::Robot<crate::robot::Khepera>>() <= 32 * 1024);
    }

    #[test]
    fn the_survey_dithers_gentle_turns_into_whole_motor_units() {
        let start = Pose::new(1.0, 1.0, 0.3);
        let mut lc = LineCorr::new(khepera_odometry(), start, 1);
        lc.start(start, 0);
        let (mut l, mut r) = (0i32, 0i32);
        for _ in 0..100 {
            let c = lc.drive(&KHEPERA, &[]);
            l += i32::from(c.left);
            r += i32::from(c.right);
        }
        // 100 mm/s = 12.5 units: the average is kept, not rounded to 12 or 13.
        let mean = (l + r) as f32 / 200.0;
        assert!((mean - 12.5).abs() < 0.05, "{mean}");
        // A wall dead ahead: the avoider turns.
        let c = lc.drive(&KHEPERA, &[(900, 0.1), (900, -0.1)]);
        assert_ne!(c.left, c.right);
    }
}
