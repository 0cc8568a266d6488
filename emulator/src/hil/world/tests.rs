use protocol::hil::{HilDecoder, Motors, Msg, PowerOn};
use protocol::{Command, Mode, ProfileId};
use robot_firmware::hal::BeaconReading;
use robot_firmware::odometry::Pose as FwPose;
use robot_firmware::{AnyRobot, Hal, MotorCommand, RobotOptions, MICRO_RATO};

use super::*;
use crate::sim::{Sim, SimConfig};

fn sim(seed: u64) -> Sim {
    let arena = crate::builtin::load(crate::builtin::MICRO_RATO_99, &Default::default())
        .expect("built-in arena");
    let mut cfg = SimConfig::new(&MICRO_RATO);
    cfg.seed = seed;
    Sim::new(arena, cfg).expect("sim")
}

fn frame(msg: &Msg) -> Vec<u8> {
    let mut out = Vec::new();
    send(msg, &mut out);
    out
}

fn decode(bytes: &[u8]) -> Vec<Msg> {
    let mut d = HilDecoder::new();
    bytes
        .iter()
        .filter_map(|&b| d.feed(b))
        .map(|r| r.expect("the world sends good frames"))
        .collect()
}

fn power_on() -> Vec<u8> {
    frame(&Msg::PowerOn(PowerOn {
        version: HIL_VERSION,
        profile: ProfileId::MicroRato,
    }))
}

#[test]
fn power_on_is_answered_with_the_setup_and_the_sensors_of_time_zero() {
    let mut w = HilWorld::new(sim(3), Some([7; KEY_LEN]), Mode::Idle).expect("world");
    let mut out = Vec::new();
    w.feed(&power_on(), &mut out).expect("accepted");
    let msgs = decode(&out);
    assert_eq!(msgs.len(), 2, "{msgs:?}");
    let Msg::Setup(s) = msgs[0] else {
        panic!("{msgs:?}")
    };
    assert_eq!(s.period_us, MICRO_RATO.cycle_us);
    assert_eq!(s.firmware_seed, firmware_seed(3));
    assert_eq!(s.key, Some([7; KEY_LEN]));
    assert!(s.beacon.is_some(), "Micro-Rato'99 has a beacon");
    let Msg::Sensors(z) = msgs[1] else {
        panic!("{msgs:?}")
    };
    assert_eq!((z.seq, z.time_us), (0, 0));
    assert!(z.compass.is_some() && z.encoders.is_none());
}

#[test]
fn motors_advance_one_period_and_a_stale_or_damaged_frame_changes_nothing() {
    let mut w = HilWorld::new(sim(1), None, Mode::Idle).expect("world");
    let mut out = Vec::new();
    w.feed(&power_on(), &mut out).expect("accepted");
    let go = |seq| {
        frame(&Msg::Motors(Motors {
            seq,
            left: 40,
            right: 40,
            arm: 0,
            closed: false,
        }))
    };
    out.clear();
    w.feed(&go(0), &mut out).expect("accepted");
    let msgs = decode(&out);
    let Msg::Sensors(s) = msgs[0] else {
        panic!("{msgs:?}")
    };
    assert_eq!((s.seq, s.time_us), (1, u64::from(MICRO_RATO.cycle_us)));
    let moved = w.summary();
    assert!(moved.distance_m > 0.0);
    // The same Motors again (a repeat): no second period.
    out.clear();
    w.feed(&go(0), &mut out).expect("accepted");
    assert!(out.is_empty());
    let mut bad = go(1);
    bad[3] ^= 0x10;
    w.feed(&bad, &mut out).expect("a bad frame is not fatal");
    assert!(out.is_empty());
    let s = w.summary();
    assert_eq!((s.exchanges, s.stale_motors, s.frame_errors), (1, 1, 1));
    assert_eq!(s.distance_m, moved.distance_m);
}

#[test]
fn a_board_built_for_another_profile_is_refused_by_name() {
    let mut w = HilWorld::new(sim(1), None, Mode::Idle).expect("world");
    let khepera = frame(&Msg::PowerOn(PowerOn {
        version: HIL_VERSION,
        profile: ProfileId::Khepera,
    }));
    let err = w.feed(&khepera, &mut Vec::new()).expect_err("refused");
    assert!(err.to_string().contains("Khepera"), "{err}");
}

