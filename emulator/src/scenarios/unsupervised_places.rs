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
//! `Robot` does not run this yet, see docs/reproductions.md):
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

mod diagnose;
mod loss;
mod report;
mod world;

use std::time::Instant;

use diagnose::Diagnoser;
pub use loss::{LossDiagnosis, WRONG_OFFSET};
pub use report::{MatchRecord, MatchStatsReport, PlacesReport, RevisitDiagnosis, SeriesPoint};
pub use world::{camera, camera_features, generate, World};

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

use crate::arena::Pose;
use crate::geometry::Point;
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
/// silent, named in docs/reproductions.md).
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
    /// (`compass_heading` false; the stored heading measured worse, docs/reproductions.md).
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
