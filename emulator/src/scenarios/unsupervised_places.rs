//! The seed 003 chapter 3 scenario: the thesis's simulated Khepera wanders in a generated arena
//! of about 15 x 15 robot diameters, classifies its raw sensors online, makes landmarks and
//! places, and resets its odometry on every landmark match; the corrected and the plain
//! odometry are judged against the truth (`robot-emulator run --task unsupervised-places
//! --arena unstructured|structured --seed N --json`).
//!
//! Layer: std, beside `line_correct`. The robot's side is the firmware's
//! `robot_firmware::unsupervised` (classifiers, landmark store, places) and
//! `robot_firmware::odometry`; it sees only its sensors and encoders. The truth is used for
//! the report only. The world is its own small kinematic model (no `Sim`: the firmware's
//! `Robot` does not run this yet, see README):
//! - arena: [`generate`], seeded; unstructured = jittered outer wall, irregular polygon
//!   obstacles and walls of random reflectance; structured = square walls, axis-aligned
//!   rectangles (right-angle corners), one reflectance. Both get the same number of lamps;
//! - sensors: the emulator's IR model read through the thesis's 5 cm curve ([`THESIS_IR`]),
//!   its ambient-light model, a compass (white noise,
//!   `Noise::compass_deg`), and the new 64-pixel, 36-degree line camera ([`camera`]);
//! - wheels: seed 003's constant per-wheel speed bias (drawn per run with sigma
//!   `Noise::motors`, clipped to two sigma, as in `line_correct`); ground speed =
//!   rotation x (1 + bias), encoders count the rotation. Into a wall the motors stall.
//!
//! Three estimates, all from what the robot senses, judged against the truth:
//! - plain odometry: the wheels alone; their constant speed bias makes the heading drift
//!   without bound (about 0.135 rad per metre of wheel difference), a diameter off within
//!   about a metre;
//! - wheels plus compass heading, no landmarks (the usual fusion of odometry with a
//!   continuous sensor, thesis ch. 1): what is left is the along-track error of the common
//!   bias (bounded by bias x arena size: 0.01-0.08 diameters with a perfect compass) and the
//!   compass noise's sideways random walk, which grows as the square root of the distance;
//! - compass plus landmarks, the corrected estimate: the same, and every landmark match moves
//!   the position towards the stored one by the variance-weighted gain of
//!   [`robot_firmware::unsupervised::fusion`] (the thesis resets all the way, gain 1,
//!   `fusion: None`: landmarks made late carry the error of their moment and resets to them
//!   walk the error). With `compass_heading: false` the heading comes from the wheels and a
//!   match sets it per [`HeadingReset`] (the earlier scenario; a landmark also stores its
//!   heading, §3.6 "position, time, direction").
//!
//! [`RevisitDiagnosis`] judges every landmark resolution against the truth (report only):
//! whether the robot was back at a stored landmark, how far the odometry had drifted, how
//! different the contexts were.

mod loss;

use std::time::Instant;

pub use loss::{LossDiagnosis, WRONG_OFFSET};

use robot_firmware::odometry::{integrate, OdometryParams, Pose as FwPose};
use robot_firmware::unsupervised::classify::{Art1, Classifier, FuzzyArt, GrowingKMeans};
use robot_firmware::unsupervised::fusion::{FusionParams, Uncertainty};
use robot_firmware::unsupervised::landmarks::{
    Event, LandmarkParams, LandmarkStore, PrototypeMetric, LANDMARK_BYTES, STORE_BYTES,
};
use robot_firmware::unsupervised::places::{PlaceEvent, PlaceParams, Places};
use robot_firmware::unsupervised::{CONTEXT, MAX_LANDMARKS, STREAMS};
use robot_firmware::KHEPERA;
use serde::Serialize;

use crate::arena::{Light, Pose};
use crate::geometry::{point_in_polygon, polygon_edges, Point, Segment, SegmentSet, Vector};
use crate::rng::{stream, SimRng};
use crate::sensors::ir::{IrArray, IrCurve};
use crate::sensors::light::AmbientLight;
use crate::sensors::Noise;

/// Khepera diameter, metres (seed 000 §1.1; the unit of every error in the report).
pub const DIAMETER_M: f64 = 0.055;
/// Arena side in robot diameters (§3.2.2: "about 15 x 15 x diameter of the robot").
pub const ARENA_DIAMETERS: f64 = 15.0;
/// Binarisation threshold of the IR and ambient sensors (§3.3.1: 300, about 2.5 cm).
pub const BINARY_THRESHOLD: u16 = 300;
/// Camera pixels and field of view (§3.2.2: 64 pixels, 36 degrees).
pub const CAMERA_PIXELS: usize = 64;
/// See [`CAMERA_PIXELS`].
pub const CAMERA_FOV_DEG: f64 = 36.0;

/// The thesis's simulated IR sensor (§3.2.2: "about 5 cm range"; §3.3.1: 300 counts at
/// about 2.5 cm): 1023 touching, 300 at 2.5 cm (exponent ln(295/1023) / ln(1/2) = 1.79 over
/// the floor of 5), nothing from 5 cm on. The emulator's Khepera curve (the real robot's,
/// seed 000: saturated below 1.7 cm, nothing from 3.3 cm) reads 300 at 2.6 cm but sees
/// nothing beyond 3.3 cm.
pub const THESIS_IR: IrCurve = IrCurve {
    saturate_m: 0.0,
    range_m: 0.05,
    exponent: 1.79,
    floor_counts: 5.0,
};

/// Sigma of a kernel's place about its landmark's, in diameters (the robot's assumption for
/// [`FusionParams::match_sigma_m`]; judged with the truth, matched kernels lie 0.07-0.17
/// diameters from the landmark's true place on average).
pub const MATCH_SIGMA_DIAMETERS: f32 = 0.15;

/// Longest run accepted, simulated seconds (the report's series grows with it).
pub const MAX_DURATION_S: f64 = 36_000.0;