/// A minimal board: the firmware over the sensors of the last `Sensors`, its clock the world's.
struct FrameHal {
    s: hil::Sensors,
    motor: MotorCommand,
}

impl Hal for FrameHal {
    fn now_us(&mut self) -> u64 {
        self.s.time_us
    }
    fn set_motors(&mut self, cmd: MotorCommand) {
        self.motor = cmd;
    }
    fn encoders(&mut self) -> Option<[i32; 2]> {
        self.s.encoders
    }
    fn ir(&mut self) -> [u16; 8] {
        self.s.ir
    }
    fn ambient(&mut self) -> [u16; 8] {
        self.s.ambient
    }
    fn compass(&mut self) -> Option<f32> {
        self.s.compass
    }
    fn ground(&mut self) -> bool {
        self.s.ground
    }
    fn line(&mut self) -> bool {
        self.s.line
    }
    fn beacon(&mut self) -> Option<BeaconReading> {
        self.s.beacon.map(|(bearing_rad, strength)| BeaconReading {
            bearing_rad,
            strength,
        })
    }
    fn battery_mv(&mut self) -> u16 {
        self.s.battery_mv
    }
    fn serial_read(&mut self, _: &mut [u8]) -> usize {
        0
    }
    fn serial_write(&mut self, b: &[u8]) -> usize {
        b.len()
    }
}

/// Lockstep reproduces the emulator: the firmware exploring through the HIL exchange, told
/// what `Setup` says, drives the body exactly as the emulator's own run of the same seed.
#[test]
fn the_firmware_in_the_loop_moves_the_body_as_the_emulator_does() {
    let seed = 4;
    let mut reference = sim(seed);
    reference
        .robot_mut()
        .apply(Command::SetMode(Mode::Explore), 0);
    let mut w = HilWorld::new(sim(seed), None, Mode::Explore).expect("world");
    let mut out = Vec::new();
    w.feed(&power_on(), &mut out).expect("accepted");
    let msgs = decode(&out);
    let Msg::Setup(setup) = msgs[0] else {
        panic!("{msgs:?}")
    };
    let [x, y, h] = setup.start;
    let mut robot = AnyRobot::new(RobotOptions {
        profile: &MICRO_RATO,
        seed: setup.firmware_seed,
        start: FwPose::new(x, y, h),
        emulated: true,
        firmware_version: env!("CARGO_PKG_VERSION"),
    });
    let fw = |p: Xy| robot_firmware::odometry::Point::new(p.x, p.y);
    let dead = robot.dead_mut();
    if let Some(b) = setup.beacon {
        dead.params.beacon = fw(b);
    }
    dead.set_bounds(robot_firmware::deadreckon::Bounds {
        min: fw(setup.bounds[0]),
        max: fw(setup.bounds[1]),
        ..dead.params.bounds
    });
    robot.apply(Command::SetMode(setup.power_on_mode), 0);
    let Msg::Sensors(mut s) = msgs[1] else {
        panic!("{msgs:?}")
    };
    let period_ms = u64::from(MICRO_RATO.cycle_us) / 1000;
    for _ in 0..300 {
        let mut hal = FrameHal {
            s,
            motor: MotorCommand::STOP,
        };
        robot.step(&mut hal);
        out.clear();
        let m = Motors {
            seq: s.seq,
            left: hal.motor.left,
            right: hal.motor.right,
            arm: 0,
            closed: false,
        };
        w.feed(&frame(&Msg::Motors(m)), &mut out).expect("accepted");
        let msgs = decode(&out);
        let Msg::Sensors(next) = msgs[0] else {
            panic!("{msgs:?}")
        };
        s = next;
        reference.run_for(period_ms);
        assert_eq!(w.sim().truth(), reference.truth(), "at {} µs", s.time_us);
    }
    assert!(reference.distance_m() > 0.5, "the robot explored");
}
