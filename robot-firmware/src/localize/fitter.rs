//! The grid fitter (seed 003 §2.6): steers the robot so that the floor grid keeps telling it
//! something.
//!
//! Layer: a steering suggestion beside [`super::Spps`], read by a pilot ([`super::Survey`])
//! that adds it to its own wish. The thesis's fitter is a potential field over zones V
//! (isolated x lines), H (isolated y lines), C (crossings, which are ambiguous) and N (none):
//! lines ahead attract, crossings repel, and V and H should alternate, "crossing the lines at
//! an angle to the PPD" (§2.6.2-2.6.3). Running parallel to one family leaves the other
//! coordinate unobserved (§2.4.2), and running at 45 degrees runs through every crossing. This
//! minimal fitter keeps only what those rules imply for the heading: it pulls the ESTIMATED
//! heading towards the nearest of 30 and 60 degrees off the grid axes, where x and y lines
//! alternate and crossings are met no more often than by chance. It is the one the host
//! reproduction validated (tests/paper_003_line_correction.rs: every robot within half a
//! square over 40 m with it, up to a square without it).
//!
//! Invariants: the suggestion is a turn rate bounded by `gain * offset_rad`; non-finite
//! headings give 0. No state, no heap, no panics.

use core::f32::consts::FRAC_PI_2;

/// Steering towards headings that cross both line families at an angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridFitter {
    /// Turn rate per radian off the preferred heading, 1/s (rad/s per rad).
    pub gain: f32,
    /// Preferred angle off the nearest grid axis, radians, below 45 degrees; its mirror
    /// `90 deg - offset` is preferred in the other half of each quadrant.
    pub offset_rad: f32,
}

impl Default for GridFitter {
    fn default() -> Self {
        Self {
            // 1 rad/s per rad: a 10 degree error is corrected in about a second (10 cm), a
            // grid square, slow enough not to fight the pilot's wandering.
            gain: 1.0,
            // 30 degrees: halfway between an axis (one family only) and the diagonal (every
            // crossing).
            offset_rad: FRAC_PI_2 / 3.0,
        }
    }
}

impl GridFitter {
    /// The preferred heading nearest to `heading`, in the same quadrant, radians.
    pub fn target(&self, heading: f32) -> f32 {
        let phi = rem_quarter(heading);
        let base = heading - phi;
        if phi < FRAC_PI_2 / 2.0 {
            base + self.offset_rad
        } else {
            base + FRAC_PI_2 - self.offset_rad
        }
    }

    /// Suggested turn rate, rad/s, counter-clockwise positive.
    pub fn turn(&self, heading: f32) -> f32 {
        if !heading.is_finite() {
            return 0.0;
        }
        self.gain * (self.target(heading) - heading)
    }
}

/// `heading` modulo a quarter turn, in `[0, pi/2)`.
fn rem_quarter(heading: f32) -> f32 {
    let r = heading - libm::floorf(heading / FRAC_PI_2) * FRAC_PI_2;
    // f32 rounding can land exactly on the modulus for tiny negative inputs.
    if r >= FRAC_PI_2 {
        0.0
    } else {
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn headings_are_pulled_to_thirty_or_sixty_degrees_off_the_axes() {
        let f = GridFitter::default();
        let deg = |d: f32| d.to_radians();
        // Along +x: turn left towards 30 deg.
        assert!((f.target(deg(2.0)) - deg(30.0)).abs() < 1e-5);
        assert!(f.turn(deg(2.0)) > 0.0);
        // Near the diagonal from above: towards 60 deg; from below: towards 30 deg.
        assert!((f.target(deg(50.0)) - deg(60.0)).abs() < 1e-5);
        assert!((f.target(deg(40.0)) - deg(30.0)).abs() < 1e-5);
        // Other quadrants, negative headings included: 30 deg off each axis.
        assert!((f.target(deg(-10.0)) - deg(-30.0)).abs() < 1e-5);
        assert!((f.target(deg(175.0)) - deg(150.0)).abs() < 1e-5);
        assert!(f.turn(deg(30.0)).abs() < 1e-5);
        assert!(f.turn(deg(88.0)) < 0.0);
        // Bounded by gain * 30 deg: an axis is the farthest a heading gets from its target.
        for k in -720..720 {
            let t = f.turn(deg(k as f32 * 0.5));
            assert!(t.abs() <= deg(30.0) * f.gain + 1e-5, "{k} {t}");
        }
        assert_eq!(f.turn(f32::NAN), 0.0);
    }
}
