//! Micro-Rato labyrinths by the contest rules of seed 004 §2: a 5 x 5 m walled arena whose
//! inner walls form a labyrinth with at least 0.5 m between obstacles, a 1 m goal circle with
//! the beacon at its centre, and start areas (three robots ran at once).
//!
//! Sizes the paper does not give are drawn over the range real CiberRato/Micro-Rato labs
//! show (Micro-Rato'99: 0.29 m thick walls, arms 1.1-2.6 m; Ciber2005: 0.14 m walls): wall
//! thickness 0.05-0.35 m, 6-14 obstacles, bars 0.6-2.5 m, L arms 0.6-2.0 m, dead ends (U) 0.8-2.0 m wide and
//! 0.6-1.6 m deep. Some bars stand against the outer wall, as in the real labs. The first
//! start is at least 2.5 m from the goal's centre, so every run crosses the labyrinth.
//! Most seeds are corridor labyrinths (a maze on a 1-1.25 m grid, partly opened), the rest
//! scattered walls.

use super::shapes::{fits_in, Shape};
use super::{pick, uniform, Layout};
use crate::geometry::{Aabb, Point};
use crate::rng::SimRng;

/// Arena side, metres (seed 004 §2).
pub const SIDE_M: f64 = 5.0;
/// Least gap between obstacles, metres (seed 004 §2: 0.5 m), plus 1 cm so the file's
/// 3-decimal CiberRato units cannot round it below the rule.
pub const GAP_M: f64 = 0.51;
/// Goal circle radius, metres (seed 004 §2: 1 m across).
pub const GOAL_RADIUS_M: f64 = 0.5;
/// Least distance from the first start to the goal's centre, metres.
pub const START_TO_GOAL_M: f64 = 2.5;
/// Clearance from a start to any obstacle, metres (the robot's 0.12 m radius and a margin).
const START_CLEARANCE_M: f64 = 0.3;

pub(crate) fn layout(name: &str, rng: &mut SimRng) -> Layout {
    if rng.chance(LABYRINTH_SHARE) {
        labyrinth(name, rng)
    } else {
        scattered(name, rng)
    }
}

/// Share of seeds drawn as a corridor labyrinth (the rest: scattered walls, L's and U's).
const LABYRINTH_SHARE: f64 = 0.7;

/// A corridor labyrinth: a random maze on a 4 x 4 or 5 x 5 grid of 1.25 or 1 m cells
/// (carved depth-first, then a random 10-40 % of its inner walls removed, so there are loops
/// and open areas as in the real labs), its walls 0.05-0.35 m thick. Pieces that meet form
/// one obstacle; any other gap is at least a cell less a wall's thickness (>= 0.65 m), over
/// the 0.5 m rule. The goal circle is at a cell centre with no wall over it; the starts at
/// cell centres at least 2.5 m (the first) or 2 m from it.
fn labyrinth(name: &str, rng: &mut SimRng) -> Layout {
    let n = pick(rng, 4, 5) as usize;
    let p = SIDE_M / n as f64;
    let t = uniform(rng, 0.05, 0.35);
    let centre = |c: usize, r: usize| Point::new((c as f64 + 0.5) * p, (r as f64 + 0.5) * p);
    let goal_cell = (
        pick(rng, 0, n as u32 - 1) as usize,
        pick(rng, 0, n as u32 - 1) as usize,
    );
    let goal = centre(goal_cell.0, goal_cell.1);
    // Walls east of (c, r) and north of (c, r), inner lines only; true = standing.
    let (east, north) = super::carve(n, n, (0, 0), rng);
    let remove = uniform(rng, 0.1, 0.4);
    let mut walls = Vec::new();
    let clip = |v: f64| v.clamp(0.0, SIDE_M);
    for r in 0..n {
        for c in 0..n {
            let (x, y) = (c as f64 * p, r as f64 * p);
            let mut pieces = Vec::new();
            if c + 1 < n && east[r * n + c] && !rng.chance(remove) {
                let lx = x + p;
                pieces.push(Aabb::from_corners(
                    Point::new(lx - t / 2.0, clip(y - t / 2.0)),
                    Point::new(lx + t / 2.0, clip(y + p + t / 2.0)),
                ));
            }
            if r + 1 < n && north[r * n + c] && !rng.chance(remove) {
                let ly = y + p;
                pieces.push(Aabb::from_corners(
                    Point::new(clip(x - t / 2.0), ly - t / 2.0),
                    Point::new(clip(x + p + t / 2.0), ly + t / 2.0),
                ));
            }
            for b in pieces {
                // The goal circle stays clear of walls (seed 004 §2: a dark floor circle).
                if b.distance_to_point(goal) >= GOAL_RADIUS_M + 0.05 {
                    walls.push(Shape::bar(b).outline);
                }
            }
        }
    }
    let mut cells: Vec<(usize, usize)> = (0..n * n).map(|i| (i % n, i / n)).collect();
    // Shuffle (Fisher-Yates) so the starts are random cells.
    for i in (1..cells.len()).rev() {
        let j = (rng.next_u64() % (i as u64 + 1)) as usize;
        cells.swap(i, j);
    }
    let mut starts: Vec<[f64; 3]> = Vec::new();
    for (c, r) in cells {
        let q = centre(c, r);
        let far = if starts.is_empty() {
            START_TO_GOAL_M
        } else {
            2.0
        };
        if starts.len() < 3 && (q - goal).norm() >= far {
            let heading = uniform(rng, -std::f64::consts::PI, std::f64::consts::PI);
            starts.push([q.x, q.y, heading]);
        }
    }
    Layout::plain(name, (SIDE_M, SIDE_M), walls, (goal, GOAL_RADIUS_M), starts)
}

