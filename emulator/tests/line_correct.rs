//! Seed 003 (Mächler 1998) reproduced in the emulator with the unchanged firmware: a Khepera
//! with a constant per-wheel speed bias (±1 %, §2.3.3) surveys a 10 cm floor grid for 40 m,
//! the grid fitter steering (§2.6), and corrects its odometry at every line pulse with the PPD
//! (§2.5). Claim (Fig 2-25, §2.7): the corrected position stays on the grid, within half a
//! square (50 mm), while plain odometry drifts far off; the nearest-line baseline, which
//! never corrects the heading, is lost too (§2.2.4); the PPD survives about three missed lines
//! in a row ("stable enough to miss three or more grid lines").
//!
//! The emulator's sensor misses 2 % of lines and doubles 2 % by default. Figures from these
//! runs are quoted in the report of the work that added them; `--nocapture` prints them.
#![allow(clippy::unwrap_used, clippy::panic)]

use emulator::builtin::floor_grid;
use emulator::scenarios::line_correct::{run_line_correct, LineCorrectOptions, LineCorrectReport};
use robot_firmware::KHEPERA;

/// Half a grid square, mm: the thesis's bound on the corrected error.
const HALF_SQUARE_MM: f64 = 50.0;

fn run(seed: u64, line_miss: Option<f64>) -> LineCorrectReport {
    let mut o = LineCorrectOptions::new(&KHEPERA);
    o.seed = seed;
    if let Some(p) = line_miss {
        o.noise.line_miss = p;
    }
    let r = run_line_correct(floor_grid(), &o).unwrap();
    println!(
        "seed {seed:>2} bias {:+.2}/{:+.2} % | {:>4.1} m | pulses {}/{} true, longest miss run {} | \
         corrected max {:>5.1} mean {:>4.1} final {:>4.1} | uncorrected max {:>5.0} final {:>5.0} \
         | nearest-line max {:>5.0} final {:>5.0} mm",
        r.wheel_bias[0] * 100.0,
        r.wheel_bias[1] * 100.0,
        r.distance_m,
        r.pulses,
        r.true_crossings,
        r.max_missed_run,
        r.corrected.max_mm,
        r.corrected.mean_mm,
        r.corrected.final_mm,
        r.uncorrected.max_mm,
        r.uncorrected.final_mm,
        r.baseline.max_mm,
        r.baseline.final_mm
    );
    r
}

#[test]
fn corrected_error_stays_within_half_a_square_over_40_m_while_odometry_drifts() {
    let reps: Vec<_> = (1..=6).map(|s| run(s, None)).collect();
    for r in &reps {
        assert!(r.distance_m >= 40.0, "{r:?}");
        assert_eq!(r.collisions, 0, "the survey keeps off the walls: {r:?}");
        assert!(r.corrected.max_mm < HALF_SQUARE_MM, "{r:?}");
        assert!(r.corrected.mean_mm < 5.0, "{r:?}");
        // Plain odometry from the same counts leaves the grid square within the run.
        assert!(r.uncorrected.max_mm > 4.0 * HALF_SQUARE_MM, "{r:?}");
        assert!(
            r.ppd_size_max_mm < HALF_SQUARE_MM,
            "the PPD stays bounded: {r:?}"
        );
        // The wheel bias is the thesis's: within ±1 %.
        assert!(r.wheel_bias.iter().all(|b| b.abs() <= 0.01), "{r:?}");
    }
    // The baseline gets lost (more than half a square) in nearly every run.
    let lost = reps
        .iter()
        .filter(|r| r.baseline.max_mm > HALF_SQUARE_MM)
        .count();
    assert!(lost >= reps.len() - 1, "nearest-line lost in {lost} runs");
}

#[test]
fn runs_of_three_and_more_missed_lines_are_tolerated() {
    // 30 % of crossings missed at random: runs of 3-5 missed lines in a row occur in every
    // 40 m run. Past the maximum odometry error there is no recovery (§2.7): a robot that
    // meets a crossing right after such a run can pick the wrong family and be lost (seed 2
    // here, whose PPD chose an x line where it crossed a y line); the others stay within half
    // a square.
    let reps: Vec<_> = (1..=6).map(|s| run(s, Some(0.3))).collect();
    let ok: Vec<_> = reps
        .iter()
        .filter(|r| r.corrected.max_mm < HALF_SQUARE_MM)
        .collect();
    assert!(
        ok.len() >= 5,
        "{} of {} within half a square",
        ok.len(),
        reps.len()
    );
    for r in &ok {
        assert!(r.max_missed_run >= 3, "{r:?}");
        assert!(
            r.pulses * 10 < r.true_crossings * 8,
            "misses happened: {r:?}"
        );
    }
}

#[test]
fn a_line_correct_run_is_deterministic() {
    let mut o = LineCorrectOptions::new(&KHEPERA);
    o.seed = 4;
    o.distance_m = 5.0;
    let a = run_line_correct(floor_grid(), &o).unwrap();
    let b = run_line_correct(floor_grid(), &o).unwrap();
    assert_eq!(a.series, b.series);
    assert_eq!(a.corrected, b.corrected);
    // An arena whose corner is off the firmware's grid is refused with the reason.
    let mut off = floor_grid();
    off.bounds.min.x = 0.03;
    let e = run_line_correct(off, &o).unwrap_err().to_string();
    assert!(e.contains("not on a line"), "{e}");
}
