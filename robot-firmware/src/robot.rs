//! The robot: one `step()` per pass of the main loop, a control cycle when its period is due.
//!
//! Layer: the top of the firmware. `Robot::step` is the only function that touches the `Hal`:
//! it moves serial bytes through the link handler, runs the control cycle (sensors, position
//! estimate, mode logic, motors) every `Profile::cycle_us`, and schedules telemetry and
//! heartbeats. Call it as often as the board allows (every millisecond or so): the link is
//! serviced on every call, so telemetry can run faster than the control cycle (up to 50 Hz)
//! and a failsafe stop takes effect at once rather than at the next cycle. When
//! `Robot::idle_until_us` gives a time, no call before it has work unless a byte arrives: a
//! board may sleep until then or its receive interrupt (the emulator skips those calls).
//!
//! Invariants: the motors move only in a mode a handshaken station (or the firmware's own
//! autonomy) asked for; a refused command changes nothing; every piece of state has a fixed
//! size (`size_of::<Robot<K>>()` is the firmware's whole RAM use apart from the stack).
//! A robot carries the capabilities its profile uses (`kit`: `Robot<DomDinis>`,
//! `Robot<Khepera>`); a board builds it in place (`Robot::init`), hosts pick one by profile
//! (`AnyRobot`).
//! What a station's frames do to the robot is `robot::commands`; the control cycle
//! `robot::cycle`; the telemetry frame `robot::telemetry`. Maps, plans and regions live in
//! `transfer::Objects`; plan following is in `robot::follow`.

use core::mem::MaybeUninit;
use core::ptr::addr_of_mut;

use heapless::Deque;
use protocol::{Event, EventCode, Message, Mode};

use crate::behaviour::{Arbiter, ArbiterParams};
use crate::deadreckon::{DeadReckonParams, DeadReckoner};
use crate::execute::{ExecuteParams, Executor};
use crate::explore::{ExploreParams, Explorer};
use crate::guided::GuidedParams;
use crate::hal::{BeaconReading, GripperCommand, GripperState, Hal, MotorCommand};
use crate::hal_trace::HalTrace;
use crate::link::{Identity, Link};
use crate::odometry::{Odometry, OdometryParams, Point, Pose};
use crate::params::RobotConfig;
use crate::profile::Profile;
use crate::transfer::Objects;

mod alice;
mod any;
mod calibrate;
mod commands;
mod cycle;
mod explore;
mod follow;
mod forage;
pub mod kit;
mod linecorr;
mod progress;
mod scan;
mod telemetry;

pub use crate::light_calibration::{CalPhase, LightCalibration, T1 as LIGHT_NEAR_T1};
pub use crate::motion_progress::{
    MotionProgress, ProgressParams, REPORT_PERIOD_MS as PROGRESS_PERIOD_MS,
};
pub use alice::AliceState;
pub use any::AnyRobot;
pub use follow::Execution;
pub use forage::{Forage, ForageParams, ForagePhase, GripStep};
pub use kit::{Absent, Alice, DomDinis, Khepera, Kit, Slot};
pub use linecorr::{LineCorr, REPORT_PERIOD_MS as LOCALIZATION_PERIOD_MS};
pub use scan::{LandmarkScan, ScanParams, Sighting};

/// Events waiting to be sent; a burst larger than this loses its oldest.
const EVENT_QUEUE: usize = 8;
/// Serial bytes read per `step`, so a flood cannot starve the control cycle.
const RX_BUDGET: usize = 1024;

/// How a robot is started.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RobotOptions {
    pub profile: &'static Profile,
    /// Seeds the behaviours' random draws (seed 000 §4.2 threshold jitter).
    pub seed: u32,
    /// Where the robot believes it starts (metres, radians).
    pub start: Pose,
    /// Set by the emulator: the HelloReply says so and `EmuTruth` frames follow telemetry.
    pub emulated: bool,
    pub firmware_version: &'static str,
}

/// The last sensor readings.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sensors {
    pub ir: [u16; 8],
    pub ambient: [u16; 8],
    pub compass: Option<f32>,
    pub ground: bool,
    pub line: bool,
    pub beacon: Option<BeaconReading>,
    pub battery_mv: u16,
    pub encoders: Option<[i32; 2]>,
    /// The gripper turret; `None` without one.
    pub gripper: Option<GripperState>,
}

