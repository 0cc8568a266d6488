//! Landmarks for position correction (seed 000 §6): light sources found by triangulation and
//! kept in a small map (§6.1), and global positioning from three landmarks seen by the K213
//! line camera (§6.2).
//!
//! Layer: pure geometry and one small map, above odometry and the SOM calibrations (which
//! give the angle to a light, §5.3, and the distance to a landmark, §5.5). Poses and points
//! are metres and radians like [`crate::odometry`]; angles are counter-clockwise.
//!
//! - [`triangulate`]: a light source from two (position, absolute bearing) fixes, Eqs 24-26.
//! - [`LightMap`]: up to `N` sources, each with two Manhattan-distance "circles" (Fig 30):
//!   a source re-found inside the outer one is the same source and the difference corrects
//!   the robot's (x, y); reaching the inner one without seeing light deletes the source.
//! - [`Camera`]: the K213 (64 px, 36 deg, 5 mm off centre): pixel to angle, Eq 29, and
//!   [`landmark_position`], Eqs 30-31, for mapping the three landmarks.
//! - [`Triple`]: resection from the two angles between three landmarks (Eqs 33-44, with the
//!   digest's fixes), its singular case, and its error propagation (Eq 45).
//!
//! Invariants: no heap, no clock; fixed capacity; nothing panics. What can fail is returned as
//! a [`LandmarkError`]: parallel bearings, angles outside their range, coincident landmarks, a
//! robot on the circle through the landmarks (no solution, §6.2), a full map. The resection
//! computes in f64: near the circle it divides by `sin(γ + δ1 + δ2) -> 0`, where f32 would
//! leave percent-level errors; a fix is a rare event, so soft-float cost does not matter.

use core::f64::consts::PI;
use core::fmt;

use crate::odometry::{wrap_angle, Point, Pose};

/// Why a landmark computation has no answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LandmarkError {
    /// The two bearings are (nearly) parallel: they do not cross (Eq 24 divides by
    /// `sin(a2 - a1)`; §6.1: "at |a1| - |a2| = 0 the algorithm diverges").
    Parallel,
    /// Angles non-finite, not in `(0, pi)`, or the outer landmarks 180 deg or more apart
    /// (§6.2: that would allow a cyclic permutation of the landmarks).
    BadAngles,
    /// Two landmarks coincide.
    Degenerate,
    /// The robot is on the circle through the three landmarks: `δ1 + δ2 + γ = 180 deg`, and
    /// Eq 38 carries no information (§6.2, Fig 38).
    Singular,
    /// The light-source map is full.
    MapFull,
}

impl fmt::Display for LandmarkError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = match self {
            LandmarkError::Parallel => "bearings are parallel",
            LandmarkError::BadAngles => "angles out of range",
            LandmarkError::Degenerate => "landmarks coincide",
            LandmarkError::Singular => "robot on the circle through the landmarks",
            LandmarkError::MapFull => "light-source map full",
        };
        f.write_str(s)
    }
}

/// `|sin|` below which two bearings count as parallel, and below which the resection is
/// singular (about 0.06 deg).
const SIN_EPS: f64 = 1e-3;

/// A robot position and the absolute bearing (heading + SOM angle, §6.1) to a light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BearingFix {
    /// Where the robot was, metres.
    pub position: Point,
    /// Absolute direction to the light, radians counter-clockwise from +x.
    pub bearing: f32,
}

/// Eqs 24-26: the light source seen from `first` and `second`.
/// `l = [(x2 - x1) sin a1 + (y1 - y2) cos a1] / sin(a2 - a1)`, `L = P2 + l (cos a2, sin a2)`.
pub fn triangulate(first: BearingFix, second: BearingFix) -> Result<Point, LandmarkError> {
    let (x1, y1, a1) = (
        f64::from(first.position.x),
        f64::from(first.position.y),
        f64::from(first.bearing),
    );
    let (x2, y2, a2) = (
        f64::from(second.position.x),
        f64::from(second.position.y),
        f64::from(second.bearing),
    );
    let s = libm::sin(a2 - a1);
    if s.is_nan() || libm::fabs(s) < SIN_EPS {
        return Err(LandmarkError::Parallel);
    }
    let l = ((x2 - x1) * libm::sin(a1) + (y1 - y2) * libm::cos(a1)) / s;
    Ok(Point::new(
        (x2 + l * libm::cos(a2)) as f32,
        (y2 + l * libm::sin(a2)) as f32,
    ))
}

