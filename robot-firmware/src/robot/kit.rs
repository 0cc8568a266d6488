//! Compositions: which capabilities' state a robot build carries.
//!
//! A robot carries what its profile uses (DEVELOPERS.md): the Dom Dinis build has no light
//! calibration, foraging or floor-grid line correction, the Khepera build no reactive search.
//! Each optional capability is an associated type of `Kit`, either its state or `Absent`
//! (0 bytes). The capability's code is written once for any composition that has it (an
//! `impl<K: Kit<Forage = Forage>> Core<K>` block in its module) and reached from the common
//! code through its slot trait (`ForageSlot` ...), whose `Absent` side refuses the capability's
//! commands (`NackReason::Unsupported`) and drives nothing: a motion command is executed or
//! refused, never ignored.
//!
//! State every profile needs (link, mode, odometry and dead reckoning, behaviours, the map and
//! plan objects, telemetry) stays in `Core` itself.

use protocol::{caps, NackReason};

use super::{AliceState, Core, Forage, LightCalibration, LineCorr};
use crate::behaviour;
use crate::explore::Explorer;
use crate::hal::{Hal, MotorCommand};
use crate::odometry::Point;

/// A capability's state, or `Absent`.
pub trait Slot<T> {
    /// Whether this is the state (not `Absent`).
    const PRESENT: bool;
    fn get(&self) -> Option<&T>;
    fn get_mut(&mut self) -> Option<&mut T>;
    /// The state `make` builds, or `Absent` (then `make` is not called).
    fn fill(make: impl FnOnce() -> T) -> Self;
}

/// A capability a composition leaves out: no bytes, no behaviour.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Absent;

impl<T> Slot<T> for Absent {
    const PRESENT: bool = false;
    fn get(&self) -> Option<&T> {
        None
    }
    fn get_mut(&mut self) -> Option<&mut T> {
        None
    }
    fn fill(_: impl FnOnce() -> T) -> Self {
        Absent
    }
}

macro_rules! present {
    ($($t:ty),*) => {$(
        impl Slot<$t> for $t {
            const PRESENT: bool = true;
            fn get(&self) -> Option<&$t> {
                Some(self)
            }
            fn get_mut(&mut self) -> Option<&mut $t> {
                Some(self)
            }
            fn fill(make: impl FnOnce() -> $t) -> Self {
                make()
            }
        }
    )*};
}
present!(Forage, LineCorr, LightCalibration, Explorer, AliceState);

/// A composition: the optional capabilities a robot build carries.
pub trait Kit: Sized + 'static {
    /// Seed 000 §7 foraging with the gripper and landmark scans.
    type Forage: ForageSlot;
    /// Seed 003 floor-grid line correction and `Mode::Survey`.
    type LineCorr: LineCorrSlot;
    /// Seed 000 §5.3 light -> angle calibration (`Mode::CalibrateLight`, its transfers).
    type LightCal: LightCalSlot;
    /// Seed 004 §5 reactive search with mapping (`Mode::Explore`).
    type Explorer: ExplorerSlot;
    /// Seed 001 ALICE: 24 whiskers and 24 photoresistors, situations (kind 16), wandering.
    type Alice: AliceSlot;
    /// Its name in reports.
    const NAME: &'static str;
}

/// Seed 004's Dom Dinis (micro-rato): compass and beacon dead reckoning, the grid map,
/// segmentation and A*, plan execution and exploration.
pub struct DomDinis;

impl Kit for DomDinis {
    type Forage = Absent;
    type LineCorr = Absent;
    type LightCal = Absent;
    type Explorer = Explorer;
    type Alice = Absent;
    const NAME: &'static str = "dom-dinis";
}

/// Seeds 000 and 003's Khepera: odometry, behaviours, foraging, light calibration, landmarks,
/// line correction; and the map and plan objects its profile announces
/// (`caps::ONBOARD_PLANNING | caps::TRANSFERS`).
pub struct Khepera;

impl Kit for Khepera {
    type Forage = Forage;
    type LineCorr = LineCorr;
    type LightCal = LightCalibration;
    type Explorer = Absent;
    type Alice = Absent;
    const NAME: &'static str = "khepera";
}

/// Seed 001's ALICE: odometry, 24 whiskers and 24 photoresistors, its situations streamed as
/// kind 16 for the station's world model, and its wandering; none of the other papers'
/// capabilities (no IR, light calibration, foraging, line correction or reactive search).
pub struct Alice;

impl Kit for Alice {
    type Forage = Absent;
    type LineCorr = Absent;
    type LightCal = Absent;
    type Explorer = Absent;
    type Alice = AliceState;
    const NAME: &'static str = "alice";
}

/// The capability bits `K` cannot serve whatever the profile says (the HelloReply leaves
/// them out).
pub fn lacking<K: Kit>() -> u32 {
    let mut bits = 0;
    if !<K::LineCorr as Slot<LineCorr>>::PRESENT {
        bits |= caps::LINE_CORRECTION;
    }
    bits
}