/// Control-cycle timing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Timing {
    pub last_cycle_us: Option<u64>,
    pub next_cycle_us: u64,
    pub period_us: u32,
    pub busy_us: u32,
    pub overruns: u8,
    pub cycles: u32,
}

/// Everything but the link: the state commands act on.
pub struct Core<K: Kit> {
    pub profile: &'static Profile,
    pub config: RobotConfig,
    pub arbiter: Arbiter,
    pub odometry: Odometry,
    pub dead: DeadReckoner,
    pub guided: GuidedParams,
    /// Heading from the compass (micro-rato), radians.
    pub compass_heading: f32,
    pub mode: Mode,
    pub goal: Option<Point>,
    /// Manual-mode request: forward mm/s, turn mrad/s.
    pub teleop: (i16, i16),
    /// The motor command in force.
    pub motor: MotorCommand,
    pub sensors: Sensors,
    prev_encoders: Option<[i32; 2]>,
    pub wheel_speed_mm_s: [i16; 2],
    pub arrived: bool,
    /// The manual-mode failsafe has stopped the motors.
    pub failsafe: bool,
    pub line_events: u8,
    last_calibration_ms: Option<u32>,
    prev_dead_end: bool,
    guided_active: bool,
    pub timing: Timing,
    next_telemetry_ms: u32,
    events: Deque<Event, EVENT_QUEUE>,
    emulated: bool,
    /// Map, plan, regions and their transfers (seed 004 §5-7, PROTOCOL.md §8).
    pub objects: Objects,
    /// Progress through the installed plan in `Mode::ExecutePlan`.
    pub exec: Option<Execution>,
    /// Seed 004 §7 heuristics for guided plan legs.
    pub executor: Executor,
    /// Seed 004 §5 reactive search with mapping.
    pub explorer: K::Explorer,
    /// Time of the current control cycle, ms.
    cycle_ms: u32,
    /// Seed 000 §7 foraging state.
    pub forage: K::Forage,
    /// The gripper command in force (sent each cycle on a robot with a gripper).
    pub gripper_cmd: GripperCommand,
    /// Seed 003 floor-grid line correction and the survey pilot.
    pub linecorr: K::LineCorr,
    /// Seed 000 §5.3 light -> angle calibration (`Mode::CalibrateLight`).
    pub light_cal: K::LightCal,
    /// What the mode in force is doing; giving up when it makes no progress.
    pub progress: MotionProgress,
    /// Seed 001 ALICE: whiskers, photoresistors, situations, wandering.
    pub alice: K::Alice,
}

/// The whole robot.
pub struct Robot<K: Kit> {
    pub link: Link,
    pub core: Core<K>,
    identity: Identity,
    /// The hardware trace (parameter 34 `hal_trace`, `hal_trace`).
    pub trace: HalTrace,
}

impl<K: Kit> Robot<K> {
    /// A robot by value, for hosts: it passes through the stack (some 30 KB), so a board
    /// builds its robot in place with `init`.
    #[allow(unsafe_code)] // one call of assume_init, after init
    pub fn new(opts: RobotOptions) -> Self {
        let mut slot = MaybeUninit::uninit();
        Self::init(&mut slot, opts);
        // SAFETY: `init` wrote every field.
        unsafe { slot.assume_init() }
    }

