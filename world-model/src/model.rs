//! The QT model's learning loop (§4.2): one call per sensor sample ([`QtModel::observe`]).
//!
//! Per sample:
//! 1. dead reckoning: the odometry's motion since the last sample (in the odometry's own robot
//!    frame) is applied to the internal pose, which is the corrected one;
//! 2. correlation (§4.2.4) against the network built so far: the internal position moves by
//!    eps_pos towards p_est, the positions of the current situation's winner (within
//!    g_search) and its topological neighbours weighted by ln(2 + u_i) exp(-d_i^2/pos_sigma^2)
//!    (the thesis: "using the sensor-distances d_i ... and the number of updates u_i", no
//!    formula; d_i over light and touch only by default, `pos_distance`); then, if
//!    `or_pos_tolerance` trusts the position, the heading by eps_or towards the orientation
//!    that aligns the light ring with the geometrically nearest cell's (eq. 9; within
//!    `or_radius`; eq. 10's principal axis is `or_method=axis`, the default aligns the
//!    whole ring). Nothing in §4.2.4 keeps a correlation from pulling the pose towards
//!    cells beyond a thin wall: the winner's neighbourhood is one side's only while the
//!    winner is, and the thesis limits neither the correction (beyond the fractions) nor
//!    the estimate's spread;
//! 3. the situation at the corrected pose joins the learning set, and the situations `l` to
//!    `l + k - 1` samples old are each presented once, so every situation is presented `k`
//!    times, the first time `l` samples after it was taken (the delay keeps a situation from
//!    correlating the pose it was taken at). Edges follow the sequence of first presentations
//!    only: a winner change between two re-presentations of different ages is not a move
//!    of the robot.

use std::collections::VecDeque;

use serde::Serialize;

use crate::network::Network;
use crate::params::{OrMethod, ParamError, Params, PosDistance};
use crate::situation::{
    axis_difference, principal_axis, ring_shift, situation, Pose, ShiftMiss, Weights,
};

/// One sensor sample as the robot gives it.
#[derive(Clone, Debug, PartialEq)]
pub struct Sample<'a> {
    /// Light readings, robot frame, sensor `i` at `i * 360/n` degrees from forward.
    pub light: &'a [f64],
    /// Binary touches, same layout.
    pub touch: &'a [bool],
    /// The robot's odometry pose (uncorrected, any frame: only its changes are used).
    pub odometry: Pose,
}

/// Counters since the model started.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Stats {
    /// Samples observed.
    pub samples: u64,
    /// Adaptation steps (k per sample once the delay is filled).
    pub adaptations: u64,
    /// Spontaneous insertions (d_opt > rho_s).
    pub spontaneous: u64,
    /// Statistical insertions (every n_insert misses).
    pub statistical: u64,
    /// Cells removed because they lost their last edge.
    pub removed: u64,
    /// Misses (d_opt > d_acc), n_miss.
    pub misses: u64,
    /// Position corrections applied.
    pub pos_corrections: u64,
    /// Orientation correlation, one outcome per sample observed while `eps_or > 0`, named for
    /// the first gate that stopped it, in the order the model applies them (the sum is
    /// [`Stats::or_reached`]): the position estimate is not within `or_pos_tolerance` of the
    /// internal position (or there is none while the tolerance is finite).
    pub or_untrusted: u64,
    /// See `or_untrusted`: no cell within `or_radius` of the internal position (an empty
    /// network included, which ends the correlation before the position is judged).
    pub or_no_cell: u64,
    /// See `or_untrusted`: the light ring has no pattern to align with the nearest cell's
    /// (`shift`: the ring is flat, [`ShiftMiss::Flat`]; `axis`: either ring's principal axis
    /// is missing or less distinct than `or_min_anisotropy`).
    pub or_no_pattern: u64,
    /// See `or_untrusted`: `shift` only, no aligning turn within `or_max_shift`
    /// ([`ShiftMiss::NoTurn`]).
    pub or_no_turn: u64,
    /// See `or_untrusted`: `shift` only, the best turn's residual is above `or_max_residual`
    /// ([`ShiftMiss::Residual`]).
    pub or_residual: u64,
    /// See `or_untrusted`: orientation corrections applied.
    pub or_corrections: u64,
    /// Cell moves: adaptation steps that moved the winner or a neighbour by a rate above 0.
    pub cell_moves: u64,
    /// Edges created by a winner change (eq. 7, the two cells were not joined).
    pub edges_created: u64,
    /// Edges refreshed to confidence 1 by a winner change (eq. 7, already joined).
    pub edges_refreshed: u64,
    /// Edges worn by a winner change (eq. 8, each of the new winner's other edges).
    pub edges_worn: u64,
}

