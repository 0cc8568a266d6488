//! The floor grid of black lines and what one line event says about a sensor's path.
//!
//! Layer: pure geometry under [`super::Spps`] and [`super::NearestLine`]. Lines run along
//! `x = origin.x + k * pitch` ([`Axis::X`], the thesis's "V" lines, which fix x) and
//! `y = origin.y + k * pitch` ([`Axis::Y`], "H" lines, which fix y) (seed 003 §2.6). A line has
//! a width; a downward sensor reports a line when it *enters* the band (seed 003 §2.2.3: one
//! short pulse per line, horizontal and vertical look the same).
//!
//! A control cycle moves the sensor along a short path; [`GridGeometry::swept`] says which
//! band that path entered, or how far it would have to be shifted, perpendicular to the
//! band, to enter the nearest one. Invariants: shifts are the smallest signed moves that make
//! the path cross the edge of a band it meets first, 0 when it already does; no function
//! panics on any input. A path or grid that names no band (a non-finite coordinate, a pitch
//! that is not a positive finite number) gives line 0 and a shift of 0, so a correction built
//! on it moves no pose; huge finite coordinates give saturated indices.

use crate::odometry::Point;

/// Which coordinate a family of lines fixes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axis {
    /// Lines `x = const` ("vertical", V zones of seed 003 §2.6): crossing one fixes x.
    X,
    /// Lines `y = const` ("horizontal", H zones): crossing one fixes y.
    Y,
}

/// One grid line: its family and its index `k` (at `origin + k * pitch`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GridLine {
    /// Family.
    pub axis: Axis,
    /// Index from the grid's origin.
    pub index: i32,
}

/// A floor grid: pitch, line width and origin, metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridGeometry {
    /// Distance between parallel lines. seed 003 §2.6.4: 10 cm squares.
    pub pitch_m: f32,
    /// Width of a line. seed 003 gives none; 1 cm (black tape) is also the emulator's width.
    pub line_width_m: f32,
    /// A point where two lines cross.
    pub origin: Point,
}

impl Default for GridGeometry {
    fn default() -> Self {
        Self {
            // seed 003 §2.6.4: "one square has a length of 10 cm"
            pitch_m: 0.10,
            line_width_m: 0.01,
            origin: Point::new(0.0, 0.0),
        }
    }
}

/// How a swept sensor path relates to the nearest band of one family.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Swept {
    /// The nearest line.
    pub line: GridLine,
    /// Signed move along the family's axis that makes the path enter the band; 0 if it does.
    pub shift_m: f32,
}

impl GridGeometry {
    /// Coordinate of `line` along its axis, metres (the centre of the band).
    pub fn coordinate(&self, line: GridLine) -> f32 {
        let o = match line.axis {
            Axis::X => self.origin.x,
            Axis::Y => self.origin.y,
        };
        o + line.index as f32 * self.pitch_m
    }

    /// The band of `axis` nearest to the path from `a` to `b` (for a cycle, the sensor's
    /// previous and current positions; a straight chord stands for the short arc).
    pub fn swept_axis(&self, axis: Axis, a: Point, b: Point) -> Swept {
        let (u, v, o) = match axis {
            Axis::X => (a.x, b.x, self.origin.x),
            Axis::Y => (a.y, b.y, self.origin.y),
        };
        let (u, v, half) = (u - o, v - o, self.line_width_m / 2.0);
        let names_a_band =
            [u, v, half, self.pitch_m].iter().all(|x| x.is_finite()) && self.pitch_m > 0.0;
        let (index, shift_m) = if names_a_band {
            swept_1d(u, v, self.pitch_m, half)
        } else {
            (0, 0.0)
        };
        Swept {
            line: GridLine { axis, index },
            shift_m,
        }
    }

    /// The nearest band of either family to the path from `a` to `b`: the one needing the
    /// smaller shift (x lines win a tie, as at a crossing either explains the pulse).
    pub fn swept(&self, a: Point, b: Point) -> Swept {
        let x = self.swept_axis(Axis::X, a, b);
        let y = self.swept_axis(Axis::Y, a, b);
        if libm::fabsf(y.shift_m) < libm::fabsf(x.shift_m) {
            y
        } else {
            x
        }
    }
}

/// 1-D core of [`GridGeometry::swept_axis`]: bands `[k p - h, k p + h]`, path `u -> v`.
///
/// A pulse starts when the sensor ENTERS a band, so the path must cross the edge it meets
/// first: `k p - h` when moving up, `k p + h` when moving down (either for a path that does
/// not move along this axis). Returns the band and the smallest shift that makes the path
/// cross that edge.
fn swept_1d(u: f32, v: f32, pitch: f32, half: f32) -> (i32, f32) {
    if v > u {
        crossing(u, v, pitch, -half)
    } else if v < u {
        crossing(v, u, pitch, half)
    } else {
        let (a, b) = (crossing(u, v, pitch, -half), crossing(u, v, pitch, half));
        if libm::fabsf(b.1) < libm::fabsf(a.1) {
            b
        } else {
            a
        }
    }
}

