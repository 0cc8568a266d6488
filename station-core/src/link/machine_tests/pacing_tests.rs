//! When a teleop repeat goes: after the robot's telemetry burst, so that it does not share the
//! half-duplex line with it.

use super::*;

/// A robot at 50 Hz on our clock: burst `k`'s telemetry (stamped `20 k` ms of the robot's
/// clock) read 5.4 ms after its stamp, its truth frame 7.2 ms after; the robot's clock reads
/// 1 s behind ours.
fn burst(m: &mut LinkMachine, k: u64) {
    burst_at(m, 1_000_000 + k * 20_000, (k * 20) as u32, 5_400, 7_200);
}

/// A burst stamped `time_ms` by the robot at our `stamp_us`: its telemetry read
/// `telemetry_after_us` later, its truth frame `truth_after_us` later.
fn burst_at(
    m: &mut LinkMachine,
    stamp_us: u64,
    time_ms: u32,
    telemetry_after_us: u64,
    truth_after_us: u64,
) {
    let t = Telemetry {
        time_ms,
        ..Telemetry::default()
    };
    m.receive_us(
        stamp_us + telemetry_after_us,
        &frame(100, &Message::Telemetry(t)),
    );
    let truth = EmuTruth {
        time_ms,
        ..EmuTruth::default()
    };
    m.receive_us(
        stamp_us + truth_after_us,
        &frame(101, &Message::EmuTruth(truth)),
    );
}

/// The commands the station sent (heartbeats and other frames left out).
fn commands_sent(m: &mut LinkMachine) -> Vec<(u16, Command)> {
    sent(m)
        .into_iter()
        .filter_map(|f| f.2.map(|c| (f.0, c)))
        .collect()
}

#[test]
fn a_teleop_repeat_waits_for_the_end_of_the_robots_burst_and_a_key_press_goes_at_once() {
    use crate::link::line_phase::MARGIN_US;
    let mut m = machine();
    connect(&mut m);
    for k in 0..20 {
        burst(&mut m, k);
    }
    sent(&mut m);
    let teleop = Command::Teleop {
        v_mm_s: 100,
        w_mrad_s: 0,
    };
    // A repeat asked for 2 ms into burst 20: held to its end.
    let start = 1_000_000 + 20 * 20_000;
    m.submit_when(start + 2_000, 1, teleop, SendWhen::QuietLine);
    assert!(commands_sent(&mut m).is_empty(), "held");
    let release = start + 7_200 + MARGIN_US;
    assert_eq!(m.next_release_us(), Some(release));
    assert!(!m.awaiting_reply(), "a held command is not in flight");
    m.poll_us(release - 1);
    assert!(commands_sent(&mut m).is_empty());
    m.poll_us(release);
    let s = commands_sent(&mut m);
    assert_eq!(s.len(), 1);
    assert_eq!(s[0].1, teleop);
    assert_eq!(m.next_release_us(), None);
    // Its round trip is timed from the send, to the microsecond.
    let ack = Message::Ack(Ack {
        cmd_seq: s[0].0,
        info: AckInfo::Done,
    });
    m.receive_us(release + 2_345, &frame(102, &ack));
    assert_eq!(m.stats(1_500).rtt_ms.p50, Some(2.345));

    // A key press 3 ms into the next burst goes at once.
    let start = 1_000_000 + 21 * 20_000;
    m.submit_when(start + 3_000, 2, teleop, SendWhen::Now);
    assert_eq!(commands_sent(&mut m).len(), 1);
    burst(&mut m, 21);
    // A repeat asked for 2 ms into the burst after is held (superseding the press still
    // unanswered, as any newer teleop does); a key press 5 ms into it goes at once and
    // supersedes the held repeat.
    m.submit_when(start + 22_000, 3, teleop, SendWhen::QuietLine);
    assert!(commands_sent(&mut m).is_empty());
    m.take_events();
    m.submit_when(start + 25_000, 4, teleop, SendWhen::Now);
    assert_eq!(commands_sent(&mut m).len(), 1);
    let superseded: Vec<_> = outcomes(&m.take_events())
        .into_iter()
        .filter(|(_, o)| *o == CommandOutcome::Failed(CommandFailure::Superseded))
        .map(|(id, _)| id)
        .collect();
    assert_eq!(superseded, vec![3]);
    assert_eq!(m.next_release_us(), None);
}

#[test]
fn a_repeat_goes_at_once_when_no_burst_is_known() {
    let mut m = machine();
    connect(&mut m);
    sent(&mut m);
    let teleop = Command::Teleop {
        v_mm_s: 100,
        w_mrad_s: 0,
    };
    m.submit_when(50_000, 1, teleop, SendWhen::QuietLine);
    assert_eq!(
        commands_sent(&mut m).len(),
        1,
        "no telemetry: nothing to wait for"
    );
}

#[test]
fn a_repeat_goes_at_once_when_the_robots_clock_runs_faster_than_ours() {
    // An emulator at ten times real time: a burst stamped every 20 ms of its clock comes every
    // 2 ms of ours. Read through the stamps, the next burst would seem 20 ms away and a
    // repeat asked for 3 ms after the last one would be held for 17 ms.
    let mut m = machine();
    connect(&mut m);
    let base = 1_000_000;
    let mut last_truth_us = 0;
    for k in 0..40u64 {
        let stamp_us = base + k * 2_000;
        burst_at(&mut m, stamp_us, (k * 20) as u32, 540, 720);
        last_truth_us = stamp_us + 720;
    }
    sent(&mut m);
    let teleop = Command::Teleop {
        v_mm_s: 100,
        w_mrad_s: 0,
    };
    m.submit_when(last_truth_us + 3_000, 1, teleop, SendWhen::QuietLine);
    assert_eq!(commands_sent(&mut m).len(), 1, "not held");
    assert_eq!(m.next_release_us(), None);
}
