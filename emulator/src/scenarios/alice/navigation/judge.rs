//! What the experiment measures from the truth and the model's counters, to judge only (the
//! robot never sees it): the map as the judge remembers it, the correlations' tally, where each
//! cell won, and the fit of the map's frame onto the world.

use std::collections::HashMap;

use world_model::{QtModel, Stats};

use super::{CorrelationJudge, MapChanges};
use crate::geometry::Point;

/// The map as the judge remembers it: cells' positions and update counts, the edges.
pub(super) struct MapSnapshot {
    pub(super) stats: Stats,
    pub(super) cells: HashMap<u32, ((f64, f64), u32)>,
    pub(super) edges: std::collections::HashSet<(u32, u32)>,
}

impl MapSnapshot {
    pub(super) fn new(m: &QtModel) -> Self {
        let net = m.network();
        let cells = net
            .cells()
            .map(|(id, c)| (id, (net.position(id), c.updates)))
            .collect();
        let edges = net
            .cells()
            .flat_map(|(id, c)| c.edges.iter().map(move |e| (id.min(e.0), id.max(e.0))))
            .collect();
        MapSnapshot {
            stats: m.stats().clone(),
            cells,
            edges,
        }
    }

    /// What changed from this snapshot to `m`.
    pub(super) fn changes(&self, m: &QtModel) -> MapChanges {
        let now = MapSnapshot::new(m);
        let d = now.stats.since(&self.stats);
        let mut out = MapChanges {
            cell_moves: d.cell_moves,
            inserted: d.spontaneous + d.statistical,
            removed: d.removed,
            edges_created: d.edges_created,
            edges_refreshed: d.edges_refreshed,
            edges_worn: d.edges_worn,
            edges_new: now.edges.difference(&self.edges).count(),
            edges_gone: self.edges.difference(&now.edges).count(),
            rates: m.rates(),
            ..MapChanges::default()
        };
        for (id, (p, u)) in &self.cells {
            if let Some((q, v)) = now.cells.get(id) {
                let d = (p.0 - q.0).hypot(p.1 - q.1);
                if d > 0.0 {
                    out.cells_moved += 1;
                    out.max_moved_m = out.max_moved_m.max(d);
                }
                out.updates += u64::from(v.saturating_sub(*u));
            }
        }
        out
    }
}

/// Counts behind a [`CorrelationJudge`]: the model's counters when the stretch began, and what
/// only the truth gives.
#[derive(Clone, Debug, Default)]
pub(super) struct Tally {
    pub(super) from: Stats,
    pub(super) samples: u64,
    pub(super) touching: u64,
    pub(super) winner_to_pose: (f64, u64),
    pub(super) winner_place: (f64, u64),
}

impl Tally {
    /// A tally that starts at the model's counters `from`.
    pub(super) fn starting(from: Stats) -> Tally {
        Tally {
            from,
            ..Tally::default()
        }
    }

    /// The stretch judged, up to the model's counters `now`.
    pub(super) fn judge(&self, now: &Stats) -> CorrelationJudge {
        let n = self.samples.max(1) as f64;
        let mean = |(sum, k): (f64, u64)| sum / k.max(1) as f64;
        let d = now.since(&self.from);
        let f = |count: u64| count as f64 / n;
        CorrelationJudge {
            samples: self.samples,
            or_applies: f(d.or_corrections),
            or_untrusted: f(d.or_untrusted),
            or_no_cell: f(d.or_no_cell),
            or_no_pattern: f(d.or_no_pattern),
            or_no_turn: f(d.or_no_turn),
            or_residual: f(d.or_residual),
            touching: self.touching as f64 / n,
            winner_to_pose_m: mean(self.winner_to_pose),
            winner_place_to_truth_m: mean(self.winner_place),
        }
    }
}

/// Truth, to judge only: per cell, the sum of the true positions where it won while exploring
/// and how often; a cell's place is their mean.
#[derive(Debug, Default)]
pub(super) struct Places(pub(super) HashMap<u32, (f64, f64, u32)>);

