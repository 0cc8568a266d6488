//! Arenas like the real CiberRato and Micro-Rato labs (issue 32), the benchmark's headline
//! family: what the 5 x 5 m Micro-Rato generator lacks, compared side by side with 69 real
//! labs, drawn over the range those labs show.
//!
//! - Size: 18-28 x 9-14 CiberRato units (one unit is a CiberRato robot's diameter, 0.286 m
//!   here; the Micro-Rato robot is 0.24 m), a fifth of them square Micro-Rato labs of 14-17.5.
//! - Routes: a detour class is drawn first (free path over straight line under 1.3, 1.3-2,
//!   2-4, 4 and more: 36/28/27/9 %, the real labs' shares) and attempts are drawn until the
//!   arena's detour
//!   ([`crate::arena::free_path`]) falls in it, from structures that make real labs long: a
//!   long wall across the way with its gap at the far end, U traps around the beacon (nested,
//!   the outer open towards the start), a pocket around the start, a spiral with the beacon
//!   at its centre, a comb of walls to snake through; or a CiberRato `<Row>` maze.
//! - Gaps: the least gap between obstacles is drawn per lab, down to 0.32 m (1.33 robot
//!   diameters; 40 % of labs under 0.45 m), and the structures' gaps (a wall's end to the
//!   lab's wall, a comb's turns) use it; their long corridors are 0.45 m or more, as
//!   CiberRato's `<Row>` corridors (1.8 units) are.
//! - Targets: radius 0.85-2 units (0.24-0.57 m: down to one robot diameter).
//! - Beacons: a quarter of the labs have one or two more beacons, each over its own target
//!   area; a fifth have a home area (a target without a beacon) around the start.
//! - Heights: walls all above the beacon (hiding it, 55 %; `<Row>` walls always are), all
//!   below it (25 %), or mixed.
//! - Starts: one to three, headings anywhere; a quarter are odd: against a wall, in a corner
//!   pocket, or facing away from the beacon.
//!
//! Every arena's features are declared ([`Drawn::features`]) so the benchmark can report
//! success per feature.

use super::shapes::{fits_in, Shape};
use super::{pick, traps, uniform, Layout};
use crate::arena::CIBERRATO_UNIT_M as U;
use crate::geometry::{Aabb, Point};
use crate::rng::SimRng;

/// Least gap between obstacles, metres: a little more than the Micro-Rato robot (0.24 m).
pub const MIN_GAP_M: f64 = 0.32;
/// A gap under this is "narrow" (the real labs' 21 of 69 with gaps under 0.5 m).
pub const NARROW_GAP_M: f64 = 0.45;
/// The narrowest long corridor (a comb's slots, a spiral's or a nested U's corridor):
/// CiberRato's `<Row>` corridors are 1.8 units (0.51 m); gaps, which are short, go down to
/// [`MIN_GAP_M`].
const CORRIDOR_M: f64 = 0.45;
/// A wall this high (units) hides the 2-unit beacon; CiberRato's default wall height.
const HIGH_WALL: f64 = 4.0;
/// Below the beacon.
const LOW_WALL: f64 = super::xml::LOW_WALL;
/// Share of labs drawn as a `<Row>` maze.
const ROWS_SHARE: f64 = 0.25;

/// The detour classes the benchmark reports by (free path over straight line).
pub const DETOUR_BUCKETS: [(&str, f64, f64); 4] = [
    ("<1.3", 0.0, 1.3),
    ("1.3-2", 1.3, 2.0),
    ("2-4", 2.0, 4.0),
    (">=4", 4.0, f64::INFINITY),
];

/// The bucket name of a detour ratio.
pub fn detour_bucket(ratio: f64) -> &'static str {
    DETOUR_BUCKETS
        .iter()
        .find(|(_, lo, hi)| ratio >= *lo && ratio < *hi)
        .map_or(">=4", |b| b.0)
}

/// Shares of the detour classes the family is drawn over: the real labs' (issue 32: of 174
/// runs on 69 real labs, 63 under 1.3, 48 at 1.3-2, 48 at 2-4, 15 over 4).
const BUCKET_SHARES: [f64; 4] = [0.36, 0.28, 0.27, 0.09];

/// The detour class seed `seed` is drawn for (its own stream, so attempts do not move it).
pub fn wanted_bucket(rng: &mut SimRng) -> usize {
    let u = rng.uniform();
    let mut acc = 0.0;
    for (i, s) in BUCKET_SHARES.iter().enumerate() {
        acc += s;
        if u < acc {
            return i;
        }
    }
    BUCKET_SHARES.len() - 1
}