/// Which arena.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ArenaKind {
    /// Irregular walls and obstacles (§3.15.1, Fig. 3-33).
    Unstructured,
    /// Right-angle corners (§3.15.4, Fig. 3-36).
    Structured,
}

impl ArenaKind {
    /// Parse `unstructured` / `structured`.
    pub fn parse(s: &str) -> Result<Self, String> {
        match s {
            "unstructured" => Ok(Self::Unstructured),
            "structured" => Ok(Self::Structured),
            other => Err(format!(
                "--arena {other:?}: --task unsupervised-places takes --arena unstructured or \
                 --arena structured (generated from --seed)"
            )),
        }
    }
}

/// Run options; [`PlacesOptions::new`] gives the defaults (each a choice where the thesis is
/// silent, named in README).
#[derive(Clone, Debug, PartialEq)]
pub struct PlacesOptions {
    /// Arena kind.
    pub arena: ArenaKind,
    /// Seed of the arena, the noise and the wandering.
    pub seed: u64,
    /// Simulated seconds. Default 1200 (20 min; §3.5 classified 10 min, the places of
    /// Fig. 3-35 grow over longer).
    pub duration_s: f64,
    /// Control period, seconds. Default 0.04 (25 Hz: §3.5's 15 000 samples in 10 minutes).
    pub period_s: f64,
    /// Forward speed, metres per second. Default 0.06.
    pub speed_mps: f64,
    /// Noise levels (IR, light, compass, wheel bias).
    pub noise: Noise,
    /// What a landmark match does to the heading when the heading comes from the wheels
    /// (`compass_heading` false; the stored heading measured worse, README).
    pub heading_reset: HeadingReset,
    /// The corrected estimate takes its heading from the compass at every step (default
    /// true: the usual fusion of odometry with a continuous sensor, thesis ch. 1); false: from
    /// the wheels, the heading touched only by `heading_reset` at matches.
    pub compass_heading: bool,
    /// How a match moves the position: Some = by the variance-weighted gain
    /// ([`robot_firmware::unsupervised::fusion`]; default); None = the thesis's reset to the
    /// stored position (gain 1).
    pub fusion: Option<FusionParams>,
    /// Lamps per arena. Default 3.
    pub lamps: usize,
    /// Vigilances: growing K-means (Euclidean distance), ART-1, Fuzzy ART (match).
    pub vigilance: [f32; 3],
    /// Fuzzy ART learning rate beta.
    pub beta: f32,
    /// Landmark limits.
    pub landmarks: LandmarkParams,
    /// Place parameters.
    pub places: PlaceParams,
    /// Seconds between series samples in the report.
    pub series_every_s: f64,
    /// Leave a followed wall now and then to cross open space (default true); false: follow
    /// the first wall met, always on the same side.
    pub excursions: bool,
    /// The IR sensors' reading against distance. Default [`THESIS_IR`] (the thesis's
    /// simulator: about 5 cm); `IrCurve::KHEPERA` is the real robot's (3.3 cm).
    pub ir_curve: IrCurve,
    /// Keep every step's class labels in the report (`class_streams`; default false: they
    /// are 3 bytes a step, for the station's view).
    pub record_labels: bool,
}

impl PlacesOptions {
    /// The defaults for `arena` and `seed`.
    pub fn new(arena: ArenaKind, seed: u64) -> Self {
        Self {
            arena,
            seed,
            duration_s: 1200.0,
            period_s: 0.04,
            speed_mps: 0.06,
            noise: Noise::default(),
            heading_reset: HeadingReset::Compass,
            compass_heading: true,
            fusion: Some(FusionParams {
                compass_sigma_rad: (Noise::default().compass_deg as f32).to_radians(),
                mean_bias_sigma: Noise::default().motors as f32 / core::f32::consts::SQRT_2,
                match_sigma_m: MATCH_SIGMA_DIAMETERS * DIAMETER_M as f32,
            }),
            lamps: 3,
            vigilance: [1.2, 0.3, 0.6],
            beta: 0.5,
            landmarks: LandmarkParams {
                diameter_m: DIAMETER_M as f32,
                max_share: 0.03,
                max_mean_run: 3.0,
                ..LandmarkParams::default()
            },
            places: PlaceParams::default(),
            series_every_s: 2.0,
            excursions: true,
            ir_curve: THESIS_IR,
            record_labels: false,
        }
    }
}

/// What a landmark match does to the odometry's heading.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum HeadingReset {
    /// The landmark's stored heading (carried over the steps since its kernel): the thesis's
    /// reset to the stored pose (§3.6: a landmark holds position and direction).
    Stored,
    /// The compass reading (a drift-free heading the thesis's robot has; not the thesis's
    /// reset, kept for comparison).
    Compass,
    /// Unchanged: position only.
    Keep,
}

/// A generated arena.
#[derive(Clone, Debug)]
pub struct World {
    /// Walls.
    pub walls: SegmentSet,
    /// Reflectance of each wall segment (camera), 0..1.
    pub reflectance: Vec<f64>,
    /// Lamps.
    pub lights: Vec<Light>,
    /// Obstacle outlines (for tests and views).
    pub obstacles: Vec<Vec<Point>>,
    /// Outer boundary.
    pub boundary: Vec<Point>,
    /// Start pose.
    pub start: Pose,
}

