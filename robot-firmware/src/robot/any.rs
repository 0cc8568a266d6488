//! The robot of a profile chosen at run time: the emulator and the station's bench build the
//! composition (`kit`) the profile uses. A board builds its one `Robot<K>` directly (in place,
//! `Robot::init`); this enum is for hosts, where the profile is an argument.

use protocol::{Command, Mode, ProfileId};

use super::{
    Alice, DomDinis, Forage, Khepera, LightCalibration, LineCorr, Robot, RobotOptions, Sensors,
    Slot, Timing,
};
use crate::behaviour::Arbiter;
use crate::deadreckon::DeadReckoner;
use crate::guided::GuidedParams;
use crate::hal::Hal;
use crate::link::{Link, Reply};
use crate::odometry::Pose;
use crate::params::RobotConfig;
use crate::profile::Profile;
use crate::transfer::Objects;

/// One robot of any composition.
// The variants differ by the capabilities one lacks (a few KB of some 30); boxing would need a
// heap, which the firmware crate has not.
#[allow(clippy::large_enum_variant)]
pub enum AnyRobot {
    DomDinis(Robot<DomDinis>),
    Khepera(Robot<Khepera>),
    Alice(Robot<Alice>),
}

/// `$body` with `$r` bound to the robot, whatever its composition.
macro_rules! each {
    ($self:expr, $r:ident => $body:expr) => {
        match $self {
            AnyRobot::DomDinis($r) => $body,
            AnyRobot::Khepera($r) => $body,
            AnyRobot::Alice($r) => $body,
        }
    };
}

impl AnyRobot {
    /// The composition `opts.profile` uses.
    pub fn new(opts: RobotOptions) -> Self {
        match opts.profile.id {
            ProfileId::MicroRato => AnyRobot::DomDinis(Robot::new(opts)),
            ProfileId::Khepera => AnyRobot::Khepera(Robot::new(opts)),
            ProfileId::Alice => AnyRobot::Alice(Robot::new(opts)),
        }
    }

    /// The composition's name (`Kit::NAME`).
    pub fn kit(&self) -> &'static str {
        use super::Kit;
        match self {
            AnyRobot::DomDinis(_) => DomDinis::NAME,
            AnyRobot::Khepera(_) => Khepera::NAME,
            AnyRobot::Alice(_) => Alice::NAME,
        }
    }

    /// The Khepera composition, when it is one (its capabilities' state in full).
    pub fn khepera(&self) -> Option<&Robot<Khepera>> {
        match self {
            AnyRobot::Khepera(r) => Some(r),
            _ => None,
        }
    }

    /// The Dom Dinis composition, when it is one.
    pub fn dom_dinis(&self) -> Option<&Robot<DomDinis>> {
        match self {
            AnyRobot::DomDinis(r) => Some(r),
            _ => None,
        }
    }

    /// The ALICE composition, when it is one.
    pub fn alice(&self) -> Option<&Robot<Alice>> {
        match self {
            AnyRobot::Alice(r) => Some(r),
            _ => None,
        }
    }

    /// The telemetry frame the robot would send at `now_ms` (`telemetry::build`).
    pub fn telemetry(&self, now_ms: u32) -> protocol::Telemetry {
        each!(self, r => super::telemetry::build(&r.core, now_ms))
    }

    /// One pass of the main loop (`Robot::step`).
    pub fn step<H: Hal>(&mut self, hal: &mut H) {
        each!(self, r => r.step(hal))
    }

    /// Until when a pass has nothing to do unless a byte arrives (`Robot::idle_until_us`).
    pub fn idle_until_us(&self) -> Option<u64> {
        each!(self, r => r.idle_until_us())
    }

    /// Executes one command or refuses it (`Core::apply`).
    pub fn apply(&mut self, command: Command, now_ms: u32) -> Reply {
        each!(self, r => r.core.apply(command, now_ms))
    }

    pub fn pose(&self) -> Pose {
        each!(self, r => r.pose())
    }

    pub fn emulated(&self) -> bool {
        each!(self, r => r.emulated())
    }

    pub fn link(&self) -> &Link {
        each!(self, r => &r.link)
    }

    pub fn link_mut(&mut self) -> &mut Link {
        each!(self, r => &mut r.link)
    }

    pub fn profile(&self) -> &'static Profile {
        each!(self, r => r.core.profile)
    }

    pub fn config(&self) -> &RobotConfig {
        each!(self, r => &r.core.config)
    }

    /// The robot-level settings, to set as an operator would (the emulator numbers a
    /// fleet's robots with `robot_id`).
    pub fn config_mut(&mut self) -> &mut RobotConfig {
        each!(self, r => &mut r.core.config)
    }

    pub fn mode(&self) -> Mode {
        each!(self, r => r.core.mode)
    }

    pub fn arrived(&self) -> bool {
        each!(self, r => r.core.arrived)
    }

    /// The go-to or exploration goal in force, metres.
    pub fn goal(&self) -> Option<crate::odometry::Point> {
        each!(self, r => r.core.goal)
    }

    /// A parameter's value as `GetParam` answers it (`Core::param`).
    pub fn param(&mut self, id: u16) -> Result<f32, protocol::NackReason> {
        each!(self, r => r.core.param(id))
    }

    pub fn failsafe(&self) -> bool {
        each!(self, r => r.core.failsafe)
    }

    /// Progress through the installed plan (`Core::exec`).
    pub fn exec(&self) -> Option<super::Execution> {
        each!(self, r => r.core.exec)
    }

    pub fn line_events(&self) -> u8 {
        each!(self, r => r.core.line_events)
    }

    pub fn timing(&self) -> &Timing {
        each!(self, r => &r.core.timing)
    }

    pub fn sensors(&self) -> &Sensors {
        each!(self, r => &r.core.sensors)
    }

    pub fn arbiter(&self) -> &Arbiter {
        each!(self, r => &r.core.arbiter)
    }

    pub fn guided(&self) -> &GuidedParams {
        each!(self, r => &r.core.guided)
    }

    pub fn dead(&self) -> &DeadReckoner {
        each!(self, r => &r.core.dead)
    }

    pub fn dead_mut(&mut self) -> &mut DeadReckoner {
        each!(self, r => &mut r.core.dead)
    }

    pub fn objects(&self) -> &Objects {
        each!(self, r => &r.core.objects)
    }

    pub fn objects_mut(&mut self) -> &mut Objects {
        each!(self, r => &mut r.core.objects)
    }

    /// Seed 003 line correction, on a composition that has it.
    pub fn linecorr(&self) -> Option<&LineCorr> {
        each!(self, r => r.core.linecorr.get())
    }

    /// Seed 000 §5.3 light calibration, on a composition that has it.
    pub fn light_cal(&self) -> Option<&LightCalibration> {
        each!(self, r => r.core.light_cal.get())
    }

    /// The calibrated light bearing (`Core::light_bearing`); `None` without a calibration.
    pub fn light_bearing(&self) -> Option<f32> {
        each!(self, r => r.core.light_bearing())
    }

    /// Seed 000 §7 foraging, on a composition that has it.
    pub fn forage(&self) -> Option<&Forage> {
        each!(self, r => r.core.forage.get())
    }
}