/// Manhattan distance `|dx| + |dy|`, metres (Fig 30's "circles").
pub fn manhattan(a: Point, b: Point) -> f32 {
    libm::fabsf(a.x - b.x) + libm::fabsf(a.y - b.y)
}

/// Radii of the two Manhattan circles around each light source (Fig 30; the paper gives no
/// numbers, these are ours).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightMapParams {
    /// A source found within this of a stored one is the same source, metres.
    pub outer_m: f32,
    /// Reaching within this of a stored source without seeing light deletes it, metres.
    pub inner_m: f32,
}

impl Default for LightMapParams {
    fn default() -> Self {
        Self {
            // Three body diameters: a re-triangulated source lands well within this unless the
            // odometry has drifted further than the correction can be trusted.
            outer_m: 0.165,
            // One body diameter: this close, a lit source is far past T1 (about 25 cm).
            inner_m: 0.055,
        }
    }
}

/// What [`LightMap::observe`] did with a triangulated source.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Sighting {
    /// A known source: add `correction` to the robot's (x, y) (stored minus measured, §6.1).
    Recognised {
        /// Slot of the source.
        index: usize,
        /// Metres to add to the robot's x and y.
        correction: Point,
    },
    /// A new source, stored in this slot.
    Registered {
        /// Slot of the source.
        index: usize,
    },
}

/// Up to `N` light sources (§6.1), in fixed slots.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightMap<const N: usize> {
    params: LightMapParams,
    slots: [Option<Point>; N],
}

impl<const N: usize> LightMap<N> {
    /// An empty map.
    pub const fn new(params: LightMapParams) -> Self {
        Self {
            params,
            slots: [None; N],
        }
    }

    /// A source was triangulated at `measured` (in the robot's current frame). If a stored
    /// source lies within the outer circle, it is the same one and the robot should move by
    /// the difference; otherwise the source is registered.
    pub fn observe(&mut self, measured: Point) -> Result<Sighting, LandmarkError> {
        let nearest = self
            .iter()
            .map(|(i, p)| (i, manhattan(p, measured)))
            .filter(|&(_, d)| d <= self.params.outer_m)
            .fold(None, |best: Option<(usize, f32)>, c| match best {
                Some(b) if b.1 <= c.1 => Some(b),
                _ => Some(c),
            });
        if let Some((index, _)) = nearest {
            let stored = self.slots.get(index).copied().flatten().unwrap_or(measured);
            return Ok(Sighting::Recognised {
                index,
                correction: Point::new(stored.x - measured.x, stored.y - measured.y),
            });
        }
        let index = self
            .slots
            .iter()
            .position(Option::is_none)
            .ok_or(LandmarkError::MapFull)?;
        if let Some(slot) = self.slots.get_mut(index) {
            *slot = Some(measured);
        }
        Ok(Sighting::Registered { index })
    }

    /// The robot is at `robot` and does (not) see light: a source whose inner circle it is in
    /// while seeing none has gone, and is deleted. Returns the deleted slot.
    pub fn visit(&mut self, robot: Point, light_seen: bool) -> Option<usize> {
        if light_seen {
            return None;
        }
        let inner = self.params.inner_m;
        let index = self.iter().find(|&(_, p)| manhattan(p, robot) <= inner)?.0;
        if let Some(slot) = self.slots.get_mut(index) {
            *slot = None;
        }
        Some(index)
    }

    /// The stored sources with their slots.
    pub fn iter(&self) -> impl Iterator<Item = (usize, Point)> + '_ {
        self.slots
            .iter()
            .enumerate()
            .filter_map(|(i, p)| p.map(|p| (i, p)))
    }

    /// Number of stored sources.
    pub fn len(&self) -> usize {
        self.iter().count()
    }

    /// No sources stored.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The K213 line camera (seed 000 §1.1, §5.4, §6.2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Pixels in the line. §1.1: 64.
    pub pixels: u16,
    /// Field of view, radians. §5.4: 36 deg.
    pub fov_rad: f32,
    /// Lateral offset of the camera from the robot's centre, to the left, metres. §6.2: 5 mm
    /// (the sign of Eq 29's "+ 5 mm").
    pub offset_m: f32,
}

