//! The simulated ALICE of the navigation experiment: its body, sensors and QT model, one
//! sample at a time, and the legs it drives.

use world_model::execute::Executor;
use world_model::navigate::Planner;
use world_model::{Pose, QtModel, Sample};

use super::judge::{MapFit, Places, Tally};
use super::{CorrelationJudge, Leg, StepBase, BACK_OFF_M};
use crate::arena::Arena;
use crate::geometry::{Point, SegmentSet, Vector};
use crate::rng::SimRng;
use crate::scenarios::alice::body::{Body, SPEED_M_S, SUBSTEPS, TURN_RAD_S};
use crate::scenarios::alice::explore::{decide, Follower, Move};
use crate::scenarios::alice::scenario::SAMPLES_PER_S;
use crate::sensors::alice::{Sensors, BODY_RADIUS_M, COUNT};

/// The simulated ALICE and its model.
pub(super) struct Robot {
    pub(super) arena: Arena,
    pub(super) walls: SegmentSet,
    pub(super) body: Body,
    pub(super) sensors: Sensors,
    pub(super) rng: SimRng,
    pub(super) model: QtModel,
    /// The latest whiskers.
    pub(super) touch: [bool; COUNT],
    pub(super) samples: u64,
    /// Truth, to judge only: where each cell won while exploring.
    pub(super) places: Places,
    /// Truth, to judge only: the map's frame in the world, once the exploration is done.
    pub(super) fit: Option<MapFit>,
    /// The correlations since the tally was last taken (the model's counters, and the truth to
    /// judge only).
    pub(super) tally: Tally,
    /// The `true_pose` counterfactual is on (once the exploration is done).
    pub(super) true_pose: bool,
}

/// What the body does during one sample.
pub(super) enum Motion {
    Still,
    Wander(f64),
    /// Turn this much, then drive this far (odometry metres).
    Step(f64, f64),
}

impl Robot {
    /// One sample: move for 1/3 s, read the sensors, feed the model. Returns false when the
    /// drive was stopped, which only a blocked body does: a front whisker's touch does not
    /// stop it (stopping on one was tried: 58 of 100 legs reached, seeds 1-10).
    pub(super) fn sample(&mut self, motion: &mut Motion) -> Result<bool, String> {
        let dt = 1.0 / SAMPLES_PER_S / SUBSTEPS as f64;
        let mut free = true;
        for _ in 0..SUBSTEPS {
            match motion {
                Motion::Still => {}
                Motion::Wander(turn) | Motion::Step(turn, _) if turn.abs() > 1e-9 => {
                    let step = turn.clamp(-TURN_RAD_S * dt, TURN_RAD_S * dt);
                    self.body.turn(step);
                    *turn -= step;
                }
                Motion::Wander(turn) => {
                    if !self.body.forward(&self.walls, SPEED_M_S * dt) {
                        *turn = crate::scenarios::alice::wrap(
                            std::f64::consts::PI + (2.0 * self.rng.uniform() - 1.0) * 1.2,
                        );
                    }
                }
                Motion::Step(_, left) => {
                    // Within a millimetre is there (a float residue would never end).
                    if *left <= 1e-3 {
                        *left = 0.0;
                        break;
                    }
                    let before = self.body.odo;
                    if !self.body.forward(&self.walls, (SPEED_M_S * dt).min(*left)) {
                        free = false;
                        *left = 0.0;
                        break;
                    }
                    *left -= (self.body.odo.0 - before.0).hypot(self.body.odo.1 - before.1);
                }
            }
        }
        self.touch = self
            .sensors
            .whiskers(&self.walls, self.body.at, self.body.heading);
        let light = self.sensors.light(
            &self.walls,
            &self.arena.lights,
            self.body.at,
            self.body.heading,
        );
        let odometry = Pose {
            x: self.body.odo.0,
            y: self.body.odo.1,
            heading: self.body.odo.2,
        };
        self.model
            .observe(&Sample {
                light: &light,
                touch: &self.touch,
                odometry,
            })
            .map_err(|e| e.to_string())?;
        self.samples += 1;
        if let Some(fit) = self.fit.filter(|_| self.true_pose) {
            let (x, y) = fit.internal((self.body.at.x, self.body.at.y));
            let heading = crate::scenarios::alice::wrap(self.body.heading - fit.rotation);
            self.model.relocate(Pose { x, y, heading });
        }
        self.judge();
        Ok(free)
    }

