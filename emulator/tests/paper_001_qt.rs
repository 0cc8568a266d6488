//! Seed 001 (ALICE) §4.5 reproduced with the QT world model in the simulated test scene, over
//! seeds 1..=4. Each test states the thesis's figure, ours (as measured when the test was
//! written, `robot-emulator run --task alice-... --seed N`), the tolerance and the seeds.
//! What is not reproduced is `#[ignore]`d with the reason and the numbers. The figures are the
//! defaults'; where a comment gives figures "before `pos_sigma`" (the position estimate's
//! weights as wide as d_acc), `--qt-param pos_sigma=0.8` reproduces them exactly.

use emulator::scenarios::alice::experiments::{
    correlation, dynamic, dynamic_with, eps_o, eps_o_continued, equilibrium, ExperimentReport,
};
use emulator::scenarios::alice::navigation::{
    navigation, Drift, NavOptions, NavReport, Scene, TestRun,
};
use world_model::Params;

const SEEDS: [u64; 4] = [1, 2, 3, 4];

fn each(f: fn(u64, &Params) -> Result<ExperimentReport, String>) -> Vec<ExperimentReport> {
    SEEDS
        .iter()
        .map(|&s| f(s, &Params::default()).expect("experiment runs"))
        .collect()
}

/// Thesis §4.5.4: "reaches an equilibrium state ... after gathering 5000 sensor situations".
/// Ours (seeds 1-4): settled (cell count within 10 % of the 8000-sample count from then on)
/// at 5000, 6750, 4500, 6000; 113-141 cells (before `pos_sigma`: 4750, 6500, 6500, 7000). Tolerance: the mean within 5000 +- 1500,
/// every seed settled by 7500 (the run is 8000).
#[test]
fn the_network_reaches_equilibrium_after_about_5000_situations() {
    let r = each(equilibrium);
    let at: Vec<u64> = r
        .iter()
        .map(|e| e.runs[0].equilibrium_at.expect("settles"))
        .collect();
    let mean = at.iter().sum::<u64>() as f64 / at.len() as f64;
    assert!((3500.0..=6500.0).contains(&mean), "settled at {at:?}");
    assert!(at.iter().all(|&a| a <= 7500), "settled at {at:?}");
}

/// Thesis §4.5.1: eps_o = 0.1 gives "only a small number of cells" and muddled connections;
/// eps_o = 0.005 (one sixth of 0.03) "a huge amount of cells". Ours (seeds 1-4), cells at
/// 8000: 107/141/184, 94/113/193, 107/131/215, 100/135/191; crossings per edge 0.074/0.065,
/// 0.119/0.039, 0.118/0.086, 0.086/0.092 (0.1 against 0.03; summed 0.398 against 0.282). Tolerance: the ordering of the
/// cell counts in every seed, 0.005 at least 1.3x the base; the mean crossings at 0.1 above
/// the base's.
#[test]
fn eps_o_large_gives_few_cells_and_muddled_edges_small_gives_many_cells() {
    let r = each(eps_o);
    let mut cross = [0.0; 2];
    for e in &r {
        let c: Vec<usize> = e.runs.iter().map(|s| s.cells).collect();
        assert!(c[0] < c[1] && c[1] < c[2], "seed {}: cells {c:?}", e.seed);
        assert!(
            c[2] as f64 >= 1.3 * c[1] as f64,
            "seed {}: cells {c:?}",
            e.seed
        );
        cross[0] += e.runs[0].crossings_per_edge;
        cross[1] += e.runs[1].crossings_per_edge;
    }
    assert!(cross[0] > cross[1], "crossings per edge summed: {cross:?}");
}

