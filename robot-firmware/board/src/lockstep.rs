//! The board's clock in hardware in the loop: the world's time, fine-grained by the timer.
//!
//! Lockstep (docs/hil.md §3): a control cycle must run at exactly the time of the world's
//! `Sensors` it uses, whatever the board's timer says, or the firmware's dead reckoning (which
//! integrates over its own clock) would drift from the world's physics by the board's speed.
//! So the firmware's clock (`Hal::now_us`) is the time of the last frame delivered plus the
//! timer's time since, held below the next frame's time until that frame is delivered: the
//! firmware sees its next cycle due only when its sensors are there. Between frames the link
//! runs on the timer (heartbeats, failsafe, telemetry), as on a board without a world.
//!
//! The timer paces delivery: frame k+1 is delivered one period of timer time after frame k
//! (on a grid, so wake-up latency does not accumulate), or when it arrives if later (a slow
//! world; the grid restarts there). Pure arithmetic over timer ticks: tested on the host.

/// Timer ticks per microsecond (the mps2-an386's 25 MHz APB clock).
pub const TICKS_PER_US: u64 = 25;

/// The lockstep clock.
#[derive(Clone, Copy, Debug)]
pub struct Lockstep {
    period_us: u64,
    /// Time of the last frame delivered, µs.
    world_us: u64,
    /// Timer ticks at the first clock read after that delivery; `None` until then, so the
    /// pass that runs the cycle reads exactly `world_us`.
    anchor: Option<u64>,
    /// Ticks from which the next frame may be delivered.
    due: u64,
    started: bool,
}

impl Lockstep {
    pub const fn new(period_us: u32) -> Self {
        Lockstep {
            period_us: period_us as u64,
            world_us: 0,
            anchor: None,
            due: 0,
            started: false,
        }
    }

    fn period_ticks(&self) -> u64 {
        self.period_us * TICKS_PER_US
    }

    /// The firmware's time at timer reading `ticks`.
    pub fn now_us(&mut self, ticks: u64) -> u64 {
        let anchor = *self.anchor.get_or_insert(ticks);
        let elapsed = ticks.saturating_sub(anchor) / TICKS_PER_US;
        self.world_us + elapsed.min(self.period_us.saturating_sub(1))
    }

    /// Whether a frame received may be delivered at `ticks`.
    pub fn is_due(&self, ticks: u64) -> bool {
        !self.started || ticks >= self.due
    }

    /// Ticks from which the next frame may be delivered.
    pub fn due_ticks(&self) -> u64 {
        self.due
    }

    /// The time the next frame must carry.
    pub fn next_frame_us(&self) -> u64 {
        if self.started {
            self.world_us + self.period_us
        } else {
            0
        }
    }

    /// Delivers the frame of time `time_us` at `ticks`.
    pub fn deliver(&mut self, time_us: u64, ticks: u64) {
        let p = self.period_ticks();
        self.due = if self.started && ticks.saturating_sub(self.due) < p {
            self.due + p
        } else {
            ticks + p
        };
        self.started = true;
        self.world_us = time_us;
        self.anchor = None;
    }

    /// The timer reading at which the firmware's clock reads `us` (at least `now_ticks`):
    /// when to wake for work the firmware has at that time.
    pub fn ticks_at(&self, us: u64, now_ticks: u64) -> u64 {
        let anchor = self.anchor.unwrap_or(now_ticks);
        (anchor + us.saturating_sub(self.world_us) * TICKS_PER_US).max(now_ticks)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const P: u32 = 50_000;
    const PT: u64 = P as u64 * TICKS_PER_US;

    #[test]
    fn the_cycle_pass_reads_exactly_the_frames_time_and_the_clock_never_reaches_the_next() {
        let mut c = Lockstep::new(P);
        assert!(c.is_due(123));
        c.deliver(0, 1000);
        // The first read after a delivery is the frame's time, however late it comes.
        assert_eq!(c.now_us(1000 + 77), 0);
        assert_eq!(c.now_us(1000 + 77 + 25 * 10), 10);
        // Held below the next frame's time while it is not delivered, whatever the timer.
        assert_eq!(c.now_us(1000 + 77 + 10 * PT), u64::from(P) - 1);
        assert!(!c.is_due(1000 + PT - 1));
        assert!(c.is_due(1000 + PT));
        assert_eq!(c.next_frame_us(), u64::from(P));
        c.deliver(u64::from(P), 1000 + PT + 40);
        assert_eq!(c.now_us(1000 + PT + 900), u64::from(P));
    }

    #[test]
    fn delivery_keeps_a_grid_and_restarts_it_after_a_late_frame() {
        let mut c = Lockstep::new(P);
        c.deliver(0, 0);
        // Woken a little late: the next is still due one period after the first.
        c.deliver(u64::from(P), PT + 30);
        assert_eq!(c.due_ticks(), 2 * PT);
        // The world was slow: more than a period late, the grid restarts from now.
        c.deliver(2 * u64::from(P), 5 * PT);
        assert_eq!(c.due_ticks(), 6 * PT);
    }

    #[test]
    fn wake_times_map_firmware_time_to_timer_ticks() {
        let mut c = Lockstep::new(P);
        c.deliver(0, 500);
        let _ = c.now_us(600);
        assert_eq!(c.ticks_at(1000, 700), 600 + 1000 * TICKS_PER_US);
        // A time already past: now.
        assert_eq!(c.ticks_at(0, 900), 900);
    }
}
