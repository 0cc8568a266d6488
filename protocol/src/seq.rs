//! Sequence-number bookkeeping: loss, duplicates and late frames from a peer's u16 counter.
//!
//! Every sender numbers its frames 0, 1, 2, ... wrapping at 2^16; a retransmitted command
//! keeps its original number. The receiver counts a forward jump of `d` as `d - 1` lost frames,
//! a repeat as a duplicate, and a step backwards of less than half the range as a late frame
//! (which was earlier counted lost, so it is taken back off the loss count). Pure state, no I/O.

/// What one observed sequence number meant.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SeqEvent {
    /// The first frame seen since `reset`.
    First,
    /// The next number, after `lost` missing frames.
    InOrder { lost: u16 },
    /// The same number as the last frame: a retransmission.
    Duplicate,
    /// Older than the last frame.
    Late,
}

/// Counts a peer's frames by sequence number.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SeqTracker {
    last: Option<u16>,
    pub received: u64,
    pub lost: u64,
    pub duplicates: u64,
    pub late: u64,
}

impl SeqTracker {
    pub const fn new() -> Self {
        SeqTracker {
            last: None,
            received: 0,
            lost: 0,
            duplicates: 0,
            late: 0,
        }
    }

    /// Forgets the last number (a new session), keeping the counters.
    pub fn reset(&mut self) {
        self.last = None;
    }

    /// Records one frame's sequence number.
    pub fn observe(&mut self, seq: u16) -> SeqEvent {
        self.received += 1;
        let Some(last) = self.last else {
            self.last = Some(seq);
            return SeqEvent::First;
        };
        let d = seq.wrapping_sub(last);
        if d == 0 {
            self.duplicates += 1;
            SeqEvent::Duplicate
        } else if d < 0x8000 {
            self.last = Some(seq);
            let lost = d - 1;
            self.lost += u64::from(lost);
            SeqEvent::InOrder { lost }
        } else {
            self.late += 1;
            self.lost = self.lost.saturating_sub(1);
            SeqEvent::Late
        }
    }

    /// Fraction of the peer's frames that never arrived, 0..=1.
    pub fn loss_ratio(&self) -> f64 {
        // A late frame was counted lost when its successor arrived and un-counted on arrival,
        // so distinct frames sent = distinct frames received + still missing.
        let expected = (self.received - self.duplicates) + self.lost;
        if expected == 0 {
            0.0
        } else {
            self.lost as f64 / expected as f64
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaps_count_as_loss_and_wrap_around_is_not_a_gap() {
        let mut t = SeqTracker::new();
        assert_eq!(t.observe(65534), SeqEvent::First);
        assert_eq!(t.observe(65535), SeqEvent::InOrder { lost: 0 });
        assert_eq!(t.observe(0), SeqEvent::InOrder { lost: 0 });
        assert_eq!(t.observe(3), SeqEvent::InOrder { lost: 2 });
        assert_eq!(t.lost, 2);
        assert_eq!(t.observe(3), SeqEvent::Duplicate);
        assert_eq!(t.observe(2), SeqEvent::Late);
        assert_eq!((t.lost, t.duplicates, t.late, t.received), (1, 1, 1, 6));
        // 4 distinct in-order frames + 1 late arrived of 6 sent: 1 lost.
        assert!((t.loss_ratio() - 1.0 / 6.0).abs() < 1e-12);
    }
}
