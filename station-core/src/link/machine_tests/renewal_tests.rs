//! The sequence-number rule (PROTOCOL.md §7): a renewed session before the counter reaches
//! a number the robot still remembers a reply for.

use super::*;

/// A robot as the station's tests need it for the sequence-number rule (PROTOCOL.md §7): it
/// answers every Hello and command at once and remembers every command of its session, a
/// superset of what a real robot remembers (the last 8, for 2 s).
#[derive(Default)]
struct RememberingRobot {
    remembered: Vec<u16>,
    seq: u16,
    /// Commands whose number the robot still remembered a reply for.
    reused: Vec<(u16, Command)>,
    hellos: u32,
}

impl RememberingRobot {
    fn frame(&mut self, msg: &Message<'_>) -> Vec<u8> {
        self.seq = self.seq.wrapping_add(1);
        frame(self.seq, msg)
    }

    /// Answers what the station sent, and what it sent in answer, until it is quiet; returns
    /// the number of frames it sent.
    fn serve(&mut self, m: &mut LinkMachine, now_ms: u64) -> usize {
        let mut frames = 0;
        loop {
            let out = sent(m);
            if out.is_empty() {
                return frames;
            }
            frames += out.len();
            self.answer(m, now_ms, &out);
        }
    }

    fn answer(
        &mut self,
        m: &mut LinkMachine,
        now_ms: u64,
        out: &[(u16, Kind, Option<Command>, Option<u32>)],
    ) {
        for (seq, kind, cmd, session) in out {
            match (kind, cmd, session) {
                (Kind::Hello, _, Some(session)) => {
                    self.hellos += 1;
                    self.remembered.clear();
                    m.receive(now_ms, &reply(*session, FINGERPRINT, true));
                }
                (Kind::Command, Some(c), _) => {
                    if self.remembered.contains(seq) {
                        self.reused.push((*seq, *c));
                    }
                    self.remembered.push(*seq);
                    let ack = Message::Ack(Ack {
                        cmd_seq: *seq,
                        info: AckInfo::Done,
                    });
                    let bytes = self.frame(&ack);
                    m.receive(now_ms, &bytes);
                }
                _ => {}
            }
        }
    }
}

#[test]
fn the_sequence_counter_never_reaches_a_number_the_robot_remembers_a_reply_for() {
    let mut m = machine();
    let mut robot = RememberingRobot::default();
    m.port_opened(0, "p");
    robot.serve(&mut m, 0);
    assert!(m.connected());
    let (mut now, mut frames, mut submitted) = (0u64, 0usize, 0u64);
    // Two wraps of the counter: an idle session at 4 Hz with a command now and then.
    while frames < 2 * 65_536 + 1_000 {
        now += 250;
        let time_ms = now as u32;
        let hb = robot.frame(&Message::Heartbeat(Heartbeat { time_ms }));
        m.receive(now, &hb);
        // Every 8th frame a command: 8 divides 65,536, so each wrap meets the old numbers.
        if now % 2_000 == 0 {
            let command = if submitted % 2 == 0 {
                Command::StartExploration
            } else {
                Command::Stop
            };
            m.submit(now, submitted, command);
            submitted += 1;
        }
        m.poll(now);
        frames += robot.serve(&mut m, now);
    }
    assert!(
        robot.reused.is_empty(),
        "reused: {:?}",
        &robot.reused[..5.min(robot.reused.len())]
    );
    let events = m.take_events();
    let done = outcomes(&events);
    assert_eq!(done.len() as u64, submitted);
    assert!(
        done.iter()
            .all(|(_, o)| matches!(o, CommandOutcome::Acked { .. })),
        "a renewal fails no command"
    );
    let stats = m.stats(now);
    assert!(stats.renewals >= 2, "renewals {}", stats.renewals);
    assert_eq!(robot.hellos, 1 + stats.renewals);
    assert_eq!(stats.link_timeouts, 0);
}

#[test]
fn at_the_renewal_point_new_commands_wait_for_those_in_flight_and_the_new_session() {
    let mut m = machine();
    connect(&mut m);
    m.session_frames = RENEW_AFTER_FRAMES - 1;
    m.submit(10, 1, Command::StartExploration);
    let first = sent(&mut m);
    assert_eq!(first.len(), 1, "the last number before the renewal point");
    m.submit(20, 2, Command::Stop);
    assert!(
        sent(&mut m).is_empty(),
        "the Stop waits: a command is in flight"
    );
    let ack = |seq| {
        frame(
            seq,
            &Message::Ack(Ack {
                cmd_seq: seq,
                info: AckInfo::Done,
            }),
        )
    };
    m.receive(30, &ack(first[0].0));
    let hello = sent(&mut m);
    assert_eq!(hello.len(), 1);
    assert_eq!(
        hello[0].1,
        Kind::Hello,
        "nothing in flight: the station handshakes again"
    );
    m.submit(40, 3, Command::Stop);
    assert!(sent(&mut m).is_empty());
    m.receive(50, &reply(hello[0].3.expect("nonce"), FINGERPRINT, true));
    let after = sent(&mut m);
    let cmds: Vec<_> = after.iter().filter_map(|f| f.2).collect();
    assert_eq!(
        cmds,
        vec![Command::Stop, Command::Stop],
        "the waiting commands go out"
    );
    assert!(after.iter().all(|f| f.0 != first[0].0));
    let events = m.take_events();
    assert!(
        !outcomes(&events)
            .iter()
            .any(|(_, o)| matches!(o, CommandOutcome::Failed(_))),
        "{events:?}"
    );
}