/// A drawn lab and the features it was drawn with.
pub(crate) struct Drawn {
    pub layout: Layout,
    pub features: Vec<&'static str>,
}

/// Draws one lab aiming at detour class `bucket` (an index of [`DETOUR_BUCKETS`]); `None`
/// when the draw broke a rule (a structure outside the lab or over the start or the goal).
pub(crate) fn layout(name: &str, rng: &mut SimRng, bucket: usize) -> Option<Drawn> {
    let mut d = if rng.chance(ROWS_SHARE) {
        rows_maze(name, rng)
    } else {
        walled(name, rng, bucket)?
    };
    add_beacons_and_homes(&mut d, rng);
    Some(d)
}

/// Lab size in metres: 18-28 x 9-14 units, or a square 14-17.5 (Micro-Rato).
fn lab_size(rng: &mut SimRng) -> (f64, f64) {
    if rng.chance(0.2) {
        let s = uniform(rng, 14.0, 17.5) * U;
        (s, s)
    } else {
        (uniform(rng, 18.0, 28.0) * U, uniform(rng, 9.0, 14.0) * U)
    }
}

/// The structure that makes a walled lab's route long.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Structure {
    None,
    LongWall,
    UTrap { nested: bool },
    Pocket,
    Spiral,
    Comb,
}

impl Structure {
    fn feature(self) -> Option<&'static str> {
        match self {
            Structure::None => None,
            Structure::LongWall => Some("long_wall"),
            Structure::UTrap { nested: false } => Some("u_trap"),
            Structure::UTrap { nested: true } => Some("nested_u"),
            Structure::Pocket => Some("start_pocket"),
            Structure::Spiral => Some("spiral"),
            Structure::Comb => Some("comb"),
        }
    }

    /// One for the detour class (weights picked so each class is reached in few attempts).
    fn draw(rng: &mut SimRng, bucket: usize) -> Structure {
        let options: &[(Structure, f64)] = match bucket {
            0 => &[
                (Structure::None, 0.5),
                (Structure::LongWall, 0.15),
                (Structure::Pocket, 0.15),
                (Structure::UTrap { nested: false }, 0.2),
            ],
            1 => &[
                (Structure::None, 0.15),
                (Structure::LongWall, 0.25),
                (Structure::UTrap { nested: false }, 0.2),
                (Structure::UTrap { nested: true }, 0.2),
                (Structure::Pocket, 0.2),
            ],
            2 => &[
                (Structure::LongWall, 0.25),
                (Structure::UTrap { nested: true }, 0.25),
                (Structure::Comb, 0.2),
                (Structure::Pocket, 0.1),
                (Structure::Spiral, 0.2),
            ],
            _ => &[
                (Structure::LongWall, 0.3),
                (Structure::UTrap { nested: true }, 0.15),
                (Structure::Spiral, 0.3),
                (Structure::Comb, 0.25),
            ],
        };
        let u = rng.uniform();
        let mut acc = 0.0;
        for &(s, p) in options {
            acc += p;
            if u < acc {
                return s;
            }
        }
        options.last().map_or(Structure::None, |o| o.0)
    }
}

/// What a walled lab is drawn with.
struct Plan {
    w: f64,
    h: f64,
    gap: f64,
    t: f64,
    goal_r: f64,
}