/// Scattered obstacles: 6-14 bars, L's and U's placed at random under the spacing rules.
fn scattered(name: &str, rng: &mut SimRng) -> Layout {
    let margin = GOAL_RADIUS_M + 0.3;
    let goal = Point::new(
        uniform(rng, margin, SIDE_M - margin),
        uniform(rng, margin, SIDE_M - margin),
    );
    let mut starts: Vec<[f64; 3]> = Vec::new();
    let want_starts = pick(rng, 1, 3) as usize;
    for _ in 0..200 {
        if starts.len() == want_starts {
            break;
        }
        let p = Point::new(
            uniform(rng, 0.4, SIDE_M - 0.4),
            uniform(rng, 0.4, SIDE_M - 0.4),
        );
        let far = if starts.is_empty() {
            START_TO_GOAL_M
        } else {
            2.0
        };
        let apart = starts
            .iter()
            .all(|s| (Point::new(s[0], s[1]) - p).norm() >= 0.6);
        if (p - goal).norm() >= far && apart {
            let heading = uniform(rng, -std::f64::consts::PI, std::f64::consts::PI);
            starts.push([p.x, p.y, heading]);
        }
    }
    let want = pick(rng, 6, 14) as usize;
    let first_start = starts.first().map(|s| Point::new(s[0], s[1]));
    let mut shapes: Vec<Shape> = Vec::new();
    for _ in 0..600 {
        if shapes.len() == want {
            break;
        }
        let s = candidate(rng, goal, first_start);
        let clear_goal = s.distance_to(goal) >= GOAL_RADIUS_M + 0.05;
        let clear_starts = starts
            .iter()
            .all(|st| s.distance_to(Point::new(st[0], st[1])) >= START_CLEARANCE_M);
        let spaced = shapes.iter().all(|o| s.gap(o) >= GAP_M);
        if clear_goal && clear_starts && spaced && fits_in(&s, SIDE_M, SIDE_M, GAP_M) {
            shapes.push(s);
        }
    }
    Layout::plain(
        name,
        (SIDE_M, SIDE_M),
        shapes.into_iter().map(|s| s.outline).collect(),
        (goal, GOAL_RADIUS_M),
        starts,
    )
}

/// One obstacle at a random place: a bar (some against the outer wall), an L or a U; half
/// the U's stand across the line from the first start to the goal, open towards the start
/// (the trap a beacon-seeking robot drives into, as the real labs' dead ends are).
fn candidate(rng: &mut SimRng, goal: Point, start: Option<Point>) -> Shape {
    let t = uniform(rng, 0.05, 0.35);
    let kind = rng.uniform();
    let free_at = |rng: &mut SimRng, s: &Shape| {
        let b = s.bounds();
        let x = uniform(rng, 0.0, (SIDE_M - b.width()).max(0.0));
        let y = uniform(rng, 0.0, (SIDE_M - b.height()).max(0.0));
        s.placed(Point::new(x, y))
    };
    if kind < 0.25 {
        // A bar standing against a side of the arena, pointing inwards.
        let len = uniform(rng, 0.6, 2.5);
        let along = uniform(rng, 0.0, SIDE_M - t);
        let b = match pick(rng, 0, 3) {
            0 => Aabb::from_corners(Point::new(along, 0.0), Point::new(along + t, len)),
            1 => Aabb::from_corners(
                Point::new(along, SIDE_M - len),
                Point::new(along + t, SIDE_M),
            ),
            2 => Aabb::from_corners(Point::new(0.0, along), Point::new(len, along + t)),
            _ => Aabb::from_corners(
                Point::new(SIDE_M - len, along),
                Point::new(SIDE_M, along + t),
            ),
        };
        Shape::bar(b)
    } else if kind < 0.55 {
        let len = uniform(rng, 0.6, 2.5);
        let b = if rng.chance(0.5) {
            Aabb::from_corners(Point::origin(), Point::new(len, t))
        } else {
            Aabb::from_corners(Point::origin(), Point::new(t, len))
        };
        free_at(rng, &Shape::bar(b))
    } else if kind < 0.8 {
        let s = Shape::ell(uniform(rng, 0.6, 2.0), uniform(rng, 0.6, 2.0), t);
        let s = s.turned(pick(rng, 0, 3)).anticlockwise();
        free_at(rng, &s)
    } else {
        // The opening must itself be a passage: at least the 0.5 m gap between the arms.
        let w = uniform(rng, (2.0 * t + GAP_M).max(0.8), 2.0);
        let s = Shape::dead_end(w, uniform(rng, 0.6, 1.6), t);
        match start.filter(|_| rng.chance(0.5)) {
            Some(st) => {
                let d = st - goal;
                // The U opens towards +y; turn its opening towards the start.
                let quarter = if d.x.abs() > d.y.abs() {
                    if d.x < 0.0 {
                        1
                    } else {
                        3
                    }
                } else if d.y > 0.0 {
                    0
                } else {
                    2
                };
                let s = s.turned(quarter).anticlockwise();
                let b = s.bounds();
                let on = goal + d * uniform(rng, 0.3, 0.7);
                s.placed(Point::new(on.x - b.width() / 2.0, on.y - b.height() / 2.0))
            }
            None => {
                let s = s.turned(pick(rng, 0, 3)).anticlockwise();
                free_at(rng, &s)
            }
        }
    }
}
