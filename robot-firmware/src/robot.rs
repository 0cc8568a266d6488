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
//! Maps, plans and regions live in `transfer::Objects`; plan following is in `robot::follow`.

use core::mem::MaybeUninit;
use core::ptr::addr_of_mut;

use heapless::Deque;
use protocol::{
    AckInfo, Command, Event, EventCode, Message, Mode, NackReason, ObjectKind, PointMm,
    TransferAck, TransferStatus,
};

use crate::behaviour::{self, Arbiter, ArbiterParams, BehaviourSet, Inputs, Side};
use crate::deadreckon::{DeadReckonInput, DeadReckonParams, DeadReckoner, DegradeEvent};
use crate::execute::{ExecuteParams, Executor};
use crate::explore::{ExploreParams, Explorer};
use crate::guided::{guided_step, GuidedParams, GuidedPhase};
use crate::hal::{BeaconReading, GripperCommand, GripperState, Hal, MotorCommand};
use crate::hal_trace::HalTrace;
use crate::link::{Identity, Inbound, Link, LinkStatus, Reply, Response};
use crate::odometry::{encoder_delta, wrap_angle, Odometry, OdometryParams, Point, Pose};
use crate::params::{RobotConfig, Tunables};
use crate::profile::Profile;
use crate::telemetry;
use crate::transfer::{Installed, Objects};

mod alice;
mod any;
mod calibrate;
mod explore;
mod follow;
mod forage;
pub mod kit;
mod linecorr;
mod progress;
mod scan;

pub use alice::AliceState;
pub use any::AnyRobot;
pub use calibrate::{CalPhase, LightCalibration, T1 as LIGHT_NEAR_T1};
pub use follow::Execution;
pub use forage::{Forage, ForageParams, ForagePhase, GripStep};
pub use kit::{Absent, Alice, DomDinis, Khepera, Kit, Slot};
use kit::{AliceSlot, ExplorerSlot, ForageSlot, LightCalSlot, LineCorrSlot};
pub use linecorr::{LineCorr, REPORT_PERIOD_MS as LOCALIZATION_PERIOD_MS};
pub use progress::{MotionProgress, ProgressParams, REPORT_PERIOD_MS as PROGRESS_PERIOD_MS};
pub use scan::{LandmarkScan, ScanParams, Sighting};