/// Generate the `kind` arena of `seed` (side `ARENA_DIAMETERS` diameters).
pub fn generate(kind: ArenaKind, seed: u64, lamps: usize) -> World {
    let mut rng = SimRng::new(seed, 101);
    let side = ARENA_DIAMETERS * DIAMETER_M;
    let boundary: Vec<Point> = match kind {
        ArenaKind::Structured => vec![
            Point::new(0.0, 0.0),
            Point::new(side, 0.0),
            Point::new(side, side),
            Point::new(0.0, side),
        ],
        ArenaKind::Unstructured => {
            // Six points a side, each pushed inwards by up to 1.2 diameters.
            let mut b = Vec::new();
            let corners = [(0.0, 0.0), (side, 0.0), (side, side), (0.0, side)];
            let inward = [(0.0, 1.0), (-1.0, 0.0), (0.0, -1.0), (1.0, 0.0)];
            for k in 0..4 {
                let (a, c) = (corners[k], corners[(k + 1) % 4]);
                for i in 0..6 {
                    let t = i as f64 / 6.0;
                    let push = if i == 0 {
                        0.0
                    } else {
                        rng.uniform() * 1.2 * DIAMETER_M
                    };
                    b.push(Point::new(
                        a.0 + (c.0 - a.0) * t + inward[k].0 * push,
                        a.1 + (c.1 - a.1) * t + inward[k].1 * push,
                    ));
                }
            }
            b
        }
    };
    let mut obstacles: Vec<Vec<Point>> = Vec::new();
    let mut centres: Vec<(Point, f64)> = Vec::new();
    let gap = 1.6 * DIAMETER_M; // a passage the robot fits through
    let mut tries = 0;
    while obstacles.len() < 7 && tries < 500 {
        tries += 1;
        let r = 0.03 + rng.uniform() * 0.04;
        let margin = r + gap + 1.2 * DIAMETER_M;
        let c = Point::new(
            margin + rng.uniform() * (side - 2.0 * margin),
            margin + rng.uniform() * (side - 2.0 * margin),
        );
        if centres.iter().any(|(o, ro)| (o - c).norm() < r + ro + gap) {
            continue;
        }
        let poly: Vec<Point> = match kind {
            ArenaKind::Structured => {
                let (w, h) = (
                    r * (0.6 + rng.uniform() * 0.4),
                    r * (0.6 + rng.uniform() * 0.4),
                );
                vec![
                    Point::new(c.x - w, c.y - h),
                    Point::new(c.x + w, c.y - h),
                    Point::new(c.x + w, c.y + h),
                    Point::new(c.x - w, c.y + h),
                ]
            }
            ArenaKind::Unstructured => {
                let n = 3 + (rng.next_u64() % 4) as usize;
                let phase = rng.uniform() * std::f64::consts::TAU;
                (0..n)
                    .map(|i| {
                        let a = phase
                            + std::f64::consts::TAU * (i as f64 + 0.3 * rng.uniform()) / n as f64;
                        let rr = r * (0.6 + 0.4 * rng.uniform());
                        Point::new(c.x + rr * a.cos(), c.y + rr * a.sin())
                    })
                    .collect()
            }
        };
        centres.push((c, r));
        obstacles.push(poly);
    }
    let mut segments: Vec<Segment> = polygon_edges(&boundary).collect();
    for o in &obstacles {
        segments.extend(polygon_edges(o));
    }
    let reflectance = segments
        .iter()
        .map(|_| match kind {
            ArenaKind::Structured => 0.8,
            ArenaKind::Unstructured => 0.2 + 0.8 * rng.uniform(),
        })
        .collect();
    let walls = SegmentSet::new(segments);
    let free = |p: Point, clearance: f64| {
        point_in_polygon(p, &boundary)
            && !obstacles.iter().any(|o| point_in_polygon(p, o))
            && walls.nearest(p, clearance).is_none()
    };
    let mut lights = Vec::new();
    let mut start = Pose {
        x: side / 2.0,
        y: side / 2.0,
        heading: 0.0,
    };
    for _ in 0..2000 {
        let p = Point::new(rng.uniform() * side, rng.uniform() * side);
        if !free(p, 1.5 * DIAMETER_M) {
            continue;
        }
        if lights.len() < lamps {
            lights.push(Light {
                position: p,
                height_m: 0.0,
                intensity: 1.0,
            });
        } else {
            start = Pose {
                x: p.x,
                y: p.y,
                heading: rng.uniform() * std::f64::consts::TAU - std::f64::consts::PI,
            };
            break;
        }
    }
    World {
        walls,
        reflectance,
        lights,
        obstacles,
        boundary,
        start,
    }
}

/// The line camera: 64 pixels over 36 degrees, brightness of the wall each pixel sees by a
/// Lambertian first approximation (§3.3.2, Fig. 3-6): reflectance x |cos incidence| /
/// (1 + (d / 0.2 m)^2); nothing within 1 m is black.
pub fn camera(world: &World, pose: Pose) -> [f64; CAMERA_PIXELS] {
    let mut img = [0.0; CAMERA_PIXELS];
    let o = Point::new(pose.x, pose.y);
    let fov = CAMERA_FOV_DEG.to_radians();
    for (i, px) in img.iter_mut().enumerate() {
        let a = pose.heading + fov / 2.0 - fov * (i as f64 + 0.5) / CAMERA_PIXELS as f64;
        let d = Vector::new(a.cos(), a.sin());
        if let Some(hit) = world.walls.ray_cast(o, d, 1.0) {
            let seg = &world.walls.segments()[hit.segment];
            let t = seg.direction();
            let n = t.norm();
            let cos_inc = if n > 0.0 {
                (t.x * d.y - t.y * d.x).abs() / n
            } else {
                1.0
            };
            *px = world.reflectance[hit.segment] * cos_inc / (1.0 + (hit.distance / 0.2).powi(2));
        }
    }
    img
}