impl Stats {
    /// The counts since `earlier` (a copy taken from the same model before): what a stretch
    /// of samples did.
    pub fn since(&self, earlier: &Stats) -> Stats {
        let d = |now: u64, then: u64| now.saturating_sub(then);
        Stats {
            samples: d(self.samples, earlier.samples),
            adaptations: d(self.adaptations, earlier.adaptations),
            spontaneous: d(self.spontaneous, earlier.spontaneous),
            statistical: d(self.statistical, earlier.statistical),
            removed: d(self.removed, earlier.removed),
            misses: d(self.misses, earlier.misses),
            pos_corrections: d(self.pos_corrections, earlier.pos_corrections),
            or_untrusted: d(self.or_untrusted, earlier.or_untrusted),
            or_no_cell: d(self.or_no_cell, earlier.or_no_cell),
            or_no_pattern: d(self.or_no_pattern, earlier.or_no_pattern),
            or_no_turn: d(self.or_no_turn, earlier.or_no_turn),
            or_residual: d(self.or_residual, earlier.or_residual),
            or_corrections: d(self.or_corrections, earlier.or_corrections),
            cell_moves: d(self.cell_moves, earlier.cell_moves),
            edges_created: d(self.edges_created, earlier.edges_created),
            edges_refreshed: d(self.edges_refreshed, earlier.edges_refreshed),
            edges_worn: d(self.edges_worn, earlier.edges_worn),
        }
    }

    /// Samples that reached the orientation correlation: each of them counts in exactly one
    /// of `or_untrusted`, `or_no_cell`, `or_no_pattern`, `or_no_turn`, `or_residual` and
    /// `or_corrections`, so this is their sum.
    pub fn or_reached(&self) -> u64 {
        self.or_untrusted
            + self.or_no_cell
            + self.or_no_pattern
            + self.or_no_turn
            + self.or_residual
            + self.or_corrections
    }
}

/// The model: network, internal pose, learning state.
#[derive(Clone, Debug)]
pub struct QtModel {
    params: Params,
    net: Network,
    eps_o: f64,
    eps_n: f64,
    pose: Pose,
    last_odometry: Option<Pose>,
    learning: VecDeque<Vec<f64>>,
    last_seq_winner: Option<u32>,
    winner: Option<u32>,
    estimate: Option<(f64, f64)>,
    map_static: bool,
    stats: Stats,
    scratch: Vec<u32>,
    buf: Vec<f64>,
}

impl QtModel {
    /// A model with an empty network and the internal pose `start`.
    pub fn new(params: Params, start: Pose) -> Result<Self, ParamError> {
        params.validate()?;
        let net = Network::new(Weights::new(&params), params.g_search, params.max_cells);
        Ok(QtModel {
            eps_o: params.eps_o,
            eps_n: params.eps_n,
            params,
            net,
            pose: start,
            last_odometry: None,
            learning: VecDeque::new(),
            last_seq_winner: None,
            winner: None,
            estimate: None,
            map_static: false,
            stats: Stats::default(),
            scratch: Vec::new(),
            buf: Vec::new(),
        })
    }

    /// The parameters.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// The network.
    pub fn network(&self) -> &Network {
        &self.net
    }

    /// The internal (corrected) pose.
    pub fn pose(&self) -> Pose {
        self.pose
    }

    /// Put the internal pose at `p` (a known pose from outside the model; the emulator's
    /// navigation uses it for a counterfactual that holds the pose at the truth).
    pub fn relocate(&mut self, p: Pose) {
        self.pose = p;
    }

    /// The winner of the latest first presentation (the cell the robot is "at").
    pub fn winner(&self) -> Option<u32> {
        self.winner
    }

    /// §4.2.4's position estimate p_est of the latest sample observed (a refused one changes
    /// nothing), when the model made one (the position correlation or its trust gate needs it,
    /// and a cell won within g_search): what the map says the position is, before eps_pos
    /// blends it into the internal pose.
    pub fn last_estimate(&self) -> Option<(f64, f64)> {
        self.estimate
    }

    /// Counters.
    pub fn stats(&self) -> &Stats {
        &self.stats
    }