/// Thesis §4.5.1: at eps_o = 0.005 "a huge amount of cells is inserted ... Even the position
/// and orientation correlation fails, when the test as shown in figure 6b is continued". §4.5
/// names what a failed correlation is: "the most important, observed feature ... is the
/// internal position of ALICE. Whenever ALICE loses its position respectively orientation
/// correlation, the world model is obviously useless" (the §4.5.3 ablation's "total loss of
/// consistency"). So: the internal pose against the truth, late in a continued run
/// (`alice-eps-o-continued`: 20000 situations, samples 8000-20000): absolute position error
/// (m) and heading error after aligning the internal track (degrees), eps_o 0.03 / 0.005,
/// seeds 1-10: 0.86/0.69 4.5/5.3, 0.42/0.47 4.7/5.5, 0.59/0.82 5.0/5.8, 0.50/1.66 5.0/9.4,
/// 0.38/0.38 6.6/6.9, 0.49/1.53 5.8/9.4, 0.39/0.88 6.5/9.4, 0.44/0.53 5.9/9.0, 0.31/0.48
/// 4.2/8.3, 0.49/0.41 5.7/6.8 (means 0.49/0.79 m, 5.4/7.6 degrees; cells at 20000 182/263,
/// 152/294, 180/323, 172/346, 223/368, 191/426, 175/328, 197/337, 158/296, 174/277). NOT
/// reproduced: seeds 1-4 1.54x the base's position error and 1.36x its heading error, short of
/// the ablation's 1.8x; seeds 11-20 1.30x and 1.31x. Before `pos_sigma`: 0.85/0.86 5.3/9.6, 0.74/0.67 7.0/7.4, 2.05/1.97 7.9/10.1, 1.84/1.77 7.9/11.9,
/// 0.82/2.01 7.1/11.6, 0.89/0.72 6.4/8.8, 0.89/1.03 7.2/10.4, 0.93/1.45 8.3/9.8, 0.52/0.64
/// 7.2/11.4, 1.01/1.22 8.0/9.0 (means 1.05/1.23 m, 7.2/10.0 degrees): the
/// position did not fail (seeds 1-4: 1.32 m against 1.37 m) and the heading degrades (1.4x,
/// every seed; see the next test) without failing; the aligned error and the place spread
/// are equal too (0.33/0.35 m, 0.18/0.17 m, samples 12500-20000), and 40000 situations
/// change nothing (seeds 1-3, 25000-40000: position 0.97/1.05, 0.74/0.75, 1.63/2.07 m;
/// heading 8.2/9.5, 5.6/6.7, 8.4/8.1 degrees). What we see instead of the failure: our "huge
/// amount" is 1.75x the cells (407 against 232 at 20000, mean of 10 seeds), mostly
/// statistical insertions, which n_insert = 60 paces by misses (seed 1: 15230 against 5880
/// misses, 253 against 98 insertions), not spontaneous ones, which slow cells failing to
/// follow the situations would make (157 against 125); about 13 against 17 cm between cells
/// over the 7 m^2 a robot's centre reaches, so a cell is still near the internal position
/// for both correlations (our reading, not a measured cause). The thesis's d_i in the
/// position estimate (`--qt-param pos_distance=situation`, the situation distance, position
/// included) weakens every run's position correlation and brings the two closer, without
/// the failure: 1.21/1.52 m and 7.3/8.9 degrees (seeds 1-4), 1.30/1.53 m and 7.6/9.0
/// degrees (seeds 1-10), 300/496 cells at 20000 (seeds 1-4). The
/// tolerance of the §4.5.3 ablation: 1.8x the base's error in the mean, position or heading,
/// seeds 1-4.
#[test]
#[ignore = "not reproduced: at eps_o = 0.005 continued to 20000 situations the position error is 1.54x and the heading error 1.36x the base's (seeds 1-4), short of 1.8x"]
fn eps_o_small_makes_the_correlation_fail() {
    let r = each(eps_o_continued);
    let (mut pos, mut head) = ([0.0; 2], [0.0; 2]);
    for e in &r {
        for i in 0..2 {
            pos[i] += e.runs[i].late_absolute_error_m;
            head[i] += e.runs[i].late_heading_error_deg;
        }
    }
    assert!(
        pos[1] >= 1.8 * pos[0] || head[1] >= 1.8 * head[0],
        "position {pos:?}, heading {head:?} (0.03, 0.005)"
    );
}

/// What §4.5.1's continued eps_o = 0.005 run does show here: the orientation correlation
/// keeps the heading less well (numbers in the test above: 5.4 against 7.6 degrees over
/// seeds 1-10, higher in every one; seeds 1-4 4.8 against 6.5; seeds 11-20 5.2 against 6.8,
/// higher in 9 and equal in one). Tolerance: higher in every
/// seed of 1-4, 1.2x in the mean.
#[test]
fn eps_o_small_continued_keeps_the_heading_less_well() {
    let r = each(eps_o_continued);
    let mut head = [0.0; 2];
    for e in &r {
        let h = [
            e.runs[0].late_heading_error_deg,
            e.runs[1].late_heading_error_deg,
        ];
        assert!(h[1] > h[0], "seed {}: heading {h:?}", e.seed);
        head[0] += h[0];
        head[1] += h[1];
    }
    assert!(head[1] >= 1.2 * head[0], "heading summed {head:?}");
}

