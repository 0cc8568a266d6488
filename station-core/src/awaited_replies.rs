//! The commands the TUI has sent and not yet seen answered, so that a redraw for the link's
//! changes does not fall inside a round trip.
//!
//! Layer: TUI state, no I/O, times passed in. Teleop repeats on a tick of the `pace` grid and
//! the link's redraw limit (`tui::LINK_FRAME`) is on the same grid, three slots apart like the
//! repeat: the screen was drawn in the very wake-up that sent each teleop, before the link
//! task (same thread) could write it, and the terminal (tmux, a terminal emulator) parsed the
//! update while the robot's answer was on its way. On a loaded two-core machine that put the
//! TUI's round trip at p50 5 ms where `station send` measured 3.4 ms (strace: every teleop
//! write right after a screen write). A redraw that only the link asks for now waits while a
//! reply is awaited, at most `HOLD`; a key still redraws at once. Cannot fail.

use std::collections::HashSet;
use std::time::Duration;

use tokio::time::Instant;

use crate::link::CommandId;

/// Longest a link redraw waits for a reply: one `pace` slot, ten round trips (a lost command
/// is retried after 200 ms; the screen does not wait for that).
pub const HOLD: Duration = crate::pace::SLOT;

/// Commands sent (robot index, id) and not answered, and since when one has been.
#[derive(Debug, Default)]
pub struct AwaitedReplies {
    ids: HashSet<(usize, CommandId)>,
    since: Option<Instant>,
}

impl AwaitedReplies {
    /// Robot `robot`'s command `id` went to its link at `now`.
    pub fn sent(&mut self, robot: usize, id: CommandId, now: Instant) {
        self.ids.insert((robot, id));
        self.since.get_or_insert(now);
    }

    /// Its outcome came (acked, refused, failed or superseded).
    pub fn answered(&mut self, robot: usize, id: CommandId) {
        self.ids.remove(&(robot, id));
        if self.ids.is_empty() {
            self.since = None;
        }
    }

    /// Whether a redraw for the link's changes should wait at `now`: a reply is awaited and
    /// has been for less than `HOLD`.
    pub fn hold_redraw(&self, now: Instant) -> bool {
        self.since
            .is_some_and(|t| now.saturating_duration_since(t) < HOLD)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_redraw_waits_for_the_answer_but_no_longer_than_a_slot() {
        let t0 = Instant::now();
        let mut a = AwaitedReplies::default();
        assert!(!a.hold_redraw(t0), "nothing sent, nothing to wait for");
        a.sent(0, 7, t0);
        a.sent(1, 7, t0 + Duration::from_millis(1));
        assert!(a.hold_redraw(t0 + Duration::from_millis(3)));
        // One robot's answer is not the other's.
        a.answered(0, 7);
        assert!(a.hold_redraw(t0 + Duration::from_millis(4)));
        a.answered(1, 7);
        assert!(!a.hold_redraw(t0 + Duration::from_millis(5)));
        // A command that is not answered (lost, retried in 200 ms) holds the screen one slot.
        a.sent(0, 8, t0 + Duration::from_millis(10));
        assert!(a.hold_redraw(t0 + Duration::from_millis(10) + HOLD - Duration::from_nanos(1)));
        assert!(!a.hold_redraw(t0 + Duration::from_millis(10) + HOLD));
        // An answer for something never sent changes nothing.
        a.answered(3, 99);
        assert!(!a.hold_redraw(t0 + Duration::from_millis(10) + HOLD));
    }
}
