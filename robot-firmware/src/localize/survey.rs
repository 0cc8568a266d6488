//! The survey pilot: a long random walk over the floor grid, as in the thesis's runs (seed 003
//! §2.7, Fig 2-25), for as long as the station lets it run.
//!
//! Layer: a pilot in the sense of §2.6: it arbitrates steering suggestions by priority. From
//! low to high: a wandering wish (a turn rate that is a slow random walk), the grid fitter's
//! pull ([`GridFitter`]), a return towards the survey's centre when the ESTIMATED pose leaves
//! a disc around it, and an obstacle avoider, which the caller supplies as a turn rate when
//! its IR sensors see something. Output: forward speed and turn rate; the robot turns them
//! into wheel commands.
//!
//! The pilot steers by the corrected pose, never the truth; that the disc is kept is itself a
//! check of the correction. Invariants: fixed state, seeded randomness (same seed, same walk);
//! outputs finite for finite inputs. Cannot fail.

use super::fitter::GridFitter;
use super::ppd::gauss;
use crate::behaviour::XorShift32;
use crate::odometry::{wrap_angle, Point, Pose};

/// How the survey drives; defaults are the thesis's Khepera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurveyParams {
    /// Forward speed, mm/s. seed 003 §2.3.3: 100 mm/s.
    pub speed_mm_s: f32,
    /// Standard deviation of the wandering turn rate's innovation per cycle, rad/s.
    pub wander_rad_s: f32,
    /// How much of the wandering turn rate is kept from one cycle to the next (0..1).
    pub wander_keep: f32,
    /// Radius of the disc around the survey's start the robot stays in, metres.
    pub radius_m: f32,
    /// Turn rate when heading back into the disc, rad/s.
    pub return_rad_s: f32,
    /// The grid fitter (seed 003 §2.6).
    pub fitter: GridFitter,
}

impl Default for SurveyParams {
    fn default() -> Self {
        Self {
            speed_mm_s: 100.0,
            // The host reproduction's wander: keep 95 %, add 5 % of N(0, 1.2 rad/s), a turn
            // rate of about 0.2 rad/s rms that changes over a few seconds.
            wander_rad_s: 0.06,
            wander_keep: 0.95,
            // 0.8 m: the reproduction's disc; fits a 2 m arena with a robot's margin.
            radius_m: 0.8,
            return_rad_s: 1.5,
            fitter: GridFitter::default(),
        }
    }
}

/// What the pilot asks for this cycle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Steer {
    /// Forward speed, mm/s.
    pub v_mm_s: f32,
    /// Turn rate, rad/s, counter-clockwise positive.
    pub w_rad_s: f32,
}

/// The survey pilot's state.
#[derive(Clone, Debug)]
pub struct Survey {
    /// Settings; may be changed between cycles.
    pub params: SurveyParams,
    centre: Point,
    wander: f32,
    rng: XorShift32,
}

impl Survey {
    /// A pilot around `centre` with a seeded wander.
    pub fn new(params: SurveyParams, centre: Point, seed: u32) -> Self {
        Self {
            params,
            centre,
            wander: 0.0,
            rng: XorShift32::new(seed),
        }
    }

    /// Restarts the walk around `centre`.
    pub fn restart(&mut self, centre: Point) {
        self.centre = centre;
        self.wander = 0.0;
    }

    /// Where the survey is centred.
    pub fn centre(&self) -> Point {
        self.centre
    }

    /// One cycle: `pose` is the robot's (corrected) estimate; `avoid` an obstacle avoider's
    /// turn rate when it wants control.
    pub fn step(&mut self, pose: Pose, avoid: Option<f32>) -> Steer {
        let p = self.params;
        self.wander = p.wander_keep * self.wander + p.wander_rad_s * gauss(&mut self.rng);
        let mut w = self.wander + p.fitter.turn(pose.heading);
        let (dx, dy) = (pose.x - self.centre.x, pose.y - self.centre.y);
        if dx * dx + dy * dy > p.radius_m * p.radius_m {
            let back = wrap_angle(libm::atan2f(-dy, -dx) - pose.heading);
            w = if back >= 0.0 {
                p.return_rad_s
            } else {
                -p.return_rad_s
            };
        }
        let mut v = p.speed_mm_s;
        if let Some(a) = avoid {
            // Turn away on the spot-ish: slow down so the turn clears the obstacle.
            w = a;
            v = p.speed_mm_s * 0.3;
        }
        Steer {
            v_mm_s: v,
            w_rad_s: w,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f32::consts::PI;

    #[test]
    fn outside_the_disc_the_pilot_turns_back_towards_the_centre() {
        let mut s = Survey::new(SurveyParams::default(), Point::new(0.0, 0.0), 3);
        // At (1, 0) heading +x (away): turn, either way, at the return rate.
        let st = s.step(Pose::new(1.0, 0.0, 0.0), None);
        assert!((st.w_rad_s.abs() - 1.5).abs() < 1e-6);
        // Heading +y at (1, 0): the centre is to the left.
        let st = s.step(Pose::new(1.0, 0.0, PI / 2.0), None);
        assert!((st.w_rad_s - 1.5).abs() < 1e-6, "{st:?}");
        // The avoider wins over everything.
        let st = s.step(Pose::new(1.0, 0.0, 0.0), Some(-2.0));
        assert_eq!(st.w_rad_s, -2.0);
        assert!(st.v_mm_s < 100.0);
    }

    #[test]
    fn the_walk_is_seeded_and_stays_near_the_preferred_headings() {
        let run = |seed| {
            let mut s = Survey::new(SurveyParams::default(), Point::new(0.0, 0.0), seed);
            let mut pose = Pose::new(0.0, 0.0, 0.0);
            let mut far = 0.0f32;
            for _ in 0..5000 {
                let st = s.step(pose, None);
                // 0.1 s cycles of an ideal unicycle.
                let h = pose.heading + st.w_rad_s * 0.05;
                pose = Pose::new(
                    pose.x + st.v_mm_s * 1e-4 * libm::cosf(h),
                    pose.y + st.v_mm_s * 1e-4 * libm::sinf(h),
                    wrap_angle(pose.heading + st.w_rad_s * 0.1),
                );
                far = far.max(libm::hypotf(pose.x, pose.y));
            }
            (pose, far)
        };
        assert_eq!(run(5).0, run(5).0);
        assert_ne!(run(5).0, run(6).0);
        // 500 s at 0.1 m/s never leaves the disc by more than a turning circle.
        assert!(run(5).1 < 0.8 + 0.15, "{:?}", run(5));
    }
}
