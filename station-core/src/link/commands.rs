//! Commands in flight: the station's half of PROTOCOL.md §7.
//!
//! Layer: pure bookkeeping, no I/O, time passed in. A command waits in a FIFO until one of
//! `MAX_IN_FLIGHT` slots is free, is then sent with a fresh sequence number, and is resent with
//! that same number every `COMMAND_RETRY_MS` until an Ack or Nack names it or
//! `COMMAND_ATTEMPTS` sends have gone unanswered. Invariant: every command that enters the
//! table leaves it exactly once (answered, expired, superseded or drained), so every caller
//! gets exactly one outcome. A newer `Teleop` supersedes older unanswered ones: resending a
//! stale velocity would only fight the operator's latest key. A queued command may be held
//! until a given time (`enqueue_at`, a teleop repeat waiting for a quiet line); the others
//! pass it.

use std::collections::VecDeque;

use protocol::timing::{COMMAND_ATTEMPTS, COMMAND_RETRY_MS};
use protocol::Command;

use super::api::CommandId;

/// Commands unanswered at once (PROTOCOL.md §7).
pub const MAX_IN_FLIGHT: usize = 8;

/// A command that has been sent at least once.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InFlight {
    pub id: CommandId,
    pub seq: u16,
    pub command: Command,
    pub last_sent_ms: u64,
    /// The first send, µs: a first-send round trip is timed from it.
    pub first_sent_us: u64,
    pub sends: u32,
}

/// A command waiting for a slot, and not to be sent before `not_before_us`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Queued {
    id: CommandId,
    command: Command,
    not_before_us: u64,
}

/// The queue and the in-flight slots.
#[derive(Debug, Default)]
pub struct CommandTable {
    queue: VecDeque<Queued>,
    in_flight: Vec<InFlight>,
}

impl CommandTable {
    /// Queues a command; returns the older teleops it supersedes (already removed).
    pub fn enqueue(&mut self, id: CommandId, command: Command) -> Vec<(CommandId, Command)> {
        self.enqueue_at(id, command, 0)
    }

    /// `enqueue`, not to be sent before `not_before_us`.
    pub fn enqueue_at(
        &mut self,
        id: CommandId,
        command: Command,
        not_before_us: u64,
    ) -> Vec<(CommandId, Command)> {
        let mut superseded = Vec::new();
        if matches!(command, Command::Teleop { .. }) {
            self.queue.retain(|q| {
                let stale = matches!(q.command, Command::Teleop { .. });
                if stale {
                    superseded.push((q.id, q.command));
                }
                !stale
            });
            self.in_flight.retain(|f| {
                let stale = matches!(f.command, Command::Teleop { .. });
                if stale {
                    superseded.push((f.id, f.command));
                }
                !stale
            });
        }
        self.queue.push_back(Queued {
            id,
            command,
            not_before_us,
        });
        superseded
    }

    /// The next queued command that may go at `now_us`, if a slot is free; the caller sends
    /// it and calls `sent`.
    pub fn next_to_send(&mut self, now_us: u64) -> Option<(CommandId, Command)> {
        if self.in_flight.len() >= MAX_IN_FLIGHT {
            return None;
        }
        let i = self.queue.iter().position(|q| q.not_before_us <= now_us)?;
        self.queue.remove(i).map(|q| (q.id, q.command))
    }

    /// When the earliest held command may go (µs), if one waits only for its time.
    pub fn next_release_us(&self) -> Option<u64> {
        if self.in_flight.len() >= MAX_IN_FLIGHT {
            return None;
        }
        self.queue.iter().map(|q| q.not_before_us).min()
    }

    /// Records the first send of a command under sequence number `seq`, at `now_us`.
    pub fn sent(&mut self, id: CommandId, seq: u16, command: Command, now_us: u64) {
        self.in_flight.push(InFlight {
            id,
            seq,
            command,
            last_sent_ms: now_us / 1000,
            first_sent_us: now_us,
            sends: 1,
        });
    }

    /// Takes the in-flight command that frame `cmd_seq` answers.
    pub fn answer(&mut self, cmd_seq: u16) -> Option<InFlight> {
        let i = self.in_flight.iter().position(|f| f.seq == cmd_seq)?;
        Some(self.in_flight.remove(i))
    }

    /// Commands to resend now (their send count and time updated), and commands whose last
    /// send went unanswered (removed).
    pub fn due(&mut self, now_ms: u64) -> (Vec<InFlight>, Vec<InFlight>) {
        let retry = u64::from(COMMAND_RETRY_MS);
        let mut resend = Vec::new();
        let mut expired = Vec::new();
        self.in_flight.retain_mut(|f| {
            if now_ms.saturating_sub(f.last_sent_ms) < retry {
                return true;
            }
            if f.sends >= COMMAND_ATTEMPTS {
                expired.push(*f);
                return false;
            }
            f.sends += 1;
            f.last_sent_ms = now_ms;
            resend.push(*f);
            true
        });
        (resend, expired)
    }