impl Camera {
    /// The Khepera's K213.
    pub const K213: Camera = Camera {
        pixels: 64,
        fov_rad: 36.0 * core::f32::consts::PI / 180.0,
        offset_m: 0.005,
    };

    /// Angle of pixel position `px` (0 = leftmost, may be fractional, e.g. an object's
    /// mid-point) from the camera axis, counter-clockwise: linear, `fov / pixels` per pixel
    /// (§6.2 uses `F_alpha_K = 36 deg / 64 px`).
    pub fn pixel_angle(&self, px: f32) -> f32 {
        let centre = (f32::from(self.pixels) - 1.0) / 2.0;
        (centre - px) * self.fov_rad / f32::from(self.pixels)
    }

    /// Eq 29: the landmark's angle from the robot's centre, given its distance `l_v_m` from
    /// the camera and its angle `a_prime` in the image:
    /// `alpha_K = atan[(l_V sin a' + 5 mm) / (l_V cos a')]`.
    pub fn bearing(&self, l_v_m: f32, a_prime: f32) -> f32 {
        libm::atan2f(
            l_v_m * libm::sinf(a_prime) + self.offset_m,
            l_v_m * libm::cosf(a_prime),
        )
    }
}

/// Eqs 30-31: a landmark `l_v_m` away at angle `alpha_k` from a robot at `robot`:
/// `x_L = x_R + l_V cos(a_R + a_K)`, `y_L = y_R + l_V sin(a_R + a_K)`. (As printed it uses
/// the distance from the camera, not from the centre; the difference is at most
/// 5 mm x sin 18 deg = 1.5 mm, against 24 mm of distance error, §6.2.)
pub fn landmark_position(robot: Pose, l_v_m: f32, alpha_k: f32) -> Point {
    let a = robot.heading + alpha_k;
    Point::new(
        robot.x + l_v_m * libm::cosf(a),
        robot.y + l_v_m * libm::sinf(a),
    )
}

/// Three landmarks L1, L2, L3, seen from the robot in that order from left to right
/// (§6.2, Fig 37).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triple {
    /// L1, L2, L3, metres.
    pub landmarks: [Point; 3],
}

/// The fixed geometry of a [`Triple`] (Eqs 33-37), f64.
struct Frame {
    l1: (f64, f64),
    t1: f64,
    gamma: f64,
    a: f64,
    b: f64,
}

impl Triple {
    /// Makes a triple.
    pub const fn new(l1: Point, l2: Point, l3: Point) -> Self {
        Self {
            landmarks: [l1, l2, l3],
        }
    }

    fn frame(&self) -> Result<Frame, LandmarkError> {
        let p = self.landmarks.map(|q| (f64::from(q.x), f64::from(q.y)));
        let [l1, l2, l3] = p;
        let a = libm::hypot(l2.0 - l1.0, l2.1 - l1.1);
        let b = libm::hypot(l3.0 - l2.0, l3.1 - l2.1);
        if !(a > 0.0 && b > 0.0) {
            return Err(LandmarkError::Degenerate);
        }
        // Eq 33, t1: the direction L1 -> L2 (atan2: printed atan needs x_L2 > x_L1).
        let t1 = libm::atan2(l2.1 - l1.1, l2.0 - l1.0);
        // Eqs 34-35 with the digest's fix (t3 = pi + atan(slope L2 -> L3), gamma = |t1 - t3|)
        // are, for landmarks ordered by x, the angle at L2 inside the quadrilateral
        // R-L1-L2-L3: clockwise from L2->L3 round to L2->L1, in [0, 2 pi). This form holds for
        // any orientation of the triple.
        let to3 = libm::atan2(l3.1 - l2.1, l3.0 - l2.0);
        let to1 = libm::atan2(l1.1 - l2.1, l1.0 - l2.0);
        let turn = to3 - to1;
        let gamma = turn - 2.0 * PI * libm::floor(turn / (2.0 * PI));
        Ok(Frame {
            l1,
            t1,
            gamma,
            a,
            b,
        })
    }