/// Foraging's entry points from the common code.
pub trait ForageSlot: Slot<Forage> + Sized {
    fn start<K: Kit<Forage = Self>>(core: &mut Core<K>) -> Result<(), NackReason>;
    fn command<K: Kit<Forage = Self>>(core: &mut Core<K>) -> MotorCommand;
    fn arbiter_mode<K: Kit<Forage = Self>>(core: &Core<K>) -> behaviour::Mode;
}

impl ForageSlot for Forage {
    fn start<K: Kit<Forage = Self>>(core: &mut Core<K>) -> Result<(), NackReason> {
        core.start_forage()
    }
    fn command<K: Kit<Forage = Self>>(core: &mut Core<K>) -> MotorCommand {
        core.forage_command()
    }
    fn arbiter_mode<K: Kit<Forage = Self>>(core: &Core<K>) -> behaviour::Mode {
        core.forage_arbiter_mode()
    }
}

impl ForageSlot for Absent {
    fn start<K: Kit<Forage = Self>>(_: &mut Core<K>) -> Result<(), NackReason> {
        Err(NackReason::Unsupported)
    }
    fn command<K: Kit<Forage = Self>>(_: &mut Core<K>) -> MotorCommand {
        MotorCommand::STOP
    }
    fn arbiter_mode<K: Kit<Forage = Self>>(_: &Core<K>) -> behaviour::Mode {
        behaviour::Mode::Idle
    }
}

/// Line correction's entry points from the common code.
pub trait LineCorrSlot: Slot<LineCorr> + Sized {
    fn line_correct<K: Kit<LineCorr = Self>>(core: &mut Core<K>, n_l: i32, n_r: i32, now: u32);
    fn survey_command<K: Kit<LineCorr = Self>>(core: &mut Core<K>) -> MotorCommand;
}

impl LineCorrSlot for LineCorr {
    fn line_correct<K: Kit<LineCorr = Self>>(core: &mut Core<K>, n_l: i32, n_r: i32, now: u32) {
        core.line_correct(n_l, n_r, now);
    }
    fn survey_command<K: Kit<LineCorr = Self>>(core: &mut Core<K>) -> MotorCommand {
        core.survey_command()
    }
}

impl LineCorrSlot for Absent {
    fn line_correct<K: Kit<LineCorr = Self>>(_: &mut Core<K>, _: i32, _: i32, _: u32) {}
    fn survey_command<K: Kit<LineCorr = Self>>(_: &mut Core<K>) -> MotorCommand {
        MotorCommand::STOP
    }
}

/// Light calibration's entry points from the common code.
pub trait LightCalSlot: Slot<LightCalibration> + Sized {
    fn start<K: Kit<LightCal = Self>>(core: &mut Core<K>);
    fn command<K: Kit<LightCal = Self>>(core: &mut Core<K>) -> MotorCommand;
    fn report_bearing<K: Kit<LightCal = Self>>(core: &mut Core<K>, now_ms: u32);
}

impl LightCalSlot for LightCalibration {
    fn start<K: Kit<LightCal = Self>>(core: &mut Core<K>) {
        core.start_light_calibration();
    }
    fn command<K: Kit<LightCal = Self>>(core: &mut Core<K>) -> MotorCommand {
        core.calibrate_command()
    }
    fn report_bearing<K: Kit<LightCal = Self>>(core: &mut Core<K>, now_ms: u32) {
        core.report_light_bearing(now_ms);
    }
}

impl LightCalSlot for Absent {
    fn start<K: Kit<LightCal = Self>>(_: &mut Core<K>) {}
    fn command<K: Kit<LightCal = Self>>(_: &mut Core<K>) -> MotorCommand {
        MotorCommand::STOP
    }
    fn report_bearing<K: Kit<LightCal = Self>>(_: &mut Core<K>, _: u32) {}
}

/// Exploration's entry points from the common code.
pub trait ExplorerSlot: Slot<Explorer> + Sized {
    fn start<K: Kit<Explorer = Self>>(core: &mut Core<K>) -> Result<(), NackReason>;
    fn command<K: Kit<Explorer = Self>>(core: &mut Core<K>) -> MotorCommand;
    /// A compass robot's go-to to `goal` planned on its map; `None` without a map or a
    /// planner (guided motion then steers straight at the point).
    fn goto<K: Kit<Explorer = Self>>(core: &mut Core<K>, goal: Point) -> Option<MotorCommand>;
}

impl ExplorerSlot for Explorer {
    fn start<K: Kit<Explorer = Self>>(core: &mut Core<K>) -> Result<(), NackReason> {
        core.start_exploration()
    }
    fn command<K: Kit<Explorer = Self>>(core: &mut Core<K>) -> MotorCommand {
        core.explore_command()
    }
    fn goto<K: Kit<Explorer = Self>>(core: &mut Core<K>, goal: Point) -> Option<MotorCommand> {
        core.planned_goto(goal)
    }
}