    /// Builds the robot in `slot` (a `static` on a board), field by field, so that no whole
    /// robot and none of its large parts (the map and plan objects) pass through the stack:
    /// the size report finds `init`'s frame small.
    #[allow(unsafe_code)] // writes to the fields of a MaybeUninit through raw pointers
    pub fn init(slot: &mut MaybeUninit<Self>, opts: RobotOptions) -> &mut Self {
        let profile = opts.profile;
        let mut capabilities = profile.capabilities & !kit::lacking::<K>();
        if opts.emulated {
            capabilities |= protocol::caps::EMULATED;
        }
        let p = slot.as_mut_ptr();
        // SAFETY: `p` points to writable memory for a `Robot<K>`; each field is written once
        // through a raw pointer to it, no reference to an unwritten field is made, and
        // `Core::init` writes every field of the core (see `every_core_field_is_written`).
        unsafe {
            addr_of_mut!((*p).link).write(Link::new());
            addr_of_mut!((*p).identity).write(Identity {
                firmware: "robot-firmware",
                firmware_version: opts.firmware_version,
                profile: profile.id,
                capabilities,
                map_capacity: profile.map_capacity(),
            });
            addr_of_mut!((*p).trace).write(HalTrace::new(opts.seed, opts.start));
            Core::init(addr_of_mut!((*p).core), &opts);
            slot.assume_init_mut()
        }
    }

    /// One pass of the main loop. While `hal_trace` is on, the board's `Hal` is wrapped in
    /// the trace's `Recorder` (the one place the trace is captured, `hal_trace`).
    pub fn step<H: Hal>(&mut self, hal: &mut H) {
        let on = self.core.config.hal_trace != 0;
        let Robot {
            link,
            core,
            identity,
            trace,
        } = self;
        if on || trace.is_on() {
            let d = &core.dead.params;
            let told = [d.beacon, d.bounds.min, d.bounds.max];
            trace.switch(on, core.profile.id as u8, core.emulated, told);
        } else {
            trace.count_untraced();
        }
        if trace.is_on() {
            let mut rec = crate::hal_trace::Recorder::new(hal, trace);
            pass(
                link,
                core,
                identity,
                &mut rec,
                &mut |rec, link, now_ms, cycle| rec.trace().emit(link, now_ms, cycle),
            );
            rec.finish();
        } else {
            pass(link, core, identity, hal, &mut |_, _, _, _| {});
        }
    }

    /// Until when (µs) a pass of the main loop has nothing to do unless a byte arrives: the
    /// next control cycle, while no station's session is open, no reply is remembered, no
    /// frame or event waits to go, tracing is off and no failsafe is counting down (each of
    /// those has work at a time of its own). `None`: a pass may have work now. A board may
    /// sleep until then or its receive interrupt, as a tickless kernel does; the emulator
    /// skips those passes, each of which found nothing to do (issue 15: they were a seventh
    /// of a headless run). `count_untraced` then counts the passes made.
    pub fn idle_until_us(&self) -> Option<u64> {
        let (link, core) = (&self.link, &self.core);
        let quiet = !link.connected()
            && link.queued() == 0
            && !link.remembers_replies()
            && core.events.is_empty()
            && core.config.hal_trace == 0
            && !self.trace.is_on()
            && (core.mode != Mode::Manual || core.failsafe)
            && !core.must_stop_now();
        quiet.then_some(core.timing.next_cycle_us)
    }

    /// Whether the robot declared itself emulated.
    pub fn emulated(&self) -> bool {
        self.core.emulated
    }

    /// The pose the robot believes in.
    pub fn pose(&self) -> Pose {
        self.core.pose()
    }
}

/// One pass of the main loop over the robot's parts; `emit_trace` hands the hardware trace to
/// the link before the link's bytes go out (a no-op while tracing is off).
fn pass<K: Kit, H: Hal>(
    link: &mut Link,
    core: &mut Core<K>,
    identity: &Identity,
    hal: &mut H,
    emit_trace: &mut dyn FnMut(&mut H, &mut Link, u32, bool),
) {
    let now_us = hal.now_us();
    let now_ms = ms(now_us);
    receive(link, core, identity, hal, now_ms);
    link.expire(now_ms, protocol::timing::LINK_TIMEOUT_MS);
    core.check_failsafe(link.last_rx_ms(), now_ms);
    if core.must_stop_now() {
        core.motor = MotorCommand::STOP;
        hal.set_motors(MotorCommand::STOP);
    }
    let cycles = core.timing.cycles;
    if now_us >= core.timing.next_cycle_us {
        core.control_cycle(hal, now_us);
    }
    // Nothing to send and no event to drop while no station listens: skipped (the loop runs
    // every millisecond in the emulator, where these calls were a twentieth of a run).
    if link.connected() || !core.events.is_empty() {
        send_periodic(link, core, now_ms);
    }
    if link.connected() {
        // Download chunks yield to replies and events, like telemetry.
        core.objects
            .poll(now_ms, &mut |m| link.send_low_priority(m, now_ms));
    }
    emit_trace(hal, link, now_ms, cycles != core.timing.cycles);
    if link.queued() > 0 {
        link.flush(&mut |bytes| hal.serial_write(bytes));
    }
}

