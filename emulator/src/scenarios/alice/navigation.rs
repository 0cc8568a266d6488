//! §5.3's navigation experiment on the simulated ALICE: plan by A* over the QT map
//! (`world_model::navigate`), execute the plan step by step with the reinforcement-trained
//! path execution (`world_model::execute`), refine the plan when a step fails (the planner's
//! weights move from hill climbing towards flooding as steps fail), and compare the first test
//! run (pre-trained memory) with the run after four test runs.
//!
//! The run: the robot explores `explore_samples` situations as the §4.5 scenarios do, which
//! builds the map; then §5.3's static drift (`static_drift_deg_per_m`, a curve of the true
//! path the odometry does not see) is switched on and the robot drives the test path, from
//! the start cell (the one nearest the start pose in the internal frame) to the cell farthest
//! from it and back, `runs` times in a row. The robot decides from its own view only: the
//! winner cell and the internal pose; the truth goes into the report only.
//!
//! A step: turn to the sub-goal's bearing plus the memory's offset, drive its distance times
//! the memory's scale, as the odometry measures it (bearing and distance of the map's edge
//! from the winner cell to the sub-goal, `StepBase::Cell`, or from the internal pose,
//! `StepBase::Pose`; the body blocked by a wall or the pillar stops it), then stand still
//! for l + 1 samples so the model's winner is the arrival's situation. The
//! step succeeded when the winner is the sub-goal (or a later cell of the plan); otherwise it
//! failed and the plan is refined from the winner. The reinforcement is the distance from the
//! winner's cell to the sub-goal's before and after. A reversal is a step that ended farther
//! from its sub-goal than it started.
//!
//! Judging the robot's self-localisation (truth only, never used by the robot): while it
//! explores, the true positions where each cell wins are averaged into the cell's "place";
//! the rigid transform that best maps the cells' internal positions onto their places
//! (`MapFit`) is the map's frame in the world. After every step the report notes how far the
//! internal pose, carried through that transform, is from the true pose (position and
//! heading): a step aimed at a cell's internal position can only reach the cell when these
//! are small.
//!
//! Sample by sample the report also follows the correlations ([`CorrelationJudge`]): which gate
//! stops the orientation correlation (the model's own counts, `world_model::Stats`), and,
//! judged from the truth, how far the winner (the centre of the position correlation's
//! neighbourhood) is from the internal pose and its place from the truth. Two options
//! separate the causes: `test_map` (`TestMap::Adapting`) lets the map keep learning during the
//! test runs, and `true_pose` holds the internal pose at the truth in the map's frame, a
//! counterfactual that shows what the planner and the memory do when the localisation holds.
//!
//! The simulated robot and its legs are `robot`; what is measured from the truth, to judge
//! only, `judge`.

use serde::Serialize;
use world_model::execute::Executor;
use world_model::{Params, Pose, QtModel};

mod judge;
mod robot;

use judge::{MapFit, MapSnapshot, Places, Tally};
use robot::Robot;

use super::body::Body;
use crate::builtin::alice::{alice, navigation_scene, CORRIDOR_TARGET};
use crate::geometry::Point;
use crate::rng::SimRng;
use crate::sensors::alice::{Sensors, COUNT};

/// Wins while exploring a cell needs to be the corridor scene's target (ours).
pub const CORRIDOR_TARGET_WINS: u32 = 20;

/// How far a blocked step backs off, metres (ours: half a body).
pub const BACK_OFF_M: f64 = 0.2;

/// A cell is in the open when each smoothed touch value of its situation (a touching whisker
/// is 1 at its sensor, 0.14 two sensors away with sigma 1) is below this (ours).
pub const OPEN_TOUCH: f64 = 0.05;