    /// Eqs 36-43: the robot's position from `d1` (the angle between L1 and L2 as seen from
    /// the robot) and `d2` (between L2 and L3), radians.
    pub fn resect(&self, d1: f32, d2: f32) -> Result<Point, LandmarkError> {
        let (x, y) = self.resect64(f64::from(d1), f64::from(d2))?;
        Ok(Point::new(x as f32, y as f32))
    }

    fn resect64(&self, d1: f64, d2: f64) -> Result<(f64, f64), LandmarkError> {
        let ok = |d: f64| d > 0.0 && d < PI;
        if !(ok(d1) && ok(d2) && d1 + d2 < PI) {
            return Err(LandmarkError::BadAngles);
        }
        let f = self.frame()?;
        let g = f.gamma + d1 + d2;
        // Eq 38: phi + psi = 360 deg - g; on the circle g = 180 deg and Eq 39 holds for every
        // phi (inscribed angles): no solution.
        let sin_g = libm::sin(g);
        if sin_g.is_nan() || libm::fabs(sin_g) < SIN_EPS {
            return Err(LandmarkError::Singular);
        }
        // Eq 40 as atan2 with phi, an angle of the triangle R-L1-L2, in (0, pi).
        let num = -f.b * libm::sin(d1) * sin_g;
        let den = f.a * libm::sin(d2) + f.b * libm::sin(d1) * libm::cos(g);
        let mut phi = libm::atan2(num, den);
        if phi < 0.0 {
            phi += PI;
        }
        // Eq 41: the sine rule in R-L1-L2; Eqs 42-43.
        let r = f.a / libm::sin(d1) * libm::sin(PI - phi - d1);
        Ok((
            f.l1.0 + r * libm::cos(f.t1 - phi),
            f.l1.1 + r * libm::sin(f.t1 - phi),
        ))
    }

    /// Eqs 36-44 from the three landmarks' bearings relative to the robot's heading
    /// (counter-clockwise, e.g. camera angles, Eq 29): position and heading. The landmarks
    /// must appear left to right: `b1 > b2 > b3` (modulo a turn).
    pub fn resect_pose(&self, bearings: [f32; 3]) -> Result<Pose, LandmarkError> {
        let d1 = wrap_angle(bearings[0] - bearings[1]);
        let d2 = wrap_angle(bearings[1] - bearings[2]);
        let p = self.resect(d1, d2)?;
        let l3 = self.landmarks[2];
        // Eq 44 (atan2 for the quadrant): heading = direction to L3 - its bearing.
        Ok(Pose::new(
            p.x,
            p.y,
            libm::atan2f(l3.y - p.y, l3.x - p.x) - bearings[2],
        ))
    }

    /// Eq 45: the position error for angle errors `f_delta` (radians) in `d1` and `d2`,
    /// `F = sqrt((|dx/dd1| + |dx/dd2|)^2 + (|dy/dd1| + |dy/dd2|)^2) F_delta`, metres; the
    /// derivatives by central differences in f64.
    pub fn error(&self, d1: f32, d2: f32, f_delta: f32) -> Result<f32, LandmarkError> {
        let (d1, d2) = (f64::from(d1), f64::from(d2));
        const H: f64 = 1e-7;
        let diff = |e1: f64, e2: f64| -> Result<(f64, f64), LandmarkError> {
            let p = self.resect64(d1 + e1, d2 + e2)?;
            let m = self.resect64(d1 - e1, d2 - e2)?;
            Ok(((p.0 - m.0) / (2.0 * H), (p.1 - m.1) / (2.0 * H)))
        };
        let (x1, y1) = diff(H, 0.0)?;
        let (x2, y2) = diff(0.0, H)?;
        let fx = libm::fabs(x1) + libm::fabs(x2);
        let fy = libm::fabs(y1) + libm::fabs(y2);
        Ok((libm::sqrt(fx * fx + fy * fy) * f64::from(f_delta)) as f32)
    }

