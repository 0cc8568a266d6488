//! Naive reference implementations the fast code is checked against.

extern crate std;

use std::collections::BTreeSet;
use std::vec;
use std::vec::Vec;

use crate::nav::{Cell, Grid, GridPoint, Square};

/// Seed 004 §6, Fig. 6 by the letter: for each cell in row-major order not yet in a square,
/// try every size from large to small and take the first square of free, uncovered cells.
pub fn fig6<S: AsRef<[u8]>>(grid: &Grid<S>) -> Vec<Square> {
    let (w, h) = (grid.width() as usize, grid.height() as usize);
    let mut covered = vec![false; w * h];
    let mut out = Vec::new();
    for i in 0..h {
        for j in 0..w {
            if covered[i * w + j] {
                continue;
            }
            let fits = |s: usize| {
                i + s <= h
                    && j + s <= w
                    && (i..i + s).all(|y| {
                        (j..j + s).all(|x| grid.get(x, y) == Cell::Free && !covered[y * w + x])
                    })
            };
            let Some(s) = (1..=w.max(h)).rev().find(|&s| fits(s)) else {
                continue;
            };
            for y in i..i + s {
                for x in j..j + s {
                    covered[y * w + x] = true;
                }
            }
            out.push(Square {
                x: j as u16,
                y: i as u16,
                size: s as u16,
            });
        }
    }
    out
}

/// Whether two squares share an edge segment of positive length (the module's adjacency rule).
pub fn touch(a: &Square, b: &Square) -> bool {
    let span = |p: u16, s: u16| (u32::from(p), u32::from(p) + u32::from(s));
    let ((ax0, ax1), (ay0, ay1)) = (span(a.x, a.size), span(a.y, a.size));
    let ((bx0, bx1), (by0, by1)) = (span(b.x, b.size), span(b.y, b.size));
    let overlap = |l0: u32, l1: u32, m0: u32, m1: u32| l0.max(m0) < l1.min(m1);
    ((ax1 == bx0 || bx1 == ax0) && overlap(ay0, ay1, by0, by1))
        || ((ay1 == by0 || by1 == ay0) && overlap(ax0, ax1, bx0, bx1))
}

/// All edges (a < b) by comparing every pair of squares: O(R^2).
pub fn edges(squares: &[Square]) -> BTreeSet<(u32, u32)> {
    let mut out = BTreeSet::new();
    for (a, sa) in squares.iter().enumerate() {
        for (b, sb) in squares.iter().enumerate().skip(a + 1) {
            if touch(sa, sb) {
                out.insert((a as u32, b as u32));
            }
        }
    }
    out
}

fn ceil_dist(a: GridPoint, b: GridPoint) -> u64 {
    let (dx, dy) = (i64::from(a.x - b.x), i64::from(a.y - b.y));
    let d2 = (dx * dx + dy * dy) as u64;
    // Independent of the planner's isqrt: float estimate, then exact integer correction.
    let mut r = (d2 as f64).sqrt() as u64;
    while r * r > d2 {
        r -= 1;
    }
    while (r + 1) * (r + 1) <= d2 {
        r += 1;
    }
    if r * r < d2 {
        r + 1
    } else {
        r
    }
}

/// Least cost start -> centres -> goal over the region graph by plain O(R^2) Dijkstra.
pub fn dijkstra(
    squares: &[Square],
    from: u32,
    to: u32,
    start: GridPoint,
    goal: GridPoint,
) -> Option<u64> {
    let n = squares.len();
    let adj = edges(squares);
    let c = |i: usize| squares[i].centre();
    let mut dist = vec![u64::MAX; n];
    let mut done = vec![false; n];
    dist[from as usize] = ceil_dist(start, c(from as usize));
    loop {
        let u = (0..n)
            .filter(|&i| !done[i] && dist[i] != u64::MAX)
            .min_by_key(|&i| dist[i])?;
        done[u] = true;
        if u == to as usize {
            return Some(dist[u] + ceil_dist(c(u), goal));
        }
        for v in 0..n {
            let e = (u.min(v) as u32, u.max(v) as u32);
            if !done[v] && adj.contains(&e) {
                dist[v] = dist[v].min(dist[u] + ceil_dist(c(u), c(v)));
            }
        }
    }
}