/// What the experiment does.
#[derive(Clone, Debug, Serialize)]
pub struct NavOptions {
    /// Seed: drift, sensors, exploration, the memory's choices.
    pub seed: u64,
    /// Situations of exploration before the test runs (the map; §4.5.4's equilibrium).
    pub explore_samples: u64,
    /// Test runs (the thesis compares the first with the one after four). 0: the exploration,
    /// the map's fit and the test path only; the robot does not drive to the path's start.
    pub runs: usize,
    /// §5.3's static drift during the test runs, degrees per metre ("up to 5").
    pub static_drift_deg_per_m: f64,
    /// What the map does during the test runs (§5.3's maps were static; see [`TestMap`]).
    pub test_map: TestMap,
    /// Most samples one leg may take before it counts as failed.
    pub leg_cap: u64,
    /// What a step's geometric command is measured from (see [`StepBase`]).
    pub step_base: StepBase,
    /// The memory learns from the reinforcement (false: the control, the pre-learned
    /// memory throughout, which shows what the first-over-fifth factors are without any
    /// learning).
    pub learn: bool,
    /// A counterfactual to judge the navigator, never the experiment itself: during the test
    /// runs the model's internal pose is set after every sample to the true pose carried into
    /// the map's frame (the inverse of the judge's fit), a localisation that holds exactly.
    /// It separates what the lost localisation costs from what the planner and the memory do.
    pub true_pose: bool,
    /// The odometry's own drift, besides the static drift of the test runs (see [`Drift`]).
    pub drift: Drift,
    /// Where it runs (see [`Scene`]).
    pub scene: Scene,
    /// The model's parameters.
    pub params: Params,
}

impl NavOptions {
    /// The thesis's experiment for `seed`.
    pub fn new(seed: u64, params: Params) -> Self {
        NavOptions {
            seed,
            explore_samples: 6000,
            runs: 5,
            static_drift_deg_per_m: 5.0,
            leg_cap: 1500,
            test_map: TestMap::Frozen,
            step_base: StepBase::Cell,
            learn: true,
            true_pose: false,
            drift: Drift::Alice,
            scene: Scene::Pillar,
            params,
        }
    }
}

/// What the map does during the test runs; also `alice-navigation`'s `--test-map` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, clap::ValueEnum)]
pub enum TestMap {
    /// Frozen by its parameters: no adaptation, no insertion, edges all but never forgotten
    /// (the default, as the reported figures were measured). Winner changes still create and
    /// refresh edges, and the cells' update counts still grow (each run's `map` says how much).
    Frozen,
    /// Static (`QtModel::set_static`, our reading of §5.3's "static QT-maps"): nothing of the
    /// map changes; the winner search and both correlations still run (they localise).
    Static,
    /// Keeps learning as while exploring (the thesis's world model has no separate phase).
    Adapting,
}

/// Where the navigation experiment runs; also `alice-navigation --scene`'s values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, clap::ValueEnum)]
pub enum Scene {
    /// The §4.5 test scene (`builtin:alice`): 3 x 3 m, the pillar; the test path runs out and
    /// back between the open cell nearest the start and the one farthest from it.
    Pillar,
    /// §5.3's scene as the thesis describes it (`arena::navigation_scene`): corridors, a rough
    /// wall, jagged obstacles; the test path runs from between the obstacles through the
    /// upper-left corridor into the pocket beyond it and back.
    Corridors,
}

/// The odometry's drift in the navigation experiment; also `alice-navigation --drift`'s values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, clap::ValueEnum)]
pub enum Drift {
    /// ALICE's (§3.1, the §4.5 scenarios'): 20-25 % translational, up to 0.5 degrees/metre
    /// rotational, throughout; the static drift on top in the test runs.
    Alice,
    /// §5.3's simulator "includes a 2-d model of light distributions as well as a static
    /// drift model" (our reading: that drift model only): the odometry is exact but for the
    /// turns' 1 % noise, and the test runs add the static drift it does not see.
    Static,
}

/// What a step's geometric command (before the memory's correction) is measured from; also
/// `alice-navigation --step-from`'s values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, clap::ValueEnum)]
pub enum StepBase {
    /// From the internal pose to the sub-goal cell's position.
    Pose,
    /// From the winner cell's position to the sub-goal cell's: the map's own relative
    /// motion along the edge, turned into the robot's frame by the internal heading. The
    /// association (winner, sub-goal) then fully determines the command, so what the memory
    /// learns for an edge applies the next time the edge is driven (§5.2: the mapping is
    /// "triggered by the current situation and the desired (sub-) goal only").
    Cell,
}

