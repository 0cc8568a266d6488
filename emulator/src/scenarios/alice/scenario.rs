//! One run of the simulated ALICE feeding the QT model, and the thesis's experiments (§4.5)
//! built from runs. Every run is a pure function of its options (seeded).

use std::collections::VecDeque;
use std::time::Instant;

use serde::Serialize;
use world_model::{Params, Pose, QtModel, Sample, Stats};

use super::body::{Body, SPEED_M_S, SUBSTEPS, TURN_RAD_S};
use super::explore::{decide, Move};
use super::metrics::{
    crossings_per_edge, edges_across, place_spread, two_sided_cells, unreachable_fraction, Rigid,
    TakenAt,
};
use crate::builtin::alice::{alice, gap_wall, PILLAR_CENTRE, PILLAR_RADIUS_M};
use crate::geometry::{Point, Segment};
use crate::rng::SimRng;
use crate::sensors::alice::Sensors;

/// One sample's true, internal and odometry positions, and the winner with the true position
/// of the situation it won (taken `l` samples earlier).
type Trace = (
    (f64, f64),
    (f64, f64),
    (f64, f64),
    Option<(u32, (f64, f64))>,
);

/// Sensor samples per second (§4.3: "3 sensor-samples per second").
pub const SAMPLES_PER_S: f64 = 3.0;
/// Most samples one run takes (the report's series grows with it).
pub const MAX_SAMPLES: u64 = 100_000;

/// What one run does.
#[derive(Clone, Debug, Serialize)]
pub struct RunOptions {
    /// Seed: drift, sensor gains and noise, the explorer's choices.
    pub seed: u64,
    /// Samples (situations) to take.
    pub samples: u64,
    /// The model's parameters.
    pub params: Params,
    /// Odometry drift as ALICE's (false: exact odometry).
    pub drift: bool,
    /// The dynamic experiment: the gap wall stands until this sample.
    pub remove_wall_at: Option<u64>,
    /// Samples between report checkpoints.
    pub checkpoint: u64,
    /// Samples in the window the checkpoint metrics look back over.
    pub window: usize,
}

impl RunOptions {
    /// A run with the default parameters.
    pub fn new(seed: u64, samples: u64) -> Self {
        RunOptions {
            seed,
            samples,
            params: Params::default(),
            drift: true,
            remove_wall_at: None,
            checkpoint: 250,
            window: 600,
        }
    }
}

/// The model's state against the truth at one sample.
#[derive(Clone, Debug, Serialize)]
pub struct Checkpoint {
    /// Samples taken.
    pub sample: u64,
    /// Cells.
    pub cells: usize,
    /// Edges.
    pub edges: usize,
    /// Mean edge confidence.
    pub mean_confidence: f64,
    /// Internal position vs truth after rigid alignment over the window, r.m.s. metres.
    pub aligned_error_m: f64,
    /// Internal heading vs truth after the same alignment, degrees (at this sample).
    pub heading_error_deg: f64,
    /// Internal position vs truth with no alignment (both start at the start pose), mean over
    /// the window, metres: what a lost robot shows first.
    pub absolute_error_m: f64,
    /// The uncorrected odometry, the same way.
    pub odometry_absolute_m: f64,
    /// The uncorrected odometry after alignment, as `aligned_error_m`.
    pub odometry_error_m: f64,
    /// Place spread of the winners over the window, metres.
    pub place_spread_m: f64,
    /// Edge crossings per edge (computed every 1000 samples and at the end; between, the
    /// last value).
    pub crossings_per_edge: f64,
    /// Fraction of cells a robot cannot be at.
    pub unreachable: f64,
    /// Dynamic experiment: edges whose cells truly win on either side of the gap wall's line
    /// (each cell placed at the running mean of the true positions where it won).
    pub gap_edges: Option<usize>,
    /// Dynamic experiment: cells that won at least [`GAP_TWO_SIDED_MIN`] times on each side of
    /// the gap wall's line while it stood, up to this sample (true positions): the folds of
    /// the internal frame that make edges across a standing wall.
    pub gap_two_sided: Option<usize>,
}

/// Wins on each side that make a cell two-sided (see [`Checkpoint::gap_two_sided`]).
pub const GAP_TWO_SIDED_MIN: usize = 3;

