//! A downward floor-line sensor over the floor grid (seed 003 §2.2.3: one light sensor under
//! the robot, a short pulse per line crossed, horizontal and vertical lines look the same).
//!
//! The physics calls [`LineSensor::update`] every step with whether the sensor (at the body's
//! centre) is over a line; the firmware reads [`LineSensor::read`] once per control cycle.
//! Like a hardware latch, a read reports a line if the sensor is over one now OR entered one
//! since the previous read, so a crossing shorter than a control cycle is not lost to
//! sampling. Faults, drawn per crossing (seed 003 asks for both, giving no rates): a MISSED
//! crossing reads false throughout; a DOUBLE detection adds an echo pulse after the crossing
//! (one read false, the next true), which the firmware counts as a second line.
//!
//! Invariants: at most one echo per crossing; without a floor grid the sensor never fires.
//! Cannot fail.

use crate::rng::SimRng;

/// State of the floor sensor.
#[derive(Clone, Debug)]
pub struct LineSensor {
    present: bool,
    miss: f64,
    double: f64,
    over: bool,
    /// The current crossing is suppressed (a missed detection).
    missed: bool,
    /// The current crossing will echo when it ends.
    echo_on_exit: bool,
    /// Entered a (reported) line since the last read.
    latched: bool,
    /// Reads left until the echo: 2 = next read is the gap, 1 = next read is the echo.
    echo: u8,
    rng: SimRng,
}

impl LineSensor {
    /// A sensor (absent ones always read false) with miss and double-detection probabilities.
    pub fn new(present: bool, miss: f64, double: f64, rng: SimRng) -> LineSensor {
        LineSensor {
            present,
            miss,
            double,
            over: false,
            missed: false,
            echo_on_exit: false,
            latched: false,
            echo: 0,
            rng,
        }
    }

    /// Whether the sensor is fitted.
    pub fn present(&self) -> bool {
        self.present
    }

    /// One physics step: the sensor is `over_line` now.
    pub fn update(&mut self, over_line: bool) {
        if !self.present || over_line == self.over {
            return;
        }
        self.over = over_line;
        if over_line {
            self.missed = self.rng.chance(self.miss);
            self.echo_on_exit = !self.missed && self.rng.chance(self.double);
            if !self.missed {
                self.latched = true;
            }
        } else if self.echo_on_exit {
            self.echo_on_exit = false;
            self.echo = 2;
        }
    }

    /// What the firmware reads now.
    pub fn read(&mut self) -> bool {
        if !self.present {
            return false;
        }
        let real = (self.over && !self.missed) || self.latched;
        self.latched = false;
        match self.echo {
            2 if !real => {
                self.echo = 1;
                false
            }
            1 if !real => {
                self.echo = 0;
                true
            }
            _ => real,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn crossing(s: &mut LineSensor, steps_on: usize) {
        s.update(true);
        for _ in 1..steps_on {
            s.update(true);
        }
        s.update(false);
    }

    #[test]
    fn a_crossing_between_two_reads_is_latched() {
        let mut s = LineSensor::new(true, 0.0, 0.0, SimRng::new(1, 1));
        assert!(!s.read());
        crossing(&mut s, 5);
        assert!(s.read());
        assert!(!s.read());
    }

    #[test]
    fn misses_and_doubles_happen_at_their_rates() {
        let mut missed = LineSensor::new(true, 1.0, 0.0, SimRng::new(1, 1));
        crossing(&mut missed, 5);
        assert!(!missed.read());
        let mut double = LineSensor::new(true, 0.0, 1.0, SimRng::new(1, 1));
        crossing(&mut double, 5);
        assert_eq!(
            [double.read(), double.read(), double.read(), double.read()],
            [true, false, true, false]
        );
        let mut absent = LineSensor::new(false, 0.0, 0.0, SimRng::new(1, 1));
        crossing(&mut absent, 5);
        assert!(!absent.read());
    }
}
