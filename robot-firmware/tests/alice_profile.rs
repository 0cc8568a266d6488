//! The ALICE composition (seed 001) over the scripted `Hal`: its situations leave as kind 16
//! three times a second with the readings and odometry it had, its wandering drives straight
//! and turns on the spot away from a front touch at once, teleop and stop are executed, the
//! modes it has no sensors for are refused, and the other robots send no situations. A traced
//! ALICE run plays back to the same bytes (the whiskers and photoresistors are in the trace).
#![allow(clippy::unwrap_used, clippy::panic)]

use protocol::{
    encode, AliceSituation, Command, Feed, FrameDecoder, Hello, Message, Mode, NackReason, ParamId,
    FINGERPRINT, MAX_FRAME, PROTOCOL_VERSION,
};
use robot_firmware::alice::wander::SPEED_MM_S;
use robot_firmware::odometry::Pose;
use robot_firmware::robot::{Alice, Khepera, Kit};
use robot_firmware::scripted::ScriptedHal;
use robot_firmware::{MotorCommand, Robot, RobotOptions, ALICE, KHEPERA};

fn robot<K: Kit>(profile: &'static robot_firmware::Profile) -> Robot<K> {
    Robot::new(RobotOptions {
        profile,
        seed: 9,
        start: Pose::new(1.0, 1.0, 0.0),
        emulated: false,
        firmware_version: "test",
    })
}

fn frame(seq: u16, m: &Message<'_>) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME];
    let n = encode(seq, m, &mut buf).unwrap();
    buf[..n].to_vec()
}

/// A robot, its scripted hardware (wheels that turn with the motors) and what it sent.
struct Bench<K: Kit> {
    r: Robot<K>,
    hal: ScriptedHal,
    t_ms: u64,
    seq: u16,
    out: Vec<u8>,
}

impl<K: Kit> Bench<K> {
    fn new(profile: &'static robot_firmware::Profile, sensors: bool) -> Self {
        Self::with(profile, sensors, false)
    }

    /// With `traced`, the hardware trace is on from power-up.
    fn with(profile: &'static robot_firmware::Profile, sensors: bool, traced: bool) -> Self {
        let mut r = robot(profile);
        if traced {
            let on = Command::SetParam {
                id: ParamId(robot_firmware::params::id::HAL_TRACE),
                value: 1.0,
            };
            r.core.apply(on, 0);
        }
        let hal = ScriptedHal {
            encoders: Some([0, 0]),
            whiskers: sensors.then_some(0),
            photoresistors: sensors.then(|| core::array::from_fn(|i| i as u8 * 10)),
            ..ScriptedHal::default()
        };
        let mut b = Bench {
            r,
            hal,
            t_ms: 0,
            seq: 0,
            out: Vec::new(),
        };
        b.send(&Message::Hello(Hello {
            fingerprint: FINGERPRINT,
            protocol: PROTOCOL_VERSION,
            session: 7,
            station: "test",
        }));
        b.run(20);
        b
    }

    fn send(&mut self, m: &Message<'_>) {
        let bytes = frame(self.seq, m);
        self.seq += 1;
        self.hal.push_rx(&bytes);
    }

    fn command(&mut self, c: Command) -> Vec<Message<'static>> {
        self.send(&Message::Command(c));
        let from = self.out.len();
        self.run(5);
        // Frames split at `from` are lost to this decode only; replies come whole after it.
        decode(&self.out[from..])
    }

    /// Runs `ms` milliseconds with heartbeats; a 0.1 mm encoder pulse per 20 motor units a ms.
    fn run(&mut self, ms: u64) {
        for _ in 0..ms {
            self.hal.now_us = self.t_ms * 1000;
            if self.t_ms % 100 == 50 {
                self.send(&Message::Heartbeat(protocol::Heartbeat { time_ms: 0 }));
            }
            // 5 mm/s a unit: 0.05 pulses a ms per unit.
            let e = self.hal.encoders.unwrap();
            let m = self.hal.motors;
            let pulse = |u: i16, t: u64| {
                (i64::from(u) * (t as i64 + 1) / 20 - i64::from(u) * t as i64 / 20) as i32
            };
            self.hal.encoders = Some([
                e[0] + pulse(m.left, self.t_ms),
                e[1] + pulse(m.right, self.t_ms),
            ]);
            self.r.step(&mut self.hal);
            let mut buf = [0u8; 4096];
            let n = self.hal.take_tx(&mut buf);
            self.out.extend_from_slice(&buf[..n]);
            self.t_ms += 1;
        }
    }
}