/// Camera preprocessing (§3.3.2, Fig. 3-7): edges from the second derivative, the image
/// stretched so the outer edges touch the borders; returns the Gaussian neuron distribution
/// (8 neurons) and the group neuron distribution (groups of 1..4 inner edges, 10 neurons).
pub fn camera_features(img: &[f64; CAMERA_PIXELS]) -> ([f32; 8], [f32; 10]) {
    let mut edges = Vec::new();
    let mut prev_edge = false;
    for i in 1..CAMERA_PIXELS - 1 {
        let dd = (img[i - 1] - 2.0 * img[i] + img[i + 1]).abs();
        let e = dd > 0.03;
        if e && !prev_edge {
            edges.push(i as f64);
        }
        prev_edge = e;
    }
    let mut gauss = [0.0f32; 8];
    let mut group = [0.0f32; 10];
    if edges.len() >= 2 {
        let (lo, hi) = (edges[0], edges[edges.len() - 1]);
        let pos: Vec<f64> = edges.iter().map(|e| (e - lo) / (hi - lo)).collect();
        for (k, g) in gauss.iter_mut().enumerate() {
            let c = k as f64 / 7.0;
            let s: f64 = pos
                .iter()
                .map(|p| (-(p - c).powi(2) / (2.0 * 0.08f64.powi(2))).exp())
                .sum();
            *g = s.min(1.0) as f32;
        }
        let inner = &pos[1..pos.len() - 1];
        let n = inner.len().min(4);
        if n > 0 {
            let base = n * (n - 1) / 2; // groups 1, 2, 3, 4 start at 0, 1, 3, 6
            for (j, p) in inner.iter().take(n).enumerate() {
                group[base + j] = *p as f32;
            }
        }
    } else if edges.len() == 1 {
        gauss[(edges[0] / CAMERA_PIXELS as f64 * 8.0) as usize % 8] = 1.0;
    }
    (gauss, group)
}

/// Wall following with excursions (the movement constraint of §3.8).
#[derive(Clone, Copy, Debug, Default)]
struct Wander {
    /// Following on the right (true) or the left.
    right: bool,
    /// Steps left before leaving the wall.
    follow_left: u32,
    /// Crossing open space.
    crossing: bool,
    /// Steps since the followed wall was last seen.
    lost: u32,
    /// Steps left backing off after a stall.
    backing: u32,
    /// Whether it leaves walls at all.
    excursions: bool,
}

impl Wander {
    fn act(&mut self, irs: &[u16; 8], v: f64, rng: &mut SimRng) -> (f64, f64) {
        if self.backing > 0 {
            self.backing -= 1;
            self.crossing = self.backing == 0;
            return (-0.5 * v, -0.1 * v); // back off, turning
        }
        let r = |i: usize| f64::from(irs[i]) / 1023.0;
        let ahead = r(2).max(r(3));
        let (near, diag) = if self.right {
            (r(5), r(4))
        } else {
            (r(0), r(1))
        };
        let side = near.max(diag);
        // Positive `turn` turns away from the followed side.
        let (fwd, turn) = if ahead > 0.3 || diag > 0.6 {
            if self.crossing {
                self.crossing = false;
                self.right = if self.excursions {
                    rng.chance(0.5)
                } else {
                    true
                };
                self.follow_left = 300 + (rng.next_u64() % 900) as u32;
            }
            (0.0, 0.7)
        } else if self.crossing {
            (1.0, 0.0)
        } else if side > 0.02 {
            self.lost = 0;
            if self.excursions {
                self.follow_left = self.follow_left.saturating_sub(1);
            }
            if self.excursions && self.follow_left == 0 {
                self.crossing = true;
            }
            // Keep the side reading near 0.3.
            (1.0, ((side - 0.3) * 1.5).clamp(-0.6, 0.6))
        } else {
            // Lost the wall: curve round its end; still nothing after a half turn: cross.
            self.lost += 1;
            if self.lost > 40 {
                self.crossing = true;
                self.lost = 0;
            }
            (0.8, -0.45)
        };
        let turn = if self.right { turn } else { -turn };
        // turn > 0 is anticlockwise: right wheel faster.
        (v * (fwd - turn), v * (fwd + turn))
    }
}

/// The three classifiers and the prototype metric the landmark store needs.
struct Classifiers {
    kmeans: GrowingKMeans,
    art1: Art1,
    fuzzy: FuzzyArt,
}

impl PrototypeMetric for Classifiers {
    fn distance(&self, stream: usize, a: u8, b: u8) -> f32 {
        match stream {
            0 => self.art1.prototype_distance(a, b),
            1 => self.kmeans.prototype_distance(a, b),
            _ => self.fuzzy.prototype_distance(a, b),
        }
    }
}

/// Errors at one time, in robot diameters, with the positions (metres).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SeriesPoint {
    /// Simulated seconds.
    pub t_s: f64,
    /// True position.
    pub truth: [f64; 2],
    /// Corrected odometry.
    pub corrected: [f64; 2],
    /// Plain odometry.
    pub plain: [f64; 2],
    /// Wheels plus compass heading, no landmarks (the baseline).
    pub compass: [f64; 2],
    /// |corrected - truth| / diameter.
    pub corrected_err: f64,
    /// |plain - truth| / diameter.
    pub plain_err: f64,
    /// |compass - truth| / diameter.
    pub compass_err: f64,
    /// The robot's own sigma of its corrected position (per axis), diameters (0 without
    /// fusion).
    pub corrected_sigma: f64,
    /// Landmarks so far.
    pub landmarks: usize,
    /// Matches so far.
    pub matches: u32,
}

/// One match as it happened.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MatchRecord {
    /// Simulated seconds.
    pub t_s: f64,
    /// Landmark index.
    pub landmark: u16,
    /// Its D.
    pub d: f32,
    /// Correction length (the move made), diameters.
    pub correction: f64,
    /// Share of the way to the stored position moved (1: the thesis's reset).
    pub gain: f64,
    /// The landmark's sigma as the robot holds it, diameters.
    pub landmark_sigma: f64,
    /// How far the landmark's stored position (after what it learnt from this match, if
    /// `refine`) is from the true place where it was made, diameters (truth, report only).
    pub landmark_err: f64,
    /// How far (truth) the kernel was from the matched landmark's true place, diameters:
    /// more than 1/2 (the thesis's least distance between two identical landmarks, §3.15.2)
    /// is a wrong identification (report only).
    pub offset: f64,
    /// Error before and after the correction, diameters (truth, for the report only).
    pub err_before: f64,
    /// See `err_before`.
    pub err_after: f64,
    /// Corrected position before and after the reset, metres.
    pub from: [f64; 2],
    /// See `from`.
    pub to: [f64; 2],
}

