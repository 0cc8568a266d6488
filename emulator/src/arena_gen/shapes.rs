//! Obstacle shapes the generators place: bars (rectangles), L corners and U dead ends, each a
//! polygon outline (what the lab file holds) plus the rectangles it is the union of (what the
//! spacing rules measure).

use crate::geometry::{polygon_signed_area, Aabb, Point};

/// An obstacle: its outline and the axis-aligned rectangles whose union it is.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Shape {
    /// Corners, anticlockwise (as in CiberRato's own labs).
    pub outline: Vec<Point>,
    /// The rectangles it is made of.
    pub rects: Vec<Aabb>,
}

fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Aabb {
    Aabb::from_corners(Point::new(x0, y0), Point::new(x1, y1))
}

impl Shape {
    /// A solid rectangle.
    pub fn bar(b: Aabb) -> Shape {
        Shape {
            outline: vec![
                b.min,
                Point::new(b.max.x, b.min.y),
                b.max,
                Point::new(b.min.x, b.max.y),
            ],
            rects: vec![b],
        }
    }

    /// An L: arms `a` along +x and `b` along +y from the origin corner, `t` thick.
    pub fn ell(a: f64, b: f64, t: f64) -> Shape {
        let p = Point::new;
        Shape {
            outline: vec![p(0.0, 0.0), p(a, 0.0), p(a, t), p(t, t), p(t, b), p(0.0, b)],
            rects: vec![rect(0.0, 0.0, a, t), rect(0.0, 0.0, t, b)],
        }
    }

    /// A U (dead end) `w` wide and `d` deep, open towards +y, walls `t` thick.
    pub fn dead_end(w: f64, d: f64, t: f64) -> Shape {
        let p = Point::new;
        Shape {
            outline: vec![
                p(0.0, 0.0),
                p(w, 0.0),
                p(w, d),
                p(w - t, d),
                p(w - t, t),
                p(t, t),
                p(t, d),
                p(0.0, d),
            ],
            rects: vec![
                rect(0.0, 0.0, w, t),
                rect(0.0, 0.0, t, d),
                rect(w - t, 0.0, w, d),
            ],
        }
    }

    /// This shape turned `quarter` quarter turns anticlockwise about the origin.
    pub fn turned(&self, quarter: u32) -> Shape {
        let turn = |q: Point| match quarter % 4 {
            0 => q,
            1 => Point::new(-q.y, q.x),
            2 => Point::new(-q.x, -q.y),
            _ => Point::new(q.y, -q.x),
        };
        Shape {
            outline: self.outline.iter().map(|&q| turn(q)).collect(),
            rects: self
                .rects
                .iter()
                .map(|r| Aabb::from_corners(turn(r.min), turn(r.max)))
                .collect(),
        }
    }

    /// The bounding box.
    pub fn bounds(&self) -> Aabb {
        self.rects
            .iter()
            .skip(1)
            .fold(self.rects[0], |acc, r| acc.union(r))
    }

    /// This shape moved so that its bounding box's lower-left corner is at `at`.
    pub fn placed(&self, at: Point) -> Shape {
        let b = self.bounds();
        let d = at - b.min;
        Shape {
            outline: self.outline.iter().map(|&q| q + d).collect(),
            rects: self
                .rects
                .iter()
                .map(|r| Aabb {
                    min: r.min + d,
                    max: r.max + d,
                })
                .collect(),
        }
    }

    /// The outline anticlockwise (turning keeps orientation, but say it once, here).
    pub fn anticlockwise(mut self) -> Shape {
        if polygon_signed_area(&self.outline) < 0.0 {
            self.outline.reverse();
        }
        self
    }

    /// Smallest distance between the two shapes (0 when they touch or overlap).
    pub fn gap(&self, o: &Shape) -> f64 {
        self.rects
            .iter()
            .flat_map(|a| o.rects.iter().map(move |b| box_gap(a, b)))
            .fold(f64::INFINITY, f64::min)
    }

    /// Distance from a point to the shape (0 inside).
    pub fn distance_to(&self, p: Point) -> f64 {
        self.rects
            .iter()
            .map(|r| r.distance_to_point(p))
            .fold(f64::INFINITY, f64::min)
    }
}

/// Distance between two closed boxes.
pub(crate) fn box_gap(a: &Aabb, b: &Aabb) -> f64 {
    let dx = (a.min.x - b.max.x).max(b.min.x - a.max.x).max(0.0);
    let dy = (a.min.y - b.max.y).max(b.min.y - a.max.y).max(0.0);
    dx.hypot(dy)
}

/// The spacing rule against the outer walls of a `w` x `h` arena: every rectangle either lies
/// against a side (touching it) or keeps at least `gap` from it; and nothing sticks out.
pub(crate) fn fits_in(s: &Shape, w: f64, h: f64, gap: f64) -> bool {
    let eps = 1e-9;
    s.rects.iter().all(|r| {
        let inside = r.min.x >= -eps && r.min.y >= -eps && r.max.x <= w + eps && r.max.y <= h + eps;
        let side_ok = |d: f64| d <= eps || d >= gap;
        inside
            && side_ok(r.min.x)
            && side_ok(r.min.y)
            && side_ok(w - r.max.x)
            && side_ok(h - r.max.y)
    })
}