    /// The adaptation rates' current state (eps_o, eps_n): eps_o decays by `eps_delta` on
    /// every hit and returns to the parameter on a miss, eps_n is the parameter after a miss
    /// and 0 after a hit.
    pub fn rates(&self) -> (f64, f64) {
        (self.eps_o, self.eps_n)
    }

    /// Whether the map is static (see [`QtModel::set_static`]).
    pub fn is_static(&self) -> bool {
        self.map_static
    }

    /// A static map (§5.3's "static QT-maps"): the learning set is still presented and its
    /// winner searched (the cell the robot is at), and the correlations still run (they are
    /// localisation), but nothing of the map changes: no cell moves, none is inserted or
    /// removed, no edge is created, refreshed or worn, and the cells' update counts, errors
    /// and the adaptation rates stay as they are.
    pub fn set_static(&mut self, on: bool) {
        self.map_static = on;
    }

    /// Switch the correlations (the §4.5.3 ablation) or change any parameter that keeps the
    /// network's layout (`lights`, `touches` and `g_search` are fixed at creation).
    pub fn set_params(&mut self, p: Params) -> Result<(), ParamError> {
        p.validate()?;
        if p.lights != self.params.lights
            || p.touches != self.params.touches
            || p.g_search != self.params.g_search
        {
            return Err(ParamError(
                "lights, touches and g_search are fixed when the model is made".into(),
            ));
        }
        self.params = p;
        Ok(())
    }

    /// Integrate one sample. Samples whose reading counts do not match the parameters are
    /// refused with the reason (untrusted input: a message may be malformed).
    pub fn observe(&mut self, sample: &Sample) -> Result<(), ParamError> {
        if sample.light.len() != self.params.lights || sample.touch.len() != self.params.touches {
            return Err(ParamError(format!(
                "sample has {} light and {} touch readings; the model expects {} and {}",
                sample.light.len(),
                sample.touch.len(),
                self.params.lights,
                self.params.touches
            )));
        }
        let o = sample.odometry;
        if !(o.x.is_finite() && o.y.is_finite() && o.heading.is_finite())
            || sample.light.iter().any(|v| !v.is_finite())
        {
            return Err(ParamError("sample has a non-finite reading or pose".into()));
        }
        self.dead_reckon(o);
        self.correlate(sample);
        let mut s = Vec::new();
        situation(&self.params, sample.light, sample.touch, self.pose, &mut s);
        self.learning.push_back(s);
        let keep = self.params.l + self.params.k;
        while self.learning.len() > keep {
            self.learning.pop_front();
        }
        self.stats.samples += 1;
        // Oldest first; the situation exactly l samples old is the first presentation.
        let n = self.learning.len();
        if n > self.params.l {
            let first = n - 1 - self.params.l;
            let oldest = (first + 1).saturating_sub(self.params.k);
            for i in oldest..=first {
                let s = self.learning[i].clone();
                self.adapt(&s, i == first);
            }
        }
        Ok(())
    }

    fn dead_reckon(&mut self, o: Pose) {
        if let Some(last) = self.last_odometry {
            let (dx, dy) = (o.x - last.x, o.y - last.y);
            let (s, c) = last.heading.sin_cos();
            // The motion in the odometry's robot frame, applied in the internal frame.
            let (fx, fy) = (c * dx + s * dy, -s * dx + c * dy);
            let (s, c) = self.pose.heading.sin_cos();
            self.pose.x += c * fx - s * fy;
            self.pose.y += s * fx + c * fy;
            self.pose.heading += wrap(o.heading - last.heading);
            self.pose.heading = wrap(self.pose.heading);
        }
        self.last_odometry = Some(o);
    }

