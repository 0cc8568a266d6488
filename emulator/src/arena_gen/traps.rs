//! The structures that make real CiberRato/Micro-Rato labs long to cross (issue 32): a long
//! wall across the way with its gap at the far end, U traps around the beacon (nested, the
//! outer one open towards the start), a pocket around the start, a square spiral with the
//! beacon at its centre, a comb of walls the robot must snake through. Each is a list of
//! rectangles in metres (its walls), built around given points, with the passages between its
//! own walls at least the gap it is given.

use crate::geometry::{Aabb, Point, Vector};

fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Aabb {
    Aabb::from_corners(Point::new(x0, y0), Point::new(x1, y1))
}

/// A wall of thickness `t` along the x axis (`across` false) or the y axis, from `from` to
/// `to` along it, centred on `at` across it.
fn bar(along_x: bool, from: f64, to: f64, at: f64, t: f64) -> Aabb {
    if along_x {
        rect(from, at - t / 2.0, to, at + t / 2.0)
    } else {
        rect(at - t / 2.0, from, at + t / 2.0, to)
    }
}

/// A wall across a `w` x `h` lab at `at` along the lab's long axis, from one side to the
/// other except for a gap of `gap_w` at one end (`gap_low`: at the low end); `t` thick.
pub(crate) fn long_wall(w: f64, h: f64, at: f64, gap_w: f64, gap_low: bool, t: f64) -> Vec<Aabb> {
    let along_x = w < h;
    let span = if along_x { w } else { h };
    let (from, to) = if gap_low {
        (gap_w, span)
    } else {
        (0.0, span - gap_w)
    };
    vec![bar(along_x, from, to, at, t)]
}

/// A comb: `n` walls across a `w` x `h` lab at the positions `at` along its long axis,
/// alternately leaving a gap of `gap_w` at the low and the high end, so the way between them
/// snakes; the first gap at the low end when `low_first`.
pub(crate) fn comb(w: f64, h: f64, at: &[f64], gap_w: f64, low_first: bool, t: f64) -> Vec<Aabb> {
    at.iter()
        .enumerate()
        .flat_map(|(k, &x)| long_wall(w, h, x, gap_w, (k % 2 == 0) == low_first, t))
        .collect()
}

/// A U of walls `t` thick around `centre`, its inside `inner_w` across and `inner_d` deep
/// (centre in the middle of the inside), open towards the unit direction `open` (one of the
/// four axis directions; the nearest is taken).
pub(crate) fn u_around(
    centre: Point,
    inner_w: f64,
    inner_d: f64,
    open: Vector,
    t: f64,
) -> Vec<Aabb> {
    // Built open towards +y, then turned.
    let (hw, hd) = (inner_w / 2.0, inner_d / 2.0);
    let local = [
        rect(-hw - t, -hd - t, hw + t, -hd),
        rect(-hw - t, -hd - t, -hw, hd),
        rect(hw, -hd - t, hw + t, hd),
    ];
    let turn = quarter_towards(open);
    local
        .iter()
        .map(|r| {
            let (a, b) = (rotate(r.min, turn), rotate(r.max, turn));
            Aabb::from_corners(
                centre + (a - Point::origin()),
                centre + (b - Point::origin()),
            )
        })
        .collect()
}

/// Quarter turns anticlockwise from +y to the axis direction nearest `d`.
fn quarter_towards(d: Vector) -> u32 {
    if d.x.abs() > d.y.abs() {
        if d.x < 0.0 {
            1
        } else {
            3
        }
    } else if d.y < 0.0 {
        2
    } else {
        0
    }
}

fn rotate(p: Point, quarter: u32) -> Point {
    match quarter % 4 {
        0 => p,
        1 => Point::new(-p.y, p.x),
        2 => Point::new(-p.x, -p.y),
        _ => Point::new(p.y, -p.x),
    }
}

/// The outside extent of [`u_around`]'s walls: half across, half along its depth.
pub(crate) fn u_half_extent(inner_w: f64, inner_d: f64, t: f64) -> (f64, f64) {
    (inner_w / 2.0 + t, inner_d / 2.0 + t)
}

/// A square spiral of `arms` walls `t` thick whose innermost room (about `room` across) holds
/// `centre`, its corridor `corridor` wide, turned by `quarter` quarter turns; the way in winds
/// from outside to the room.
pub(crate) fn spiral(
    centre: Point,
    room: f64,
    corridor: f64,
    arms: u32,
    quarter: u32,
    t: f64,
) -> Vec<Aabb> {
    let s = corridor + t;
    // The turtle's path (see the module notes of `real_like`): arm k runs along direction k
    // (+x, +y, -x, -y, ...) with lengths a, a, a + s, a + s, a + 2s, ...; the room it closes
    // is centred at (-s/2, 0) from where the turtle began + (a/2, a/2).
    let a = room;
    let mut p = Point::new(-a / 2.0 + s / 2.0, -a / 2.0);
    let dirs = [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)];
    let mut out = Vec::new();
    for k in 0..arms as usize {
        let len = a + (k / 2) as f64 * s;
        let (dx, dy) = dirs[k % 4];
        let q = Point::new(p.x + dx * len, p.y + dy * len);
        // Grown by half a wall at both ends so the corners close.
        let lo = Point::new(p.x.min(q.x) - t / 2.0, p.y.min(q.y) - t / 2.0);
        let hi = Point::new(p.x.max(q.x) + t / 2.0, p.y.max(q.y) + t / 2.0);
        let (a, b) = (rotate(lo, quarter), rotate(hi, quarter));
        out.push(Aabb::from_corners(
            centre + (a - Point::origin()),
            centre + (b - Point::origin()),
        ));
        p = q;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::arena_gen::shapes::box_gap;

    #[test]
    fn a_spiral_leaves_its_room_and_corridor_clear() {
        let (room, corridor, t) = (1.0, 0.4, 0.1);
        let c = Point::new(5.0, 5.0);
        for quarter in 0..4 {
            let walls = spiral(c, room, corridor, 6, quarter, t);
            let near = walls
                .iter()
                .map(|r| r.distance_to_point(c))
                .fold(f64::INFINITY, f64::min);
            assert!(near >= (room - t) / 2.0 - 1e-9, "{near}");
            // Successive turns on the same side are a corridor apart.
            assert!((box_gap(&walls[0], &walls[4]) - corridor).abs() < 1e-9);
        }
    }

    #[test]
    fn a_u_opens_where_it_is_told() {
        let c = Point::new(0.0, 0.0);
        let walls = u_around(c, 1.0, 0.8, Vector::new(-1.0, 0.0), 0.1);
        // Open towards -x: nothing between the centre and x = -2 on its line.
        let probe = rect(-2.0, -0.01, -0.01, 0.01);
        assert!(walls.iter().all(|w| box_gap(w, &probe) > 0.0));
        let back = rect(0.01, -0.01, 2.0, 0.01);
        assert!(walls.iter().any(|w| box_gap(w, &back) == 0.0));
    }
}