/// The frames in `bytes`, owned where it matters here.
fn decode(bytes: &[u8]) -> Vec<Message<'static>> {
    let mut dec = FrameDecoder::new();
    let mut out = Vec::new();
    let mut input = bytes;
    loop {
        match dec.feed(input) {
            Feed::Frame { frame, rest } => {
                let m = match frame.message {
                    Message::AliceSituation(s) => Message::AliceSituation(s),
                    Message::Ack(a) => Message::Ack(a),
                    Message::Nack(n) => Message::Nack(n),
                    Message::Telemetry(t) => Message::Telemetry(t),
                    _ => Message::Heartbeat(protocol::Heartbeat { time_ms: 0 }),
                };
                out.push(m);
                input = rest;
            }
            Feed::Error { rest, .. } => input = rest,
            Feed::NeedMore => break,
        }
    }
    out
}

fn situations(ms: &[Message<'_>]) -> Vec<AliceSituation> {
    ms.iter()
        .filter_map(|m| match m {
            Message::AliceSituation(s) => Some(*s),
            _ => None,
        })
        .collect()
}

#[test]
fn situations_leave_three_times_a_second_with_the_readings_and_the_odometry() {
    let mut b = Bench::<Alice>::new(&ALICE, true);
    b.hal.whiskers = Some(0b101);
    b.out.clear();
    b.run(10_000);
    let s = situations(&decode(&b.out));
    assert!(
        (29..=31).contains(&s.len()),
        "{} situations in 10 s",
        s.len()
    );
    for w in s.windows(2) {
        assert_eq!(w[1].seq, w[0].seq.wrapping_add(1), "consecutive");
        let dt = w[1].time_ms - w[0].time_ms;
        assert!((300..=350).contains(&dt), "{dt} ms apart");
    }
    let last = s.last().unwrap();
    assert_eq!(last.whiskers, 0b101);
    assert_eq!(last.light, core::array::from_fn(|i| i as u8 * 10));
    // Idle: the odometry stays at the start pose.
    assert_eq!((last.odometry.x_mm, last.odometry.y_mm), (1000, 1000));
}

#[test]
fn wandering_drives_straight_and_turns_away_from_a_front_touch_within_a_cycle() {
    let mut b = Bench::<Alice>::new(&ALICE, true);
    let replies = b.command(Command::SetMode(Mode::Wander));
    assert!(
        replies.iter().any(|m| matches!(m, Message::Ack(_))),
        "{replies:?}"
    );
    b.run(200);
    let cruise = ALICE.motor_units(SPEED_MM_S);
    assert_eq!(
        b.hal.motors,
        MotorCommand::new(cruise, cruise),
        "straight at 25 cm/s"
    );
    let x0 = b.r.pose().x;
    b.run(1000);
    assert!(b.r.pose().x - x0 > 0.2, "it drove: {} m", b.r.pose().x - x0);
    // A touch straight ahead: turning on the spot by the next cycle (50 ms).
    b.hal.whiskers = Some(1);
    b.run(60);
    let m = b.hal.motors;
    assert!(m.left == -m.right && m.left != 0, "{m:?}");
    b.hal.whiskers = Some(0);
    let h0 = b.r.pose().heading;
    b.run(3000);
    let turned = robot_firmware::odometry::wrap_angle(b.r.pose().heading - h0);
    assert!(
        turned.abs() > 1.5,
        "turned away from the touch: {turned} rad"
    );
    // Stop is executed.
    b.command(Command::Stop);
    b.run(60);
    assert_eq!(b.hal.motors, MotorCommand::STOP);
}

#[test]
fn teleop_is_executed_and_what_alice_has_no_sensors_for_is_refused() {
    let mut b = Bench::<Alice>::new(&ALICE, true);
    let r = b.command(Command::Teleop {
        v_mm_s: 200,
        w_mrad_s: 0,
    });
    assert!(r.iter().any(|m| matches!(m, Message::Ack(_))), "{r:?}");
    b.run(100);
    assert_eq!(b.hal.motors, MotorCommand::new(40, 40));
    for mode in [
        Mode::EdgeFollowLeft,
        Mode::SeekLight,
        Mode::Forage,
        Mode::Explore,
    ] {
        let r = b.command(Command::SetMode(mode));
        assert!(
            r.iter()
                .any(|m| matches!(m, Message::Nack(n) if n.reason == NackReason::Unsupported)),
            "{mode:?}: {r:?}"
        );
    }
    let r = b.command(Command::GoTo(protocol::PointMm {
        x_mm: 1500,
        y_mm: 1500,
    }));
    assert!(r.iter().any(|m| matches!(m, Message::Nack(_))), "{r:?}");
    b.command(Command::Stop);
    b.run(60);
    assert_eq!(b.hal.motors, MotorCommand::STOP);
}

#[test]
fn other_robots_send_no_situations_and_alice_without_sensors_sends_zeros() {
    let mut k = Bench::<Khepera>::new(&KHEPERA, false);
    k.run(2000);
    assert!(situations(&decode(&k.out)).is_empty());
    let mut a = Bench::<Alice>::new(&ALICE, false);
    a.run(2000);
    let s = situations(&decode(&a.out));
    assert!(!s.is_empty());
    assert!(s.iter().all(|s| s.whiskers == 0 && s.light == [0; 24]));
    assert!(!a.r.core.alice.sensed, "it knows it read nothing");
}

#[test]
fn a_traced_alice_run_plays_back_to_the_same_bytes() {
    let run = || {
        let mut b = Bench::<Alice>::with(&ALICE, true, true);
        b.command(Command::SetMode(Mode::Wander));
        for i in 0..40u32 {
            b.hal.whiskers = Some(if i % 7 == 3 { 1 << (i % 24) } else { 0 });
            b.hal.photoresistors = Some(core::array::from_fn(|k| (k as u32 * 7 + i) as u8));
            b.run(100);
        }
        b.out
    };
    let out = run();
    assert_eq!(out, run(), "same inputs, same run");
    let trace = trace_of(&out);
    check_playback(&out, &trace);
    bad_alice_entries_are_refused_by_offset(&trace);
}

/// The trace stream of a traced run's bytes.
fn trace_of(out: &[u8]) -> Vec<u8> {
    let mut dec = FrameDecoder::new();
    let mut trace = Vec::new();
    let mut input = out;
    loop {
        match dec.feed(input) {
            Feed::Frame { frame, rest } => {
                if let Message::HalTrace(t) = frame.message {
                    assert_eq!(t.offset as usize, trace.len());
                    trace.extend_from_slice(t.data);
                }
                input = rest;
            }
            Feed::Error { rest, .. } => input = rest,
            Feed::NeedMore => break,
        }
    }
    trace
}

/// Untrusted trace bytes: a whisker value beyond 32 bits is refused at its byte, and a
/// photoresistor entry cut by the end of the stream ends the playback, neither panics.
fn bad_alice_entries_are_refused_by_offset(trace: &[u8]) {
    use robot_firmware::hal_trace::playback::{Next, Playback, TraceError};
    use robot_firmware::hal_trace::tag;
    let play_all = |bytes: &[u8]| {
        let mut p = Playback::new(bytes).unwrap();
        loop {
            match p.next_step() {
                Ok(Next::Step) => {}
                other => return other,
            }
        }
    };
    let mut bad = trace.to_vec();
    let at = bad.len();
    bad.extend_from_slice(&[tag::STEP, 1, tag::WHISKERS]);
    bad.extend_from_slice(&[0xFF, 0xFF, 0xFF, 0xFF, 0x7F]); // 2^35 - 1
    bad.extend_from_slice(&[tag::STEP, 1]);
    match play_all(&bad) {
        Err(TraceError::BadValue { offset, field }) => {
            assert_eq!((offset, field), (at + 3, "WHISKERS"));
        }
        other => panic!("{other:?}"),
    }
    let mut cut = trace.to_vec();
    cut.extend_from_slice(&[tag::STEP, 1, tag::LIGHT24, 1, 2, 3]);
    assert_eq!(play_all(&cut).unwrap(), Next::End);
}

fn check_playback(out: &[u8], trace: &[u8]) {
    use robot_firmware::hal_trace::playback::{Next, Playback};
    let mut play = Playback::new(trace).unwrap();
    assert_eq!(play.start.steps_before, 0, "traced from power-up");
    let mut again = robot::<Alice>(&ALICE);
    again.core.apply(
        Command::SetParam {
            id: ParamId(robot_firmware::params::id::HAL_TRACE),
            value: 1.0,
        },
        0,
    );
    let mut replayed = Vec::new();
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
    }
    assert_eq!(play.misses, 0, "{:?}", play.first_miss);
    assert!(replayed.len() > out.len() * 9 / 10);
    assert_eq!(&out[..replayed.len()], &replayed[..]);
    assert!(
        !situations(&decode(&replayed)).is_empty(),
        "the retraced ALICE sent situations"
    );
}