/// Thesis §4.5.3: without position or without orientation correlation "none of these
/// test-runs could be completed without a total loss of consistency". Ours (seeds 1-4), mean
/// absolute position error over samples 5000-8000, metres, both / no position / no
/// orientation / plain odometry: 0.87/4.15/1.65/3.56, 0.43/3.45/1.84/3.54,
/// 0.56/1.96/1.94/2.80, 0.53/3.10/1.90/3.01 (before `pos_sigma` both gave 0.78, 0.80, 1.47,
/// 0.86). Tolerance: each ablation at least 1.25x the
/// error with both in every seed, and 1.8x in the mean; with both, the mean below 1.5 m.
#[test]
fn turning_either_correlation_off_loses_consistency_under_the_drift() {
    let r = each(correlation);
    let mut sum = [0.0; 3];
    for e in &r {
        let v: Vec<f64> = e.runs.iter().map(|s| s.late_absolute_error_m).collect();
        assert!(
            v[1] >= 1.25 * v[0] && v[2] >= 1.25 * v[0],
            "seed {}: {v:?}",
            e.seed
        );
        for i in 0..3 {
            sum[i] += v[i];
        }
    }
    let n = r.len() as f64;
    assert!(sum[0] / n < 1.5, "{sum:?}");
    assert!(sum[1] >= 1.8 * sum[0] && sum[2] >= 1.8 * sum[0], "{sum:?}");
}

/// Thesis §4.5.4 dynamic: a wall cut the circle round the pillar until situation 3500 ("a
/// clear gap"); the gap closed within about 1500 more. Judged by truth: each cell placed
/// where it truly wins (the true position of the situation it won, `l` samples before the
/// win is reported), an edge is across when those places lie on either side of the wall's
/// line. NOT reproduced in every seed. Edges across at removal, seeds 1-10: 4, 0, 4, 0, 5, 0,
/// 0, 5, 0, 0; the closing (2 edges across) 0, 250, 0, 750, 0, 250, 500, 0, 500, 250 samples
/// after; cells that won at least 3 times on each side of the standing wall 3, 0, 2, 0, 4, 0,
/// 0, 11, 0, 0: a clear gap closed in time in 6 of 10 seeds (11 of 20 in seeds 11-30, 4 of 20
/// before `pos_sigma`); with exact odometry and both correlations in 10 of 10 (5 folded
/// before), so the folds left are the drift's (`examples/alice_dynamic_probe`). The analysis that follows was made before `pos_sigma`, when 4 of
/// seeds 1-10 showed it: edges across 8, 0, 6, 0, 2, 0, 0, 18, 15, 2; closing 0, 250, 0, 750,
/// 0, 250, 500, 0, 0, 0. Why: the internal frame folded the wall's two sides onto each other, and one cell
/// came to stand for places on both. Cells that won at least 3 times on each side of the
/// standing wall, seeds 1-10: 10, 0, 11, 0, 0, 0, 0, 10, 9, 0. Of the 60 edges across at
/// sample 3499 in seeds 1, 3, 5, 8, 9, 10, 40 are eq. 7's (consecutive winners), 16 a
/// statistical insertion's (between a runner and its farthest neighbour, already joined
/// across), 4 the spontaneous insertion's join to the cell it beat; 54 have an end that won
/// on both sides (seed 10's two join a cell that won 1.2 m apart, left of the pillar and
/// right of the wall). At the wins of a two-sided cell the internal positions on the two
/// sides were 0.03-0.19 m apart (seeds 1, 3), the true ones at least 0.44 m (a 4 cm wall, a
/// 40 cm robot). A fold follows a stretch where the internal track turned against the true
/// one (seed 3, samples 963-980: 19 degrees and 14 % long over 1.4 m), bringing the robot on
/// one side to the other side's cells, and the sensors do not keep the sides apart: right
/// of the wall (y 0.3-1.0 m) the weighted light ring differs from the one straight across by
/// 0.29-0.36 and from the most similar place on the left by 0.23-0.27, what 6-9 cm of
/// position weigh, against d_acc 0.8. The folds need the correlations, not only the drift:
/// with exact odometry and both correlations off every seed shows the clear gap (the next
/// test), with exact odometry and both on 5 of 10 fold; no eps_or (0.02-0.2) or the thesis's
/// axis fit (`or_method=axis`) removes them under the drift (4-8 of 10 seeds fold). Neither
/// the spontaneous insertion's join (edges from
/// the path only: 2, 0, 9, 0, 2, 8, 0, 17, 24, 4) nor the winner's 2-sample lag in the
/// measure (fixed: seeds 1-4 unchanged) is the cause. Nothing in the thesis's §4.2.4 keeps
/// a correlation from pulling the pose across a thin wall (the audit is in
/// `world_model::model`'s doc): the winner's topological neighbourhood lies on one side only
/// while the winner does, and the thesis gives no confidence of the estimate and no limit on
/// the correction beyond the fractions eps_pos and eps_or. Its own readings, now parameters,
/// do not help under the drift; a clear gap closed in time, of seeds 1-10
/// (`examples/alice_dynamic_probe`): default 4; d_i in p_est over the whole situation
/// (`pos_distance=situation`, the thesis's) 4; the heading corrected only while p_est is
/// within 0.2 m (`or_pos_tolerance=0.2`, §4.2.4's "certain tolerance") 4, with both 4; only
/// the position correlation 5, only the orientation one 5; w_pos 2, 3, 6: 6, 3, 4;
/// or_radius 0.05, 0.08, 0.1: 6, 4, 4. With exact odometry the count falls as the heading
/// estimate's cell comes nearer: or_radius 0.05 8 (0.15, the default, 4), eps_or = 0 10,
/// `or_pos_tolerance=0.2` 8, `or_method=axis` 4; a cell up to 15 cm away turns the lamps'
/// bearings by parallax (our reading of that dependence). Correcting the position only
/// from a winner the network accepts (d_opt <= d_acc, tried and not kept: the thesis is
/// silent) removes the exact-odometry folds (2 of 10 close after 2000) but not the drifted
/// ones (4 clear), and costs the position (1.35 against 0.84 m with both correlations,
/// seeds 1-10). What the thesis saw, "the
/// absolute position error between the two sides of the gap is larger than it would be
/// without the splitting wall", is the sides drifting apart, not folding: our light rings
/// keep the sides apart by what 6-9 cm of position weigh (above), so a drifted frame folds
/// them. Tolerance: at most 1 edge across at removal, closed within 1500, seeds 1-10.
#[test]
#[ignore = "not reproduced: the internal frame folds the wall's two sides in 4 of seeds 1-10 (4-5 edges across at removal, seeds 1, 3, 5, 8)"]
fn a_removed_wall_leaves_a_gap_that_closes_within_1500_situations() {
    for seed in 1..=10 {
        let e = dynamic(seed, &Params::default()).expect("experiment runs");
        assert!(
            e.gap_clear(),
            "seed {}: {:?} edges across, {:?} cells on both sides",
            e.seed,
            e.gap_edges_at_removal,
            e.gap_two_sided_at_removal
        );
        assert!(
            e.gap_closed_in_time(),
            "seed {}: {:?}",
            e.seed,
            e.gap_closed_after
        );
    }
}