fn receive<K: Kit, H: Hal>(
    link: &mut Link,
    core: &mut Core<K>,
    identity: &Identity,
    hal: &mut H,
    now_ms: u32,
) {
    let mut buf = [0u8; 128];
    let mut budget = RX_BUDGET;
    while budget > 0 {
        let want = buf.len().min(budget);
        let n = hal.serial_read(&mut buf[..want]).min(want);
        if n == 0 {
            break;
        }
        budget -= n;
        let status = core.link_status();
        link.receive(&buf[..n], now_ms, identity, status, &mut |inbound| {
            core.handle(inbound, now_ms)
        });
    }
}

fn send_periodic<K: Kit>(link: &mut Link, core: &mut Core<K>, now_ms: u32) {
    while let Some(ev) = core.events.pop_front() {
        if !link.connected() {
            continue;
        }
        link.send(&Message::Event(ev), now_ms);
    }
    if !link.connected() {
        return;
    }
    let hz = core.config.telemetry_hz;
    if hz > 0 && due(now_ms, core.next_telemetry_ms) {
        let t = telemetry::build(core, now_ms);
        link.send_low_priority(&Message::Telemetry(t), now_ms);
        let period = 1000 / u32::from(hz);
        let next = core.next_telemetry_ms.wrapping_add(period);
        // Fell behind by more than a period (a stall): restart the schedule from now.
        core.next_telemetry_ms = if due(now_ms, next.wrapping_add(period)) {
            now_ms.wrapping_add(period)
        } else {
            next
        };
    }
    let plan = core.plan_position();
    if let Some(p) = core.progress.report_due(core.mode, now_ms, plan) {
        link.send_low_priority(&Message::Progress(p), now_ms);
    }
    if let Some(a) = core.alice.get_mut() {
        alice::send_situation(link, a, now_ms);
    }
    if let Some(lc) = core.linecorr.get_mut() {
        if lc.report_due(now_ms) {
            let m = lc.report(now_ms);
            link.send_low_priority(&Message::Localization(m), now_ms);
        }
    }
    link.heartbeat(now_ms, protocol::timing::HEARTBEAT_PERIOD_MS);
}

impl<K: Kit> Core<K> {
    /// Writes every field of the core at `p` (`Robot::init`).
    ///
    /// # Safety
    /// `p` must point to writable memory for a `Core<K>`; its old contents are overwritten,
    /// not dropped.
    #[allow(unsafe_code)] // raw-pointer writes of each field
    unsafe fn init(p: *mut Self, opts: &RobotOptions) {
        /// The map, plan and staging buffers (24 KB): copied from a constant straight into
        /// place rather than built in a stack frame.
        const NO_OBJECTS: Objects = Objects::new();
        macro_rules! put {
            ($($field:ident: $value:expr,)*) => {
                // SAFETY: the caller's; one write per field, none read.
                $(unsafe { addr_of_mut!((*p).$field).write($value) };)*
            };
        }
        let profile = opts.profile;
        let odometry_params = OdometryParams {
            wheel_distance_mm: profile.wheel_distance_m * 1000.0,
            mm_per_pulse: profile.pulse_m * 1000.0,
            ..OdometryParams::default()
        };
        put! {
            profile: profile,
            config: RobotConfig::default(),
            arbiter: Arbiter::new(ArbiterParams::default(), opts.seed),
            odometry: Odometry::new(odometry_params, opts.start),
            dead: DeadReckoner::new(DeadReckonParams::default(), opts.start.point()),
            guided: GuidedParams::default(),
            compass_heading: opts.start.heading,
            mode: Mode::Idle,
            goal: None,
            teleop: (0, 0),
            motor: MotorCommand::STOP,
            sensors: Sensors::default(),
            prev_encoders: None,
            wheel_speed_mm_s: [0, 0],
            arrived: false,
            failsafe: false,
            line_events: 0,
            last_calibration_ms: None,
            prev_dead_end: false,
            guided_active: false,
            timing: Timing::default(),
            next_telemetry_ms: 0,
            events: Deque::new(),
            emulated: opts.emulated,
            objects: NO_OBJECTS,
            exec: None,
            executor: Executor::new(ExecuteParams::default(), opts.start.point()),
            explorer: Slot::fill(|| {
                Explorer::new(ExploreParams::default(), opts.seed ^ 0x5EED_0004)
            }),
            cycle_ms: 0,
            forage: Slot::fill(Forage::default),
            gripper_cmd: GripperCommand::default(),
            linecorr: Slot::fill(|| {
                LineCorr::new(odometry_params, opts.start, opts.seed ^ 0x5EED_0003)
            }),
            light_cal: Slot::fill(|| LightCalibration::new(opts.seed ^ 0x5EED_0005)),
            progress: MotionProgress::new(ProgressParams::for_profile(profile)),
            alice: Slot::fill(|| AliceState::new(opts.seed ^ 0x5EED_0001)),
        }
    }

