//! The hardware trace (`hal_trace`): recorded by the wrapper around the `Hal`, played back by
//! `hal_trace::playback`, over the scripted `Hal` (no emulator): a traced run played back to a
//! fresh robot gives the same bytes and motor commands; a transmitter that cannot keep up
//! makes a gap that is counted in every frame and marked in the stream, never silent.
#![allow(clippy::unwrap_used, clippy::panic)]

use protocol::{
    encode, Command, Feed, FrameDecoder, Hello, Message, Mode, ParamId, FINGERPRINT, MAX_FRAME,
    PROTOCOL_VERSION,
};
use robot_firmware::hal_trace::playback::{Next, Playback};
use robot_firmware::odometry::Pose;
use robot_firmware::robot::Khepera;
use robot_firmware::scripted::ScriptedHal;
use robot_firmware::{Robot, RobotOptions, KHEPERA};

fn robot() -> Robot<Khepera> {
    let mut r = Robot::<Khepera>::new(RobotOptions {
        profile: &KHEPERA,
        seed: 42,
        start: Pose::new(0.5, 0.5, 0.3),
        emulated: false,
        firmware_version: "test",
    });
    let on = Command::SetParam {
        id: ParamId(robot_firmware::params::id::HAL_TRACE),
        value: 1.0,
    };
    r.core.apply(on, 0);
    r
}

fn frame(seq: u16, m: &Message<'_>) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME];
    let n = encode(seq, m, &mut buf).unwrap();
    buf[..n].to_vec()
}

/// The station's side: a Hello at 5 ms, Wander at 200 ms, heartbeats.
fn inbound(ms: u64) -> Option<Vec<u8>> {
    match ms {
        5 => Some(frame(
            1,
            &Message::Hello(Hello {
                fingerprint: FINGERPRINT,
                protocol: PROTOCOL_VERSION,
                session: 7,
                station: "test",
            }),
        )),
        200 => Some(frame(2, &Message::Command(Command::SetMode(Mode::Wander)))),
        m if m % 250 == 0 => Some(frame(
            (m / 250) as u16 + 2,
            &Message::Heartbeat(protocol::Heartbeat { time_ms: m as u32 }),
        )),
        _ => None,
    }
}

/// Runs a traced robot for `ms` milliseconds; the transmitter takes nothing while `stalled`.
/// Returns every byte it sent and its motor commands.
fn traced_run(ms: u64, stalled: impl Fn(u64) -> bool) -> (Vec<u8>, u32) {
    let mut r = robot();
    let mut hal = ScriptedHal {
        encoders: Some([0, 0]),
        battery_mv: 8000,
        ..ScriptedHal::default()
    };
    let mut out = Vec::new();
    for t in 0..ms {
        hal.now_us = t * 1000;
        // Sensors that change: noise-like IR, wheels that turn with the motors.
        hal.ir = core::array::from_fn(|i| ((t * 37 + i as u64 * 101) % 300) as u16);
        hal.ambient = core::array::from_fn(|i| 400 + ((t / 7 + i as u64) % 50) as u16);
        let e = hal.encoders.unwrap();
        hal.encoders = Some([
            e[0] + i32::from(hal.motors.left) / 8,
            e[1] + i32::from(hal.motors.right) / 8,
        ]);
        if let Some(bytes) = inbound(t) {
            hal.push_rx(&bytes);
        }
        hal.tx_chunk = if stalled(t) { 0 } else { usize::MAX };
        r.step(&mut hal);
        let mut buf = [0u8; 4096];
        let n = hal.take_tx(&mut buf);
        out.extend_from_slice(&buf[..n]);
    }
    (out, hal.motor_moves)
}

/// The robot's frames: (kind, payload bytes) and the joined trace stream.
fn split(bytes: &[u8]) -> (Vec<Vec<u8>>, Vec<u8>, u32) {
    let mut dec = FrameDecoder::new();
    let (mut frames, mut trace, mut dropped) = (Vec::new(), Vec::new(), 0);
    let mut input = bytes;
    let mut start = 0usize;
    loop {
        match dec.feed(input) {
            Feed::Frame { frame, rest } => {
                let used = input.len() - rest.len();
                frames.push(bytes[start..start + used].to_vec());
                start += used;
                if let Message::HalTrace(t) = frame.message {
                    assert_eq!(t.offset as usize, trace.len(), "no frame lost here");
                    trace.extend_from_slice(t.data);
                    dropped = dropped.max(t.dropped_steps);
                }
                input = rest;
            }
            Feed::Error { rest, .. } => {
                start += input.len() - rest.len();
                input = rest;
            }
            Feed::NeedMore => break,
        }
    }
    (frames, trace, dropped)
}

#[test]
fn a_traced_run_played_back_to_a_fresh_robot_sends_the_same_bytes() {
    let (sent, moves) = traced_run(3000, |_| false);
    assert!(moves > 0, "the robot wandered");
    let (frames, trace, dropped) = split(&sent);
    assert_eq!(dropped, 0);
    assert!(frames.len() > 60, "{} frames", frames.len());

    let mut play = Playback::new(&trace).unwrap();
    assert_eq!(play.start.seed, 42);
    assert_eq!(play.start.steps_before, 0, "traced from power-up");
    let mut again = robot();
    let mut replayed = Vec::new();
    let mut motor_checks = 0;
    while play.next_step().unwrap() == Next::Step {
        again.step(&mut play);
        replayed.extend_from_slice(play.written());
        let rec = play.recorded();
        assert_eq!(
            &play.motors_out[..play.n_motors_out],
            &rec.motors[..rec.n_motors],
            "pass {}",
            play.steps
        );
        motor_checks += rec.n_motors;
    }
    assert_eq!(play.misses, 0, "{:?}", play.first_miss);
    assert!(motor_checks > 30);
    // Every byte the retraced robot sent is the recorded robot's (the last pass or two, whose
    // trace had not left yet, are not played).
    assert!(replayed.len() > sent.len() * 9 / 10);
    assert_eq!(&sent[..replayed.len()], &replayed[..]);
}

#[test]
fn a_transmitter_that_cannot_keep_up_makes_a_counted_and_marked_gap() {
    // The port takes nothing from 1 s to 2 s: the link's queue and then the trace's fill.
    let (sent, _) = traced_run(4000, |t| (1000..2000).contains(&t));
    let (_, trace, dropped) = split(&sent);
    assert!(dropped > 0, "the frames count the dropped passes");
    let mut play = Playback::new(&trace).unwrap();
    let stop = loop {
        match play.next_step().unwrap() {
            Next::Step => {}
            other => break other,
        }
    };
    match stop {
        Next::Gap { steps, .. } => {
            assert!(steps > 0 && steps <= dropped, "{steps} of {dropped}");
            // The passes before the gap are all there (from power-up, without a hole).
            assert!(play.steps > 900, "{} passes before the gap", play.steps);
        }
        other => panic!("no gap marked: {other:?}"),
    }
}