/// A lab of free-standing walls around one structure, filled with posts, bars and L's.
fn walled(name: &str, rng: &mut SimRng, bucket: usize) -> Option<Drawn> {
    let (w, h) = lab_size(rng);
    let narrow = rng.chance(0.4);
    let gap = if narrow {
        uniform(rng, MIN_GAP_M, NARROW_GAP_M)
    } else {
        uniform(rng, NARROW_GAP_M, 0.8)
    };
    let plan = Plan {
        w,
        h,
        gap,
        t: uniform(rng, 0.05, 0.3),
        goal_r: uniform(rng, 0.85, 2.0) * U,
    };
    let structure = Structure::draw(rng, bucket);
    let (goal, start, mut rects) = place_structure(&plan, structure, rng);
    let odd = rng.chance(0.25);
    let start_clear = if odd { 0.14 } else { 0.3 };
    // The structure keeps the rules too: inside the lab (or against its wall), clear of the
    // goal area and the start.
    let keeps = |r: &Aabb| {
        fits_in(&Shape::bar(*r), w, h, gap)
            && r.distance_to_point(goal) >= plan.goal_r + 0.05
            && r.distance_to_point(start) >= start_clear
    };
    if !rects.iter().all(keeps) {
        return None;
    }
    // Filler: posts, bars and L's, kept a gap from everything (or touching the outer wall).
    let mut shapes: Vec<Shape> = rects.iter().map(|r| Shape::bar(*r)).collect();
    let want = pick(rng, 2, 4 + (w * h / 3.0) as u32) as usize;
    let mut added = 0;
    for _ in 0..400 {
        if added == want {
            break;
        }
        let s = filler(&plan, rng);
        let ok = fits_in(&s, w, h, gap)
            && s.distance_to(goal) >= plan.goal_r + 0.05
            && s.distance_to(start) >= start_clear.max(0.3)
            && shapes.iter().all(|o| s.gap(o) >= gap);
        if ok {
            rects.extend(s.rects.iter().copied());
            shapes.push(s);
            added += 1;
        }
    }
    let mut starts = vec![start_pose(start, goal, odd, rng)];
    more_starts(&mut starts, &shapes, &plan, goal, rng);
    let heights = wall_heights(rects.len(), rng);
    let mut layout = Layout::plain(
        name,
        (w, h),
        rects.iter().map(|r| Shape::bar(*r).outline).collect(),
        (goal, plan.goal_r),
        starts,
    );
    layout.wall_heights = heights;
    let mut features = vec!["walls"];
    features.extend(structure.feature());
    if odd {
        features.push("odd_start");
    }
    Some(Drawn { layout, features })
}

/// Goal, start and the structure's walls.
fn place_structure(p: &Plan, s: Structure, rng: &mut SimRng) -> (Point, Point, Vec<Aabb>) {
    let (w, h, gap, t, r) = (p.w, p.h, p.gap, p.t, p.goal_r);
    let long_x = w >= h;
    // Coordinates along the long axis (a) and across it (c).
    let (la, lc) = if long_x { (w, h) } else { (h, w) };
    let pt = |a: f64, c: f64| {
        if long_x {
            Point::new(a, c)
        } else {
            Point::new(c, a)
        }
    };
    let margin = r + 0.3;
    match s {
        Structure::None => {
            let goal = pt(
                uniform(rng, margin, la - margin),
                uniform(rng, margin, lc - margin),
            );
            let start = far_point(p, goal, rng);
            (goal, start, Vec::new())
        }
        Structure::LongWall | Structure::Comb => {
            let n = if s == Structure::Comb {
                pick(rng, 2, 4)
            } else {
                1
            };
            let gap_w = uniform(rng, gap, (2.0 * gap).max(gap + 0.1));
            let low_first = rng.chance(0.5);
            // The walls between 25 % and 75 % of the long axis, a gap or more apart.
            let lo = la * 0.25;
            let hi = la * 0.75;
            // Each wall in its own share of the span, jittered so that neighbours keep a gap.
            let step = ((hi - lo) / f64::from(n)).max(CORRIDOR_M + t);
            let slack = ((step - CORRIDOR_M - t) / 2.0).max(0.0);
            let at: Vec<f64> = (0..n)
                .map(|k| lo + step * (f64::from(k) + 0.5) + uniform(rng, -slack, slack))
                .collect();
            let first = at.first().copied().unwrap_or(lo);
            let last = at.last().copied().unwrap_or(hi);
            // Start and goal near the end away from the first and last gaps (the long way).
            let far_c = |gap_low: bool, rng: &mut SimRng| {
                if rng.chance(0.7) {
                    if gap_low {
                        uniform(rng, lc * 0.55, lc - margin.min(lc / 2.0))
                    } else {
                        uniform(rng, margin.min(lc / 2.0), lc * 0.45)
                    }
                } else {
                    uniform(rng, margin.min(lc / 2.0), lc - margin.min(lc / 2.0))
                }
            };
            let start = pt(
                uniform(rng, 0.3, (first - t - 0.3).max(0.31)),
                far_c(low_first, rng),
            );
            let last_low = (n % 2 == 1) == low_first;
            let goal = pt(
                uniform(rng, (last + t + margin).min(la - margin), la - margin),
                far_c(last_low, rng),
            );
            let walls = traps::comb(w, h, &at, gap_w, low_first, t);
            (goal, start, walls)
        }
        Structure::UTrap { nested } => {
            let goal = pt(
                uniform(rng, la * 0.3, la * 0.7),
                uniform(rng, lc * 0.3, lc * 0.7),
            );
            // The start's side first (the U opens away from it), then the walls are moved
            // into the lab with the goal, and the start drawn again outside them.
            let side = far_point(p, goal, rng) - goal;
            let inner_w = 2.0 * r + 2.0 * uniform(rng, 0.1, 0.3);
            let inner_d = 2.0 * r + 2.0 * uniform(rng, 0.1, 0.3);
            let mut walls = traps::u_around(goal, inner_w, inner_d, -side, t);
            if nested {
                // The outer U around the inner one, open the other way (towards the start),
                // a corridor on its three sides.
                let corridor = uniform(rng, CORRIDOR_M, CORRIDOR_M + 0.2);
                let (hw, hd) = traps::u_half_extent(inner_w, inner_d, t);
                let outer_w = 2.0 * (hw + corridor);
                let outer_d = 2.0 * (hd + corridor);
                walls.extend(traps::u_around(goal, outer_w, outer_d, side, t));
            }
            let goal = shift_into(&mut walls, goal, p);
            let start = far_point_outside(p, goal, &walls, rng);
            (goal, start, walls)
        }
        Structure::Pocket => {
            let goal = pt(
                uniform(rng, margin, la - margin),
                uniform(rng, margin, lc - margin),
            );
            let start = far_point(p, goal, rng);
            let inner_w = uniform(rng, 0.6, 1.2);
            let inner_d = uniform(rng, 0.6, 1.4);
            let mut walls = traps::u_around(start, inner_w, inner_d, start - goal, t);
            let start = shift_into(&mut walls, start, p);
            (goal, start, walls)
        }
        Structure::Spiral => {
            let goal = pt(
                uniform(rng, la * 0.3, la * 0.7),
                uniform(rng, lc * 0.3, lc * 0.7),
            );
            let room = 2.0 * (r + uniform(rng, 0.1, 0.3)) + t;
            let corridor = uniform(rng, CORRIDOR_M, CORRIDOR_M + 0.3);
            let mut walls =
                traps::spiral(goal, room, corridor, pick(rng, 4, 8), pick(rng, 0, 3), t);
            let goal = shift_into(&mut walls, goal, p);
            let start = far_point_outside(p, goal, &walls, rng);
            (goal, start, walls)
        }
    }
}

