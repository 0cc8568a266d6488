//! What a run reports: the error series, the landmark matches and their statistics, why
//! landmarks are or are not met again.

use robot_firmware::unsupervised::STREAMS;
use serde::Serialize;

use super::loss::LossDiagnosis;
use super::ArenaKind;

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
