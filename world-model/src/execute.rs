//! Path execution (§5.2): which motor command takes the robot from its current situation to
//! the plan's next sub-goal. An associative memory maps (situation, sub-goal) to proposed
//! commands with their expected success; the command is picked by probability, not always the
//! best ("multiple potential solutions are always kept in mind"); after it is driven the
//! association is adapted by the reinforcement the thesis names: the distance to the sub-goal
//! after the command.
//!
//! Our memory and its limits: the thesis's is a supervised growing cell structure over the
//! continuous (situation, goal) input. Ours is keyed by the QT map's own quantisation of that
//! input, the winner cell and the sub-goal cell, so it learns per edge of the map and does not
//! generalise between edges; on the thesis's experiment (the same test path driven again and
//! again) the two meet the same associations. A command is a correction of the geometric one
//! (turn to the sub-goal's bearing, drive its distance): a turn offset and a distance scale.
//! "Pre-learned on a noisy world free of systematic errors" becomes the prior: every proposal
//! starts at the progress it would make in a drift-free world, `1 - |k e^(i delta) - 1|`.

use std::collections::HashMap;

use serde::Serialize;

/// Turn offsets the memory proposes, degrees.
pub const TURN_OFFSETS_DEG: [f64; 7] = [-40.0, -20.0, -10.0, 0.0, 10.0, 20.0, 40.0];
/// Distance scales it proposes.
pub const DISTANCE_SCALES: [f64; 3] = [0.8, 1.0, 1.25];
/// Proposals per association.
pub const PROPOSALS: usize = TURN_OFFSETS_DEG.len() * DISTANCE_SCALES.len();

/// One proposal: a correction of the geometric command.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Command {
    /// Index into the proposals.
    pub index: usize,
    /// Added to the sub-goal's bearing, radians.
    pub turn_offset: f64,
    /// Multiplies the sub-goal's distance.
    pub distance_scale: f64,
}

impl Command {
    /// Proposal `index` (0..PROPOSALS).
    pub fn of(index: usize) -> Command {
        let i = index % PROPOSALS;
        Command {
            index: i,
            turn_offset: TURN_OFFSETS_DEG[i / DISTANCE_SCALES.len()].to_radians(),
            distance_scale: DISTANCE_SCALES[i % DISTANCE_SCALES.len()],
        }
    }

    /// The progress this command makes in a drift-free world (1: arrives; 0: no closer).
    pub fn prior(&self) -> f64 {
        let (s, c) = self.turn_offset.sin_cos();
        let k = self.distance_scale;
        1.0 - (k * c - 1.0).hypot(k * s)
    }
}

/// The associative memory of the path execution.
#[derive(Clone, Debug, Serialize)]
pub struct Executor {
    /// Learning rate of the reinforcement (ours: 0.3).
    pub rate: f64,
    /// Selection temperature: proposals are picked with probability proportional to
    /// exp(value / temperature) (ours: 0.08; 0 always picks the best).
    pub temperature: f64,
    #[serde(skip)]
    values: HashMap<(u32, u32), [f64; PROPOSALS]>,
}

impl Default for Executor {
    fn default() -> Self {
        Executor {
            rate: 0.3,
            temperature: 0.08,
            values: HashMap::new(),
        }
    }
}

impl Executor {
    fn row(&mut self, at: u32, goal: u32) -> &mut [f64; PROPOSALS] {
        self.values.entry((at, goal)).or_insert_with(|| {
            let mut r = [0.0; PROPOSALS];
            for (i, v) in r.iter_mut().enumerate() {
                *v = Command::of(i).prior();
            }
            r
        })
    }

    /// Associations learned so far (situation and sub-goal pairs met).
    pub fn associations(&self) -> usize {
        self.values.len()
    }

    /// The expected progress of each proposal from cell `at` to sub-goal `goal`.
    pub fn values(&mut self, at: u32, goal: u32) -> [f64; PROPOSALS] {
        *self.row(at, goal)
    }

    /// Pick a command from `at` towards `goal`; `u` is a uniform draw in [0, 1) (the caller's
    /// random stream keeps this module free of one).
    pub fn choose(&mut self, at: u32, goal: u32, u: f64) -> Command {
        let t = self.temperature;
        let row = *self.row(at, goal);
        let best = (0..PROPOSALS)
            .max_by(|&a, &b| row[a].total_cmp(&row[b]))
            .unwrap_or(0);
        if t <= 0.0 {
            return Command::of(best);
        }
        let top = row[best];
        let w: Vec<f64> = row.iter().map(|v| ((v - top) / t).exp()).collect();
        let total: f64 = w.iter().sum();
        let mut x = u.clamp(0.0, 1.0) * total;
        for (i, wi) in w.iter().enumerate() {
            if x < *wi {
                return Command::of(i);
            }
            x -= wi;
        }
        Command::of(best)
    }

    /// Reinforce: command `c` from `at` towards `goal` took the distance to the sub-goal from
    /// `before` to `after` metres. The reward is the fraction of the distance gained (1: there;
    /// negative: farther away), clamped to [-1, 1].
    pub fn reinforce(&mut self, at: u32, goal: u32, c: Command, before: f64, after: f64) -> f64 {
        let reward = if before > 1e-9 {
            ((before - after) / before).clamp(-1.0, 1.0)
        } else {
            0.0
        };
        let rate = self.rate;
        let v = &mut self.row(at, goal)[c.index];
        *v += rate * (reward - *v);
        reward
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_prior_prefers_the_geometric_command() {
        let best = (0..PROPOSALS)
            .max_by(|&a, &b| Command::of(a).prior().total_cmp(&Command::of(b).prior()))
            .unwrap();
        let c = Command::of(best);
        assert_eq!((c.turn_offset, c.distance_scale), (0.0, 1.0));
        assert!((c.prior() - 1.0).abs() < 1e-12);
        let mut e = Executor {
            temperature: 0.0,
            ..Executor::default()
        };
        assert_eq!(e.choose(1, 2, 0.5).index, best);
    }

    /// A systematic error the prior does not know (the geometric command always ends 20
    /// degrees off): reinforcement moves the choice to the offset that compensates it.
    #[test]
    fn reinforcement_learns_a_systematic_offset() {
        let mut e = Executor::default();
        let bias = -20f64.to_radians();
        let mut u = 0.123;
        for _ in 0..60 {
            u = (u * 7.31 + 0.377) % 1.0;
            let c = e.choose(5, 6, u);
            let (s, co) = (c.turn_offset + bias).sin_cos();
            let k = c.distance_scale;
            let after = (k * co - 1.0).hypot(k * s);
            e.reinforce(5, 6, c, 1.0, after);
        }
        let greedy = Executor {
            temperature: 0.0,
            ..e.clone()
        }
        .choose(5, 6, 0.0);
        assert!(
            (greedy.turn_offset.to_degrees() - 20.0).abs() < 1e-9,
            "learned {greedy:?}"
        );
        // Another association is untouched.
        assert_eq!(
            e.values(6, 5)[greedy.index],
            Command::of(greedy.index).prior()
        );
    }
}