    fn correlate(&mut self, sample: &Sample) {
        self.estimate = None;
        if self.net.is_empty() {
            if self.params.eps_or > 0.0 {
                self.stats.or_no_cell += 1;
            }
            return;
        }
        let p = self.params.clone();
        let gate = p.or_pos_tolerance.is_finite() && p.eps_or > 0.0;
        let estimate = if p.eps_pos > 0.0 || gate {
            self.position_estimate(sample)
        } else {
            None
        };
        self.estimate = estimate;
        // §4.2.4: the orientation is correlated only "assuming the current position is
        // correct to within a certain tolerance": the map's estimate is the only witness.
        let trusted = !gate
            || estimate.is_some_and(|(x, y)| {
                (x - self.pose.x).hypot(y - self.pose.y) <= p.or_pos_tolerance
            });
        if let (true, Some((x, y))) = (p.eps_pos > 0.0, estimate) {
            self.pose.x += p.eps_pos * (x - self.pose.x);
            self.pose.y += p.eps_pos * (y - self.pose.y);
            self.stats.pos_corrections += 1;
        }
        if p.eps_or <= 0.0 {
            return;
        }
        // From here on every return counts one outcome (see `Stats::or_untrusted`).
        if !trusted {
            self.stats.or_untrusted += 1;
            return;
        }
        let at = (self.pose.x, self.pose.y);
        let Some(near) = self
            .net
            .nearest(at, p.or_radius, &mut self.scratch)
            .and_then(|(near, _)| self.net.cell(near))
        else {
            self.stats.or_no_cell += 1;
            return;
        };
        let stored = &near.s[..p.lights];
        let mut light = std::mem::take(&mut self.buf);
        crate::situation::rotate_to_world(sample.light, self.pose.heading, &mut light);
        let error = match p.or_method {
            OrMethod::Axis => match (principal_axis(&light), principal_axis(stored)) {
                (Some((oc, rc)), Some((on, rn)))
                    if rc >= p.or_min_anisotropy && rn >= p.or_min_anisotropy =>
                {
                    Ok(axis_difference(oc, on))
                }
                _ => Err(ShiftMiss::Flat),
            },
            OrMethod::Shift => ring_shift(&light, stored, p.or_max_shift, p.or_max_residual),
        };
        self.buf = light;
        match error {
            Ok(e) => {
                // The world-frame pattern turns with the heading error: undo part of it.
                self.pose.heading = wrap(self.pose.heading - p.eps_or * e);
                self.stats.or_corrections += 1;
            }
            Err(ShiftMiss::Flat) => self.stats.or_no_pattern += 1,
            Err(ShiftMiss::NoTurn) => self.stats.or_no_turn += 1,
            Err(ShiftMiss::Residual) => self.stats.or_residual += 1,
        }
    }

    /// §4.2.4's p_est: the positions of the current situation's winner and its topological
    /// neighbours, each weighted by its update count and its distance d_i to the situation.
    fn position_estimate(&mut self, sample: &Sample) -> Option<(f64, f64)> {
        let p = &self.params;
        let at = (self.pose.x, self.pose.y);
        let mut s = std::mem::take(&mut self.buf);
        situation(p, sample.light, sample.touch, self.pose, &mut s);
        let mut out = None;
        if let Some((w, _)) = self.net.winner(&s, at, p.g_search, &mut self.scratch) {
            let net = &self.net;
            let part = match p.pos_distance {
                PosDistance::Situation => s.len(),
                PosDistance::Sensor => p.lights + p.touches,
            };
            let members = || {
                let edges = net.cell(w).into_iter().flat_map(|c| c.edges.iter());
                std::iter::once(w)
                    .chain(edges.map(|e| e.0))
                    .filter_map(|id| net.cell(id).map(|c| (id, c)))
            };
            // The weights are taken relative to the best match, exp(-(d^2 - d_min^2) / sigma^2):
            // the same estimate, but no weight underflows to zero when every d_i is large.
            let d_min = members()
                .map(|(_, c)| net.distance_part(&c.s, &s, part))
                .fold(f64::INFINITY, f64::min);
            let (mut sx, mut sy, mut sw) = (0.0, 0.0, 0.0);
            for (id, c) in members() {
                let d = net.distance_part(&c.s, &s, part);
                let u = c.updates as f64;
                let excess = (d * d - d_min * d_min) / (p.pos_sigma * p.pos_sigma);
                let wt = (1.0 + u).ln_1p() * (-excess).exp();
                let (x, y) = net.position(id);
                sx += wt * x;
                sy += wt * y;
                sw += wt;
            }
            if sw > 0.0 {
                out = Some((sx / sw, sy / sw));
            }
        }
        self.buf = s;
        out
    }

