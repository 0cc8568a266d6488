//! Position correction from a floor grid of black lines (seed 003 §2, Mächler's SPPS).
//!
//! Layer: above [`crate::odometry`], beside the behaviours. Odometry drifts mainly through
//! heading, because each wheel's speed error is a near-constant bias (seed 003 §2.2-2.3); the
//! set of poses the robot may be at is a thin banana (the PPD). A single downward sensor
//! pulses once per line crossed without telling x lines from y lines (§2.2.3). [`Spps`] keeps
//! the PPD as a fixed set of wheel-bias hypotheses ([`ppd`]), cuts it with the grid on every
//! pulse at the line holding the most PPD mass, and so corrects position and heading
//! (§2.5); [`NearestLine`] is the baseline the thesis rejects (§2.2.4), kept for comparison.
//!
//! - [`grid`]: the floor grid and what a sensor path over one cycle says about it.
//! - [`ppd`]: samples, their motion under a wheel bias, prior and lattice seeding.
//! - [`spps`]: the corrector, stepped per control cycle with the encoder counts.
//! - [`baseline`]: nearest-line snapping.
//! - [`fitter`]: the grid fitter (§2.6), steering so that lines are crossed at an angle.
//! - [`survey`]: the pilot of the long survey runs (a random walk with the fitter's pull).
//!
//! Invariants: no heap, no clock, no I/O; fixed capacity by const generic; seeded randomness.
//! Nothing here panics. What can fail is reported, not raised: a line event far from every
//! sample, or shared by two lines at a crossing, is rejected ([`LineOutcome::Rejected`]), and
//! one right after a correction is taken as a double detection ([`LineOutcome::Echo`]).
//!
//! Sizes: a [`Sample`] is 20 bytes; [`Spps64`] is 1388 bytes; a line event uses about 3.4 KB
//! of stack for N = 64 (two scratch arrays). Reproduction: tests/paper_003_line_correction.rs.

pub mod baseline;
pub mod fitter;
pub mod grid;
pub mod ppd;
pub mod spps;
pub mod survey;

pub use baseline::NearestLine;
pub use fitter::GridFitter;
pub use grid::{Axis, GridGeometry, GridLine, Swept};
pub use ppd::{Prior, Sample, SAMPLE_BYTES};
pub use spps::{LineCorrection, LineOutcome, Spps, Spps64, SppsCounters, SppsParams};
pub use survey::{Steer, Survey, SurveyParams};

/// Turns a latched floor-sensor level (true while over a line or entered since the last read)
/// into one event per line: true on a rising edge only. A double detection (an echo after a
/// gap) still gives two events, as on the real sensor.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct LineEdge {
    last: bool,
}

impl LineEdge {
    /// Feeds this cycle's level; returns whether a new line was entered.
    pub fn update(&mut self, level: bool) -> bool {
        let event = level && !self.last;
        self.last = level;
        event
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_edge_reports_rising_edges_only() {
        let mut e = LineEdge::default();
        let got: [bool; 6] = [true, true, false, true, false, false].map(|l| e.update(l));
        assert_eq!(got, [true, false, false, true, false, false]);
    }
}