/// One leg (start to target, or back).
#[derive(Clone, Debug, Default, Serialize)]
pub struct Leg {
    /// Reached the target within the cap.
    pub reached: bool,
    /// Situations (1/3 s each) until the target's cell won.
    pub samples: u64,
    /// Plans after the first (each after a failed step or a vanished cell).
    pub refinements: u32,
    /// Steps driven.
    pub steps: u32,
    /// Steps reversed: blocked drives backed off, and drives that ended farther from their
    /// sub-goal than they started.
    pub reversals: u32,
    /// Steps whose drive the body could not finish (a wall or the pillar in the way).
    pub blocked: u32,
    /// Steps that failed (the winner after it was neither the sub-goal nor a later cell of
    /// the plan).
    pub failed: u32,
    /// Judged from the truth (never used by the robot): steps whose sub-goal cell's internal
    /// position, carried into the world by the map's fit, is no place the body can stand
    /// (within its radius of a wall or the pillar, inside one, or outside the arena).
    pub aimed_outside: u32,
    /// See `aimed_outside`: the blocked steps among them.
    pub blocked_aimed_outside: u32,
    /// Blocked steps that stopped within the first 2 cm: they started against the obstacle
    /// and headed into it.
    pub blocked_at_once: u32,
    /// Blocked steps whose commanded end, from the true pose, is a place the body can stand
    /// and that did not stop at once: a cut corner of a wall or the pillar, or the static
    /// drift's curve or the odometry's error carried the body into one.
    pub blocked_cutting: u32,
    /// Steps whose sub-goal's place (where it won while exploring), seen from the true pose,
    /// is beyond the memory's proposals: more than 50 degrees off the geometric command's
    /// direction (the proposals reach 40, spaced 20), or its distance outside 0.7-1.4 of the
    /// command's (they scale 0.8-1.25). Ours, to judge only.
    pub beyond_proposals: u32,
    /// Internal distance from the robot to the target cell at the end, metres (None: the
    /// cell is gone).
    pub final_gap_m: Option<f64>,
    /// Judged from the truth after each step: mean distance between the true position and
    /// the internal one carried into the world by the map's fit, metres.
    pub localisation_error_m: f64,
    /// See `localisation_error_m`: mean absolute heading error against the map's frame,
    /// degrees (90 is a heading that knows nothing).
    pub heading_error_deg: f64,
}

/// One test run: out and back.
#[derive(Clone, Debug, Serialize)]
pub struct TestRun {
    /// The two legs.
    pub legs: [Leg; 2],
    /// Both legs' samples.
    pub samples: u64,
    /// Both legs' refinements.
    pub refinements: u32,
    /// Both legs' reversals.
    pub reversals: u32,
    /// Both legs' localisation error after a step (see `Leg`), mean over steps, metres.
    pub localisation_error_m: f64,
    /// Both legs' heading error after a step (see `Leg`), mean over steps, degrees.
    pub heading_error_deg: f64,
    /// The correlations over the run's samples (`or_applies` is the orientation correlation
    /// that would hold the heading against the static drift).
    pub correlation: CorrelationJudge,
    /// What of the map changed during the run (judged only, never used by the robot).
    pub map: MapChanges,
}

/// What of the model's map changed over a stretch of samples: the model's own counters
/// (differences of `world_model::Stats`) and a comparison of the network before and after.
/// Judged only, never used by the robot.
#[derive(Clone, Debug, Default, Serialize)]
pub struct MapChanges {
    /// Adaptation steps that moved a cell (winner or neighbour) by a rate above 0.
    pub cell_moves: u64,
    /// Cells whose position differs after the stretch (of those there before).
    pub cells_moved: usize,
    /// The largest of their displacements, metres.
    pub max_moved_m: f64,
    /// Cells inserted (spontaneous and statistical).
    pub inserted: u64,
    /// Cells removed.
    pub removed: u64,
    /// Edges created, refreshed to 1 and worn by winner changes (eqs. 7-8).
    pub edges_created: u64,
    /// See `edges_created`.
    pub edges_refreshed: u64,
    /// See `edges_created`.
    pub edges_worn: u64,
    /// Edges (cell pairs) present after the stretch and not before, and before and not after.
    pub edges_new: usize,
    /// See `edges_new`.
    pub edges_gone: usize,
    /// Sum of the cells' update counts added over the stretch.
    pub updates: u64,
    /// The adaptation rates (eps_o, eps_n) at the end of the stretch.
    pub rates: (f64, f64),
}