/// One run's report.
#[derive(Clone, Debug, Serialize)]
pub struct RunReport {
    /// The options.
    pub options: RunOptions,
    /// Metres driven.
    pub distance_m: f64,
    /// Translational drift r.m.s. this run (fraction of distance).
    pub trans_drift: f64,
    /// Rotational drift this run, degrees per metre.
    pub rot_drift_deg_per_m: f64,
    /// The model's counters.
    pub stats: Stats,
    /// Checkpoints, one per `checkpoint` samples.
    pub checkpoints: Vec<Checkpoint>,
    /// First checkpoint from which the cell count stays within 10 % of the final count.
    pub equilibrium_at: Option<u64>,
    /// Dynamic experiment: first checkpoint after the wall's removal with at least 2 edges
    /// across the former wall, as samples after the removal.
    pub gap_closed_after: Option<u64>,
    /// Wall-clock seconds the run took.
    pub wall_s: f64,
}

/// Run the simulated ALICE for `o.samples` samples; `observe` sees the model after each, with
/// the robot's true position (to judge by, never fed to the model).
pub fn run_with(
    o: &RunOptions,
    mut observe: impl FnMut(u64, &QtModel, (f64, f64)),
) -> Result<RunReport, String> {
    if o.samples > MAX_SAMPLES {
        return Err(format!(
            "{} samples: a run takes at most {MAX_SAMPLES}",
            o.samples
        ));
    }
    let started = Instant::now();
    let mut arena = alice();
    let gap = gap_wall();
    let gap_line = {
        let (cx, cy) = PILLAR_CENTRE;
        Segment::new(Point::new(cx, 0.0), Point::new(cx, cy - PILLAR_RADIUS_M))
    };
    if o.remove_wall_at.is_some() {
        arena.walls.push(gap.clone());
    }
    let mut walls = arena.segment_set();
    let start = arena.starts[0];
    let mut body = Body::new(
        Point::new(start.x, start.y),
        start.heading,
        SimRng::new(o.seed, 101),
        o.drift,
    );
    let mut sensors = Sensors::new(SimRng::new(o.seed, 102));
    let mut rng = SimRng::new(o.seed, 103);
    let mut model = QtModel::new(
        o.params.clone(),
        Pose {
            x: start.x,
            y: start.y,
            heading: start.heading,
        },
    )
    .map_err(|e| e.to_string())?;
    let dt = 1.0 / SAMPLES_PER_S / SUBSTEPS as f64;
    let mut pending_turn = 0.0f64;
    let mut hist: VecDeque<Trace> = VecDeque::new();
    let mut checkpoints = Vec::new();
    let mut true_place: std::collections::HashMap<u32, (f64, f64)> =
        std::collections::HashMap::new();
    let mut taken = TakenAt::new(o.params.l);
    let mut gap_wins = Vec::new();
    for t in 1..=o.samples {
        if o.remove_wall_at == Some(t) {
            arena.walls.retain(|w| *w != gap);
            walls = arena.segment_set();
        }
        for _ in 0..SUBSTEPS {
            if pending_turn.abs() > 1e-9 {
                let step = pending_turn.clamp(-TURN_RAD_S * dt, TURN_RAD_S * dt);
                body.turn(step);
                pending_turn -= step;
            } else if !body.forward(&walls, SPEED_M_S * dt) {
                // Blocked before a whisker told: turn away at random (the reflex layer).
                pending_turn =
                    super::wrap(std::f64::consts::PI + (2.0 * rng.uniform() - 1.0) * 1.2);
            }
        }
        let touch = sensors.whiskers(&walls, body.at, body.heading);
        let light = sensors.light(&walls, &arena.lights, body.at, body.heading);
        if pending_turn.abs() <= 1e-9 {
            if let Move::Turn(a) = decide(&touch, &mut rng) {
                pending_turn = a;
            }
        }
        let odometry = Pose {
            x: body.odo.0,
            y: body.odo.1,
            heading: body.odo.2,
        };
        model
            .observe(&Sample {
                light: &light,
                touch: &touch,
                odometry,
            })
            .map_err(|e| e.to_string())?;
        observe(t, &model, (body.at.x, body.at.y));
        let winner_at = taken.push((body.at.x, body.at.y));
        if let (Some(w), Some(r)) = (model.winner(), o.remove_wall_at) {
            if t < r {
                gap_wins.push((w, winner_at));
            }
        }
        if let Some(w) = model.winner() {
            // Where, truly, this cell wins (a running mean that forgets): the gap metric's
            // frame, free of the internal frame's drift.
            let e = true_place.entry(w).or_insert(winner_at);
            e.0 += 0.05 * (winner_at.0 - e.0);
            e.1 += 0.05 * (winner_at.1 - e.1);
        }
        let p = model.pose();
        hist.push_back((
            (body.at.x, body.at.y),
            (p.x, p.y),
            (odometry.x, odometry.y),
            model.winner().map(|w| (w, winner_at)),
        ));
        while hist.len() > o.window {
            hist.pop_front();
        }
        if t % o.checkpoint.max(1) == 0 || t == o.samples {
            let truth: Vec<_> = hist.iter().map(|h| h.0).collect();
            let internal: Vec<_> = hist.iter().map(|h| h.1).collect();
            let odo: Vec<_> = hist.iter().map(|h| h.2).collect();
            let r = Rigid::fit(&internal, &truth);
            let ro = Rigid::fit(&odo, &truth);
            let wins: Vec<_> = hist.iter().filter_map(|h| h.3).collect();
            let net = model.network();
            let (mut edges, mut conf) = (0usize, 0.0);
            for (_, _, w) in net.edges() {
                edges += 1;
                conf += w;
            }
            checkpoints.push(Checkpoint {
                sample: t,
                cells: net.len(),
                edges,
                mean_confidence: if edges > 0 { conf / edges as f64 } else { 0.0 },
                aligned_error_m: r.rms(&internal, &truth),
                odometry_error_m: ro.rms(&odo, &truth),
                absolute_error_m: mean_gap(&internal, &truth),
                odometry_absolute_m: mean_gap(&odo, &truth),
                heading_error_deg: super::wrap(p.heading + r.angle - body.heading).to_degrees(),
                place_spread_m: place_spread(&wins),
                // Quadratic in the edges: every 1000 samples and at the end only.
                crossings_per_edge: if t % 1000 == 0 || t == o.samples {
                    crossings_per_edge(net)
                } else {
                    checkpoints
                        .last()
                        .map_or(0.0, |c: &Checkpoint| c.crossings_per_edge)
                },
                unreachable: unreachable_fraction(net, &r, &walls, |p| arena.is_solid(p)),
                gap_edges: o
                    .remove_wall_at
                    .map(|_| edges_across(net, &true_place, gap_line)),
                gap_two_sided: o
                    .remove_wall_at
                    .map(|_| two_sided_cells(&gap_wins, gap_line, GAP_TWO_SIDED_MIN)),
            });
        }
    }
    let equilibrium_at = checkpoints.last().and_then(|last| {
        let f = last.cells as f64;
        let mut at = None;
        for c in checkpoints.iter().rev() {
            if (c.cells as f64 - f).abs() <= 0.1 * f {
                at = Some(c.sample);
            } else {
                break;
            }
        }
        at
    });
    let gap_closed_after = o.remove_wall_at.and_then(|r| {
        checkpoints
            .iter()
            .find(|c| c.sample >= r && c.gap_edges.unwrap_or(0) >= 2)
            .map(|c| c.sample - r)
    });
    Ok(RunReport {
        options: o.clone(),
        distance_m: body.distance_m,
        trans_drift: body.trans_drift,
        rot_drift_deg_per_m: body.rot_drift.to_degrees(),
        stats: model.stats().clone(),
        checkpoints,
        equilibrium_at,
        gap_closed_after,
        wall_s: started.elapsed().as_secs_f64(),
    })
}

/// [`run_with`] without an observer.
pub fn run(o: &RunOptions) -> Result<RunReport, String> {
    run_with(o, |_, _, _| {})
}

/// Mean of a checkpoint field over the checkpoints at or after `from` samples.
pub fn late_mean(r: &RunReport, from: u64, f: impl Fn(&Checkpoint) -> f64) -> f64 {
    let v: Vec<f64> = r
        .checkpoints
        .iter()
        .filter(|c| c.sample >= from)
        .map(f)
        .collect();
    if v.is_empty() {
        0.0
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

fn mean_gap(a: &[(f64, f64)], b: &[(f64, f64)]) -> f64 {
    let n = a.len().min(b.len());
    if n == 0 {
        return 0.0;
    }
    (0..n)
        .map(|i| (a[i].0 - b[i].0).hypot(a[i].1 - b[i].1))
        .sum::<f64>()
        / n as f64
}