    /// Removes everything, in flight first, for a link that went down.
    pub fn drain(&mut self) -> Vec<(CommandId, Command)> {
        let mut all: Vec<_> = self
            .in_flight
            .drain(..)
            .map(|f| (f.id, f.command))
            .collect();
        all.extend(self.queue.drain(..).map(|q| (q.id, q.command)));
        all
    }

    /// When `due` next has something to do.
    pub fn next_deadline(&self) -> Option<u64> {
        let retry = u64::from(COMMAND_RETRY_MS);
        self.in_flight.iter().map(|f| f.last_sent_ms + retry).min()
    }

    pub fn in_flight(&self) -> usize {
        self.in_flight.len()
    }

    pub fn queued(&self) -> usize {
        self.queue.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use protocol::Mode;

    #[test]
    fn at_most_eight_commands_are_in_flight_and_the_rest_wait_in_order() {
        let mut t = CommandTable::default();
        for id in 0..10 {
            t.enqueue(id, Command::SetMode(Mode::Idle));
        }
        let mut sent = Vec::new();
        while let Some((id, c)) = t.next_to_send(0) {
            t.sent(id, id as u16, c, 0);
            sent.push(id);
        }
        assert_eq!(sent, (0..8).collect::<Vec<_>>());
        assert_eq!(t.queued(), 2);
        assert!(t.answer(3).is_some());
        assert_eq!(t.next_to_send(0).map(|(id, _)| id), Some(8));
    }

    #[test]
    fn a_command_is_resent_every_200_ms_and_expires_after_five_sends() {
        let mut t = CommandTable::default();
        t.enqueue(1, Command::Stop);
        let (id, c) = t.next_to_send(0).expect("slot");
        t.sent(id, 42, c, 0);
        let mut resends = 0;
        let mut now = 0;
        loop {
            now += 50;
            let (r, e) = t.due(now);
            resends += r.len();
            assert!(r.iter().all(|f| f.seq == 42), "a retry keeps its seq");
            if let Some(f) = e.first() {
                assert_eq!(f.sends, 5);
                break;
            }
        }
        assert_eq!(resends, 4);
        assert_eq!(
            now, 1000,
            "five sends 200 ms apart, then 200 ms for the last answer"
        );
    }

    #[test]
    fn a_new_teleop_supersedes_older_unanswered_teleops_only() {
        let mut t = CommandTable::default();
        let teleop = Command::Teleop {
            v_mm_s: 100,
            w_mrad_s: 0,
        };
        t.enqueue(1, teleop);
        t.enqueue(2, Command::Stop);
        let (id, c) = t.next_to_send(0).expect("slot");
        t.sent(id, 10, c, 0);
        t.enqueue(3, teleop);
        let gone = t.enqueue(4, teleop);
        assert_eq!(gone.iter().map(|g| g.0).collect::<Vec<_>>(), vec![3]);
        assert_eq!(t.in_flight(), 0, "teleop 1 was superseded by teleop 3");
        assert_eq!(t.queued(), 2, "stop and the newest teleop remain");
    }

    #[test]
    fn a_held_command_waits_for_its_time_and_the_others_pass_it() {
        let mut t = CommandTable::default();
        let teleop = Command::Teleop {
            v_mm_s: 100,
            w_mrad_s: 0,
        };
        t.enqueue_at(1, teleop, 5_000);
        t.enqueue(2, Command::Stop);
        assert_eq!(t.next_release_us(), Some(0), "the stop may go at once");
        assert_eq!(t.next_to_send(1_000).map(|(id, _)| id), Some(2));
        assert_eq!(t.next_to_send(1_000), None, "the teleop is held");
        assert_eq!(t.next_release_us(), Some(5_000));
        let (id, c) = t.next_to_send(5_000).expect("released");
        assert_eq!(id, 1);
        t.sent(id, 7, c, 5_000);
        // A held repeat supersedes the teleop unanswered, and a key press the held repeat.
        let gone = t.enqueue_at(3, teleop, 9_000);
        assert_eq!(gone.iter().map(|g| g.0).collect::<Vec<_>>(), vec![1]);
        let gone = t.enqueue(4, teleop);
        assert_eq!(gone.iter().map(|g| g.0).collect::<Vec<_>>(), vec![3]);
        assert_eq!(t.next_to_send(5_001).map(|(id, _)| id), Some(4));
    }
}
