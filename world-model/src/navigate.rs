//! Path planning over the cell graph (§5.1): A* (Hart, Nilsson, Raphael 1968) with
//! f(n) = w_g g(n) + w_h h(n). g sums edge costs (geometric length divided by the edge's
//! confidence, so doubtful edges look long); h is the straight distance to the target cell.
//! w_g = 0 is hill climbing, w_h = 0 is flooding; [`Planner`] moves from the first towards the
//! second as steps fail, its "time" scaled by the estimated distance to the goal.

use std::cmp::Ordering;
use std::collections::{BinaryHeap, HashMap};

use serde::Serialize;

use crate::network::Network;

/// A plan: cells from start to target, and how many nodes the search expanded.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Plan {
    /// Cell ids, start first, target last.
    pub path: Vec<u32>,
    /// Nodes expanded (moved to the closed set).
    pub expanded: usize,
}

#[derive(PartialEq)]
struct Open(f64, u32);
impl Eq for Open {}
impl PartialOrd for Open {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Open {
    // Smallest f first; ties by id so the search is deterministic.
    fn cmp(&self, o: &Self) -> Ordering {
        o.0.total_cmp(&self.0).then(o.1.cmp(&self.1))
    }
}

/// A* from `start` to `target` with weights `w_g`, `w_h`. Bounded: every cell is expanded at
/// most once per improvement of its g, and the heap holds at most one entry per edge relaxation.
pub fn plan(net: &Network, start: u32, target: u32, w_g: f64, w_h: f64) -> Option<Plan> {
    net.cell(start)?;
    let goal = net.cell(target).map(|_| net.position(target))?;
    let h = |id: u32| {
        let (x, y) = net.position(id);
        (x - goal.0).hypot(y - goal.1)
    };
    let mut g: HashMap<u32, f64> = HashMap::new();
    let mut parent: HashMap<u32, u32> = HashMap::new();
    let mut closed: HashMap<u32, ()> = HashMap::new();
    let mut open = BinaryHeap::new();
    g.insert(start, 0.0);
    open.push(Open(w_h * h(start), start));
    let mut expanded = 0;
    while let Some(Open(_, n)) = open.pop() {
        if closed.contains_key(&n) {
            continue;
        }
        if n == target {
            let mut path = vec![n];
            let mut c = n;
            while let Some(&p) = parent.get(&c) {
                path.push(p);
                c = p;
            }
            path.reverse();
            return Some(Plan { path, expanded });
        }
        closed.insert(n, ());
        expanded += 1;
        let gn = g.get(&n).copied().unwrap_or(0.0);
        let Some(cell) = net.cell(n) else { continue };
        let pn = net.position(n);
        for &(m, conf) in &cell.edges {
            if closed.contains_key(&m) || conf <= 0.0 {
                continue;
            }
            let pm = net.position(m);
            let gm = gn + (pm.0 - pn.0).hypot(pm.1 - pn.1) / conf;
            if g.get(&m).is_none_or(|&old| gm < old) {
                g.insert(m, gm);
                parent.insert(m, n);
                open.push(Open(w_g * gm + w_h * h(m), m));
            }
        }
    }
    None
}

/// The heuristic weights' schedule: hill climbing at first, flooding after
/// `fail_per_m` failed steps per metre of the start's distance to the goal.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Planner {
    /// Failed steps since the current goal was set.
    pub failures: u32,
    /// Plans made since the current goal was set (the first plan plus refinements).
    pub plans: u32,
}

impl Planner {
    /// (w_g, w_h) after the failures so far, for a goal `distance_m` away.
    pub fn weights(&self, distance_m: f64, fail_per_m: f64) -> (f64, f64) {
        let scale = (fail_per_m * distance_m).max(1.0);
        let lambda = (self.failures as f64 / scale).min(1.0);
        (lambda, 1.0 - lambda)
    }

    /// Plan from `start` to `target` with the current weights.
    pub fn plan(
        &mut self,
        net: &Network,
        start: u32,
        target: u32,
        fail_per_m: f64,
    ) -> Option<Plan> {
        let (a, b) = (net.position(start), net.position(target));
        let (w_g, w_h) = self.weights((a.0 - b.0).hypot(a.1 - b.1), fail_per_m);
        self.plans += 1;
        plan(net, start, target, w_g, w_h)
    }

    /// A step of the plan did not reach its sub-goal.
    pub fn failed(&mut self) {
        self.failures = self.failures.saturating_add(1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::situation::Weights;
    use crate::Params;

    fn cell(net: &mut Network, x: f64, y: f64) -> u32 {
        let p = Params::default();
        let mut s = vec![0.0; p.lights + p.touches];
        s.extend([x, y]);
        net.insert(s, 0.0).expect("room")
    }

    /// A dead end pointing at the goal and a detour: hill climbing walks into the dead end
    /// first (more expansions), flooding finds the shortest path.
    #[test]
    fn hill_climbing_and_flooding_differ_as_the_thesis_says() {
        let p = Params::default();
        let mut net = Network::new(Weights::new(&p), 1.0, 100);
        let s = cell(&mut net, 0.0, 0.0);
        let dead: Vec<u32> = (1..=4)
            .map(|i| cell(&mut net, i as f64 * 0.5, 0.0))
            .collect();
        net.set_edge(s, dead[0], 1.0);
        for w in dead.windows(2) {
            net.set_edge(w[0], w[1], 1.0);
        }
        let up = cell(&mut net, 0.0, 1.0);
        let over = cell(&mut net, 1.5, 1.5);
        let t = cell(&mut net, 2.5, 0.5);
        net.set_edge(s, up, 1.0);
        net.set_edge(up, over, 1.0);
        net.set_edge(over, t, 1.0);
        let hill = plan(&net, s, t, 0.0, 1.0).expect("path");
        let flood = plan(&net, s, t, 1.0, 0.0).expect("path");
        assert_eq!(hill.path, vec![s, up, over, t]);
        assert_eq!(flood.path, vec![s, up, over, t]);
        assert!(
            hill.expanded > 4,
            "hill climbing explored the dead end: {hill:?}"
        );
        // A low-confidence edge looks long to g.
        net.set_edge(up, over, 0.01);
        assert!(plan(&net, s, t, 1.0, 0.0).is_none_or(|p| p.path.len() == 4));
        let mut pl = Planner::default();
        assert_eq!(pl.weights(1.0, 4.0), (0.0, 1.0));
        for _ in 0..4 {
            pl.failed();
        }
        assert_eq!(pl.weights(1.0, 4.0), (1.0, 0.0));
    }
}
