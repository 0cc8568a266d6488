//! The rejected baseline of seed 003 §2.2.4 and §2.4.1: snap to the nearest line.
//!
//! Layer: a state machine beside [`super::Spps`], stepped the same way, kept only so tests
//! and the station can show why the PPD is needed. It integrates plain odometry and, on a
//! line event, moves the pose perpendicular to whichever line (x or y) the sensor's path came
//! nearest to, so that the path touches it. It never corrects the heading, so once the
//! heading has drifted it confuses x and y lines and gets lost (Fig 2-5, Fig 2-16).
//!
//! Invariants: no heap, no clock; nothing fails or panics.

use super::grid::{Axis, GridGeometry};
use super::ppd::sensor_point;
use crate::odometry::{integrate, OdometryParams, Pose};

/// Nearest-line correction (the baseline the thesis rejects).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NearestLine {
    odometry: OdometryParams,
    grid: GridGeometry,
    sensor_offset_m: f32,
    pose: Pose,
}

impl NearestLine {
    /// Starts at a known pose.
    pub fn new(
        odometry: OdometryParams,
        grid: GridGeometry,
        sensor_offset_m: f32,
        pose: Pose,
    ) -> Self {
        Self {
            odometry,
            grid,
            sensor_offset_m,
            pose,
        }
    }

    /// One control cycle (same inputs as [`super::Spps::step`]).
    pub fn step(&mut self, n_l: i32, n_r: i32, line: bool) -> Pose {
        let before = sensor_point(self.pose, self.sensor_offset_m);
        self.pose = integrate(self.pose, n_l, n_r, &self.odometry);
        if line {
            let after = sensor_point(self.pose, self.sensor_offset_m);
            let s = self.grid.swept(before, after);
            match s.line.axis {
                Axis::X => self.pose.x += s.shift_m,
                Axis::Y => self.pose.y += s.shift_m,
            }
        }
        self.pose
    }

    /// Current pose.
    pub fn pose(&self) -> Pose {
        self.pose
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_event_snaps_to_the_nearest_line_and_keeps_the_heading() {
        let mut b = NearestLine::new(
            OdometryParams::default(),
            GridGeometry::default(),
            0.0,
            Pose::new(0.26, 0.05, 0.1),
        );
        let p = b.step(100, 100, true);
        // The path ends near x = 0.268; the x = 0.3 band's edge (0.295) is nearer than any
        // y band's, so x moves there and the heading is kept.
        assert!((p.x - 0.295).abs() < 1e-4, "{p:?}");
        assert!((p.heading - 0.1).abs() < 1e-6);
    }
}