/// The control for the test above: with exact odometry (but 1 % of each turn) and both
/// correlations off, the internal position is the true one and cannot fold, and then the
/// thesis's edge rule leaves the standing wall a clear gap that closes after its removal:
/// edges across at removal 0 in every one of seeds 1-10, closed 250, 250, 1250, 750, 1000,
/// 250, 1000, 250, 500, 250 samples after. With exact odometry and both correlations on,
/// seeds 1, 3, 5, 9, 10 fold (3, 6, 1, 14, 4 cells on both sides; 3, 14, 3, 17, 4 edges
/// across): the orientation correlation alone folds seeds 8 and 10, the position
/// correlation alone none. Tolerance (the thesis's): at most 1 edge across at removal,
/// closed within 1500 samples, seeds 1-10.
#[test]
fn with_the_true_position_the_wall_leaves_a_clear_gap_that_closes_within_1500() {
    let p = Params {
        eps_pos: 0.0,
        eps_or: 0.0,
        ..Params::default()
    };
    for seed in 1..=10 {
        let e = dynamic_with(seed, &p, false).expect("experiment runs");
        assert!(
            e.gap_clear(),
            "seed {seed}: {:?} edges across",
            e.gap_edges_at_removal
        );
        assert!(
            e.gap_closed_in_time(),
            "seed {seed}: closed after {:?}",
            e.gap_closed_after
        );
    }
}

/// The navigation experiment's exploration, map fit and test path only (no test run).
fn explored(seed: u64, drift: Drift, scene: Scene) -> NavReport {
    let mut o = NavOptions::new(seed, Params::default());
    o.runs = 0;
    o.drift = drift;
    o.scene = scene;
    navigation(&o).expect("navigation runs")
}

fn navigation_runs_with(learn: bool) -> Vec<NavReport> {
    SEEDS
        .iter()
        .map(|&s| {
            let mut o = NavOptions::new(s, Params::default());
            o.learn = learn;
            navigation(&o).expect("navigation runs")
        })
        .collect()
}

fn navigation_runs() -> Vec<NavReport> {
    navigation_runs_with(true)
}

/// Over the seeds, run 1's total over run 5's (the factor of the pooled runs: one leg stuck
/// at its cap decides a single seed's factor).
fn pooled(r: &[NavReport], f: fn(&TestRun) -> f64) -> f64 {
    let first: f64 = r.iter().map(|n| f(&n.runs[0])).sum();
    let fifth: f64 = r.iter().map(|n| f(&n.runs[4])).sum();
    first / fifth.max(1.0)
}