/// The correlations (§4.2.4) over a stretch of samples. The orientation correlation's gates are
/// the model's own counts (`world_model::Stats`, differences over the stretch), as fractions of
/// the stretch's samples; each sample ends at one gate, in the order the model applies them: the
/// position estimate is not trusted (`or_pos_tolerance`); no cell lies within `or_radius` of
/// the internal position; the light ring has no pattern to align; no turn within
/// `or_max_shift` aligns the ring with the nearest cell's (a heading error beyond the search);
/// the best turn leaves a residual above `or_max_residual` (the nearest cell's ring is another
/// place's); or the correlation applies. They sum to 1 while `eps_or > 0` (all 0 when it is
/// off). The rest is judged from the truth at the internal pose after each sample (never used
/// by the robot): the position correlation's estimate comes from the winner's neighbourhood,
/// and the winner search weighs the position: how far the winner cell is from the internal
/// pose, and how far the place where it won while exploring is from the truth, show whether
/// that estimate can pull the pose back.
#[derive(Clone, Debug, Default, Serialize)]
pub struct CorrelationJudge {
    /// Samples judged.
    pub samples: u64,
    /// Fraction of the samples on which the orientation correlation applies (the model's
    /// orientation corrections per sample).
    pub or_applies: f64,
    /// Fraction whose position estimate is not within `or_pos_tolerance` (0 at the default,
    /// no tolerance).
    pub or_untrusted: f64,
    /// Fraction with no cell within `or_radius` of the internal position.
    pub or_no_cell: f64,
    /// Fraction whose light ring has no pattern to align (flat; `axis`: no distinct axis).
    pub or_no_pattern: f64,
    /// Fraction with no aligning turn within `or_max_shift`.
    pub or_no_turn: f64,
    /// Fraction whose best turn leaves too large a residual.
    pub or_residual: f64,
    /// Fraction with a whisker touching.
    pub touching: f64,
    /// Mean distance from the winner cell's internal position to the internal pose, metres.
    pub winner_to_pose_m: f64,
    /// Mean distance from the true position to the winner's place (the mean true position
    /// where it won while exploring), metres.
    pub winner_place_to_truth_m: f64,
}

/// The experiment's report.
#[derive(Clone, Debug, Serialize)]
pub struct NavReport {
    /// The options.
    pub options: NavOptions,
    /// Cells and edges of the map when the test runs began.
    pub cells: usize,
    /// See `cells`.
    pub edges: usize,
    /// Start and target cells, and their internal distance, metres.
    pub start_cell: u32,
    /// See `start_cell`.
    pub target_cell: u32,
    /// See `start_cell`.
    pub path_m: f64,
    /// The corridor scene: how far the target cell's place (where it won while exploring)
    /// is from the pocket's centre, metres (truth, to judge the path).
    pub target_from_pocket_m: Option<f64>,
    /// The map's frame in the world (truth, to judge): rotation, degrees, and the cells'
    /// mean distance from their places after the fit, metres.
    pub map_rotation_deg: f64,
    /// See `map_rotation_deg`.
    pub map_fit_residual_m: f64,
    /// See `map_rotation_deg`: world metres per internal metre.
    pub map_scale: f64,
    /// The correlations over the exploration (see `TestRun`).
    pub exploring: CorrelationJudge,
    /// The test runs in order.
    pub runs: Vec<TestRun>,
    /// First run over the run after four (index 4): time, refinements, reversals
    /// (thesis: 2-3, 3-4, about 5). None when the runs are too few.
    pub time_factor: Option<f64>,
    /// See `time_factor`.
    pub refinement_factor: Option<f64>,
    /// See `time_factor`.
    pub reversal_factor: Option<f64>,
    /// Associations the memory holds at the end.
    pub associations: usize,
    /// Wall-clock seconds.
    pub wall_s: f64,
}

