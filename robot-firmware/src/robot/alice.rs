//! ALICE on the robot (seed 001 §3.1): its 24 whiskers and 24 photoresistors read through the
//! `Hal` every control cycle, its situation sampled 3 times a second and sent as message
//! kind 16 (`alice::situation`), and its wandering (`alice::wander`) in `Mode::Wander`.
//!
//! Reached from the common code through `AliceSlot` (`kit`): the ALICE composition carries an
//! [`AliceState`], the others `Absent` (no bytes, no wandering by whiskers, no kind 16).
//! Situations are sampled in every mode (the model learns while an operator drives too); the
//! sampled pose is the odometry's own, uncorrected, as the model wants it.

use protocol::{AliceSituation, Message};

use super::{Core, Kit};
use crate::alice::situation::{situation, Schedule};
use crate::alice::wander::Wander;
use crate::alice::SENSORS;
use crate::hal::{Hal, MotorCommand};
use crate::link::Link;

/// ALICE's readings, schedule and wandering.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AliceState {
    /// This cycle's whisker bits (0 when the `Hal` has none).
    pub whiskers: u32,
    /// This cycle's photoresistor readings (all 0 when the `Hal` has none).
    pub light: [u8; SENSORS],
    /// Whether the `Hal` gave whiskers and photoresistors at the last read.
    pub sensed: bool,
    pub schedule: Schedule,
    pub wander: Wander,
    /// A situation sampled this cycle and not yet handed to the link.
    pending: Option<AliceSituation>,
    /// A situation was sampled in the cycle in force (the stochastic turn is drawn then).
    sampled: bool,
}

impl AliceState {
    pub fn new(seed: u32) -> Self {
        AliceState {
            whiskers: 0,
            light: [0; SENSORS],
            sensed: false,
            schedule: Schedule::default(),
            wander: Wander::new(seed),
            pending: None,
            sampled: false,
        }
    }

    /// The last situation sampled, once, for the link.
    pub fn take_pending(&mut self) -> Option<AliceSituation> {
        self.pending.take()
    }
}

impl<K: Kit<Alice = AliceState>> Core<K> {
    /// Reads the whiskers and photoresistors (the control cycle's sensor read).
    pub(super) fn read_alice<H: Hal>(&mut self, hal: &mut H) {
        let whiskers = hal.whiskers();
        let light = hal.photoresistors();
        let a = &mut self.alice;
        a.sensed = whiskers.is_some() && light.is_some();
        a.whiskers = whiskers.unwrap_or(0);
        a.light = light.unwrap_or([0; SENSORS]);
    }

    /// Samples the situation when one is due (after the position estimate of the cycle).
    pub(super) fn sample_alice(&mut self, now_ms: u32) {
        let odometry = self.odometry.pose();
        let a = &mut self.alice;
        a.sampled = false;
        if let Some(seq) = a.schedule.due(now_ms) {
            a.pending = Some(situation(seq, now_ms, a.whiskers, a.light, odometry));
            a.sampled = true;
        }
    }

    /// `Mode::Wander` on ALICE: the whisker reflex, stochastic turns, straight ahead.
    pub(super) fn alice_wander_command(&mut self) -> MotorCommand {
        let heading = self.odometry.pose().heading;
        let a = &mut self.alice;
        let (v_mm_s, w_rad_s) = a.wander.step(a.whiskers, heading, a.sampled);
        let half_base_mm = self.profile.wheel_distance_m * 500.0;
        let turn = w_rad_s * half_base_mm;
        MotorCommand::new(
            self.profile.motor_units(v_mm_s - turn),
            self.profile.motor_units(v_mm_s + turn),
        )
    }
}

/// Hands a sampled situation to the link (low priority, like telemetry: a full queue loses
/// it, and the station counts the loss from the sequence gap).
pub(super) fn send_situation(link: &mut Link, alice: &mut AliceState, now_ms: u32) {
    if let Some(s) = alice.take_pending() {
        if link.connected() {
            link.send_low_priority(&Message::AliceSituation(s), now_ms);
        }
    }
}
