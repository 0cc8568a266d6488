//! One grid of wake-up times for the whole process, so that periodic work shares wake-ups.
//!
//! Layer: timing helper, no I/O. An idle station's CPU goes mostly to waking up (a context
//! switch costs more than the work it wakes for), so the TUI's periodic timers (its tick, the
//! link's heartbeat and statistics, the paced port's reads, the redraw limit) are all put on
//! the same `SLOT` grid: tokio fires every timer of one millisecond in one wake-up, so timers
//! on the grid cost one wake-up per slot between them instead of one each. Being on the grid
//! only moves a timer later, by less than a slot.
//!
//! Tokio's timer wheel also wakes at every 64 ms boundary of its own clock while a timer lies
//! beyond it, to move that timer down a level. A slot of 32 ms whose grid starts within the
//! millisecond before the runtime's clock does (`start`, called just before the runtime is
//! built) puts those boundaries on the grid too. Anywhere else the grid still works; the
//! boundaries then cost about 16 wake-ups a second of their own. Cannot fail.

use std::sync::OnceLock;
use std::time::Duration;

use tokio::time::Instant;

/// The grid's pitch: the paced port's read period and the TUI's tick; half of tokio's 64 ms
/// wheel level.
pub const SLOT: Duration = Duration::from_millis(32);

static ORIGIN: OnceLock<Instant> = OnceLock::new();

/// Starts the grid now; call just before building the runtime (see the module's note). Later
/// calls, and the first use of the grid without it, change nothing / start it then.
pub fn start() {
    let _ = ORIGIN.get_or_init(Instant::now);
}

/// The grid's origin.
fn origin() -> Instant {
    *ORIGIN.get_or_init(Instant::now)
}

/// `d` rounded up to whole slots (one at least).
pub fn slots(d: Duration) -> Duration {
    let n = d.as_nanos().div_ceil(SLOT.as_nanos()).max(1);
    SLOT * u32::try_from(n).unwrap_or(u32::MAX)
}

/// The first grid time at or after `t`.
pub fn slot_at_or_after(t: Instant) -> Instant {
    let o = origin();
    if t <= o {
        return o;
    }
    let floor = slot_at_or_before(t);
    if floor == t {
        t
    } else {
        floor + SLOT
    }
}

/// The last grid time at or before `t` (the origin for times before it).
pub fn slot_at_or_before(t: Instant) -> Instant {
    let o = origin();
    let since = t.saturating_duration_since(o).as_nanos();
    let pitch = SLOT.as_nanos();
    let whole = since - since % pitch;
    o + Duration::from_nanos(u64::try_from(whole).unwrap_or(u64::MAX))
}

/// The first grid time strictly after now.
pub fn next_slot() -> Instant {
    slot_at_or_before(Instant::now()) + SLOT
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn times_round_onto_the_grid_and_never_earlier() {
        let o = origin();
        for ms in [0u64, 1, 31, 32, 33, 63, 64, 1234] {
            let t = o + Duration::from_millis(ms);
            let up = slot_at_or_after(t);
            let down = slot_at_or_before(t);
            assert!(
                up >= t && up - t < SLOT,
                "{ms} ms rounds up to {:?}",
                up - o
            );
            assert!(
                down <= t && t - down < SLOT,
                "{ms} ms rounds down to {:?}",
                down - o
            );
            assert_eq!((up - o).as_nanos() % SLOT.as_nanos(), 0);
            assert_eq!((down - o).as_nanos() % SLOT.as_nanos(), 0);
        }
        assert_eq!(slot_at_or_after(o + SLOT), o + SLOT);
        assert!(next_slot() > Instant::now());
    }

    #[test]
    fn durations_round_up_to_whole_slots() {
        assert_eq!(slots(Duration::ZERO), SLOT);
        assert_eq!(slots(SLOT), SLOT);
        assert_eq!(slots(SLOT + Duration::from_nanos(1)), SLOT * 2);
        assert_eq!(slots(Duration::from_millis(100)), SLOT * 4);
    }
}