/// Moves `walls` (and the point they are built around) so that they keep the gap from the
/// lab's walls where they can; returns the point moved.
fn shift_into(walls: &mut [Aabb], around: Point, p: &Plan) -> Point {
    let Some(b) = walls.iter().copied().reduce(|a, b| a.union(&b)) else {
        return around;
    };
    let fit = |lo: f64, hi: f64, side: f64| {
        if hi - lo > side - 2.0 * p.gap {
            0.0
        } else if lo < p.gap {
            p.gap - lo
        } else if hi > side - p.gap {
            side - p.gap - hi
        } else {
            0.0
        }
    };
    let d = crate::geometry::Vector::new(fit(b.min.x, b.max.x, p.w), fit(b.min.y, b.max.y, p.h));
    for r in walls.iter_mut() {
        *r = Aabb {
            min: r.min + d,
            max: r.max + d,
        };
    }
    around + d
}

/// [`far_point`] outside the box round `walls` (grown by 0.3 m), when one of 50 draws is.
fn far_point_outside(p: &Plan, goal: Point, walls: &[Aabb], rng: &mut SimRng) -> Point {
    let Some(b) = walls.iter().copied().reduce(|a, b| a.union(&b)) else {
        return far_point(p, goal, rng);
    };
    let grown = b.expanded(0.3);
    let mut q = far_point(p, goal, rng);
    for _ in 0..50 {
        if !grown.contains(q) {
            break;
        }
        q = far_point(p, goal, rng);
    }
    q
}

/// A point at least 60 % of the lab's diagonal from `goal` (or the farthest of 50 draws).
fn far_point(p: &Plan, goal: Point, rng: &mut SimRng) -> Point {
    let want = 0.6 * p.w.hypot(p.h);
    let mut best = Point::new(0.3, 0.3);
    for _ in 0..50 {
        let q = Point::new(uniform(rng, 0.3, p.w - 0.3), uniform(rng, 0.3, p.h - 0.3));
        if (q - goal).norm() > (best - goal).norm() {
            best = q;
        }
        if (q - goal).norm() >= want {
            return q;
        }
    }
    best
}

