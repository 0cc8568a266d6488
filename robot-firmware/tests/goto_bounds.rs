//! Go-to refuses a point outside the arena (issue 16: `station send goto 100 100` was
//! acknowledged for a 5 m arena and the robot drove at the wall): `BadPoint`, nothing changes.
#![allow(clippy::unwrap_used)]

use protocol::{Command, Mode, NackReason, ParamId, PointMm};
use robot_firmware::link::Reply;
use robot_firmware::odometry::Pose;
use robot_firmware::params::id;
use robot_firmware::{AnyRobot, RobotOptions, KHEPERA, MICRO_RATO};

fn robot(profile: &'static robot_firmware::Profile) -> AnyRobot {
    AnyRobot::new(RobotOptions {
        profile,
        seed: 1,
        start: Pose::new(1.0, 1.0, 0.0),
        emulated: false,
        firmware_version: "test",
    })
}

fn goto(x_mm: i32, y_mm: i32) -> Command {
    Command::GoTo(PointMm { x_mm, y_mm })
}

#[test]
fn a_point_outside_the_arena_bounds_is_refused_and_changes_nothing() {
    for profile in [&MICRO_RATO, &KHEPERA] {
        let mut r = robot(profile);
        // The default arena is seed 004's 5 x 5 m square.
        assert_eq!(
            r.apply(goto(100_000, 100_000), 0),
            Reply::Nack(NackReason::BadPoint)
        );
        assert_eq!(
            r.apply(goto(-10, 2000), 0),
            Reply::Nack(NackReason::BadPoint)
        );
        assert_eq!(r.mode(), Mode::Idle);
        assert_eq!(r.goal(), None);
        assert!(matches!(r.apply(goto(4000, 4000), 0), Reply::Ack(_)));
        assert_eq!(r.mode(), Mode::GoTo);
        // The bounds are parameters: a wider arena takes the point.
        let set = |id: u16, value: f32| Command::SetParam {
            id: ParamId(id),
            value,
        };
        assert!(matches!(
            r.apply(set(id::ARENA_MAX_X_M, 100.0), 0),
            Reply::Ack(_)
        ));
        assert!(matches!(
            r.apply(set(id::ARENA_MAX_Y_M, 100.0), 0),
            Reply::Ack(_)
        ));
        assert!(matches!(r.apply(goto(99_000, 99_000), 0), Reply::Ack(_)));
    }
}
