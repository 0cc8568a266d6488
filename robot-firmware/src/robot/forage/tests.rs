use super::*;

#[test]
fn a_map_scan_on_a_robot_that_cannot_turn_gives_up_and_searches() {
    use crate::scripted::ScriptedHal;
    use crate::{Robot, RobotOptions, KHEPERA};
    use protocol::Command;

    let mut robot = Robot::<crate::robot::Khepera>::new(RobotOptions {
        profile: &KHEPERA,
        seed: 1,
        start: Pose::new(0.5, 0.5, 0.0),
        emulated: false,
        firmware_version: "test",
    });
    // Wheels blocked; a camera that sees a plain wall.
    let mut hal = ScriptedHal {
        encoders: Some([0, 0]),
        ambient: [500; 8],
        gripper: Some(GripperState::default()),
        camera: Some([180; CAMERA_PIXELS]),
        ..ScriptedHal::default()
    };
    let core = &mut robot.core;
    let _ = core.apply(Command::SetMode(Mode::Forage), 0);
    assert_eq!(core.forage.phase, ForagePhase::Map);
    // A full scan takes about 300 cycles; without a bound this one never ends.
    for k in 1..=2_000u64 {
        hal.now_us = k * 80_000;
        let now_us = hal.now_us;
        core.control_cycle(&mut hal, now_us);
        if core.forage.phase != ForagePhase::Map {
            break;
        }
    }
    assert_eq!(core.forage.phase, ForagePhase::Search);
    assert_eq!(core.forage.triple, None);
    assert_eq!(core.mode, Mode::Forage);
}

#[test]
fn a_drop_is_counted_when_the_object_leaves_the_fingers_not_once_the_arm_is_up() {
    use crate::{Robot, RobotOptions, KHEPERA};

    let mut robot = Robot::<crate::robot::Khepera>::new(RobotOptions {
        profile: &KHEPERA,
        seed: 1,
        start: Pose::new(0.5, 0.5, 0.0),
        emulated: false,
        firmware_version: "test",
    });
    let core = &mut robot.core;
    let gripper = |arm, closed, object| {
        Some(GripperState {
            arm,
            closed,
            object,
        })
    };
    core.forage
        .set_phase(ForagePhase::Drop(GripStep::Lower), 0.0);
    core.sensors.gripper = gripper(ARM_DOWN, true, true);
    let _ = core.forage_command();
    assert_eq!(core.forage.phase, ForagePhase::Drop(GripStep::Grip));
    // The grip has started opening; the object is still between the fingers.
    core.sensors.gripper = gripper(ARM_DOWN, false, true);
    let _ = core.forage_command();
    assert_eq!(core.forage.delivered, 0);
    // It is on the floor: delivered now, with the arm still down (the emulated run ends
    // 0.5 s after the last object lands; the arm takes 1 s to rise).
    core.sensors.gripper = gripper(ARM_DOWN, false, false);
    let _ = core.forage_command();
    assert_eq!(core.forage.delivered, 1);
    core.sensors.gripper = gripper(ARM_UP, false, false);
    for _ in 0..3 {
        if matches!(core.forage.phase, ForagePhase::Drop(_)) {
            let _ = core.forage_command();
        }
    }
    assert_eq!(core.forage.delivered, 1, "counted once");
    assert_eq!(core.forage.phase, ForagePhase::Search);
    // The next drop counts again.
    core.forage
        .set_phase(ForagePhase::Drop(GripStep::Lower), 0.0);
    core.sensors.gripper = gripper(ARM_DOWN, true, true);
    let _ = core.forage_command();
    core.sensors.gripper = gripper(ARM_DOWN, false, false);
    let _ = core.forage_command();
    assert_eq!(core.forage.delivered, 2);
    // With a landmark map, one put down where no fix has corrected the pose since the
    // grasp is not counted.
    core.forage.triple = Some(Triple::new(
        Point::new(0.0, 1.0),
        Point::new(1.0, 1.0),
        Point::new(1.0, 0.0),
    ));
    core.forage.fixes_at_grasp = core.forage.fixes;
    core.forage
        .set_phase(ForagePhase::Drop(GripStep::Lower), 0.0);
    core.sensors.gripper = gripper(ARM_DOWN, true, true);
    let _ = core.forage_command();
    core.sensors.gripper = gripper(ARM_DOWN, false, false);
    let _ = core.forage_command();
    assert_eq!(core.forage.delivered, 2, "pose never fixed: not delivered");
    assert_eq!(core.forage.phase, ForagePhase::Drop(GripStep::Raise));
}

#[test]
fn remembered_sources_are_recognised_nearby_and_the_oldest_goes_when_full() {
    let mut f = Forage::default();
    f.remember(Point::new(0.5, 0.5));
    assert!(f.known(Point::new(0.55, 0.52)));
    assert!(!f.known(Point::new(0.7, 0.5)));
    f.remember(Point::new(0.52, 0.5));
    assert_eq!(f.sources().len(), 1, "the same source is not stored twice");
    for i in 0..MAX_SOURCES {
        f.remember(Point::new(1.0 + i as f32, 0.0));
    }
    assert_eq!(f.sources().len(), MAX_SOURCES);
    assert!(!f.known(Point::new(0.5, 0.5)), "the oldest was forgotten");
}