/// [`robot_firmware::unsupervised::landmarks::MatchStats`] for the report.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct MatchStatsReport {
    /// Kernels resolved.
    pub kernels: u32,
    /// No landmark with the same kernel.
    pub unknown_kernel: u32,
    /// Same-kernel landmarks only beyond one diameter (ignored).
    pub too_far: u32,
    /// Near candidates, none similar enough.
    pub dissimilar: u32,
    /// Mean scaled d_lev of the best near candidate.
    pub mean_near_lev: f32,
}

/// Why landmarks are (not) met again, judged with the truth (report only; the robot never
/// sees it). A *revisit* is a resolved kernel whose true position lies within half a diameter
/// of the true position of a stored landmark with the same kernel (the same significant class
/// of the same stream): the robot is back at that landmark.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct RevisitDiagnosis {
    /// Kernels resolved.
    pub kernels: u32,
    /// Kernels whose true position is within half a diameter of any stored landmark.
    pub near_any_landmark: u32,
    /// ... of those, the nearest such landmark has the same kernel (a revisit).
    pub revisits: u32,
    /// Revisits that matched (some landmark).
    pub revisits_matched: u32,
    /// Revisits whose odometric distance to the revisited landmark exceeded one diameter.
    pub revisits_too_far: u32,
    /// Revisits where the robot travelled within 45 degrees of the landmark's direction.
    pub revisits_same_direction: u32,
    /// Mean weighted Levenshtein distance per stream (label costs, of 31 labels) between a
    /// revisit's context and the revisited landmark's.
    pub revisit_lev: [f32; STREAMS],
    /// The same for same-direction revisits only.
    pub revisit_lev_same_direction: [f32; STREAMS],
    /// Mean odometric distance of a revisit to its landmark, diameters.
    pub revisit_odo_dist: f32,
    /// Impostors: same-kernel landmarks within one diameter by odometry but more than one
    /// diameter away in truth (a match with one would be wrong); how many were compared.
    pub impostors: u32,
    /// Their mean per-stream distance (label costs, as `revisit_lev`).
    pub impostor_lev: [f32; STREAMS],
    /// Matches, and how far (truth) the kernel was from the matched landmark's true place:
    /// mean, diameters, and how many were more than half a diameter off.
    pub matches: u32,
    /// See `matches`.
    pub match_offset_mean: f32,
    /// See `matches`.
    pub match_offset_over_half: u32,
}

/// The run's report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PlacesReport {
    /// Arena kind.
    pub arena: ArenaKind,
    /// Seed.
    pub seed: u64,
    /// Simulated seconds.
    pub duration_s: f64,
    /// True distance travelled, metres.
    pub distance_m: f64,
    /// Wheel bias drawn (relative, left/right).
    pub wheel_bias: [f64; 2],
    /// Classes per stream (ART-1, growing K-means, Fuzzy ART).
    pub classes: [usize; STREAMS],
    /// Landmarks stored (capacity `landmark_capacity`).
    pub landmarks: usize,
    /// The store's capacity and memory.
    pub landmark_capacity: usize,
    /// Bytes of one landmark.
    pub landmark_bytes: usize,
    /// Bytes of the whole landmark store.
    pub store_bytes: usize,
    /// Landmark matches (odometry resets).
    pub matches: u32,
    /// Matches that made the error larger (judged with the truth, report only).
    pub worsening_matches: u32,
    /// Places made.
    pub places: usize,
    /// Place sequences recognised as a known place.
    pub places_recognised: u32,
    /// Peak and mean absolute position error of the corrected odometry, diameters.
    pub corrected_peak: f64,
    /// See `corrected_peak`.
    pub corrected_mean: f64,
    /// Same for the plain odometry.
    pub plain_peak: f64,
    /// See `plain_peak`.
    pub plain_mean: f64,
    /// Same for wheels + compass heading every step, no landmarks (baseline).
    pub compass_peak: f64,
    /// See `compass_peak`.
    pub compass_mean: f64,
    /// Corrected error's peak after the first minute (the landmarks exist), diameters.
    pub corrected_peak_after_60s: f64,
    /// Why kernels did not match.
    pub match_stats: MatchStatsReport,
    /// Why landmarks are (not) met again, against the truth.
    pub revisit: RevisitDiagnosis,
    /// Classes per stream that are significant at the end (could make a landmark).
    pub significant_classes: [usize; STREAMS],
    /// Each way the robot could get lost, measured against the truth (§3.15.4).
    pub loss: LossDiagnosis,
    /// Collisions (stalled steps).
    pub stalls: u32,
    /// Wall-clock seconds.
    pub wall_s: f64,
    /// Errors over time.
    pub series: Vec<SeriesPoint>,
    /// Every match.
    pub match_log: Vec<MatchRecord>,
    /// Landmark positions as stored (metres) with their kernel stream.
    pub landmark_positions: Vec<[f64; 3]>,
    /// Each landmark's true position when it was made (metres; report only).
    pub landmark_truth: Vec<[f64; 2]>,
    /// Control period, seconds (the time step of `class_streams`).
    pub period_s: f64,
    /// Every step's label per stream (ART-1, growing K-means, Fuzzy ART), when
    /// `record_labels`; empty otherwise.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub class_streams: Vec<[u8; STREAMS]>,
}