    /// Add this sample's truth to the tally (see [`CorrelationJudge`]; the model counts the
    /// orientation correlation's gates itself).
    pub(super) fn judge(&mut self) {
        let net = self.model.network();
        let pose = self.model.pose();
        let t = &mut self.tally;
        t.samples += 1;
        if self.touch.iter().any(|&b| b) {
            t.touching += 1;
        }
        if let Some(w) = self.model.winner().filter(|&w| net.cell(w).is_some()) {
            let (x, y) = net.position(w);
            t.winner_to_pose.0 += (x - pose.x).hypot(y - pose.y);
            t.winner_to_pose.1 += 1;
            if let Some(d) = self.places.distance(w, (self.body.at.x, self.body.at.y)) {
                t.winner_place.0 += d;
                t.winner_place.1 += 1;
            }
        }
    }

    /// The tally since it was last taken, judged; the tally starts again.
    pub(super) fn take_judge(&mut self) -> CorrelationJudge {
        let now = self.model.stats().clone();
        let judged = self.tally.judge(&now);
        self.tally = Tally::starting(now);
        judged
    }

    /// Explore `samples` situations: the wanderer, with wall following when `follow`.
    pub(super) fn explore(&mut self, samples: u64, follow: bool) -> Result<(), String> {
        let mut m = Motion::Wander(0.0);
        let mut follower = follow.then(Follower::default);
        for _ in 0..samples {
            self.sample(&mut m)?;
            if let Some(w) = self.model.winner() {
                self.places.record(w, self.body.at);
            }
            if let Motion::Wander(turn) = &mut m {
                if turn.abs() <= 1e-9 {
                    let next = match follower.as_mut() {
                        Some(f) => f.decide(&self.touch, &mut self.rng),
                        None => decide(&self.touch, &mut self.rng),
                    };
                    if let Move::Turn(a) = next {
                        *turn = a;
                    }
                }
            }
        }
        Ok(())
    }

    /// Turn by `turn`, then drive `distance` metres by the odometry, until sample `until` at
    /// the latest. False when the body was blocked.
    pub(super) fn drive(&mut self, turn: f64, distance: f64, until: u64) -> Result<bool, String> {
        let mut m = Motion::Step(turn, distance);
        let mut free = true;
        while matches!(m, Motion::Step(t, l) if t.abs() > 1e-9 || l > 0.0) && self.samples < until {
            free &= self.sample(&mut m)?;
        }
        Ok(free)
    }

    /// Whether the body fits at `p` (truth, to judge only).
    pub(super) fn body_fits(&self, p: Point) -> bool {
        !self.arena.is_solid(p) && !self.walls.circle_collides(p, BODY_RADIUS_M)
    }

    /// The truth's judgement of a step before it is driven (see `Leg::aimed_outside` and
    /// `Leg::beyond_proposals`): (the sub-goal's internal position is no place the body
    /// fits, its place is beyond the memory's proposals). None before the map's fit.
    pub(super) fn judge_aim(&self, sub: u32, bearing: f64, dist: f64) -> Option<(bool, bool)> {
        let fit = self.fit?;
        let aim = fit.world(self.model.network().position(sub));
        let outside = !self.body_fits(Point::new(aim.0, aim.1));
        let beyond = self.places.of(sub).is_some_and(|((x, y), _)| {
            let (dx, dy) = (x - self.body.at.x, y - self.body.at.y);
            let turn = crate::scenarios::alice::wrap(dy.atan2(dx) - self.body.heading - bearing);
            let scale = dx.hypot(dy) / dist.max(1e-9);
            turn.abs() > 50f64.to_radians() || !(0.7..=1.4).contains(&scale)
        });
        Some((outside, beyond))
    }

    /// The truth's judgement of a blocked drive that started at `from` (true position) and
    /// was commanded `distance` along `heading` (true): (stopped within 2 cm, the commanded
    /// end is a place the body fits).
    pub(super) fn judge_block(&self, from: Point, heading: f64, distance: f64) -> (bool, bool) {
        let end = from + Vector::new(heading.cos(), heading.sin()) * distance;
        ((self.body.at - from).norm() < 0.02, self.body_fits(end))
    }

    /// Where `cell` lies relative to the internal pose: (distance, bearing in the robot's
    /// frame).
    pub(super) fn towards(&self, cell: u32) -> (f64, f64) {
        let (x, y) = self.model.network().position(cell);
        let p = self.model.pose();
        let (dx, dy) = (x - p.x, y - p.y);
        (
            dx.hypot(dy),
            crate::scenarios::alice::wrap(dy.atan2(dx) - p.heading),
        )
    }

    /// The map's relative motion from cell `from` to cell `to`: (distance, bearing in the
    /// robot's frame by the internal heading).
    pub(super) fn along(&self, from: u32, to: u32) -> (f64, f64) {
        let net = self.model.network();
        let (a, b) = (net.position(from), net.position(to));
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        (
            dx.hypot(dy),
            crate::scenarios::alice::wrap(dy.atan2(dx) - self.model.pose().heading),
        )
    }