/// Thesis §5.3 (simulation, static maps, static drift up to 5 deg/m): after four test runs
/// the time to target is 2-3x better, plan refinements 3-4x fewer, reversed manoeuvres about
/// 5x fewer. Ours (`--task alice-navigation`: 6000 situations of exploration, the map frozen,
/// out and back between well-known open cells 1.65-3.21 m apart, 5 deg/m, A* with the weights
/// moving to flooding, the reinforcement-trained memory of `world_model::execute` commanding
/// the map's edge from the winner cell), run 1 over run 5 per seed 1-4: time 0.97, 0.47,
/// 3.55, 2.91; refinements 0.50, 0.45, 4.36, 3.67; reversals 1.00, 0.19, 4.75, 4.89; pooled
/// over seeds 1-4 1.90, 2.06, 2.53. Pooled over seeds 1-10: time 1.14, refinements 1.07,
/// reversals 1.15, 87 of 100 legs; the control, a memory that never learns (`--no-learning`),
/// 0.79, 0.74, 0.72, 75 legs: single-seed factors are decided by which leg happens to stick
/// at the 1500-sample cap. With `--drift static`, seeds 1-40: 0.73, 0.64, 0.56 (control 1.05,
/// 0.99, 1.06), 389 of 400 legs (control 387), the learned run 5 faster than the control's
/// in 21 of 40 seeds. NOT reproduced. `pos_sigma` halved the time every run takes (seeds
/// 1-30, run 1: 17,394 samples against 39,706) but not run 1 over run 5. The analysis below
/// was made before `pos_sigma` (then pooled over seeds 1-10 0.91, 0.88, 0.89, control 1.01,
/// 1.00, 0.95; per seed 1-4 time 3.37, 0.31, 2.36, 1.20). Why, measured with the truth (the
/// report's `exploring` and per-run `correlation`, seeds 1-10):
/// - The robot gets lost against the map as it drives: the internal pose is 0.74, 0.94, 1.25,
///   1.16, 1.10 m and 54, 87, 99, 94, 72 degrees off in runs 1-5 (no static drift: 0.60 ->
///   0.81 m, 7 -> 23 degrees), judged through the similarity fit of the map to the world.
/// - The position correlation cannot pull it back: its estimate comes from the winner's
///   neighbourhood, and the winner search weighs the position (4 per metre), so the winner is
///   the cell 0.09-0.10 m from the internal pose while the place where that cell won while
///   exploring is 0.87-1.32 m from the truth (exploring: 0.16 and 0.38 m; there the map itself
///   follows the robot, the thesis's "mutual stabilizing technique", §4.2.4).
/// - The orientation correlation then compares the light ring with another place's: it
///   applies on 28 % of the samples while exploring but on 13, 5, 3, 2, 10 % in runs 1-5; the
///   residual gate rejects 60-71 % of the samples, and 17-35 % have no aligning turn within
///   the search (the heading error is already beyond it). The static drift turns the heading
///   unopposed, and run 5 starts worse localised than run 1.
/// - Letting the map keep learning while navigating (`--adapting-map`, the thesis's world
///   model has no separate application phase, §3.1) makes the orientation correlation apply
///   again (22-35 %) but against a map that follows the lost pose: 56 of 100 legs, pooled
///   time 0.70, refinements 0.66.
/// - A localisation that holds is not enough either. Holding the internal pose at the truth in
///   the map's frame after every sample (`--true-pose`, a counterfactual, through the judge's
///   similarity fit): 93 of 100 legs, pooled 1.39, 1.47, 1.49, but its no-learning control
///   gains as much (1.43, 1.37, 1.43; 90 legs), so the gain is not the memory's. 1130 of its
///   2369 steps are drives blocked by a wall or the pillar (control 1581 of 2779). Judged from
///   the truth (per leg `aimed_outside`, `blocked_aimed_outside`, `blocked_at_once`,
///   `blocked_cutting`, `beyond_proposals`; over `--true-pose` with and without
///   `--step-from pose` and their controls): 45-53 % of the steps aim at a sub-goal whose
///   internal position is no place the 40 cm body can stand, 75-96 % of those are blocked
///   (10-34 % of the others); of the blocked steps 67-90 % are these, 9-18 % start against
///   the obstacle, 3-5 % cut a corner. The map is 4-40 % larger than the world (fit scale
///   0.71-0.96) and its cells 0.23-0.35 m off after the fit, about an edge's length, so
///   84-87 % of the steps need a correction beyond the memory's 21 proposals (97-98 % with
///   the lost pose). With the former rigid fit the counterfactual gave 1.10, 1.04, 1.08
///   (control 1.01, 0.96, 1.03), 2083 of 3711 steps blocked.
/// - Measuring the command from the internal pose too (`--true-pose --step-from pose`): 1.64,
///   1.71, 1.80, 92 of 100 legs (control 1.66, 1.68, 1.77, 86 legs); with the rigid fit it was
///   1.58, 1.60, 1.66 against a control of 1.01, 1.00, 1.00. Without the counterfactual
///   (`--step-from pose`) 1.41, 1.45, 1.47 against a control of 1.09, 1.07, 1.06, but not run
///   by run (runs 1-5: 12,309, 17,673, 15,935, 12,046, 8705 samples) and 73 of 100 legs.
/// - §5.3's simulator "includes a 2-d model of light distributions as well as a static drift
///   model" (`--drift static`, our reading: that drift model only, the odometry otherwise
///   exact but for the turns' 1 %): the map then has the world's scale (the test above) and
///   run 1 starts better localised (0.42 m, 26.5 degrees, seeds 1-40), but the orientation
///   correlation does not hold the static drift against the frozen map: 46, 64, 70, 66
///   degrees in runs 2-5 (1 deg/m: 7 -> 40 degrees over runs 1-5, 0 deg/m: 7 -> 12; seeds
///   1-20; neither eps_or 0.3, or_max_shift 1.0, or_radius 0.3 nor or_max_residual 0.5 holds
///   5 deg/m). Seeds 1-40, samples runs 1-5: 25097, 18412, 19012, 18582, 18530 against the
///   control's 23167, 25634, 32322, 37636, 33818: run 1 over run 5 1.35, 1.44, 1.48 (time,
///   refinements, reversals; control 0.69, 0.63, 0.61), the control's run 5 over the learned
///   one 1.83, 2.06, 2.23 (faster in 24 of 40 seeds). So the memory does compensate what the
///   drift costs (the control slows as the heading is lost, the learned runs 2-5 stay level),
///   but the thesis's run 1 over run 5 is not there, and the gain is not stable across seed
///   sets (seeds 1-20: control run 5 over learned 2.44; seeds 21-40: 1.26, 10 of 20 faster).
///   With the map static (`--test-map static`) 0.86, 0.76, 0.82 (control 0.94, 0.92, 0.89;
///   seeds 1-20).
/// - In §5.3's own scene as the thesis describes it (`--scene corridors`: the test path from
///   between jagged obstacles through a 0.7 m corridor into a pocket and back, the exploration
///   with wall following; the next test) no gain either, seeds 1-20: with `--drift static`
///   run 1 over run 5 1.02, 0.99, 0.95 (control 1.23, 1.20, 1.22), 118 of 200 legs (control
///   123); under ALICE's drift 0.88, 0.90, 0.83 (control 1.09, 1.08, 1.05), 101 legs (control
///   95). With the pose held at the truth as well (`--true-pose`): 1.03, 1.00, 1.01 (control
///   1.03, 1.07, 1.06), 115 of 200 legs (control 97). The corridor defeats the step execution
///   itself (legs stuck at the cap in both directions), not only the localisation, whatever
///   the memory has learned: the correlations distort the map even without drift (fit
///   residual 0.18-0.38 m, seeds 1, 2, 4, 5, where the corridor leaves 7-12 cm a side).
/// - What the memory could learn at all: with the map exact (exact odometry and both
///   correlations off while exploring, `--drift static --qt-param eps_pos=0 --qt-param
///   eps_or=0`: fit residual 0.05-0.07 m) and the pose held at the truth, every one of 200
///   legs is reached in either scene (seeds 1-20) and there is nothing to learn: corridors
///   run 1 over run 5 0.99, 0.99, 0.92 (control 1.12, 1.20, 1.24), the pillar scene 0.95,
///   0.83, 1.33 (control 1.07, 1.32, 2.75). 5 deg/m over a step of about 0.3 m curves the
///   path by 1.5 degrees, under a centimetre at its end: the static drift costs a command
///   nothing unless it has turned the internal heading, and the correlations that would
///   keep that turn small enough to navigate by are what lose the pose (above). The thesis's
///   drift compensation needs the regime in between, which our model does not have.
///
/// Tolerance: pooled time factor >= 2 and refinement factor >= 3 over seeds 1-4, and both
/// above the control's.
#[test]
#[ignore = "not reproduced: pooled run 1 over run 5 time 1.14x, refinements 1.07x (seeds 1-10; control without learning 0.79x, 0.74x); see the doc comment"]
fn navigation_improves_after_four_runs() {
    let r = navigation_runs();
    let c = navigation_runs_with(false);
    let time = |t: &TestRun| t.samples as f64;
    let refine = |t: &TestRun| t.refinements as f64;
    let (lt, lr) = (pooled(&r, time), pooled(&r, refine));
    let (ct, cr) = (pooled(&c, time), pooled(&c, refine));
    assert!(lt >= 2.0 && lt > ct, "time factor {lt} (control {ct})");
    assert!(
        lr >= 3.0 && lr > cr,
        "refinement factor {lr} (control {cr})"
    );
}