/// Nearest of the lines `k p + e` to the interval `[lo, hi]`: (k, shift to touch it).
fn crossing(lo: f32, hi: f32, pitch: f32, e: f32) -> (i32, f32) {
    // First line at or above `lo`. `as` saturates (and maps NaN to 0): no input can panic.
    let k = libm::ceilf((lo - e) / pitch) as i32;
    let above = k as f32 * pitch + e;
    if above <= hi {
        return (k, 0.0);
    }
    let below = k.saturating_sub(1) as f32 * pitch + e;
    let (up, down) = (above - hi, below - lo); // up > 0, down < 0
    if up <= -down {
        (k, up)
    } else {
        (k.saturating_sub(1), down)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const G: GridGeometry = GridGeometry {
        pitch_m: 0.1,
        line_width_m: 0.01,
        origin: Point { x: 0.0, y: 0.0 },
    };

    #[test]
    fn a_path_across_a_band_needs_no_shift() {
        let s = G.swept_axis(Axis::X, Point::new(0.29, 0.0), Point::new(0.301, 0.0));
        assert_eq!(s.line.index, 3);
        assert_eq!(s.shift_m, 0.0);
        // Entering the band's near edge counts (the pulse starts there)...
        let s = G.swept_axis(Axis::X, Point::new(0.29, 0.0), Point::new(0.2951, 0.0));
        assert_eq!((s.line.index, s.shift_m), (3, 0.0));
        // ... from either side.
        let s = G.swept_axis(Axis::X, Point::new(0.31, 0.0), Point::new(0.3049, 0.0));
        assert_eq!((s.line.index, s.shift_m), (3, 0.0));
        // A path already inside the band entered it earlier: it must move back to the edge.
        let s = G.swept_axis(Axis::X, Point::new(0.297, 0.0), Point::new(0.299, 0.0));
        assert_eq!(s.line.index, 3);
        assert!((s.shift_m + 0.002).abs() < 1e-6, "{s:?}");
    }

    #[test]
    fn a_path_short_of_a_band_is_shifted_to_its_nearer_edge() {
        let s = G.swept_axis(Axis::Y, Point::new(0.0, 0.27), Point::new(0.0, 0.28));
        assert_eq!(
            s.line,
            GridLine {
                axis: Axis::Y,
                index: 3
            }
        );
        assert!((s.shift_m - 0.015).abs() < 1e-6, "{s:?}");
        // Moving up past band 2 without entering it: back to its lower edge (0.195).
        let s = G.swept_axis(Axis::Y, Point::new(0.0, 0.215), Point::new(0.0, 0.22));
        assert_eq!(s.line.index, 2);
        assert!((s.shift_m + 0.02).abs() < 1e-6, "{s:?}");
        // Moving down towards band 2: on to its upper edge (0.205).
        let s = G.swept_axis(Axis::Y, Point::new(0.0, 0.22), Point::new(0.0, 0.215));
        assert_eq!(s.line.index, 2);
        assert!((s.shift_m + 0.01).abs() < 1e-6, "{s:?}");
        // Negative coordinates index negative lines.
        let s = G.swept_axis(Axis::X, Point::new(-0.13, 0.0), Point::new(-0.12, 0.0));
        assert_eq!(s.line.index, -1);
        assert!((s.shift_m - 0.015).abs() < 1e-6, "{s:?}");
    }

    #[test]
    fn the_family_needing_the_smaller_shift_is_chosen() {
        // Near a y line (1 mm short) and far from any x line.
        let s = G.swept(Point::new(0.05, 0.193), Point::new(0.051, 0.194));
        assert_eq!(
            s.line,
            GridLine {
                axis: Axis::Y,
                index: 2
            }
        );
        assert!((s.shift_m - 0.001).abs() < 1e-5);
        assert!((G.coordinate(s.line) - 0.2).abs() < 1e-7);
    }

    #[test]
    fn a_path_or_grid_that_names_no_band_moves_no_pose() {
        let nowhere = Swept {
            line: GridLine {
                axis: Axis::X,
                index: 0,
            },
            shift_m: 0.0,
        };
        let nan = G.swept(Point::new(f32::NAN, 0.3), Point::new(0.2, f32::INFINITY));
        assert_eq!(nan, nowhere);
        for pitch_m in [0.0, -0.1, f32::NAN, f32::INFINITY] {
            let bad = GridGeometry { pitch_m, ..G };
            let s = bad.swept(Point::new(0.1, 0.2), Point::new(0.3, 0.4));
            assert_eq!(s, nowhere, "pitch {pitch_m}");
        }
        // Huge but finite: a saturated index and a finite shift, no panic.
        let far = G.swept(Point::new(1e30, -1e30), Point::new(1e30, -1e30));
        assert!(far.shift_m.is_finite(), "{far:?}");
        assert!(matches!(far.line.index, i32::MAX | i32::MIN | 0), "{far:?}");
    }
}