impl ExplorerSlot for Absent {
    fn start<K: Kit<Explorer = Self>>(_: &mut Core<K>) -> Result<(), NackReason> {
        Err(NackReason::Unsupported)
    }
    fn command<K: Kit<Explorer = Self>>(_: &mut Core<K>) -> MotorCommand {
        MotorCommand::STOP
    }
    fn goto<K: Kit<Explorer = Self>>(_: &mut Core<K>, _: Point) -> Option<MotorCommand> {
        None
    }
}

/// ALICE's entry points from the common code.
pub trait AliceSlot: Slot<AliceState> + Sized {
    /// Reads the whiskers and photoresistors (nothing without them).
    fn read<K: Kit<Alice = Self>, H: Hal>(core: &mut Core<K>, hal: &mut H);
    /// Samples the situation when due.
    fn sample<K: Kit<Alice = Self>>(core: &mut Core<K>, now_ms: u32);
    /// `Mode::Wander`'s command on ALICE; `None` elsewhere (the arbiter's wander drives).
    fn wander<K: Kit<Alice = Self>>(core: &mut Core<K>) -> Option<MotorCommand>;
}

impl AliceSlot for AliceState {
    fn read<K: Kit<Alice = Self>, H: Hal>(core: &mut Core<K>, hal: &mut H) {
        core.read_alice(hal);
    }
    fn sample<K: Kit<Alice = Self>>(core: &mut Core<K>, now_ms: u32) {
        core.sample_alice(now_ms);
    }
    fn wander<K: Kit<Alice = Self>>(core: &mut Core<K>) -> Option<MotorCommand> {
        Some(core.alice_wander_command())
    }
}

impl AliceSlot for Absent {
    fn read<K: Kit<Alice = Self>, H: Hal>(_: &mut Core<K>, _: &mut H) {}
    fn sample<K: Kit<Alice = Self>>(_: &mut Core<K>, _: u32) {}
    fn wander<K: Kit<Alice = Self>>(_: &mut Core<K>) -> Option<MotorCommand> {
        None
    }
}

#[cfg(test)]
mod tests {
    use protocol::{Command, Mode, NackReason, ObjectKind, TransferStatus};

    use super::*;
    use crate::link::Reply;
    use crate::odometry::Pose;
    use crate::robot::{Robot, RobotOptions};
    use crate::{KHEPERA, MICRO_RATO};

    fn robot<K: Kit>(profile: &'static crate::Profile) -> Robot<K> {
        Robot::new(RobotOptions {
            profile,
            seed: 1,
            start: Pose::new(0.5, 0.5, 0.0),
            emulated: false,
            firmware_version: "test",
        })
    }

    #[test]
    fn a_composition_refuses_the_commands_of_a_capability_it_lacks_whatever_the_profile() {
        // A Khepera profile on the Dom Dinis composition: the profile allows foraging, the
        // survey and the light calibration, the composition has no state for them.
        let mut r = robot::<DomDinis>(&KHEPERA);
        for mode in [Mode::Forage, Mode::Survey, Mode::CalibrateLight] {
            let reply = r.core.apply(Command::SetMode(mode), 0);
            assert_eq!(reply, Reply::Nack(NackReason::Unsupported), "{mode:?}");
            assert_eq!(r.core.mode, Mode::Idle, "{mode:?} changed the mode");
        }
        let refusal = r.core.upload_refusal(ObjectKind::LightCalibration);
        assert_eq!(refusal, Some(TransferStatus::Rejected));
        assert_ne!(lacking::<DomDinis>() & caps::LINE_CORRECTION, 0);
        // The profile's own composition runs them.
        let mut k = robot::<Khepera>(&KHEPERA);
        for mode in [Mode::Survey, Mode::CalibrateLight] {
            let reply = k.core.apply(Command::SetMode(mode), 0);
            assert!(matches!(reply, Reply::Ack(_)), "{mode:?}: {reply:?}");
            k.core.apply(Command::Stop, 0);
        }
        assert_eq!(k.core.upload_refusal(ObjectKind::LightCalibration), None);
        assert_eq!(lacking::<Khepera>(), 0);
        // And the other way round: no exploration without the explorer.
        let mut k = robot::<Khepera>(&MICRO_RATO);
        let reply = k.core.apply(Command::StartExploration, 0);
        assert_eq!(reply, Reply::Nack(NackReason::Unsupported));
        let mut d = robot::<DomDinis>(&MICRO_RATO);
        assert!(matches!(
            d.core.apply(Command::StartExploration, 0),
            Reply::Ack(_)
        ));
    }

    #[test]
    fn a_capability_left_out_costs_no_bytes() {
        use core::mem::size_of;
        assert_eq!(size_of::<Absent>(), 0);
        let full = size_of::<Forage>() + size_of::<LineCorr>() + size_of::<LightCalibration>();
        let (d, k) = (size_of::<Robot<DomDinis>>(), size_of::<Robot<Khepera>>());
        // Khepera carries those three and not the explorer; the compiler reorders fields, so
        // allow up to 64 bytes of alignment padding between the two layouts.
        assert!(
            k + size_of::<Explorer>() + 64 >= d + full,
            "{k} - {d}, {full}"
        );
        // And Dom Dinis carries none of them.
        assert!(d + full > k, "{k} - {d}, {full}");
    }
}