    /// The circle through the three landmarks (centre, radius): where resection is singular.
    /// `None` if they are collinear or coincide.
    pub fn circle(&self) -> Option<(Point, f32)> {
        let [(ax, ay), (bx, by), (cx, cy)] =
            self.landmarks.map(|q| (f64::from(q.x), f64::from(q.y)));
        let d = 2.0 * (ax * (by - cy) + bx * (cy - ay) + cx * (ay - by));
        if libm::fabs(d) < 1e-12 {
            return None;
        }
        let (a2, b2, c2) = (ax * ax + ay * ay, bx * bx + by * by, cx * cx + cy * cy);
        let ux = (a2 * (by - cy) + b2 * (cy - ay) + c2 * (ay - by)) / d;
        let uy = (a2 * (cx - bx) + b2 * (ax - cx) + c2 * (bx - ax)) / d;
        let r = libm::hypot(ax - ux, ay - uy);
        Some((Point::new(ux as f32, uy as f32), r as f32))
    }
}

/// seed 000 §6.2: `F_delta = 2 px * 18 deg / 64 px` = 0.5625 deg, radians.
pub const F_DELTA_RAD: f32 = 2.0 * 18.0 / 64.0 * core::f32::consts::PI / 180.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangulation_of_a_light_seen_from_two_places() {
        let light = Point::new(0.3, 0.2);
        let fix = |x: f32, y: f32| BearingFix {
            position: Point::new(x, y),
            bearing: Point::new(x, y).bearing_to(light),
        };
        let got = triangulate(fix(0.0, 0.0), fix(0.25, -0.1)).unwrap();
        assert!(got.distance_to(light) < 1e-6, "{got:?}");
        assert_eq!(
            triangulate(fix(0.0, 0.0), fix(0.15, 0.1)),
            Err(LandmarkError::Parallel)
        );
    }

    #[test]
    fn the_light_map_recognises_corrects_deletes_and_fills() {
        let mut m = LightMap::<2>::new(LightMapParams::default());
        assert_eq!(
            m.observe(Point::new(0.5, 0.5)),
            Ok(Sighting::Registered { index: 0 })
        );
        // Found again 4 cm + 3 cm away (Manhattan 7 cm < 16.5 cm): same source.
        let Ok(Sighting::Recognised { index, correction }) = m.observe(Point::new(0.54, 0.47))
        else {
            panic!("not recognised");
        };
        assert_eq!(index, 0);
        assert!((correction.x + 0.04).abs() < 1e-6 && (correction.y - 0.03).abs() < 1e-6);
        // Manhattan, not Euclidean: (0.12, 0.12) is 17 cm Euclidean but 24 cm Manhattan.
        assert_eq!(
            m.observe(Point::new(0.62, 0.62)),
            Ok(Sighting::Registered { index: 1 })
        );
        assert_eq!(m.observe(Point::new(2.0, 2.0)), Err(LandmarkError::MapFull));
        // Inside the inner circle: with light nothing happens, without it the source goes.
        assert_eq!(m.visit(Point::new(0.52, 0.51), true), None);
        assert_eq!(m.visit(Point::new(0.52, 0.51), false), Some(0));
        assert_eq!(m.len(), 1);
        assert_eq!(m.visit(Point::new(0.52, 0.51), false), None);
    }

    #[test]
    fn k213_pixels_map_linearly_onto_the_field_of_view() {
        let c = Camera::K213;
        assert!(c.pixel_angle(31.5).abs() < 1e-7);
        // Outer edges of the outer pixels: ±18 deg.
        assert!((c.pixel_angle(-0.5).to_degrees() - 18.0).abs() < 1e-4);
        assert!((c.pixel_angle(63.5).to_degrees() + 18.0).abs() < 1e-4);
        // Eq 29: straight ahead at 300 mm, the 5 mm offset is atan(5/300) = 0.955 deg.
        assert!((c.bearing(0.3, 0.0).to_degrees() - 0.9548).abs() < 1e-3);
    }

    #[test]
    fn errors_display() {
        use core::fmt::Write;
        let mut s = heapless::String::<64>::new();
        write!(s, "{}", LandmarkError::Singular).unwrap();
        assert_eq!(s.as_str(), "robot on the circle through the landmarks");
    }
}
