//! What the station keeps of the robot's floor-grid line correction (seed 003): the
//! `Localization` messages' three pose tracks, the line events, the last PPD summary, and,
//! with the emulator's truth, each estimate's error over time.
//!
//! Layer: app state, fed by `App::on_link`; drawn by `ui::localization`. Errors need the true
//! pose at the message's time: `EmuTruth` follows telemetry, so a `Localization` usually
//! arrives before the truth of its moment. Its poses wait in `pending` until a truth sample at
//! or after its time arrives, and are then judged against the truth interpolated between the
//! two samples around it. Bounded: tracks as `history::Track`, events and errors as below.
//! Cannot fail; a message older than every kept truth sample is judged against the oldest.

use std::collections::VecDeque;

use protocol::{EmuTruth, LineVerdict, Localization};

use super::history::Track;

/// Line events kept for the map.
pub const MAX_EVENTS: usize = 400;
/// Error samples kept for the chart (an hour at 5 Hz would be 18000; 20 minutes is plenty).
pub const MAX_ERRORS: usize = 6000;
/// Localization messages waiting for their truth.
const MAX_PENDING: usize = 32;

/// A line event where the robot put it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineMark {
    /// Corrected position just after the event, metres.
    pub x: f64,
    pub y: f64,
    pub verdict: LineVerdict,
}

/// Position errors against the truth at one moment, millimetres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorPoint {
    /// Robot clock, seconds.
    pub t_s: f64,
    pub corrected_mm: f64,
    pub uncorrected_mm: f64,
    pub baseline_mm: f64,
}

/// The line-correction views' state.
#[derive(Debug, Default)]
pub struct LocalizationState {
    /// The latest message.
    pub last: Option<Localization>,
    pub corrected: Track,
    pub uncorrected: Track,
    pub baseline: Track,
    pub events: VecDeque<LineMark>,
    pub errors: VecDeque<ErrorPoint>,
    /// Largest errors seen (corrected, uncorrected, baseline), millimetres.
    pub max_mm: [f64; 3],
    last_event_ms: Option<u32>,
    pending: VecDeque<Localization>,
    /// The last two truth samples: (robot ms, x m, y m).
    truth: [Option<(u32, f64, f64)>; 2],
}

impl LocalizationState {
    /// Whether the robot has sent any `Localization`.
    pub fn active(&self) -> bool {
        self.last.is_some()
    }

    /// A `Localization` from the robot.
    pub fn on_message(&mut self, m: Localization) {
        let (cx, cy) = xy(&m.corrected);
        self.corrected.push(cx, cy);
        let (ux, uy) = xy(&m.uncorrected);
        self.uncorrected.push(ux, uy);
        let (bx, by) = xy(&m.baseline);
        self.baseline.push(bx, by);
        if let Some(e) = m.last_event {
            if self.last_event_ms != Some(e.time_ms) {
                self.last_event_ms = Some(e.time_ms);
                if self.events.len() == MAX_EVENTS {
                    self.events.pop_front();
                }
                self.events.push_back(LineMark {
                    x: cx,
                    y: cy,
                    verdict: e.verdict,
                });
            }
        }
        if self.truth[1].is_some() {
            if self.pending.len() == MAX_PENDING {
                self.pending.pop_front();
            }
            self.pending.push_back(m);
            self.judge();
        }
        self.last = Some(m);
    }

    /// A truth sample from the emulator.
    pub fn on_truth(&mut self, t: &EmuTruth) {
        let (x, y) = xy(&t.pose);
        self.truth = [self.truth[1], Some((t.time_ms, x, y))];
        self.judge();
    }

    /// Forgets the tracks, events and errors (the `x` key), keeping the last message.
    pub fn clear(&mut self) {
        let last = self.last;
        *self = LocalizationState {
            last,
            truth: self.truth,
            ..LocalizationState::default()
        };
    }

    /// The latest error sample.
    pub fn latest_error(&self) -> Option<ErrorPoint> {
        self.errors.back().copied()
    }

    fn judge(&mut self) {
        let Some((t1, x1, y1)) = self.truth[1] else {
            return;
        };
        while let Some(m) = self.pending.front().copied() {
            if m.time_ms.wrapping_sub(t1) < 0x8000_0000 && m.time_ms != t1 {
                // Newer than the newest truth: wait for the next one.
                return;
            }
            self.pending.pop_front();
            let (x, y) = match self.truth[0] {
                Some((t0, x0, y0)) if t1 > t0 && m.time_ms > t0 => {
                    let f = f64::from(m.time_ms - t0) / f64::from(t1 - t0);
                    (x0 + f * (x1 - x0), y0 + f * (y1 - y0))
                }
                Some((_, x0, y0)) if m.time_ms < t1 => (x0, y0),
                _ => (x1, y1),
            };
            let err = |p: &protocol::Pose| {
                let (px, py) = xy(p);
                (px - x).hypot(py - y) * 1000.0
            };
            let e = ErrorPoint {
                t_s: f64::from(m.time_ms) / 1000.0,
                corrected_mm: err(&m.corrected),
                uncorrected_mm: err(&m.uncorrected),
                baseline_mm: err(&m.baseline),
            };
            for (max, v) in
                self.max_mm
                    .iter_mut()
                    .zip([e.corrected_mm, e.uncorrected_mm, e.baseline_mm])
            {
                *max = max.max(v);
            }
            if self.errors.len() == MAX_ERRORS {
                self.errors.pop_front();
            }
            self.errors.push_back(e);
        }
    }
}

fn xy(p: &protocol::Pose) -> (f64, f64) {
    (f64::from(p.x_mm) / 1000.0, f64::from(p.y_mm) / 1000.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use protocol::{LineEventInfo, Pose};

    fn pose(x_mm: i32) -> Pose {
        Pose {
            x_mm,
            y_mm: 0,
            heading_mrad: 0,
        }
    }

    fn truth(time_ms: u32, x_mm: i32) -> EmuTruth {
        EmuTruth {
            time_ms,
            pose: pose(x_mm),
            collisions: 0,
            robot_id: 1,
        }
    }

    #[test]
    fn errors_are_judged_against_the_truth_at_the_message_time() {
        let mut s = LocalizationState::default();
        s.on_truth(&truth(0, 0));
        s.on_truth(&truth(100, 100));
        let m = Localization {
            time_ms: 150,
            corrected: pose(150),
            uncorrected: pose(180),
            baseline: pose(100),
            last_event: Some(LineEventInfo {
                time_ms: 140,
                ..LineEventInfo::default()
            }),
            ..Localization::default()
        };
        s.on_message(m);
        // Waits for a truth at or after 150 ms.
        assert!(s.errors.is_empty());
        s.on_truth(&truth(200, 200));
        let e = s.latest_error().unwrap();
        assert!(e.corrected_mm.abs() < 1e-9, "{e:?}");
        assert!((e.uncorrected_mm - 30.0).abs() < 1e-9);
        assert!((e.baseline_mm - 50.0).abs() < 1e-9);
        // The same event twice is one mark.
        s.on_message(Localization { time_ms: 250, ..m });
        assert_eq!(s.events.len(), 1);
        s.clear();
        assert!(s.events.is_empty() && s.errors.is_empty() && s.active());
    }
}
