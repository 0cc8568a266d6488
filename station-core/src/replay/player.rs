//! The replay's transport controls: where in the recording we are, how fast it runs, paused.
//!
//! Layer: pure state with the wall clock passed in (µs since the replay started), like the
//! link machine's `poll(now)`. While playing, the position is `anchor position + (wall - anchor
//! wall) x speed`, clamped to the recording; every control change re-anchors, so changing speed
//! or pausing never jumps. Reaching the end pauses there. Cannot fail.

/// Speeds `+`/`-` step through.
pub const SPEEDS: [f64; 11] = [0.1, 0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0, 128.0];
/// One arrow press seeks this far, µs.
pub const SEEK_STEP_US: i64 = 5_000_000;

/// Position, speed and pause of a replay.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Player {
    duration_us: u64,
    /// Position at `anchor_wall_us`.
    anchor_pos_us: u64,
    anchor_wall_us: u64,
    speed: f64,
    paused: bool,
}

impl Player {
    /// Playing from the start at `speed`.
    pub fn new(duration_us: u64, speed: f64) -> Player {
        Player {
            duration_us,
            anchor_pos_us: 0,
            anchor_wall_us: 0,
            speed: clamp_speed(speed),
            paused: false,
        }
    }

    pub fn duration_us(&self) -> u64 {
        self.duration_us
    }

    pub fn speed(&self) -> f64 {
        self.speed
    }

    pub fn paused(&self) -> bool {
        self.paused
    }

    /// The recording time shown at wall time `wall_us`.
    pub fn position(&self, wall_us: u64) -> u64 {
        if self.paused {
            return self.anchor_pos_us.min(self.duration_us);
        }
        let dt = wall_us.saturating_sub(self.anchor_wall_us) as f64 * self.speed;
        let pos = self.anchor_pos_us as f64 + dt;
        if pos >= self.duration_us as f64 {
            self.duration_us
        } else {
            pos as u64
        }
    }

    /// Whether the end has been reached.
    pub fn at_end(&self, wall_us: u64) -> bool {
        self.position(wall_us) >= self.duration_us
    }

    /// Pauses at the end once it is reached; call after each wake-up.
    pub fn settle(&mut self, wall_us: u64) {
        if !self.paused && self.at_end(wall_us) {
            self.anchor(wall_us);
            self.paused = true;
        }
    }

    fn anchor(&mut self, wall_us: u64) {
        self.anchor_pos_us = self.position(wall_us);
        self.anchor_wall_us = wall_us;
    }

    /// Pause or resume; resuming at the end starts again from the beginning.
    pub fn toggle_pause(&mut self, wall_us: u64) {
        self.anchor(wall_us);
        if self.paused && self.anchor_pos_us >= self.duration_us {
            self.anchor_pos_us = 0;
        }
        self.paused = !self.paused;
    }

    pub fn set_speed(&mut self, wall_us: u64, speed: f64) {
        self.anchor(wall_us);
        self.speed = clamp_speed(speed);
    }

    /// One step along `SPEEDS` (from the nearest one).
    pub fn step_speed(&mut self, wall_us: u64, d: i32) {
        let i = SPEEDS
            .iter()
            .position(|&s| s >= self.speed - 1e-9)
            .unwrap_or(SPEEDS.len() - 1) as i32;
        let j = (i + d).clamp(0, SPEEDS.len() as i32 - 1) as usize;
        let s = SPEEDS.get(j).copied().unwrap_or(1.0);
        self.set_speed(wall_us, s);
    }

    /// Jumps to `t_us` (clamped to the recording).
    pub fn seek(&mut self, wall_us: u64, t_us: u64) {
        self.anchor_wall_us = wall_us;
        self.anchor_pos_us = t_us.min(self.duration_us);
    }

    /// Jumps by `d_us` (negative: back).
    pub fn seek_by(&mut self, wall_us: u64, d_us: i64) {
        let now = self.position(wall_us);
        let t = if d_us < 0 {
            now.saturating_sub(d_us.unsigned_abs())
        } else {
            now.saturating_add(d_us.unsigned_abs())
        };
        self.seek(wall_us, t);
    }

    /// The wall time at which the position reaches `t_us`, if playing.
    pub fn wall_at(&self, t_us: u64) -> Option<u64> {
        if self.paused {
            return None;
        }
        let ahead = t_us.saturating_sub(self.anchor_pos_us) as f64 / self.speed;
        Some(self.anchor_wall_us.saturating_add(ahead.ceil() as u64))
    }
}

fn clamp_speed(s: f64) -> f64 {
    if s.is_finite() {
        s.clamp(0.01, 1000.0)
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn position_runs_at_speed_and_stops_at_the_end() {
        let mut p = Player::new(10_000_000, 2.0);
        assert_eq!(p.position(1_000_000), 2_000_000);
        p.settle(6_000_000);
        assert!(p.paused());
        assert_eq!(p.position(9_000_000), 10_000_000);
    }

    #[test]
    fn pausing_and_changing_speed_do_not_jump() {
        let mut p = Player::new(100_000_000, 1.0);
        p.toggle_pause(3_000_000);
        assert_eq!(p.position(50_000_000), 3_000_000);
        p.toggle_pause(50_000_000);
        assert_eq!(p.position(51_000_000), 4_000_000);
        p.set_speed(51_000_000, 4.0);
        assert_eq!(p.position(52_000_000), 8_000_000);
        p.step_speed(52_000_000, 1);
        assert_eq!(p.speed(), 8.0);
        p.step_speed(52_000_000, -3);
        assert_eq!(p.speed(), 1.0);
    }

    #[test]
    fn seeking_clamps_to_the_recording() {
        let mut p = Player::new(10_000_000, 1.0);
        p.seek_by(0, -SEEK_STEP_US);
        assert_eq!(p.position(0), 0);
        p.seek_by(0, 3 * SEEK_STEP_US);
        assert_eq!(p.position(0), 10_000_000);
        p.seek(0, 4_000_000);
        assert_eq!(p.wall_at(5_000_000), Some(1_000_000));
    }

    #[test]
    fn resuming_at_the_end_starts_over() {
        let mut p = Player::new(1_000_000, 1.0);
        p.settle(2_000_000);
        p.toggle_pause(3_000_000);
        assert_eq!(p.position(3_500_000), 500_000);
    }
}