/// A post (0.5-1 unit square), a bar (1-6 units) or an L, somewhere in the lab.
fn filler(p: &Plan, rng: &mut SimRng) -> Shape {
    let kind = rng.uniform();
    let shape = if kind < 0.35 {
        let s = uniform(rng, 0.5, 1.0) * U;
        Shape::bar(Aabb::from_corners(Point::origin(), Point::new(s, s)))
    } else if kind < 0.8 {
        let len = uniform(rng, 1.0, 6.0) * U;
        let b = if rng.chance(0.5) {
            Point::new(len, p.t)
        } else {
            Point::new(p.t, len)
        };
        Shape::bar(Aabb::from_corners(Point::origin(), b))
    } else {
        let s = Shape::ell(uniform(rng, 1.5, 5.0) * U, uniform(rng, 1.5, 5.0) * U, p.t);
        s.turned(pick(rng, 0, 3)).anticlockwise()
    };
    let b = shape.bounds();
    let x = uniform(rng, 0.0, (p.w - b.width()).max(0.0));
    let y = uniform(rng, 0.0, (p.h - b.height()).max(0.0));
    shape.placed(Point::new(x, y))
}

/// The first start's heading: anywhere, or (odd) facing away from the goal.
fn start_pose(start: Point, goal: Point, odd: bool, rng: &mut SimRng) -> [f64; 3] {
    let pi = std::f64::consts::PI;
    let heading = if odd && rng.chance(0.5) {
        let away = (start.y - goal.y).atan2(start.x - goal.x);
        away + uniform(rng, -0.5, 0.5)
    } else {
        uniform(rng, -pi, pi)
    };
    [start.x, start.y, heading]
}

/// Up to two more starts (a grid file holds several), clear of walls and the goal.
fn more_starts(
    starts: &mut Vec<[f64; 3]>,
    shapes: &[Shape],
    p: &Plan,
    goal: Point,
    rng: &mut SimRng,
) {
    let want = pick(rng, 0, 2) as usize;
    for _ in 0..100 {
        if starts.len() > want {
            break;
        }
        let q = Point::new(uniform(rng, 0.3, p.w - 0.3), uniform(rng, 0.3, p.h - 0.3));
        let clear = shapes.iter().all(|s| s.distance_to(q) >= 0.3);
        let apart = starts
            .iter()
            .all(|s| (Point::new(s[0], s[1]) - q).norm() >= 0.6);
        if clear && apart && (q - goal).norm() > p.goal_r + 0.3 {
            let pi = std::f64::consts::PI;
            starts.push([q.x, q.y, uniform(rng, -pi, pi)]);
        }
    }
}

/// Every wall above the beacon, every wall below it, or each its own.
fn wall_heights(n: usize, rng: &mut SimRng) -> Vec<f64> {
    let u = rng.uniform();
    (0..n)
        .map(|_| {
            if u < 0.55 {
                HIGH_WALL
            } else if u < 0.8 {
                LOW_WALL
            } else if rng.chance(0.5) {
                HIGH_WALL
            } else {
                LOW_WALL
            }
        })
        .collect()
}

/// A CiberRato `<Row>` maze: 2-unit cells, 0.2-unit walls, 4 units high (above the beacon),
/// carved depth-first and then opened by 5-60 % of its inner walls.
fn rows_maze(name: &str, rng: &mut SimRng) -> Drawn {
    let nx = pick(rng, 9, 14) as usize;
    let ny = pick(rng, 5, 7) as usize;
    let cell = 2.0 * U;
    let (w, h) = (nx as f64 * cell, ny as f64 * cell);
    // east[c][r]: wall right of (c, r); north: wall above it.
    let from = (pick(rng, 0, nx as u32 - 1) as usize, 0);
    let (mut east, mut north) = super::carve(nx, ny, from, rng);
    let open = uniform(rng, 0.05, 0.6);
    for v in east.iter_mut().chain(north.iter_mut()) {
        if *v && rng.chance(open) {
            *v = false;
        }
    }
    let mut rows = Vec::new();
    for r in (0..ny).rev() {
        if r + 1 < ny {
            let pattern: String = (0..nx)
                .map(|c| if north[r * nx + c] { "--+" } else { "  +" })
                .collect();
            rows.push((2 * r as u32 + 1, pattern));
        }
        let pattern: String = (0..nx)
            .map(|c| {
                if c + 1 < nx && east[r * nx + c] {
                    "  |"
                } else {
                    "   "
                }
            })
            .collect();
        rows.push((2 * r as u32, pattern));
    }
    let centre = |c: usize, r: usize| Point::new((c as f64 + 0.5) * cell, (r as f64 + 0.5) * cell);
    let goal_cell = (
        pick(rng, 0, nx as u32 - 1) as usize,
        pick(rng, 0, ny as u32 - 1) as usize,
    );
    let goal = centre(goal_cell.0, goal_cell.1);
    let mut start = centre(0, 0);
    for _ in 0..50 {
        let s = centre(
            pick(rng, 0, nx as u32 - 1) as usize,
            pick(rng, 0, ny as u32 - 1) as usize,
        );
        if (s - goal).norm() > (start - goal).norm() {
            start = s;
        }
        if (s - goal).norm() >= 0.5 * w.hypot(h) {
            start = s;
            break;
        }
    }
    let pi = std::f64::consts::PI;
    let mut layout = Layout::plain(
        name,
        (w, h),
        Vec::new(),
        (goal, uniform(rng, 0.85, 1.0) * U),
        vec![[start.x, start.y, uniform(rng, -pi, pi)]],
    );
    layout.rows = rows;
    Drawn {
        layout,
        features: vec!["rows"],
    }
}