impl Places {
    pub(super) fn record(&mut self, cell: u32, at: Point) {
        let e = self.0.entry(cell).or_insert((0.0, 0.0, 0));
        e.0 += at.x;
        e.1 += at.y;
        e.2 += 1;
    }

    /// Where `cell` won on average, and how often (None: it never won).
    pub(super) fn of(&self, cell: u32) -> Option<((f64, f64), u32)> {
        let &(x, y, k) = self.0.get(&cell)?;
        let n = f64::from(k);
        Some(((x / n, y / n), k))
    }

    /// `cell`'s place's distance from `to`.
    pub(super) fn distance(&self, cell: u32, to: (f64, f64)) -> Option<f64> {
        self.of(cell).map(|((x, y), _)| (x - to.0).hypot(y - to.1))
    }
}

/// A cell's internal position and its place in the world.
pub(super) type Pair = ((f64, f64), (f64, f64));

/// The similarity transform that maps internal positions onto the world (least squares over
/// the cells' places): world = scale R(rotation) (internal - from) + to. The scale is there
/// because the map's size is not the world's: over seeds 1-10 the internal map is 4-40 %
/// larger (scale 0.71-0.96; the odometry's drift: with the odometry exact, `Drift::Static`,
/// 0.94-1.04, test `the_map_is_larger_than_the_world_by_the_odometrys_drift`), and a rigid
/// fit left that as residual and put the `true_pose` counterfactual's pose inside the ring of
/// cells the map has near the walls (17-42 % of the cells' internal positions then lay where
/// the body cannot stand, while only 1-9 cells' places did).
#[derive(Clone, Copy, Debug)]
pub(super) struct MapFit {
    pub(super) from: (f64, f64),
    pub(super) to: (f64, f64),
    pub(super) rotation: f64,
    pub(super) scale: f64,
    pub(super) residual_m: f64,
}

impl MapFit {
    /// Fit `pairs` of (internal, world) points; None for fewer than three.
    pub(super) fn new(pairs: &[Pair]) -> Option<MapFit> {
        if pairs.len() < 3 {
            return None;
        }
        let n = pairs.len() as f64;
        let mean = |f: &dyn Fn(&Pair) -> f64| pairs.iter().map(f).sum::<f64>() / n;
        let from = (mean(&|p| p.0 .0), mean(&|p| p.0 .1));
        let to = (mean(&|p| p.1 .0), mean(&|p| p.1 .1));
        let (mut dot, mut cross, mut norm) = (0.0, 0.0, 0.0);
        for (a, b) in pairs {
            let (ax, ay, bx, by) = (a.0 - from.0, a.1 - from.1, b.0 - to.0, b.1 - to.1);
            dot += ax * bx + ay * by;
            cross += ax * by - ay * bx;
            norm += ax * ax + ay * ay;
        }
        let mut fit = MapFit {
            from,
            to,
            rotation: cross.atan2(dot),
            scale: if norm > 1e-12 {
                dot.hypot(cross) / norm
            } else {
                1.0
            },
            residual_m: 0.0,
        };
        fit.residual_m = pairs
            .iter()
            .map(|(a, b)| {
                let w = fit.world(*a);
                (w.0 - b.0).hypot(w.1 - b.1)
            })
            .sum::<f64>()
            / n;
        Some(fit)
    }

    /// The inverse of [`MapFit::world`].
    pub(super) fn internal(&self, w: (f64, f64)) -> (f64, f64) {
        let (s, c) = (-self.rotation).sin_cos();
        let (x, y) = (
            (w.0 - self.to.0) / self.scale,
            (w.1 - self.to.1) / self.scale,
        );
        (c * x - s * y + self.from.0, s * x + c * y + self.from.1)
    }

    pub(super) fn world(&self, p: (f64, f64)) -> (f64, f64) {
        let (s, c) = self.rotation.sin_cos();
        let (x, y) = (
            self.scale * (p.0 - self.from.0),
            self.scale * (p.1 - self.from.1),
        );
        (c * x - s * y + self.to.0, s * x + c * y + self.to.1)
    }
}
