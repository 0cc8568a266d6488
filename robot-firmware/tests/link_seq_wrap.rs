//! Issue 13 item 1: the station numbers every frame, heartbeats included, so its 16-bit
//! counter wraps in a long session. A reply the robot remembers may only answer a true retry
//! (PROTOCOL.md §7), never a new command that happens to reuse an old number.
#![allow(clippy::unwrap_used, clippy::panic)]

mod link_bench;

use link_bench::*;
use protocol::*;
use robot_firmware::{MotorCommand, KHEPERA, MICRO_RATO};

/// Heartbeats per robot step in a fast wrap: about 1 KB, the robot's read budget a step.
const FAST_BATCH: usize = 90;

fn heartbeat(b: &mut Bench) {
    b.send(&Message::Heartbeat(Heartbeat { time_ms: 0 }));
}

/// StartExploration at seq 1, 65,535 heartbeats `step_ms` apart, Stop at seq 1 again.
fn explore_then_stop_at_the_same_seq(b: &mut Bench, batch: usize, step_ms: u64) -> Vec<Seen> {
    b.hal.compass = Some(0.0);
    b.handshake();
    b.seq = 1;
    let explore = b.command(Command::StartExploration);
    assert_eq!(explore, 1);
    let seen = b.run(10);
    assert_eq!(
        replies(&seen),
        vec![Seen::Ack {
            cmd_seq: 1,
            info: AckInfo::Done
        }]
    );
    assert_eq!(b.robot.mode(), Mode::Explore);
    let mut sent = 0;
    while sent < 65_535 {
        for _ in 0..batch.min(65_535 - sent) {
            heartbeat(b);
            sent += 1;
        }
        b.robot.step(&mut b.hal);
        b.drain(&mut Vec::new());
        b.hal.now_us += step_ms * 1000;
    }
    assert!(b.robot.link().connected(), "heartbeats kept the session");
    assert_eq!(b.robot.mode(), Mode::Explore, "still exploring");
    assert_eq!(b.seq, 1, "the station's counter wrapped");
    let stop = b.command(Command::Stop);
    assert_eq!(stop, 1);
    b.run(50)
}

fn assert_stopped(b: &Bench, seen: &[Seen]) {
    assert_eq!(
        replies(seen),
        vec![Seen::Ack {
            cmd_seq: 1,
            info: AckInfo::Done
        }]
    );
    assert_eq!(b.robot.mode(), Mode::Idle, "the Stop was executed");
    assert_eq!(b.hal.motors, MotorCommand::STOP, "the motors stopped");
    assert_eq!(b.robot.link().counters().retries_answered, 0);
}

#[test]
fn a_stop_after_the_counter_wrapped_at_4_hz_is_executed_not_answered_from_memory() {
    let mut b = Bench::new(&MICRO_RATO);
    // 4.5 hours of an idle station: a heartbeat every 250 ms.
    let seen = explore_then_stop_at_the_same_seq(&mut b, 1, 250);
    assert_stopped(&b, &seen);
}

#[test]
fn a_stop_after_a_fast_wrap_is_executed_because_its_content_differs() {
    let mut b = Bench::new(&MICRO_RATO);
    // The whole wrap within the reply memory: only the content tells the frames apart.
    let seen = explore_then_stop_at_the_same_seq(&mut b, FAST_BATCH, 1);
    let elapsed_ms = b.hal.now_us / 1000;
    assert!(
        elapsed_ms < u64::from(timing::REPLY_MEMORY_MS),
        "the wrap took {elapsed_ms} ms"
    );
    assert_stopped(&b, &seen);
}

#[test]
fn the_same_command_at_the_same_seq_after_the_reply_memory_is_executed_again() {
    let mut b = Bench::new(&KHEPERA);
    b.handshake();
    let teleop = Command::Teleop {
        v_mm_s: 80,
        w_mrad_s: 0,
    };
    let s = b.command(teleop);
    b.run(10);
    b.command(Command::Stop);
    b.run_alive(u64::from(timing::REPLY_MEMORY_MS) + 250);
    assert_eq!(b.hal.motors, MotorCommand::STOP);
    b.send_with_seq(s, &Message::Command(teleop));
    let seen = b.run(100);
    assert_eq!(
        replies(&seen),
        vec![Seen::Ack {
            cmd_seq: s,
            info: AckInfo::Done
        }]
    );
    assert_eq!(
        b.hal.motors,
        MotorCommand::new(10, 10),
        "executed, not replayed"
    );
    assert_eq!(b.robot.link().counters().retries_answered, 0);
}