/// Why the §5.3 judge finds the internal map larger than the world: ALICE's odometry drift.
/// The similarity fit's scale (world metres per internal metre, `map_scale`) after the 6000
/// situations of exploration, seeds 1-10: under ALICE's drift (20-25 % translational, up to
/// 0.5 degrees/metre rotational) 0.92, 1.02, 0.93, 0.89, 0.74, 0.92, 1.01, 0.91, 1.00, 0.84
/// (mean 0.92: the map up to 35 % larger), cells 0.15-0.34 m from their places after the fit;
/// with the odometry exact but for the turns' 1 % (`--drift static`) 1.09, 1.09, 1.07, 1.06,
/// 1.10, 1.09, 1.13, 1.10, 1.07, 1.08 (the map 6-13 % smaller than the world), cells
/// 0.08-0.15 m off. Before `pos_sigma` (the estimate's weights as wide as d_acc) the drift's
/// scales were 0.71-0.96 and exact odometry's 0.94-1.04. Tolerance (seeds 1-4): exact
/// odometry within 0.95..=1.15 in every seed; ALICE's drift at least 0.05 below it in every
/// seed and at most 0.95 in the mean.
///
/// Where the exact odometry's shrink comes from, measured (not asserted here). It forms while
/// the map is young and relaxes as it settles: mean scale over seeds 1-10 after 1500, 3000,
/// 6000 and 12000 situations 1.13, 1.10, 1.09, 1.07 (with the wide weights 1.10, 1.06, 1.01,
/// 0.98). And the position estimate leans away from the walls and the pillar: with a map kept
/// in the world's frame, p_est lies 5.1 cm (clearance 0.2-0.4 m) and 7.3 cm (0.4-0.6 m)
/// farther from the nearest obstacle than the robot, pooled over seeds 1-10
/// (`examples/alice_estimate_bias_probe`). The single best match leans the same
/// (`pos_sigma=0.005`: 5.1 and 7.2 cm), so the winner itself does: a matching error can pick
/// a cell on the open side but none beyond the obstacle. Correcting the pose towards such an
/// estimate pulls the young map inwards. The wide weights lean as far (12.3 and 6.7 cm) and
/// their map relaxes faster; why, is not examined.
#[test]
fn the_map_is_larger_than_the_world_by_the_odometrys_drift() {
    let scale = |seed: u64, drift: Drift| explored(seed, drift, Scene::Pillar).map_scale;
    let mut sum = 0.0;
    for seed in SEEDS {
        let (alice, exact) = (scale(seed, Drift::Alice), scale(seed, Drift::Static));
        assert!(
            (0.95..=1.15).contains(&exact),
            "seed {seed}: exact odometry {exact}"
        );
        assert!(
            alice <= exact - 0.05,
            "seed {seed}: ALICE's drift {alice}, exact {exact}"
        );
        sum += alice;
    }
    assert!(
        sum / SEEDS.len() as f64 <= 0.95,
        "ALICE's drift: mean {}",
        sum / 4.0
    );
}