    /// The truth's judgement of the internal pose: (position error, metres; absolute heading
    /// error, radians) against the map's frame.
    pub(super) fn localisation_error(&self) -> Option<(f64, f64)> {
        let fit = self.fit?;
        let p = self.model.pose();
        let w = fit.world((p.x, p.y));
        Some((
            (w.0 - self.body.at.x).hypot(w.1 - self.body.at.y),
            crate::scenarios::alice::wrap(p.heading + fit.rotation - self.body.heading).abs(),
        ))
    }

    pub(super) fn cell_gap(&self, a: Option<u32>, b: u32) -> f64 {
        let net = self.model.network();
        match a.filter(|&a| net.cell(a).is_some()) {
            Some(a) => {
                let (p, q) = (net.position(a), net.position(b));
                (p.0 - q.0).hypot(p.1 - q.1)
            }
            None => self.towards(b).0,
        }
    }

    /// Drive to `target`'s cell: plan, execute, refine on failure.
    pub(super) fn leg(
        &mut self,
        target: u32,
        exec: &mut Executor,
        cap: u64,
        base: StepBase,
    ) -> Result<Leg, String> {
        let started = self.samples;
        let fail_per_m = self.model.params().nav_fail_per_m;
        let mut planner = Planner::default();
        let mut leg = Leg::default();
        let (mut judged, mut pos_err, mut head_err) = (0u32, 0.0, 0.0);
        let settle = self.model.params().l as u64 + 1;
        'plan: while self.samples - started < cap {
            if self.model.network().cell(target).is_none() {
                break;
            }
            let Some(at) = self.model.winner() else {
                self.sample(&mut Motion::Still)?;
                continue;
            };
            if at == target {
                leg.reached = true;
                break;
            }
            let Some(plan) = planner.plan(self.model.network(), at, target, fail_per_m) else {
                // No path in the map from here: a failed step; a short wander finds another
                // place to plan from.
                planner.failed();
                let mut m = Motion::Wander((self.rng.uniform() - 0.5) * 3.0);
                for _ in 0..3 {
                    self.sample(&mut m)?;
                }
                continue;
            };
            for (i, &sub) in plan.path.iter().enumerate().skip(1) {
                let Some(from) = self.model.winner() else {
                    continue 'plan;
                };
                if self.model.network().cell(sub).is_none() {
                    planner.failed();
                    continue 'plan;
                }
                let (dist, bearing) = match base {
                    StepBase::Pose => self.towards(sub),
                    StepBase::Cell => self.along(from, sub),
                };
                let before = self.cell_gap(Some(from), sub);
                let c = exec.choose(from, sub, self.rng.uniform());
                leg.steps += 1;
                let aim = self.judge_aim(sub, bearing, dist);
                let (at, heading) = (self.body.at, self.body.heading);
                let turn = crate::scenarios::alice::wrap(bearing + c.turn_offset);
                let free = self.drive(turn, dist * c.distance_scale, started + cap)?;
                if let Some((outside, beyond)) = aim {
                    leg.aimed_outside += u32::from(outside);
                    leg.blocked_aimed_outside += u32::from(outside && !free);
                    leg.beyond_proposals += u32::from(beyond);
                }
                if !free {
                    let (at_once, end_fits) =
                        self.judge_block(at, heading + turn, dist * c.distance_scale);
                    leg.blocked_at_once += u32::from(at_once);
                    leg.blocked_cutting += u32::from(!at_once && end_fits);
                    // Blocked: back off (the manoeuvre is reversed), as ALICE's reflexes do.
                    leg.reversals += 1;
                    leg.blocked += 1;
                    let back = std::f64::consts::PI + (self.rng.uniform() - 0.5);
                    self.drive(back, BACK_OFF_M, started + cap)?;
                }
                for _ in 0..settle {
                    self.sample(&mut Motion::Still)?;
                }
                if let Some((e, h)) = self.localisation_error() {
                    judged += 1;
                    pos_err += e;
                    head_err += h.to_degrees();
                }
                let now = self.model.winner();
                let after = if now == Some(sub) {
                    0.0
                } else {
                    self.cell_gap(now, sub)
                };
                exec.reinforce(from, sub, c, before, after);
                if after > before && free {
                    leg.reversals += 1;
                }
                if now == Some(target) {
                    leg.reached = true;
                    break 'plan;
                }
                let ahead = now.is_some_and(|w| plan.path[i..].contains(&w));
                if !ahead {
                    leg.failed += 1;
                    planner.failed();
                    continue 'plan;
                }
                if now != Some(sub) {
                    // Skipped ahead: go on from the cell reached.
                    continue 'plan;
                }
            }
        }
        leg.samples = self.samples - started;
        leg.refinements = planner.plans.saturating_sub(1);
        if judged > 0 {
            leg.localisation_error_m = pos_err / judged as f64;
            leg.heading_error_deg = head_err / judged as f64;
        }
        Ok(leg)
    }
}