/// Events waiting to be sent; a burst larger than this loses its oldest.
const EVENT_QUEUE: usize = 8;
/// Serial bytes read per `step`, so a flood cannot starve the control cycle.
const RX_BUDGET: usize = 1024;
/// Largest teleop request accepted, before clamping to `teleop_max_mm_s`.
const TELEOP_LIMIT_MM_S: i16 = 2000;
const TELEOP_LIMIT_MRAD_S: i16 = 20_000;
/// Largest coordinate accepted for a goal or pose, millimetres (1 km).
const COORD_LIMIT_MM: i32 = 1_000_000;
/// Minimum time between two beacon calibrations, ms (seed 004 §4 gives no rate).
const CALIBRATION_INTERVAL_MS: u32 = 1000;
/// Beacon bearing under which the beacon is taken to be straight ahead, radians (~3 degrees).
const BEACON_AHEAD_RAD: f32 = 0.05;
/// Beacon strength above which a calibration is attempted.
const CALIBRATION_MIN_STRENGTH: u8 = 20;

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

    /// What the link states of the robot in a `HelloReply`.
    fn link_status(&self) -> LinkStatus {
        LinkStatus {
            telemetry_hz: self.config.telemetry_hz,
            failsafe_ms: self.config.failsafe_ms,
            robot_id: self.config.robot_id,
        }
    }

    fn handle(&mut self, inbound: Inbound<'_>, now_ms: u32) -> Response {
        match inbound {
            Inbound::Connected => {
                // A new session starts at the default telemetry rate (PROTOCOL.md §4).
                self.config.telemetry_hz = protocol::timing::TELEMETRY_DEFAULT_HZ;
                self.next_telemetry_ms = now_ms;
                // The new session's station asks again for what it wants; a partial upload
                // is kept so that it can resume.
                self.objects.abort_download();
                self.objects.new_session();
                // The HelloReply states the settings of the session that starts now.
                Response::Session(self.link_status())
            }
            Inbound::Command { command, .. } => Response::Reply(self.apply(command, now_ms)),
            Inbound::Transfer(m) => self.transfer(&m, now_ms),
        }
    }

    /// A transfer frame: uploads to the robot (begin, chunk) and acks of its downloads.
    fn transfer(&mut self, m: &Message<'_>, now_ms: u32) -> Response {
        match m {
            Message::TransferBegin(b) => {
                let ack = match self.upload_refusal(b.object) {
                    Some(status) => TransferAck {
                        tag: b.tag,
                        next: 0,
                        status,
                        sack: 0,
                    },
                    None => self.objects.on_begin(b),
                };
                Response::Send(Message::TransferAck(ack))
            }
            // A calibration begun before `Mode::CalibrateLight` must not land in the middle of
            // one: the chunk is refused and the partial upload kept for later.
            Message::TransferData(c)
                if let Some(status) = self
                    .objects
                    .uploading(c.tag)
                    .and_then(|o| self.upload_refusal(o)) =>
            {
                Response::Send(Message::TransferAck(TransferAck {
                    tag: c.tag,
                    next: 0,
                    status,
                    sack: 0,
                }))
            }
            // Protocol 1's chunk, named by id: refused, nothing changed (PROTOCOL.md §8).
            Message::TransferChunk(c) => Response::Send(Message::TransferAck(
                protocol::transfer::refuse_retired_chunk(c),
            )),
            Message::TransferData(c) => {
                let (ack, installed) = self.objects.on_chunk(c, self.light_cal.get_mut());
                if let Some(i) = installed {
                    self.installed(i);
                }
                Response::Send(Message::TransferAck(ack))
            }
            Message::TransferAck(a) => {
                self.objects.on_ack(a, now_ms);
                Response::Nothing
            }
            _ => Response::Nothing,
        }
    }

    /// Why an upload of `object` is refused before its bytes are looked at: a light
    /// calibration on a robot without light sensors (no use for it), or while one is being
    /// trained (it would replace the network under training; try later).
    fn upload_refusal(&self, object: ObjectKind) -> Option<TransferStatus> {
        if object != ObjectKind::LightCalibration {
            None
        } else if !self.profile.has(protocol::caps::AMBIENT_LIGHT) || self.light_cal.get().is_none()
        {
            Some(TransferStatus::Rejected)
        } else if self.mode == Mode::CalibrateLight {
            Some(TransferStatus::Busy)
        } else {
            None
        }
    }

    /// Reports a new map, plan or calibration; a plan being executed is abandoned when replaced.
    fn installed(&mut self, what: Installed) {
        // Event values carry the object id's 32 bits (PROTOCOL.md §8).
        match what {
            Installed::LightCalibration { id } => {
                self.push_event(EventCode::CalibrationInstalled, id as i32)
            }
            Installed::Map { id } => self.push_event(EventCode::MapUpdated, id as i32),
            Installed::Plan { id } => {
                self.abort_plan();
                self.push_event(EventCode::PlanInstalled, id as i32);
            }
        }
    }

    /// Executes one command, or refuses it having changed nothing.
    pub fn apply(&mut self, command: Command, now_ms: u32) -> Reply {
        match self.try_apply(command, now_ms) {
            Ok(info) => Reply::Ack(info),
            Err(reason) => Reply::Nack(reason),
        }
    }

    fn try_apply(&mut self, command: Command, now_ms: u32) -> Result<AckInfo, NackReason> {
        match command {
            Command::SetMode(Mode::Explore) => K::Explorer::start(self)?,
            Command::SetMode(Mode::Forage) => K::Forage::start(self)?,
            Command::SetMode(mode) => {
                self.check_mode(mode)?;
                if mode == Mode::GoTo && self.goal.is_none() {
                    // SetMode(GoTo) resumes an earlier goal; GoTo(point) gives one.
                    return Err(NackReason::BadState);
                }
                self.enter(mode);
            }
            Command::Teleop { v_mm_s, w_mrad_s } => {
                if v_mm_s.unsigned_abs() > TELEOP_LIMIT_MM_S.unsigned_abs()
                    || w_mrad_s.unsigned_abs() > TELEOP_LIMIT_MRAD_S.unsigned_abs()
                {
                    return Err(NackReason::OutOfRange);
                }
                self.teleop = (v_mm_s, w_mrad_s);
                self.failsafe = false;
                if self.mode != Mode::Manual {
                    self.enter(Mode::Manual);
                }
            }
            Command::Stop => {
                self.teleop = (0, 0);
                self.enter(Mode::Idle);
            }
            Command::GoTo(p) => {
                let target = point_from_mm(p.x_mm, p.y_mm)?;
                self.check_mode(Mode::GoTo)?;
                // A point outside the arena (parameters arena_*_m) cannot be reached.
                if !self.in_arena(target) {
                    return Err(NackReason::BadPoint);
                }
                self.goal = Some(target);
                self.enter(Mode::GoTo);
            }
            Command::SetParam { id, value } => {
                self.check_param(id.0)?;
                let v = self.tunables().set(id.0, value)?;
                self.after_param_change(id.0);
                self.push_event(EventCode::ParamChanged, i32::from(id.0));
                return Ok(AckInfo::Param { id, value: v });
            }
            Command::GetParam { id } => {
                let value = self.param(id.0)?;
                return Ok(AckInfo::Param { id, value });
            }
            Command::SetTelemetryRate { hz } => {
                if hz > 50 {
                    return Err(NackReason::OutOfRange);
                }
                self.config.telemetry_hz = hz;
                self.next_telemetry_ms = now_ms;
                // The rate is parameter `telemetry_hz` too: say so, as a SetParam would, so a
                // station's editor and header follow whichever way it was set.
                self.push_event(
                    EventCode::ParamChanged,
                    i32::from(crate::params::id::TELEMETRY_HZ),
                );
            }
            Command::SetPose { pose } => {
                let p = point_from_mm(pose.x_mm, pose.y_mm)?;
                let heading = f32::from(pose.heading_mrad) / 1000.0;
                if libm::fabsf(heading) > core::f32::consts::PI + 1e-3 {
                    return Err(NackReason::OutOfRange);
                }
                self.odometry.set_pose(Pose::new(p.x, p.y, heading));
                if let Some(lc) = self.linecorr.get_mut() {
                    lc.set_pose(Pose::new(p.x, p.y, heading));
                }
                // Without encoders the heading comes from the compass; only x, y are set.
                self.dead.set_position(p);
            }
            Command::StartExploration => K::Explorer::start(self)?,
            Command::ExecutePlan { plan_id } => self.start_plan(plan_id)?,
            Command::Segment => {
                self.objects.segment()?;
            }
            Command::Plan { from, to } => {
                let here = self.pose();
                let from = from.unwrap_or(PointMm {
                    x_mm: libm::roundf(here.x * 1000.0) as i32,
                    y_mm: libm::roundf(here.y * 1000.0) as i32,
                });
                for p in [Some(from), to].into_iter().flatten() {
                    point_from_mm(p.x_mm, p.y_mm)?;
                }
                let id = self.objects.plan_route(from, to)?;
                self.installed(Installed::Plan { id });
            }
            Command::Download { object } => {
                return self.objects.start_download(object, self.light_cal.get());
            }
        }
        Ok(AckInfo::Done)
    }

    /// Whether `p` lies inside the arena bounds (parameters `arena_min_x_m` .. `arena_max_y_m`).
    fn in_arena(&self, p: Point) -> bool {
        let b = self.dead.params.bounds;
        (b.min.x..=b.max.x).contains(&p.x) && (b.min.y..=b.max.y).contains(&p.y)
    }

    fn tunables(&mut self) -> Tunables<'_> {
        Tunables {
            progress: &mut self.progress.params,
            robot: &mut self.config,
            odometry: &mut self.odometry.params,
            arbiter: &mut self.arbiter.params,
            dead_reckon: &mut self.dead.params,
            guided: &mut self.guided,
            explore: self.explorer.get_mut().map(|e| &mut e.params),
        }
    }

    /// The value of parameter `id` in force, as `GetParam` answers it.
    pub fn param(&mut self, id: u16) -> Result<f32, NackReason> {
        self.check_param(id)?;
        self.tunables().get(id)
    }

    /// Refuses a parameter this robot lacks the hardware for (`ParamInfo::requires`).
    fn check_param(&self, id: u16) -> Result<(), NackReason> {
        let info = crate::params::info(id).ok_or(NackReason::UnknownParam)?;
        if self.profile.has(info.requires) {
            Ok(())
        } else {
            Err(NackReason::Unsupported)
        }
    }

    fn after_param_change(&mut self, id: u16) {
        // A new rate takes effect at once rather than after the old period.
        if self.config.telemetry_hz > 0 {
            self.next_telemetry_ms = 0;
        }
        // New arena bounds validate the position again (seed 004 §4), the start as given.
        if (crate::params::id::ARENA_MIN_X_M..=crate::params::id::ARENA_MAX_Y_M).contains(&id) {
            self.dead.bounds_changed();
        }
    }

    /// Whether this robot can run `mode` now.
    fn check_mode(&self, mode: Mode) -> Result<(), NackReason> {
        let khepera_like =
            self.profile.has(protocol::caps::IR_PROXIMITY) && self.profile.ir.count == 8;
        match mode {
            Mode::Idle | Mode::Manual => Ok(()),
            Mode::GoTo => {
                if khepera_like || self.profile.has(protocol::caps::COMPASS) {
                    Ok(())
                } else {
                    Err(NackReason::Unsupported)
                }
            }
            // ALICE wanders by its whiskers (`robot::alice`).
            Mode::Wander if <K::Alice as Slot<AliceState>>::PRESENT => Ok(()),
            Mode::Wander | Mode::EdgeFollowLeft | Mode::EdgeFollowRight => {
                if khepera_like {
                    Ok(())
                } else {
                    Err(NackReason::Unsupported)
                }
            }
            Mode::SeekLight => {
                if khepera_like && self.profile.has(protocol::caps::AMBIENT_LIGHT) {
                    Ok(())
                } else {
                    Err(NackReason::Unsupported)
                }
            }
            Mode::Forage => {
                let caps = protocol::caps::AMBIENT_LIGHT
                    | protocol::caps::ENCODERS
                    | protocol::caps::GRIPPER;
                if khepera_like && self.profile.has(caps) {
                    Ok(())
                } else {
                    Err(NackReason::Unsupported)
                }
            }
            Mode::Survey if self.linecorr.get().is_none() => Err(NackReason::Unsupported),
            Mode::Survey => linecorr::check(self.profile),
            Mode::CalibrateLight => {
                let caps = protocol::caps::AMBIENT_LIGHT | protocol::caps::ENCODERS;
                if khepera_like && self.profile.has(caps) && self.light_cal.get().is_some() {
                    Ok(())
                } else {
                    Err(NackReason::Unsupported)
                }
            }
            // Handled by `start_exploration`, which `SetMode(Explore)` is routed to.
            Mode::Explore => Err(NackReason::BadState),
            // `ExecutePlan { plan_id }` starts a plan: the id proves which one the station
            // means, so `SetMode` alone is refused.
            Mode::ExecutePlan if self.objects.has_plan() => Err(NackReason::BadState),
            Mode::ExecutePlan => Err(NackReason::NoPlan),
        }
    }

    fn enter(&mut self, mode: Mode) {
        self.arrived = false;
        self.guided_active = false;
        let arbiter_mode = match mode {
            Mode::Wander => behaviour::Mode::Wander,
            Mode::EdgeFollowLeft => behaviour::Mode::EdgeFollow(Side::Left),
            Mode::EdgeFollowRight => behaviour::Mode::EdgeFollow(Side::Right),
            Mode::SeekLight => behaviour::Mode::DriveToLight,
            Mode::GoTo if self.profile.has(protocol::caps::ENCODERS) => match self.goal {
                Some(g) => behaviour::Mode::GoTo(g),
                None => behaviour::Mode::Idle,
            },
            Mode::GoTo => {
                self.guided_active = true;
                behaviour::Mode::Idle
            }
            Mode::ExecutePlan => self.plan_arbiter_mode(),
            Mode::Forage => K::Forage::arbiter_mode(self),
            _ => behaviour::Mode::Idle,
        };
        self.arbiter.set_mode(arbiter_mode);
        if mode == Mode::SeekLight {
            self.arbiter.release_light();
        }
        if mode == Mode::Survey {
            let (pose, now) = (self.pose(), self.cycle_ms);
            if let Some(lc) = self.linecorr.get_mut() {
                lc.start(pose, now);
            }
        }
        if mode == Mode::CalibrateLight {
            K::LightCal::start(self);
        }
        if let Some(a) = self.alice.get_mut() {
            a.wander.reset();
        }
        if mode != self.mode {
            self.mode = mode;
            self.push_event(EventCode::ModeChanged, mode as i32);
        }
        self.progress.restart(self.cycle_ms);
        // The report sent at once on entering names the distance left already (a mode with a
        // target has it from the start: the point, the plan, the goal light).
        let left = self.distance_left();
        self.progress.observe(self.cycle_ms, left);
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

    fn control_cycle<H: Hal>(&mut self, hal: &mut H, now_us: u64) {
        let now_ms = ms(now_us);
        self.cycle_ms = now_ms;
        let t = &mut self.timing;
        let cycle_us = u64::from(self.profile.cycle_us);
        if let Some(last) = t.last_cycle_us {
            t.period_us = u32::try_from(now_us.saturating_sub(last)).unwrap_or(u32::MAX);
            if u64::from(t.period_us) > cycle_us + cycle_us / 2 {
                t.overruns = t.overruns.wrapping_add(1);
            }
        }
        t.last_cycle_us = Some(now_us);
        t.cycles = t.cycles.wrapping_add(1);
        // Keep the cycle grid; after a stall of more than a cycle, restart it from now.
        t.next_cycle_us = if t.next_cycle_us + cycle_us > now_us {
            t.next_cycle_us + cycle_us
        } else {
            now_us + cycle_us
        };

        self.read_sensors(hal);
        K::Alice::read(self, hal);
        self.estimate(now_ms);
        K::Alice::sample(self, now_ms);
        K::LightCal::report_bearing(self, now_ms);
        self.map_as_it_moves();
        let cmd = match self.track_progress() {
            Some(stop) => stop,
            None => self.decide(),
        };
        let max = self.profile.motor_max;
        let cmd = cmd.clamped(max);
        self.motor = cmd;
        hal.set_motors(cmd);
        if self.profile.has(protocol::caps::GRIPPER) {
            hal.set_gripper(self.gripper_cmd);
        }
        let end = hal.now_us();
        self.timing.busy_us = u32::try_from(end.saturating_sub(now_us)).unwrap_or(u32::MAX);
    }

    fn read_sensors<H: Hal>(&mut self, hal: &mut H) {
        let s = Sensors {
            ir: hal.ir(),
            ambient: hal.ambient(),
            compass: hal.compass(),
            ground: hal.ground(),
            line: hal.line(),
            beacon: hal.beacon(),
            battery_mv: hal.battery_mv(),
            encoders: hal.encoders(),
            gripper: hal.gripper(),
        };
        let heading = self.pose().heading;
        if let Some(forage) = self.forage.get_mut() {
            if self.mode == Mode::Forage && forage.wants_frame() {
                // Only when a landmark scan asks (the K213 gives 2 frames a second), straight
                // into the scan, so the line is not kept.
                let mut line = [0u8; crate::hal::CAMERA_PIXELS];
                let ok = hal.camera(&mut line);
                forage.take_frame(heading, ok.then_some(&line));
            }
        }
        if s.line && !self.sensors.line {
            self.line_events = self.line_events.wrapping_add(1);
            self.push_event(EventCode::LineCrossed, i32::from(self.line_events));
        }
        self.sensors = s;
    }

    fn estimate(&mut self, now_ms: u32) {
        let period_s = (self.timing.period_us as f32) * 1e-6;
        if let Some(enc) = self.sensors.encoders {
            if let Some(prev) = self.prev_encoders {
                let dl = encoder_delta(prev[0], enc[0]);
                let dr = encoder_delta(prev[1], enc[1]);
                self.odometry.step(dl, dr);
                K::LineCorr::line_correct(self, dl, dr, now_ms);
                if period_s > 0.0 {
                    let mm = self.odometry.params.mm_per_pulse;
                    self.wheel_speed_mm_s = [
                        behaviour::units(dl as f32 * mm / period_s),
                        behaviour::units(dr as f32 * mm / period_s),
                    ];
                }
            }
            self.prev_encoders = Some(enc);
        }
        if !self.profile.has(protocol::caps::ENCODERS) {
            if let Some(h) = self.sensors.compass {
                self.compass_heading = wrap_angle(h);
            }
            let battery = self.battery_level();
            self.dead.step(
                now_ms,
                DeadReckonInput {
                    heading_rad: self.compass_heading,
                    nominal: [f32::from(self.motor.left), f32::from(self.motor.right)],
                    battery,
                },
            );
            let speed = |u: i16| {
                let mps = self.dead.params.speed.speed_mps(f32::from(u), battery);
                behaviour::units(mps * 1000.0)
            };
            self.wheel_speed_mm_s = [speed(self.motor.left), speed(self.motor.right)];
            self.calibrate_on_beacon(now_ms);
        }
    }

    /// Seed 004 §4: with the beacon straight ahead, its strength gives the distance and the
    /// compass the direction, an alternative position blended in by the confidence xi.
    fn calibrate_on_beacon(&mut self, now_ms: u32) {
        let Some(b) = self.sensors.beacon else { return };
        let recent = self
            .last_calibration_ms
            .is_some_and(|t| now_ms.wrapping_sub(t) < CALIBRATION_INTERVAL_MS);
        if recent
            || b.strength < CALIBRATION_MIN_STRENGTH
            || libm::fabsf(b.bearing_rad) > BEACON_AHEAD_RAD
        {
            return;
        }
        let bearing = wrap_angle(self.compass_heading + b.bearing_rad);
        if self.dead.calibrate(u16::from(b.strength), bearing).is_ok() {
            self.last_calibration_ms = Some(now_ms);
            let xi = libm::roundf(self.dead.confidence() * 1000.0) as i32;
            self.push_event(EventCode::BeaconCalibration, xi);
        }
    }

    /// Battery level 0..=1 from the voltage, for the speed table.
    fn battery_level(&self) -> f32 {
        let (lo, hi) = (self.config.battery_empty_mv, self.config.battery_full_mv);
        if hi <= lo || self.sensors.battery_mv == 0 {
            // Unknown battery: assume average, the paper's reference point.
            return 0.5;
        }
        let v = f32::from(self.sensors.battery_mv.saturating_sub(lo)) / f32::from(hi - lo);
        v.clamp(0.0, 1.0)
    }

    /// The motor command for this cycle, by mode.
    fn decide(&mut self) -> MotorCommand {
        let cmd = self.mode_command();
        // A task that ended this cycle (it arrived) left the robot Idle: stopped at once.
        if self.mode == Mode::Idle {
            MotorCommand::STOP
        } else {
            cmd
        }
    }

    fn mode_command(&mut self) -> MotorCommand {
        if self.mode == Mode::Wander {
            // ALICE wanders by its whiskers; the others by the arbiter's IR behaviours.
            if let Some(cmd) = K::Alice::wander(self) {
                return cmd;
            }
        }
        match self.mode {
            Mode::Idle => MotorCommand::STOP,
            Mode::Manual => {
                if self.failsafe {
                    MotorCommand::STOP
                } else {
                    self.teleop_command()
                }
            }
            Mode::GoTo if self.guided_active => self.guided_command(),
            Mode::GoTo
            | Mode::Wander
            | Mode::EdgeFollowLeft
            | Mode::EdgeFollowRight
            | Mode::SeekLight => self.behaviour_command(),
            Mode::ExecutePlan => self.plan_command(),
            Mode::Explore => K::Explorer::command(self),
            Mode::Forage => K::Forage::command(self),
            Mode::Survey => K::LineCorr::survey_command(self),
            Mode::CalibrateLight => K::LightCal::command(self),
        }
    }

    /// Differential-drive kinematics: wheel speeds from forward speed and turn rate.
    fn teleop_command(&self) -> MotorCommand {
        let (v, w) = self.teleop;
        let half_base_mm = self.profile.wheel_distance_m * 500.0;
        let max = self.config.teleop_max_mm_s;
        let turn = f32::from(w) / 1000.0 * half_base_mm;
        let left = (f32::from(v) - turn).clamp(-max, max);
        let right = (f32::from(v) + turn).clamp(-max, max);
        MotorCommand::new(
            self.profile.motor_units(left),
            self.profile.motor_units(right),
        )
    }

    fn behaviour_command(&mut self) -> MotorCommand {
        let inputs = Inputs::fresh(self.sensors.ir, self.sensors.ambient, self.pose());
        let cmd = self.arbiter.step(&inputs);
        let st = self.arbiter.state();
        let dead_end = st.dead_end;
        let reached = st.drift_phase == behaviour::drift::DriftPhase::Reached;
        if dead_end && !self.prev_dead_end {
            self.dead.degrade(DegradeEvent::DeadEnd);
        }
        self.prev_dead_end = dead_end;
        if self.mode == Mode::GoTo && reached {
            self.mark_arrived();
        }
        cmd
    }

    /// The IR readings with their mounting directions (radians, positive to the left), as
    /// guided motion, plan execution and exploration take them; `n` of the slots are in use.
    fn ir_rays(&self) -> ([(u16, f32); 8], usize) {
        let mut ir = [(0u16, 0.0f32); 8];
        let n = self.profile.ir.count.min(8);
        for (i, slot) in ir.iter_mut().enumerate().take(n) {
            *slot = (self.sensors.ir[i], self.profile.ir.angle_rad[i]);
        }
        (ir, n)
    }

    fn guided_command(&mut self) -> MotorCommand {
        let Some(goal) = self.goal else {
            return MotorCommand::STOP;
        };
        if let Some(cmd) = K::Explorer::goto(self, goal) {
            return cmd;
        }
        let (ir, n) = self.ir_rays();
        let (cmd, phase) = guided_step(self.pose(), goal, &ir[..n], &self.guided);
        if phase == GuidedPhase::Arrived {
            self.mark_arrived();
        }
        cmd
    }

    /// The task is done: `GoalReached`, and the robot goes Idle with its motors stopped, so
    /// that its mode, its progress reports (none in Idle) and the station's status line say
    /// the task is over instead of counting time without progress at its end. `arrived`
    /// stays set until the next mode begins: it says the last task ended by arriving.
    fn mark_arrived(&mut self) {
        if !self.arrived {
            self.push_event(EventCode::GoalReached, 0);
            self.enter(Mode::Idle);
            self.arrived = true;
        }
    }

    /// The behaviour bits and motor output telemetry reports.
    pub fn behaviour_report(&self) -> (u8, MotorCommand) {
        use protocol::behaviours as b;
        let mut bits = 0u8;
        let arbiter_driven = match self.mode {
            Mode::GoTo => !self.guided_active,
            Mode::Wander | Mode::EdgeFollowLeft | Mode::EdgeFollowRight | Mode::SeekLight => true,
            Mode::ExecutePlan => !self.plan_guided(),
            Mode::Forage => true,
            _ => false,
        };
        if arbiter_driven {
            let active = self.arbiter.state().active;
            for (from, to) in [
                (BehaviourSet::AVOID, b::AVOID),
                (BehaviourSet::EDGE, b::EDGE),
                (BehaviourSet::DRIFT, b::DRIFT),
                (BehaviourSet::TURN, b::TURN),
                (BehaviourSet::LIGHT, b::LIGHT),
            ] {
                if active.contains(from) {
                    bits |= to;
                }
            }
        }
        if (self.guided_active && self.mode == Mode::GoTo)
            || (self.mode == Mode::ExecutePlan && self.plan_guided())
        {
            bits |= b::GUIDED;
        }
        (bits, self.motor)
    }

    pub fn emulated(&self) -> bool {
        self.emulated
    }
}

fn point_from_mm(x_mm: i32, y_mm: i32) -> Result<Point, NackReason> {
    if x_mm.unsigned_abs() > COORD_LIMIT_MM.unsigned_abs()
        || y_mm.unsigned_abs() > COORD_LIMIT_MM.unsigned_abs()
    {
        return Err(NackReason::BadPoint);
    }
    Ok(Point::new(x_mm as f32 / 1000.0, y_mm as f32 / 1000.0))
}

/// Milliseconds of a microsecond clock, wrapping at 2^32 (49.7 days) like the wire's time_ms.
fn ms(us: u64) -> u32 {
    (us / 1000) as u32
}

/// Whether wrapping time `now` has reached `deadline`.
fn due(now: u32, deadline: u32) -> bool {
    now.wrapping_sub(deadline) < 0x8000_0000
}