    /// Never called: names every field of `Core` without `..`, so that a field added to the
    /// struct and not to `init` fails to compile here instead of being left unwritten.
    #[allow(dead_code)]
    fn every_core_field_is_written(self) {
        let Core {
            profile: _,
            config: _,
            arbiter: _,
            odometry: _,
            dead: _,
            guided: _,
            compass_heading: _,
            mode: _,
            goal: _,
            teleop: _,
            motor: _,
            sensors: _,
            prev_encoders: _,
            wheel_speed_mm_s: _,
            arrived: _,
            failsafe: _,
            line_events: _,
            last_calibration_ms: _,
            prev_dead_end: _,
            guided_active: _,
            timing: _,
            next_telemetry_ms: _,
            events: _,
            emulated: _,
            objects: _,
            exec: _,
            executor: _,
            explorer: _,
            cycle_ms: _,
            forage: _,
            gripper_cmd: _,
            linecorr: _,
            light_cal: _,
            progress: _,
            alice: _,
        } = self;
    }

    /// The pose estimate: odometry on robots with encoders, compass dead reckoning otherwise.
    pub fn pose(&self) -> Pose {
        if let Some(lc) = self.linecorr.get().filter(|lc| lc.active()) {
            lc.pose()
        } else if self.profile.has(protocol::caps::ENCODERS) {
            self.odometry.pose()
        } else {
            let p = self.dead.position();
            Pose::new(p.x, p.y, self.compass_heading)
        }
    }

    fn push_event(&mut self, code: EventCode, value: i32) {
        if self.events.is_full() {
            self.events.pop_front();
        }
        let _ = self.events.push_back(Event { code, value });
    }

    fn check_failsafe(&mut self, last_rx_ms: u32, now_ms: u32) {
        if self.mode != Mode::Manual || self.failsafe {
            return;
        }
        let silence = now_ms.wrapping_sub(last_rx_ms);
        // ">=": the motors must be stopped within failsafe_ms of the last byte, not after it.
        if silence >= u32::from(self.config.failsafe_ms) {
            self.failsafe = true;
            self.teleop = (0, 0);
            self.push_event(
                EventCode::FailsafeStop,
                i32::try_from(silence).unwrap_or(i32::MAX),
            );
        }
    }

    fn must_stop_now(&self) -> bool {
        self.motor != MotorCommand::STOP
            && (self.mode == Mode::Idle || (self.mode == Mode::Manual && self.failsafe))
    }

    pub fn emulated(&self) -> bool {
        self.emulated
    }
}

/// Milliseconds of a microsecond clock, wrapping at 2^32 (49.7 days) like the wire's time_ms.
fn ms(us: u64) -> u32 {
    (us / 1000) as u32
}

/// Whether wrapping time `now` has reached `deadline`.
fn due(now: u32, deadline: u32) -> bool {
    now.wrapping_sub(deadline) < 0x8000_0000
}
