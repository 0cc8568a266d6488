//! The robot's side of a session: what a station's frames do to the core. A handshake
//! (`handle`), transfer frames (`transfer`), commands (`apply`: checked against the mode,
//! the profile and the parameters' ranges, then carried out or refused whole), parameter
//! reads and writes, and entering a mode.
//!
//! Layer: part of `Robot::step`'s link pass; no I/O (the link handler owns the bytes).
//! A refused command changes nothing.

use protocol::{
    AckInfo, Command, EventCode, Message, Mode, NackReason, ObjectKind, PointMm, TransferAck,
    TransferStatus,
};

use super::kit::{ExplorerSlot, ForageSlot, LightCalSlot};
use super::{linecorr, AliceState, Core, Kit, Slot};
use crate::behaviour::{self, Side};
use crate::link::{Inbound, LinkStatus, Reply, Response};
use crate::odometry::{Point, Pose};
use crate::params::Tunables;
use crate::transfer::Installed;

/// Largest teleop request accepted, before clamping to `teleop_max_mm_s`.
const TELEOP_LIMIT_MM_S: i16 = 2000;
const TELEOP_LIMIT_MRAD_S: i16 = 20_000;
/// Largest coordinate accepted for a goal or pose, millimetres (1 km).
const COORD_LIMIT_MM: i32 = 1_000_000;

impl<K: Kit> Core<K> {
    /// What the link states of the robot in a `HelloReply`.
    pub(super) fn link_status(&self) -> LinkStatus {
        LinkStatus {
            telemetry_hz: self.config.telemetry_hz,
            failsafe_ms: self.config.failsafe_ms,
            robot_id: self.config.robot_id,
        }
    }

    pub(super) fn handle(&mut self, inbound: Inbound<'_>, now_ms: u32) -> Response {
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
    pub(super) fn transfer(&mut self, m: &Message<'_>, now_ms: u32) -> Response {
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
    pub(super) fn upload_refusal(&self, object: ObjectKind) -> Option<TransferStatus> {
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
    pub(super) fn installed(&mut self, what: Installed) {
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

    pub(super) fn try_apply(
        &mut self,
        command: Command,
        now_ms: u32,
    ) -> Result<AckInfo, NackReason> {
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
    pub(super) fn in_arena(&self, p: Point) -> bool {
        let b = self.dead.params.bounds;
        (b.min.x..=b.max.x).contains(&p.x) && (b.min.y..=b.max.y).contains(&p.y)
    }

    pub(super) fn tunables(&mut self) -> Tunables<'_> {
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
    pub(super) fn check_param(&self, id: u16) -> Result<(), NackReason> {
        let info = crate::params::info(id).ok_or(NackReason::UnknownParam)?;
        if self.profile.has(info.requires) {
            Ok(())
        } else {
            Err(NackReason::Unsupported)
        }
    }

    pub(super) fn after_param_change(&mut self, id: u16) {
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
    pub(super) fn check_mode(&self, mode: Mode) -> Result<(), NackReason> {
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

    pub(super) fn enter(&mut self, mode: Mode) {
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
}

fn point_from_mm(x_mm: i32, y_mm: i32) -> Result<Point, NackReason> {
    if x_mm.unsigned_abs() > COORD_LIMIT_MM.unsigned_abs()
        || y_mm.unsigned_abs() > COORD_LIMIT_MM.unsigned_abs()
    {
        return Err(NackReason::BadPoint);
    }
    Ok(Point::new(x_mm as f32 / 1000.0, y_mm as f32 / 1000.0))
}