/// Run the scenario.
pub fn run(opts: &PlacesOptions) -> PlacesReport {
    let started = Instant::now();
    let world = generate(opts.arena, opts.seed, opts.lamps);
    let noise = opts.noise.sanitised();
    let mut run_rng = SimRng::new(opts.seed, stream::RUN);
    let limit = 2.0 * noise.motors;
    let bias = [
        run_rng.gaussian(noise.motors).clamp(-limit, limit),
        run_rng.gaussian(noise.motors).clamp(-limit, limit),
    ];
    let mut ir = IrArray::new(
        &KHEPERA,
        noise.obstacle_counts,
        noise.obstacle_gain_spread,
        &mut run_rng,
        SimRng::new(opts.seed, stream::IR),
    )
    .with_curve(opts.ir_curve);
    let mut light = AmbientLight::new(
        &KHEPERA,
        noise.light_counts,
        SimRng::new(opts.seed, stream::LIGHT),
    );
    let mut compass_rng = SimRng::new(opts.seed, stream::COMPASS);
    let mut wander = SimRng::new(opts.seed, stream::FIRMWARE);
    let mut cls = Classifiers {
        kmeans: GrowingKMeans::new(opts.vigilance[0]),
        art1: Art1::new(opts.vigilance[1]),
        fuzzy: FuzzyArt::new(opts.vigilance[2], opts.beta),
    };
    let mut store = LandmarkStore::new(opts.landmarks);
    let mut places = Places::new(opts.places);
    let odo = OdometryParams::default();
    let radius = DIAMETER_M / 2.0;

    let mut truth = world.start;
    let fw = |p: Pose| FwPose::new(p.x as f32, p.y as f32, p.heading as f32);
    let mut corrected = fw(truth);
    let mut plain = fw(truth);
    let mut compass_odo = fw(truth);
    // The corrected estimate's variance (the robot's own model, from its sensors' specs).
    let mut unc = Uncertainty::at(corrected.x, corrected.y);
    let mut acc = [0.0f64; 2]; // fractional encoder pulses
    let steps = (opts.duration_s / opts.period_s).ceil() as u64;
    let series_every = ((opts.series_every_s / opts.period_s).round() as u64).max(1);
    let mut behaviour = Wander {
        crossing: true,
        excursions: opts.excursions,
        ..Wander::default()
    };
    let mut report = PlacesReport {
        arena: opts.arena,
        seed: opts.seed,
        duration_s: opts.duration_s,
        distance_m: 0.0,
        wheel_bias: bias,
        classes: [0; STREAMS],
        landmarks: 0,
        landmark_capacity: MAX_LANDMARKS,
        landmark_bytes: LANDMARK_BYTES,
        store_bytes: STORE_BYTES,
        matches: 0,
        worsening_matches: 0,
        places: 0,
        places_recognised: 0,
        corrected_peak: 0.0,
        corrected_mean: 0.0,
        plain_peak: 0.0,
        plain_mean: 0.0,
        compass_peak: 0.0,
        compass_mean: 0.0,
        corrected_peak_after_60s: 0.0,
        match_stats: MatchStatsReport::default(),
        revisit: RevisitDiagnosis::default(),
        significant_classes: [0; STREAMS],
        loss: LossDiagnosis::default(),
        stalls: 0,
        wall_s: 0.0,
        series: Vec::new(),
        match_log: Vec::new(),
        landmark_positions: Vec::new(),
        landmark_truth: Vec::new(),
        period_s: opts.period_s,
        class_streams: Vec::new(),
    };
    let err =
        |p: &FwPose, t: &Pose| ((f64::from(p.x) - t.x).hypot(f64::from(p.y) - t.y)) / DIAMETER_M;
    let (mut sum_c, mut sum_p, mut sum_q) = (0.0, 0.0, 0.0);
    // The truth and the corrected position of the last CONTEXT + 1 steps: a kernel resolves
    // CONTEXT steps after it happened (report only).
    let mut ring: std::collections::VecDeque<(Pose, [f32; 2])> =
        std::collections::VecDeque::with_capacity(CONTEXT + 2);
    let mut lm_truth: Vec<Pose> = Vec::new();
    let mut diag = Diagnoser::default();
    for step in 0..steps {
        let t_s = step as f64 * opts.period_s;
        ring.push_back((truth, [corrected.x, corrected.y]));
        if ring.len() > CONTEXT + 1 {
            ring.pop_front();
        }
        // Sense.
        let irs = ir.read(&world.walls, truth);
        let amb = light.read(&world.walls, &world.lights, truth);
        let compass = truth.heading + compass_rng.gaussian(noise.compass_deg.to_radians());
        let (gauss, group) = camera_features(&camera(&world, truth));
        // Classify: stream 0 ART-1 on binary IR, light and compass sector; stream 1 growing
        // K-means on the camera's Gaussian distribution and the compass; stream 2 Fuzzy ART on
        // the camera's groups and the analogue IR (§3.2.3: signals "partially mixed").
        let mut bits = [0.0f32; 24];
        for i in 0..8 {
            bits[i] = f32::from(u8::from(irs[i] > BINARY_THRESHOLD));
            bits[8 + i] = f32::from(u8::from(amb[i] < BINARY_THRESHOLD));
        }
        let sector = ((compass.rem_euclid(std::f64::consts::TAU)) / (std::f64::consts::TAU / 8.0))
            as usize
            % 8;
        bits[16 + sector] = 1.0;
        let mut v1 = [0.0f32; 10];
        v1[..8].copy_from_slice(&gauss);
        v1[8] = ((compass.cos() + 1.0) / 2.0) as f32;
        v1[9] = ((compass.sin() + 1.0) / 2.0) as f32;
        let mut v2 = [0.0f32; 18];
        v2[..10].copy_from_slice(&group);
        for i in 0..8 {
            v2[10 + i] = f32::from(irs[i]) / 1023.0;
        }
        let labels = [
            cls.art1.classify(&bits).unwrap_or(0),
            cls.kmeans.classify(&v1).unwrap_or(0),
            cls.fuzzy.classify(&v2).unwrap_or(0),
        ];
        // Landmarks: kernel-time position is the corrected odometry.
        if opts.record_labels {
            report.class_streams.push(labels);
        }
        let var = opts
            .fusion
            .map_or(0.0, |f| unc.variance((corrected.x, corrected.y), &f));
        let event = store.step(
            labels,
            (corrected.x, corrected.y, corrected.heading),
            var,
            &cls,
        );
        if let (Some(e), Some(&(kt, ko))) = (event, ring.front()) {
            diag.resolved(e, kt, ko, &store, &cls, &mut lm_truth);
        }
        match event {
            Some(Event::Matched {
                index,
                dx,
                dy,
                dheading,
                d,
                var: lm_var,
            }) => {
                let before = err(&corrected, &truth);
                let from = [f64::from(corrected.x), f64::from(corrected.y)];
                let (cx, cy) = (corrected.x, corrected.y);
                let gain = opts.fusion.map_or(1.0, |f| {
                    unc.fuse((cx, cy), |k| (cx + k * dx, cy + k * dy), lm_var, &f)
                });
                corrected.x += gain * dx;
                corrected.y += gain * dy;
                if !opts.compass_heading {
                    match opts.heading_reset {
                        HeadingReset::Stored => corrected.heading += dheading,
                        HeadingReset::Compass => corrected.heading = compass as f32,
                        HeadingReset::Keep => {}
                    }
                }
                let after = err(&corrected, &truth);
                report.matches += 1;
                if after > before {
                    report.worsening_matches += 1;
                }
                report.match_log.push(MatchRecord {
                    t_s,
                    landmark: index,
                    d,
                    correction: f64::from(gain * dx.hypot(dy)) / DIAMETER_M,
                    gain: f64::from(gain),
                    landmark_sigma: f64::from(lm_var.max(0.0).sqrt()) / DIAMETER_M,
                    landmark_err: lm_truth.get(usize::from(index)).map_or(0.0, |t| {
                        let l = &store.landmarks()[usize::from(index)];
                        (f64::from(l.x) - t.x).hypot(f64::from(l.y) - t.y) / DIAMETER_M
                    }),
                    offset: match (ring.front(), lm_truth.get(usize::from(index))) {
                        (Some((kt, _)), Some(t)) => (t.x - kt.x).hypot(t.y - kt.y) / DIAMETER_M,
                        _ => 0.0,
                    },
                    err_before: before,
                    err_after: after,
                    from,
                    to: [f64::from(corrected.x), f64::from(corrected.y)],
                });
                if let Some(PlaceEvent::Recognised { .. }) = places.push(index) {
                    report.places_recognised += 1;
                }
            }
            Some(Event::Created(index)) => {
                if let Some(PlaceEvent::Recognised { .. }) = places.push(index) {
                    report.places_recognised += 1;
                }
            }
            Some(Event::Full) | None => {}
        }
        // Act (§3.8: the robot is attracted by walls and contours; the thesis programmed the
        // expected behaviour): follow a wall on one side; now and then leave it and cross
        // open space until the next wall, then follow that one on a random side.
        let (vl, vr) = behaviour.act(&irs, opts.speed_mps, &mut wander);
        // Encoders count the commanded rotation; the ground moves with the bias.
        let gl = vl * (1.0 + bias[0]) * opts.period_s;
        let gr = vr * (1.0 + bias[1]) * opts.period_s;
        let l = KHEPERA.wheel_distance_m as f64;
        let dth = (gr - gl) / l;
        let ds = (gl + gr) / 2.0;
        let mid = truth.heading + dth / 2.0;
        let next = Pose {
            x: truth.x + ds * mid.cos(),
            y: truth.y + ds * mid.sin(),
            heading: (truth.heading + dth + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI,
        };
        // Into a wall the motors stall: nothing moves and the encoders count nothing; the
        // robot notices (its encoders stand still under command) and backs off.
        let mut pulses = [0i32; 2];
        if world
            .walls
            .circle_collides(Point::new(next.x, next.y), radius)
        {
            report.stalls += 1;
            behaviour.backing = 25;
        } else {
            report.distance_m += ds.abs();
            truth = next;
            for (k, w) in [vl, vr].iter().enumerate() {
                acc[k] += w * opts.period_s * 1000.0 / f64::from(odo.mm_per_pulse);
                pulses[k] = acc[k].trunc() as i32;
                acc[k] -= f64::from(pulses[k]);
            }
        }
        compass_odo.heading = compass as f32;
        if opts.compass_heading {
            corrected.heading = compass as f32;
        }
        let before = (corrected.x, corrected.y);
        for est in [&mut corrected, &mut plain, &mut compass_odo] {
            *est = integrate(*est, pulses[0], pulses[1], &odo);
        }
        if let Some(f) = &opts.fusion {
            unc.advance((corrected.x - before.0).hypot(corrected.y - before.1), f);
        }
        let (ec, ep) = (err(&corrected, &truth), err(&plain, &truth));
        let eq = err(&compass_odo, &truth);
        report.compass_peak = report.compass_peak.max(eq);
        sum_q += eq;
        report.corrected_peak = report.corrected_peak.max(ec);
        report.plain_peak = report.plain_peak.max(ep);
        if t_s >= 60.0 {
            report.corrected_peak_after_60s = report.corrected_peak_after_60s.max(ec);
        }
        sum_c += ec;
        sum_p += ep;
        if step % series_every == 0 {
            report.series.push(SeriesPoint {
                t_s,
                truth: [truth.x, truth.y],
                corrected: [f64::from(corrected.x), f64::from(corrected.y)],
                plain: [f64::from(plain.x), f64::from(plain.y)],
                compass: [f64::from(compass_odo.x), f64::from(compass_odo.y)],
                corrected_err: ec,
                plain_err: ep,
                compass_err: eq,
                corrected_sigma: opts.fusion.map_or(0.0, |f| {
                    f64::from(unc.variance((corrected.x, corrected.y), &f).sqrt()) / DIAMETER_M
                }),
                landmarks: store.landmarks().len(),
                matches: report.matches,
            });
        }
    }
    let n = steps.max(1) as f64;
    report.corrected_mean = sum_c / n;
    report.plain_mean = sum_p / n;
    report.compass_mean = sum_q / n;
    report.classes = [cls.art1.len(), cls.kmeans.len(), cls.fuzzy.len()];
    report.landmarks = store.landmarks().len();
    report.landmark_positions = store
        .landmarks()
        .iter()
        .map(|l| [f64::from(l.x), f64::from(l.y), f64::from(l.stream)])
        .collect();
    report.places = places.len();
    let m = store.match_stats();
    report.match_stats = MatchStatsReport {
        kernels: m.kernels,
        unknown_kernel: m.unknown_kernel,
        too_far: m.too_far,
        dissimilar: m.dissimilar,
        mean_near_lev: if m.near > 0 {
            m.lev_sum / m.near as f32
        } else {
            0.0
        },
    };
    report.revisit = diag.finish();
    report.landmark_truth = lm_truth.iter().map(|p| [p.x, p.y]).collect();
    report.significant_classes = store.significant_classes();
    report.loss = LossDiagnosis::of(&report, store.landmarks());
    report.wall_s = started.elapsed().as_secs_f64();
    report
}

/// Accumulates [`RevisitDiagnosis`].
#[derive(Default)]
struct Diagnoser {
    d: RevisitDiagnosis,
    lev: [f64; STREAMS],
    lev_same: [f64; STREAMS],
    odo: f64,
    imp: [f64; STREAMS],
    off: f64,
}

impl Diagnoser {
    /// A kernel resolved as `e`; it happened at true pose `kt`, corrected position `ko`.
    fn resolved(
        &mut self,
        e: Event,
        kt: Pose,
        ko: [f32; 2],
        store: &LandmarkStore,
        cls: &Classifiers,
        lm_truth: &mut Vec<Pose>,
    ) {
        let lms = store.landmarks();
        let (me, matched) = match e {
            Event::Created(i) => (Some(usize::from(i)), false),
            Event::Matched { .. } => (None, true),
            Event::Full => (None, false),
        };
        // The kernel: the created landmark's, or re-read from the store's statistics of a
        // match (the matched landmark has the same kernel).
        let kernel = match e {
            Event::Created(i) => lms.get(usize::from(i)).map(|l| (l.stream, l.class)),
            Event::Matched { index, .. } => {
                lms.get(usize::from(index)).map(|l| (l.stream, l.class))
            }
            Event::Full => None,
        };
        self.d.kernels += 1;
        if let Event::Matched { index, .. } = e {
            if let Some(t) = lm_truth.get(usize::from(index)) {
                let off = (t.x - kt.x).hypot(t.y - kt.y) / DIAMETER_M;
                self.d.matches += 1;
                self.off += off;
                if off > 0.5 {
                    self.d.match_offset_over_half += 1;
                }
            }
        }
        let limit = 0.5 * DIAMETER_M;
        let nearest = lms
            .iter()
            .enumerate()
            .filter(|(i, _)| Some(*i) != me && *i < lm_truth.len())
            .map(|(i, l)| (i, l, (lm_truth[i].x - kt.x).hypot(lm_truth[i].y - kt.y)))
            .filter(|(_, _, d)| *d < limit)
            .min_by(|a, b| a.2.total_cmp(&b.2));
        if let Some((i, l, _)) = nearest {
            self.d.near_any_landmark += 1;
            if kernel == Some((l.stream, l.class)) {
                self.d.revisits += 1;
                if matched {
                    self.d.revisits_matched += 1;
                }
                let odo = f64::from((l.x - ko[0]).hypot(l.y - ko[1])) / DIAMETER_M;
                self.odo += odo;
                if odo > 1.0 {
                    self.d.revisits_too_far += 1;
                }
                let dh = (lm_truth[i].heading - kt.heading + std::f64::consts::PI)
                    .rem_euclid(std::f64::consts::TAU)
                    - std::f64::consts::PI;
                let lev = store.stream_distances(&store.window(), l, cls);
                let same = dh.abs() < std::f64::consts::FRAC_PI_4;
                if same {
                    self.d.revisits_same_direction += 1;
                }
                for ((all, same_dir), v) in self.lev.iter_mut().zip(&mut self.lev_same).zip(lev) {
                    *all += f64::from(v);
                    if same {
                        *same_dir += f64::from(v);
                    }
                }
            }
        }
        for (i, l) in lms.iter().enumerate() {
            if Some(i) == me || i >= lm_truth.len() || kernel != Some((l.stream, l.class)) {
                continue;
            }
            let odo = f64::from((l.x - ko[0]).hypot(l.y - ko[1])) / DIAMETER_M;
            let tru = (lm_truth[i].x - kt.x).hypot(lm_truth[i].y - kt.y) / DIAMETER_M;
            if odo <= 1.0 && tru > 1.0 {
                self.d.impostors += 1;
                let lev = store.stream_distances(&store.window(), l, cls);
                for (a, v) in self.imp.iter_mut().zip(lev) {
                    *a += f64::from(v);
                }
            }
        }
        if let Some(i) = me {
            if lm_truth.len() == i {
                lm_truth.push(kt);
            }
        }
    }

    fn finish(mut self) -> RevisitDiagnosis {
        let n = f64::from(self.d.revisits.max(1));
        let m = f64::from(self.d.revisits_same_direction.max(1));
        self.d.revisit_lev = self.lev.map(|v| (v / n) as f32);
        self.d.revisit_lev_same_direction = self.lev_same.map(|v| (v / m) as f32);
        self.d.revisit_odo_dist = (self.odo / n) as f32;
        let k = f64::from(self.d.impostors.max(1));
        self.d.impostor_lev = self.imp.map(|v| (v / k) as f32);
        self.d.match_offset_mean = (self.off / f64::from(self.d.matches.max(1))) as f32;
        self.d
    }
}