/// §5.3's scene as the thesis describes it (`--scene corridors`, `builtin:alice-navigation`):
/// the exploration, the wanderer with §6.2's wall following, gets through the upper-left
/// corridor, so the test path's far end is a cell that won in the pocket beyond it. Ours,
/// the target cell's place from the pocket's centre, seeds 1-8: 0.09, 0.25, 1.02 (the pocket
/// never entered), 0.26, 0.25, 0.19, 0.27, 0.19 m. Tolerance: within 0.3 m in 3 of seeds 1-4.
#[test]
fn the_corridor_scenes_test_path_ends_beyond_the_corridor() {
    let within = SEEDS
        .iter()
        .filter(|&&seed| {
            explored(seed, Drift::Static, Scene::Corridors)
                .target_from_pocket_m
                .is_some_and(|m| m < 0.3)
        })
        .count();
    assert!(within >= 3, "{within} of 4 seeds end in the pocket");
}

/// What the navigator does reach: planning over the QT map and executing step by step gets
/// the robot to the target cell in 38 of the 40 legs of seeds 1-4 (cap 1500 situations, about
/// 8 minutes, a leg; before `pos_sigma` 34, and 23 when the far end was the farthest open cell, which had won only 3-12
/// times while exploring; 29 measuring the command from the internal pose, 28 from the cell
/// without that choice); every leg plans at least once and drives. Tolerance: at least 30 legs.
#[test]
fn the_navigator_reaches_its_target_in_most_legs() {
    let r = navigation_runs();
    let legs: Vec<_> = r
        .iter()
        .flat_map(|n| n.runs.iter().flat_map(|t| t.legs.iter()))
        .collect();
    assert_eq!(legs.len(), 40);
    assert!(legs.iter().all(|l| l.steps > 0), "a leg never drove");
    let reached = legs.iter().filter(|l| l.reached).count();
    assert!(reached >= 30, "reached {reached} of 40 legs");
    for n in &r {
        assert!(n.associations > 0 && n.cells > 50, "{} cells", n.cells);
    }
}