/// A quarter of the labs get one or two more beacons over their own target areas, away from
/// the goal; a fifth a home area (a target without a beacon) around the first start.
fn add_beacons_and_homes(d: &mut Drawn, rng: &mut SimRng) {
    let l = &mut d.layout;
    let goal = l.beacon;
    let r = l.target.1;
    if rng.chance(0.25) {
        let want = pick(rng, 1, 2) as usize;
        for _ in 0..100 {
            if l.more_beacons.len() == want {
                break;
            }
            let q = Point::new(
                uniform(rng, r + 0.2, l.width_m - r - 0.2),
                uniform(rng, r + 0.2, l.height_m - r - 0.2),
            );
            let clear_of_start = l
                .starts
                .iter()
                .all(|s| (Point::new(s[0], s[1]) - q).norm() > r + 0.3);
            let apart =
                (q - goal).norm() >= 1.5 && l.more_beacons.iter().all(|b| (b.0 - q).norm() >= 1.0);
            if clear_of_start && apart {
                l.more_beacons.push((q, r));
            }
        }
    }
    if rng.chance(0.2) {
        if let Some(s) = l.starts.first() {
            let home = (Point::new(s[0], s[1]), uniform(rng, 0.85, 2.0) * U);
            if (home.0 - goal).norm() > home.1 + r + 0.1 {
                l.homes.push(home);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn buckets_name_the_detour_classes() {
        assert_eq!(detour_bucket(1.0), "<1.3");
        assert_eq!(detour_bucket(1.3), "1.3-2");
        assert_eq!(detour_bucket(3.9), "2-4");
        assert_eq!(detour_bucket(4.0), ">=4");
        assert_eq!(detour_bucket(40.0), ">=4");
    }

    #[test]
    fn the_family_covers_every_detour_class_and_the_real_labs_features() {
        let radius = f64::from(robot_firmware::MICRO_RATO.body_diameter_m) / 2.0;
        let mut classes = std::collections::BTreeMap::new();
        let mut features = std::collections::BTreeSet::new();
        let mut larger = 0;
        for seed in 1..=60 {
            let g = crate::arena_gen::generate(crate::arena_gen::Kind::RealLike, seed)
                .expect("generates");
            let ratio = crate::arena_gen::detour_of(&g.arena, radius).expect("a route");
            *classes.entry(detour_bucket(ratio)).or_insert(0) += 1;
            features.extend(g.features.iter().copied());
            let a = &g.arena;
            larger += usize::from(a.bounds.width().max(a.bounds.height()) > 5.0);
            if a.beacons.len() > 1 {
                features.insert("several_beacons");
            }
            let t = a.target().expect("a goal area");
            assert!(t.radius_m >= 0.24 - 1e-9, "down to one robot diameter");
        }
        for (class, _, _) in DETOUR_BUCKETS {
            assert!(
                classes.get(class).copied().unwrap_or(0) >= 3,
                "{class}: {classes:?}"
            );
        }
        for f in [
            "rows",
            "walls",
            "long_wall",
            "comb",
            "odd_start",
            "several_beacons",
        ] {
            assert!(features.contains(f), "{f} missing: {features:?}");
        }
        assert!(
            larger >= 20,
            "most labs are larger than Micro-Rato's 5 m: {larger}"
        );
    }
}