    fn adapt(&mut self, s: &[f64], first: bool) {
        let p = &self.params;
        let at = Network::pos_of(s);
        if self.map_static {
            // Only the winner of the first presentation: where the robot is.
            if let (true, Some((w, _))) =
                (first, self.net.winner(s, at, p.g_search, &mut self.scratch))
            {
                self.last_seq_winner = Some(w);
                self.winner = Some(w);
            }
            return;
        }
        self.stats.adaptations += 1;
        let found = self.net.winner(s, at, p.g_search, &mut self.scratch);
        let (winner, d_opt) = match found {
            Some((w, d)) if d <= p.rho_s => {
                let slow = |u: u32| if u >= p.n_fix { p.fix_slowdown } else { 1.0 };
                let u = self.net.cell(w).map_or(0, |c| c.updates);
                let rate = self.eps_o * slow(u);
                self.net.move_toward(w, s, rate);
                if rate > 0.0 {
                    self.stats.cell_moves += 1;
                }
                if self.eps_n > 0.0 {
                    let ns: Vec<u32> = self
                        .net
                        .cell(w)
                        .map_or(Vec::new(), |c| c.edges.iter().map(|e| e.0).collect());
                    for n in ns {
                        let u = self.net.cell(n).map_or(0, |c| c.updates);
                        self.net.move_toward(n, s, self.eps_n * slow(u));
                        self.stats.cell_moves += 1;
                    }
                }
                (w, d)
            }
            _ => {
                // Spontaneous insertion: the situation itself becomes a cell, joined to the
                // cell it was nearest to (so a newborn cell is never isolated).
                let d = found.map_or(f64::INFINITY, |f| f.1);
                let Some(id) = self.net.insert(s.to_vec(), 0.0) else {
                    return;
                };
                self.stats.spontaneous += 1;
                if let Some((w, _)) = found {
                    self.net.set_edge(id, w, 1.0);
                }
                (id, d)
            }
        };
        let p = &self.params;
        let miss = d_opt > p.d_acc;
        if let Some(c) = self.net.cell_mut(winner) {
            if d_opt.is_finite() {
                c.d_total += d_opt;
            }
            c.updates = c.updates.saturating_add(1);
        }
        if miss {
            self.eps_o = p.eps_o;
            self.eps_n = p.eps_n;
            self.stats.misses += 1;
            if self.stats.misses % p.n_insert as u64 == 0 {
                self.statistical_insert();
            }
        } else {
            self.eps_o *= p.eps_delta;
            self.eps_n = 0.0;
        }
        if first {
            if let Some(old) = self.last_seq_winner {
                let change = self.net.winner_changed(winner, old, self.params.a_red);
                if change.joined {
                    self.stats.edges_worn += change.worn as u64;
                    if change.created {
                        self.stats.edges_created += 1;
                    } else {
                        self.stats.edges_refreshed += 1;
                    }
                }
                self.stats.removed += change.removed.len() as u64;
            }
            self.last_seq_winner = Some(winner);
            self.winner = Some(winner);
        }
    }

    /// Insert between the cell with the largest accumulated error and its (situation-)
    /// farthest neighbour: mean light and position, minimal (zero) touch (§4.2.3).
    fn statistical_insert(&mut self) {
        let Some((runner, _)) = self
            .net
            .cells()
            .filter(|(_, c)| !c.edges.is_empty())
            .max_by(|a, b| a.1.d_total.total_cmp(&b.1.d_total))
            .map(|(id, c)| (id, c.d_total))
        else {
            return;
        };
        let Some(rc) = self.net.cell(runner) else {
            return;
        };
        let far = rc
            .edges
            .iter()
            .filter_map(|&(n, _)| {
                self.net
                    .cell(n)
                    .map(|c| (n, self.net.distance(&c.s, &rc.s)))
            })
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(n, _)| n);
        let Some(far) = far else { return };
        let (Some(a), Some(b)) = (self.net.cell(runner), self.net.cell(far)) else {
            return;
        };
        let l = self.params.lights;
        let t = self.params.touches;
        let mut s: Vec<f64> = a.s.iter().zip(&b.s).map(|(x, y)| 0.5 * (x + y)).collect();
        for v in &mut s[l..l + t] {
            *v = 0.0;
        }
        let half = 0.5 * a.d_total;
        let Some(id) = self.net.insert(s, half) else {
            return;
        };
        self.stats.statistical += 1;
        if let Some(c) = self.net.cell_mut(runner) {
            c.d_total = half;
        }
        if let Some(c) = self.net.cell_mut(far) {
            c.d_total *= 0.5;
        }
        self.net.set_edge(runner, far, 0.0);
        self.net.set_edge(id, runner, 1.0);
        self.net.set_edge(id, far, 1.0);
    }
}

/// Angle wrapped to (-pi, pi].
pub fn wrap(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let r = a.rem_euclid(t);
    if r > std::f64::consts::PI {
        r - t
    } else {
        r
    }
}

#[cfg(test)]
mod tests;