/// Why the orientation correlation (§4.2.4, eq. 9) and the position are bound together, which
/// stands behind the map distortions the tests above report: the light ring's shift against a
/// cell's stored ring reads a heading error exactly only at the cell's own spot. Measured in the
/// §4.5 scene at five spots, the stored ring the mean of 200 world-frame rings at random headings,
/// 20 readings per heading error of -20..20 degrees, sensor seeds 1-10: at the cell's spot the mean
/// read error is within 0.34-0.72 degrees of the true one (worst spot and error, per seed); 10 cm
/// away, with no heading error, the lamps' parallax reads 3.2-7.3 degrees (mean over the spots
/// 5.09-5.28 per seed). So a position 10 cm off turns the heading by degrees, and a turned heading
/// moves the position on. What the correlations cost where there is little to correct
/// (`cargo run --release -p emulator --example alice_correlation_probe -- exact`: the odometry
/// exact but for 1 % of each turn; late absolute position error in metres / aligned heading error
/// in degrees, mean of seeds 1-10): both 0.39/3.9, the orientation correlation alone 1.32/6.4, the
/// position correlation alone 0.41/2.2, the plain odometry 0.10 m (before `pos_sigma` both
/// 0.60/6.1, position alone 0.62/2.3). Under ALICE's drift (the same without `exact`) they pay:
/// 0.49/5.2, 3.01/7.8, 1.86/8.3, the odometry 3.03 m. Tolerance: within
/// 1.5 degrees at the spot; at least 2 degrees in the mean 10 cm away, every seed.
#[test]
fn the_light_ring_reads_a_turn_at_the_cells_spot_and_a_parallax_beside_it() {
    use emulator::builtin::alice::alice;
    use emulator::geometry::Point;
    use emulator::rng::SimRng;
    use emulator::sensors::alice::Sensors;
    use world_model::situation::{ring_shift, rotate_to_world};
    let arena = alice();
    let walls = arena.segment_set();
    let spots = [(0.6, 0.6), (1.5, 0.5), (2.4, 2.4), (0.5, 2.0), (2.5, 1.0)];
    let p = Params::default();
    for seed in 1..=10u64 {
        let mut sensors = Sensors::new(SimRng::new(seed, 102));
        let mut rng = SimRng::new(seed, 5);
        let mut ring = |x: f64, y: f64, believed: f64, rng: &mut SimRng| {
            let h = rng.uniform() * std::f64::consts::TAU;
            let l = sensors.light(&walls, &arena.lights, Point::new(x, y), h);
            let mut w = Vec::new();
            rotate_to_world(&l, h + believed, &mut w);
            w
        };
        let (mut worst, mut parallax) = (0.0f64, Vec::new());
        for &(x, y) in &spots {
            let mut stored = vec![0.0; 24];
            for _ in 0..200 {
                for (s, v) in stored.iter_mut().zip(ring(x, y, 0.0, &mut rng)) {
                    *s += v / 200.0;
                }
            }
            let mut read = |at: f64, e: f64, rng: &mut SimRng| {
                let reads: Vec<f64> = (0..20)
                    .filter_map(|_| {
                        let w = ring(x + at, y, e, rng);
                        ring_shift(&w, &stored, p.or_max_shift, p.or_max_residual).ok()
                    })
                    .collect();
                assert!(
                    reads.len() >= 15,
                    "seed {seed} at ({x}, {y}): {} reads",
                    reads.len()
                );
                reads.iter().sum::<f64>() / reads.len() as f64
            };
            for e in [-20.0f64, -10.0, -5.0, 0.0, 5.0, 10.0, 20.0] {
                let e = e.to_radians();
                worst = worst.max((read(0.0, e, &mut rng) - e).abs().to_degrees());
            }
            parallax.push(read(0.1, 0.0, &mut rng).abs().to_degrees());
        }
        let mean = parallax.iter().sum::<f64>() / parallax.len() as f64;
        assert!(
            worst <= 1.5,
            "seed {seed}: {worst:.2} degrees off at the cell's spot"
        );
        assert!(
            mean >= 2.0,
            "seed {seed}: 10 cm away reads only {mean:.2} degrees"
        );
    }
}