/// Run §5.3's experiment for one seed.
pub fn navigation(o: &NavOptions) -> Result<NavReport, String> {
    let started = std::time::Instant::now();
    let arena = match o.scene {
        Scene::Pillar => alice(),
        Scene::Corridors => navigation_scene(),
    };
    let walls = arena.segment_set();
    let start = arena.starts[0];
    let start_pose = Pose {
        x: start.x,
        y: start.y,
        heading: start.heading,
    };
    let mut r = Robot {
        walls,
        body: Body::new(
            Point::new(start.x, start.y),
            start.heading,
            SimRng::new(o.seed, 101),
            o.drift == Drift::Alice,
        ),
        sensors: Sensors::new(SimRng::new(o.seed, 102)),
        rng: SimRng::new(o.seed, 103),
        model: QtModel::new(o.params.clone(), start_pose).map_err(|e| e.to_string())?,
        arena,
        touch: [false; COUNT],
        samples: 0,
        places: Places::default(),
        fit: None,
        tally: Tally::default(),
        true_pose: false,
    };
    r.explore(o.explore_samples, o.scene == Scene::Corridors)?;
    let exploring = r.take_judge();
    let net = r.model.network();
    let pairs: Vec<_> = net
        .cells()
        .filter_map(|(id, _)| {
            let (place, _) = r.places.of(id)?;
            Some((net.position(id), place))
        })
        .collect();
    let fit = MapFit::new(&pairs);
    // The test path's ends are open places, as the thesis's (between the obstacles, the open
    // space): cells whose situation has no whisker touching, judged from the map alone. And
    // places the map knows well: a leg is reached when the target cell wins, and a cell that
    // won a handful of times in the whole exploration (the farthest open cell often is one,
    // 3-12 wins in 6000 samples) is one the robot can stand on and still not be "at"; so the
    // ends are taken among the open cells with at least the median of their updates.
    let p = &o.params;
    let mut open: Vec<(u32, u32)> = net
        .cells()
        .filter(|(_, c)| {
            c.s[p.lights..p.lights + p.touches]
                .iter()
                .all(|&t| t.abs() < OPEN_TOUCH)
        })
        .map(|(id, c)| (id, c.updates))
        .collect();
    let mut updates: Vec<u32> = open.iter().map(|c| c.1).collect();
    updates.sort_unstable();
    let median = updates.get(updates.len() / 2).copied().unwrap_or(0);
    open.retain(|c| c.1 >= median);
    let open: Vec<u32> = open.into_iter().map(|c| c.0).collect();
    let gap = |id: u32, to: (f64, f64)| {
        let q = net.position(id);
        (q.0 - to.0).hypot(q.1 - to.1)
    };
    let home = open
        .iter()
        .copied()
        .min_by(|&a, &b| gap(a, (start.x, start.y)).total_cmp(&gap(b, (start.x, start.y))))
        .ok_or("the exploration made no cell in the open")?;
    let hp = net.position(home);
    // The experimenter's path. The corridor scene's far end is the cell that won nearest the
    // pocket's centre (truth), among those that won at least `CORRIDOR_TARGET_WINS` times
    // (the pocket is reached only through the corridor, so its cells win less often than the
    // median, and a 1.3 m pocket has little room where no whisker touches).
    let (away, target_from_pocket_m) = match o.scene {
        Scene::Pillar => open
            .iter()
            .copied()
            .max_by(|&a, &b| gap(a, hp).total_cmp(&gap(b, hp)))
            .map(|away| (away, None))
            .ok_or("the exploration made no cell in the open")?,
        Scene::Corridors => net
            .cells()
            .filter_map(|(id, _)| {
                let (_, wins) = r.places.of(id)?;
                let d = r.places.distance(id, CORRIDOR_TARGET)?;
                (wins >= CORRIDOR_TARGET_WINS).then_some((id, d))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(away, d)| (away, Some(d)))
            .ok_or("the exploration made no cell that won often enough to end the test path")?,
    };
    let path_m = gap(away, hp);
    let (cells, edges) = (net.len(), net.edges().count());
    r.fit = fit;
    r.true_pose = o.true_pose;
    r.body.curve = o.static_drift_deg_per_m.to_radians();
    match o.test_map {
        TestMap::Frozen => r
            .model
            .set_params(frozen(&o.params))
            .map_err(|e| e.to_string())?,
        TestMap::Static => r.model.set_static(true),
        TestMap::Adapting => {}
    }
    let mut exec = Executor::default();
    if !o.learn {
        exec.rate = 0.0;
    }
    // Get to the start of the test path first (not measured; the memory learns already, as
    // it would on any drive).
    if o.runs > 0 {
        r.leg(home, &mut exec, o.leg_cap, o.step_base)?;
    }
    r.take_judge();
    let mut runs = Vec::new();
    for _ in 0..o.runs {
        let snapshot = MapSnapshot::new(&r.model);
        let mut legs: [Leg; 2] = Default::default();
        for (i, target) in [away, home].into_iter().enumerate() {
            let mut leg = r.leg(target, &mut exec, o.leg_cap, o.step_base)?;
            leg.final_gap_m = r.model.network().cell(target).map(|_| r.towards(target).0);
            legs[i] = leg;
        }
        let steps = legs.iter().map(|l| l.steps.max(1) as f64).sum::<f64>();
        let weighted = |f: fn(&Leg) -> f64| {
            legs.iter()
                .map(|l| f(l) * l.steps.max(1) as f64)
                .sum::<f64>()
                / steps
        };
        runs.push(TestRun {
            correlation: r.take_judge(),
            map: snapshot.changes(&r.model),
            localisation_error_m: weighted(|l| l.localisation_error_m),
            heading_error_deg: weighted(|l| l.heading_error_deg),
            samples: legs.iter().map(|l| l.samples).sum(),
            refinements: legs.iter().map(|l| l.refinements).sum(),
            reversals: legs.iter().map(|l| l.reversals).sum(),
            legs,
        });
    }
    let factor = |f: &dyn Fn(&TestRun) -> f64| {
        let (a, b) = (runs.first()?, runs.get(4)?);
        Some(f(a) / f(b).max(1.0))
    };
    Ok(NavReport {
        cells,
        edges,
        start_cell: home,
        target_cell: away,
        path_m,
        target_from_pocket_m,
        map_rotation_deg: fit.map_or(0.0, |f| f.rotation.to_degrees()),
        map_fit_residual_m: fit.map_or(0.0, |f| f.residual_m),
        map_scale: fit.map_or(1.0, |f| f.scale),
        exploring,
        time_factor: factor(&|t| t.samples as f64),
        refinement_factor: factor(&|t| t.refinements as f64),
        reversal_factor: factor(&|t| t.reversals as f64),
        associations: exec.associations(),
        runs,
        options: o.clone(),
        wall_s: started.elapsed().as_secs_f64(),
    })
}

/// `p` with the map frozen: no adaptation, no insertion, edges all but never forgotten.
fn frozen(p: &Params) -> Params {
    Params {
        eps_o: 0.0,
        eps_n: 0.0,
        rho_s: f64::MAX,
        n_insert: u32::MAX,
        a_red: 1e-9,
        ..p.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The judge's fit recovers a known rotation and shift, and says how far the points
    /// stray from it.
    #[test]
    fn the_map_fit_recovers_a_rigid_transform() {
        let (rot, shift) = (0.3f64, (1.0, -2.0));
        let internal = [(0.0, 0.0), (1.0, 0.0), (0.0, 2.0), (1.5, 1.5)];
        let pairs: Vec<_> = internal
            .iter()
            .map(|&(x, y)| {
                let (s, c) = rot.sin_cos();
                ((x, y), (c * x - s * y + shift.0, s * x + c * y + shift.1))
            })
            .collect();
        let fit = MapFit::new(&pairs).expect("enough points");
        assert!((fit.rotation - rot).abs() < 1e-9, "{fit:?}");
        assert!(fit.residual_m < 1e-9, "{fit:?}");
        let w = fit.world((2.0, 3.0));
        let (s, c) = rot.sin_cos();
        assert!((w.0 - (c * 2.0 - s * 3.0 + shift.0)).abs() < 1e-9);
        assert!((w.1 - (s * 2.0 + c * 3.0 + shift.1)).abs() < 1e-9);
        // One point moved 1 m: the residual shows it, spread over the four.
        let mut moved = pairs.clone();
        moved[3].1 .0 += 1.0;
        assert!(MapFit::new(&moved).expect("fit").residual_m > 0.2);
        assert!(MapFit::new(&pairs[..2]).is_none());
        let back = fit.internal(fit.world((2.0, 3.0)));
        assert!(
            (back.0 - 2.0).abs() < 1e-9 && (back.1 - 3.0).abs() < 1e-9,
            "{back:?}"
        );
        assert!((fit.scale - 1.0).abs() < 1e-9, "{fit:?}");
        // A map 25 % larger than the world: the scale is recovered, no residual left.
        let larger: Vec<_> = pairs
            .iter()
            .map(|&(a, w)| ((a.0 * 1.25, a.1 * 1.25), w))
            .collect();
        let fit = MapFit::new(&larger).expect("fit");
        assert!((fit.scale - 0.8).abs() < 1e-9, "{fit:?}");
        assert!(
            (fit.rotation - rot).abs() < 1e-9 && fit.residual_m < 1e-9,
            "{fit:?}"
        );
        let back = fit.internal(fit.world((2.0, 3.0)));
        assert!((back.0 - 2.0).abs() < 1e-9 && (back.1 - 3.0).abs() < 1e-9);
    }
}
