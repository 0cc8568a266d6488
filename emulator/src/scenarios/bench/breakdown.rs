//! The benchmark's figures per class of arena (issue 32): every arena's detour (shortest free
//! path over the straight line to the goal area, [`crate::arena::free_path`]) and features,
//! and success, route length and collisions per detour class and per feature, so that a
//! regression in one class shows instead of vanishing in the total.
//!
//! Features come from the arena itself where it shows them (several beacons, a home area,
//! walls hiding the beacon, a small target, a large lab, a narrow gap every route passes; the
//! sizes in the robot's diameters, so a Khepera box is judged as a Micro-Rato lab is), so
//! files get them too; a generated arena adds the structures it was drawn with (`rows`,
//! `spiral`, `nested_u`, ...).

use serde::Serialize;

use super::{spread, Row, Spread};
use crate::arena::free_path::FreePath;
use crate::arena::{Arena, CIBERRATO_UNIT_M};
use crate::arena_gen::real_like::{detour_bucket, DETOUR_BUCKETS, NARROW_GAP_M};

/// The Micro-Rato robot's diameter, m: the thresholds below are in its diameters.
const RATO_M: f64 = 0.24;
/// A target radius under this many robot diameters is "small" (1.2 CiberRato units for the
/// Micro-Rato robot).
const SMALL_TARGET: f64 = 1.2 * CIBERRATO_UNIT_M / RATO_M;
/// A lab whose longer side is over this many robot diameters is "large" (20 units for the
/// Micro-Rato robot; Micro-Rato'99's is 17.5).
const LARGE_SIDE: f64 = 20.0 * CIBERRATO_UNIT_M / RATO_M;
/// A gap every route passes under this many robot diameters is "narrow".
const NARROW_GAP: f64 = NARROW_GAP_M / RATO_M;

/// The features `arena` shows to a robot of `diameter_m`, with the measured route's narrow
/// gap, after `declared` (the generator's structures).
pub fn features_of(
    arena: &Arena,
    route: Option<&FreePath>,
    declared: &[&'static str],
    diameter_m: f64,
) -> Vec<&'static str> {
    let mut out: Vec<&'static str> = declared.to_vec();
    let beacon_h = arena.beacons.first().map(|b| b.height_m);
    let marks = |t: &crate::arena::Target| arena.beacon_marks(t);
    let derived = [
        (arena.beacons.len() > 1, "several_beacons"),
        (
            arena.targets.iter().any(marks) && arena.targets.iter().any(|t| !marks(t)),
            "home_area",
        ),
        (
            beacon_h.is_some_and(|bh| {
                arena
                    .walls
                    .iter()
                    .any(|w| w.height_m.is_some_and(|h| h > bh))
            }),
            "hidden_beacon",
        ),
        (
            arena
                .target()
                .is_some_and(|t| t.radius_m < SMALL_TARGET * diameter_m),
            "small_target",
        ),
        (
            arena.bounds.width().max(arena.bounds.height()) > LARGE_SIDE * diameter_m,
            "large",
        ),
        (
            route.is_some_and(|r| r.bottleneck_m < NARROW_GAP * diameter_m),
            "narrow_gap",
        ),
    ];
    for (has, name) in derived {
        if has && !out.contains(&name) {
            out.push(name);
        }
    }
    out
}

/// Success and route figures over one class of runs.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Breakdown {
    /// The class: a detour bucket (`<1.3`, `1.3-2`, `2-4`, `>=4`) or a feature.
    pub class: String,
    /// Runs in it.
    pub runs: usize,
    /// Of those, successful.
    pub successes: usize,
    /// `successes / runs`.
    pub success_rate: f64,
    /// Route driven over the shortest free path, successful runs.
    pub route_ratio: Option<Spread>,
    /// Wall contacts per completed run.
    pub collisions_mean: f64,
}

fn breakdown(class: &str, rows: &[&Row]) -> Breakdown {
    let successes = rows.iter().filter(|r| r.success).count();
    let completed: Vec<&&Row> = rows.iter().filter(|r| r.sim_s.is_some()).collect();
    let contacts: u64 = completed
        .iter()
        .map(|r| u64::from(r.collisions.unwrap_or(0)))
        .sum();
    Breakdown {
        class: class.to_string(),
        runs: rows.len(),
        successes,
        success_rate: if rows.is_empty() {
            0.0
        } else {
            successes as f64 / rows.len() as f64
        },
        route_ratio: spread(
            rows.iter()
                .filter(|r| r.success)
                .filter_map(|r| r.route_ratio)
                .collect(),
        ),
        collisions_mean: if completed.is_empty() {
            0.0
        } else {
            contacts as f64 / completed.len() as f64
        },
    }
}

/// Per detour bucket (every bucket listed, empty ones too), in order.
pub fn by_detour(rows: &[Row]) -> Vec<Breakdown> {
    DETOUR_BUCKETS
        .iter()
        .map(|(name, _, _)| {
            let of: Vec<&Row> = rows
                .iter()
                .filter(|r| r.detour_ratio.map(detour_bucket) == Some(*name))
                .collect();
            breakdown(name, &of)
        })
        .collect()
}

/// Per feature seen in any row, by name.
pub fn by_feature(rows: &[Row]) -> Vec<Breakdown> {
    let mut names: Vec<&'static str> = rows
        .iter()
        .flat_map(|r| r.features.iter().copied())
        .collect();
    names.sort_unstable();
    names.dedup();
    names
        .into_iter()
        .map(|f| {
            let of: Vec<&Row> = rows.iter().filter(|r| r.features.contains(&f)).collect();
            breakdown(f, &of)
        })
        .collect()
}

/// The breakdown lines of the text report.
pub fn render(title: &str, b: &[Breakdown]) -> String {
    let mut out = format!("  {title}\n");
    for x in b.iter().filter(|x| x.runs > 0) {
        let route = x
            .route_ratio
            .map_or("-".to_string(), |s| format!("{:.2}x", s.median));
        out += &format!(
            "    {:<16} {:>4}/{:<4} ({:>5.1} %)  route median {route:>6}  collisions {:.1}/run\n",
            x.class,
            x.successes,
            x.runs,
            100.0 * x.success_rate,
            x.collisions_mean
        );
    }
    out
}
