//! Khepera boxes after seed 000 §4 and Fig. 17: a walled box of 75 x 60 cm (the paper's
//! odometry box) or larger, start A near one end and goal B near the other, and between them
//! blocks of 5-35 cm, bars, and none, one or two successive dead ends (U shapes open towards
//! A, so the straight line from A to B runs into them, as in Fig. 17).
//!
//! Sizes the paper does not give: box 0.75-1.2 x 0.60-1.0 m; dead ends 12-30 cm wide (an
//! opening of at least 8 cm, so the 5.5 cm robot can drive in) and 8-20 cm deep, walls 1-3 cm;
//! bars 15-35 cm long, 1-3 cm thick. Obstacles keep 8 cm from each other and from the outer
//! walls (or touch them), room for the robot to pass. The goal is a 5 cm circle, the paper's
//! tolerance (Fig. 17), with a beacon over it (which the Khepera has no sensor for).

use super::shapes::{fits_in, Shape};
use super::{pick, uniform, Layout};
use crate::geometry::{Aabb, Point};
use crate::rng::SimRng;

/// Least gap between obstacles, metres: the 5.5 cm robot and a margin.
pub const GAP_M: f64 = 0.08;
/// Goal circle radius, metres: seed 000 Fig. 17's 5 cm tolerance.
pub const GOAL_RADIUS_M: f64 = 0.05;
/// Clearance from A and B to any obstacle, metres.
const END_CLEARANCE_M: f64 = 0.07;

pub(crate) fn layout(name: &str, rng: &mut SimRng) -> Layout {
    let (w, h) = (uniform(rng, 0.75, 1.2), uniform(rng, 0.60, 1.0));
    let end = 0.1;
    let mut a = Point::new(end, uniform(rng, 0.2, h - 0.2));
    let mut b = Point::new(w - end, uniform(rng, 0.2, h - 0.2));
    let dead_ends = match rng.uniform() {
        u if u < 0.2 => 0,
        u if u < 0.6 => 1,
        _ => 2,
    };
    let mut shapes: Vec<Shape> = Vec::new();
    let ok = |s: &Shape, shapes: &[Shape], a: Point, b: Point| {
        fits_in(s, w, h, GAP_M)
            && s.distance_to(a) >= END_CLEARANCE_M
            && s.distance_to(b) >= END_CLEARANCE_M
            && shapes.iter().all(|o| s.gap(o) >= GAP_M)
    };
    let fractions: &[f64] = match dead_ends {
        0 => &[],
        1 => &[0.5],
        _ => &[0.35, 0.7],
    };
    for &f in fractions {
        for _ in 0..50 {
            let t = uniform(rng, 0.01, 0.03);
            let width = uniform(rng, (2.0 * t + 0.08).max(0.12), 0.30);
            let depth = uniform(rng, 0.08, 0.20);
            // Open towards -x (towards A): a quarter turn of the +y-open U.
            let u = Shape::dead_end(width, depth, t).turned(1);
            let p = a + (b - a) * f;
            let at = Point::new(p.x - depth / 2.0, p.y - width / 2.0);
            let s = u.placed(at).anticlockwise();
            if ok(&s, &shapes, a, b) {
                shapes.push(s);
                break;
            }
        }
    }
    let (blocks, bars) = (pick(rng, 0, 3), pick(rng, 0, 2));
    for i in 0..blocks + bars {
        for _ in 0..50 {
            let local = if i < blocks {
                let side = uniform(rng, 0.05, 0.35);
                Aabb::from_corners(Point::origin(), Point::new(side, side))
            } else {
                let (len, t) = (uniform(rng, 0.15, 0.35), uniform(rng, 0.01, 0.03));
                let across = if rng.chance(0.5) { (t, len) } else { (len, t) };
                Aabb::from_corners(Point::origin(), Point::new(across.0, across.1))
            };
            // Half of them on the line from A to B, in the robot's way.
            let centre = if rng.chance(0.5) {
                a + (b - a) * uniform(rng, 0.2, 0.8)
            } else {
                Point::new(uniform(rng, 0.0, w), uniform(rng, 0.0, h))
            };
            let at = Point::new(
                centre.x - local.width() / 2.0,
                centre.y - local.height() / 2.0,
            );
            let s = Shape::bar(local).placed(at);
            if ok(&s, &shapes, a, b) {
                shapes.push(s);
                break;
            }
        }
    }
    // Either end of the box may be the start, either way up.
    let heading = uniform(rng, -std::f64::consts::PI, std::f64::consts::PI);
    let (mirror_x, mirror_y) = (rng.chance(0.5), rng.chance(0.5));
    let flip = |p: Point| {
        Point::new(
            if mirror_x { w - p.x } else { p.x },
            if mirror_y { h - p.y } else { p.y },
        )
    };
    a = flip(a);
    b = flip(b);
    let walls = shapes
        .into_iter()
        .map(|s| {
            let mut outline: Vec<Point> = s.outline.into_iter().map(flip).collect();
            // A single mirror turns the outline clockwise; CiberRato's labs list them the
            // other way round.
            if mirror_x != mirror_y {
                outline.reverse();
            }
            outline
        })
        .collect();
    Layout::plain(
        name,
        (w, h),
        walls,
        (b, GOAL_RADIUS_M),
        vec![[a.x, a.y, heading]],
    )
}
