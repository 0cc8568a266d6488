//! Feeds arbitrary bytes to the robot's serial port, with or without a valid handshake first,
//! stepping its clock between chunks. Invariants: no panic; before a handshake no motor ever
//! moves; the robot keeps answering (its output always decodes).
#![no_main]

use libfuzzer_sys::fuzz_target;
use protocol::{encode, Feed, FrameDecoder, Hello, Message, FINGERPRINT, MAX_FRAME, PROTOCOL_VERSION};
use robot_firmware::odometry::Pose;
use robot_firmware::scripted::ScriptedHal;
use robot_firmware::{AnyRobot, RobotOptions, KHEPERA, MICRO_RATO};

fuzz_target!(|data: &[u8]| {
    let Some((&flags, bytes)) = data.split_first() else { return };
    let profile = if flags & 1 == 0 { &KHEPERA } else { &MICRO_RATO };
    let handshake = flags & 2 != 0;
    let mut robot = AnyRobot::new(RobotOptions {
        profile,
        seed: 1,
        start: Pose::new(0.5, 0.5, 0.0),
        emulated: false,
        firmware_version: "fuzz",
    });
    let mut hal = ScriptedHal {
        encoders: Some([0, 0]),
        compass: Some(0.0),
        ..ScriptedHal::default()
    };
    if handshake {
        let mut buf = [0u8; MAX_FRAME];
        let hello = Hello { fingerprint: FINGERPRINT, protocol: PROTOCOL_VERSION, session: 1, station: "fuzz" };
        if let Ok(n) = encode(0, &Message::Hello(hello), &mut buf) {
            hal.push_rx(&buf[..n]);
        }
    }
    let mut out = FrameDecoder::new();
    let mut sink = [0u8; 4096];
    for chunk in bytes.chunks(64) {
        hal.push_rx(chunk);
        for _ in 0..10 {
            robot.step(&mut hal);
            hal.now_us += 1000;
        }
        let n = hal.take_tx(&mut sink);
        let mut input = &sink[..n];
        loop {
            match out.feed(input) {
                Feed::NeedMore => break,
                Feed::Frame { rest, .. } => input = rest,
                Feed::Error { error, .. } => panic!("the robot sent a bad frame: {error}"),
            }
        }
        if !handshake {
            assert_eq!(hal.motor_moves, 0, "a motor moved before any handshake");
        }
    }
});
