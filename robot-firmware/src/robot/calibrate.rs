//! Light calibration mode (seed 000 §5.3) in the robot's control cycle: `Core::decide` in
//! `Mode::CalibrateLight` turns the robot as the calibration asks, and
//! `Core::report_light_bearing` reports, every cycle, where a trained calibration sees a light.
//! The calibration itself (the sweeps, the training, the bearing) is
//! `crate::light_calibration`.

use protocol::{EventCode, Mode};

use super::{Core, Kit, Slot};
use crate::hal::MotorCommand;
use crate::light_calibration::{stall_limit_ms, CalStep, LightCalibration, FRONT, TURN_UNITS};

impl<K: Kit> Core<K> {
    /// The angle of a light from the heading, radians counter-clockwise, when the light
    /// calibration is trained and a light is near; `None` otherwise (and without one).
    pub fn light_bearing(&self) -> Option<f32> {
        let cal = self.light_cal.get()?;
        cal.bearing(&self.sensors.ambient)
    }
}

impl<K: Kit<LightCal = LightCalibration>> Core<K> {
    /// `SetMode(CalibrateLight)`, after `check_mode`: begins the align turn.
    pub(super) fn start_light_calibration(&mut self) {
        self.light_cal.start(self.cycle_ms);
    }

    /// The longest a turn may take before it counts as stalled, ms.
    fn calibration_stall_ms(&self) -> u32 {
        stall_limit_ms(self.profile)
    }

    /// This cycle's motor command in `Mode::CalibrateLight`.
    pub(super) fn calibrate_command(&mut self) -> MotorCommand {
        let heading = self.pose().heading;
        let angles = self.profile.ir.angle_rad;
        let angles = angles.get(..FRONT).unwrap_or(&[]);
        let now = self.cycle_ms;
        let stall_ms = self.calibration_stall_ms();
        match self
            .light_cal
            .step(heading, &self.sensors.ambient, angles, now, stall_ms)
        {
            CalStep::Turn => MotorCommand::new(TURN_UNITS, -TURN_UNITS),
            CalStep::End(value) => self.end_calibration(value),
        }
    }

    fn end_calibration(&mut self, value: i32) -> MotorCommand {
        self.push_event(EventCode::LightCalibrated, value);
        self.enter(Mode::Idle);
        MotorCommand::STOP
    }

    /// Every control cycle: a `LightBearing` event when a trained calibration sees a light,
    /// at most every `REPORT_MS`.
    pub(super) fn report_light_bearing(&mut self, now_ms: u32) {
        if self.mode == Mode::CalibrateLight {
            return;
        }
        let Some(b) = self.light_bearing() else {
            return;
        };
        if !self.light_cal.bearing_report_due(now_ms) {
            return;
        }
        let ddeg = libm::roundf(b.to_degrees() * 10.0) as i32;
        self.push_event(EventCode::LightBearing, ddeg);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use protocol::calibration;

    #[test]
    fn a_robot_that_cannot_turn_gives_up_the_calibration_as_stalled() {
        use crate::scripted::ScriptedHal;
        use crate::{odometry::Pose, Robot, RobotOptions, KHEPERA};
        use protocol::{Command, Event};

        let mut robot = Robot::<crate::robot::Khepera>::new(RobotOptions {
            profile: &KHEPERA,
            seed: 1,
            start: Pose::new(0.5, 0.5, 0.0),
            emulated: false,
            firmware_version: "test",
        });
        // Wheels blocked: the encoders never move whatever the motors are told.
        let mut hal = ScriptedHal {
            encoders: Some([0, 0]),
            ambient: [300, 250, 200, 210, 260, 320, 500, 500],
            ..ScriptedHal::default()
        };
        let core = &mut robot.core;
        let _ = core.apply(Command::SetMode(Mode::CalibrateLight), 0);
        assert_eq!(core.mode, Mode::CalibrateLight);
        let stall_ms = u64::from(core.calibration_stall_ms());
        let mut ended = None;
        // Two nominal turn limits of 80 ms cycles: without a bound the robot turns forever.
        for k in 1..=(2 * stall_ms / 80) {
            hal.now_us = k * 80_000;
            let now_us = hal.now_us;
            core.control_cycle(&mut hal, now_us);
            while let Some(Event { code, value }) = core.events.pop_front() {
                if code == EventCode::LightCalibrated {
                    ended = Some((value, k * 80));
                }
            }
            if ended.is_some() {
                break;
            }
        }
        let (value, at_ms) = ended.expect("the calibration never ended");
        assert_eq!(value, calibration::STALLED);
        assert!(at_ms > stall_ms, "gave up at {at_ms} ms, before the limit");
        assert_eq!(core.mode, Mode::Idle);
        assert_eq!(core.motor, MotorCommand::STOP);
        assert!(!core.light_cal.trained);
    }
}
