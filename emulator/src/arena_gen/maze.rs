//! Micromouse mazes: 4-16 cells a side (so the classic 0.18 m pitch), carved as a perfect
//! maze by a randomised depth-first search, then about one interior wall in twelve removed so
//! that, as in contest mazes, there are loops and more than one way. Start: the bottom-left
//! cell (the contest's corner start); goal: the cell farthest from it along the maze.
//! Written in the text format [`crate::arena::micromouse`] reads (`S` and `G` marks).

use std::collections::VecDeque;

use super::pick;
use crate::arena::micromouse::{Maze, Side};
use crate::rng::SimRng;

/// Chance that an interior wall left by the carving is removed (loops).
const LOOP_CHANCE: f64 = 1.0 / 12.0;

pub(crate) fn generate(rng: &mut SimRng) -> String {
    let (cols, rows) = (pick(rng, 4, 16), pick(rng, 4, 16));
    let (n, m) = (cols as usize, rows as usize);
    let mut maze = Maze {
        cols,
        rows,
        horizontal: vec![true; (m + 1) * n],
        vertical: vec![true; m * (n + 1)],
        starts: vec![(0, 0)],
        goals: Vec::new(),
    };
    // Carve: iterative depth-first search with a random next neighbour.
    let mut seen = vec![false; n * m];
    let mut stack = vec![(0usize, 0usize)];
    seen[0] = true;
    while let Some(&(c, r)) = stack.last() {
        let options: Vec<(usize, usize)> = neighbours(c, r, n, m)
            .into_iter()
            .filter(|&(nc, nr)| !seen[nr * n + nc])
            .collect();
        if options.is_empty() {
            stack.pop();
            continue;
        }
        let (nc, nr) = options[(rng.next_u64() % options.len() as u64) as usize];
        open(&mut maze, (c, r), (nc, nr));
        seen[nr * n + nc] = true;
        stack.push((nc, nr));
    }
    // Loops: knock out a few interior walls.
    for r in 0..m {
        for c in 0..n {
            if c + 1 < n && rng.chance(LOOP_CHANCE) {
                open(&mut maze, (c, r), (c + 1, r));
            }
            if r + 1 < m && rng.chance(LOOP_CHANCE) {
                open(&mut maze, (c, r), (c, r + 1));
            }
        }
    }
    let far = farthest(&maze);
    maze.goals.push((far.0 as u32, far.1 as u32));
    maze_text(&maze)
}

fn neighbours(c: usize, r: usize, n: usize, m: usize) -> Vec<(usize, usize)> {
    let mut v = Vec::with_capacity(4);
    if c > 0 {
        v.push((c - 1, r));
    }
    if c + 1 < n {
        v.push((c + 1, r));
    }
    if r > 0 {
        v.push((c, r - 1));
    }
    if r + 1 < m {
        v.push((c, r + 1));
    }
    v
}

/// Removes the wall between two adjacent cells.
fn open(maze: &mut Maze, a: (usize, usize), b: (usize, usize)) {
    let n = maze.cols as usize;
    let (lo, hi) = if (a.1, a.0) < (b.1, b.0) {
        (a, b)
    } else {
        (b, a)
    };
    if lo.1 == hi.1 {
        // Side by side: the vertical line east of `lo`.
        maze.vertical[lo.1 * (n + 1) + lo.0 + 1] = false;
    } else {
        // One above the other: the horizontal line north of `lo`.
        maze.horizontal[(lo.1 + 1) * n + lo.0] = false;
    }
}

/// The cell farthest (in moves) from the start cell (0, 0); ties go to the first found.
fn farthest(maze: &Maze) -> (usize, usize) {
    let (n, m) = (maze.cols as usize, maze.rows as usize);
    let mut dist = vec![usize::MAX; n * m];
    dist[0] = 0;
    let mut queue = VecDeque::from([(0usize, 0usize)]);
    let mut best = (0, 0);
    while let Some((c, r)) = queue.pop_front() {
        if dist[r * n + c] > dist[best.1 * n + best.0] {
            best = (c, r);
        }
        let (cu, ru) = (c as u32, r as u32);
        let moves = [
            (Side::West, c.wrapping_sub(1), r),
            (Side::East, c + 1, r),
            (Side::South, c, r.wrapping_sub(1)),
            (Side::North, c, r + 1),
        ];
        for (side, nc, nr) in moves {
            if !maze.wall(cu, ru, side) && nc < n && nr < m && dist[nr * n + nc] == usize::MAX {
                dist[nr * n + nc] = dist[r * n + c] + 1;
                queue.push_back((nc, nr));
            }
        }
    }
    best
}

/// A maze as text: posts `o` every 4 characters, `---` and `|` walls, `S`/`G` cell marks,
/// north at the top (the format [`crate::arena::micromouse::parse_maze`] reads).
pub fn maze_text(maze: &Maze) -> String {
    let (n, m) = (maze.cols as usize, maze.rows as usize);
    let mut out = String::new();
    for line in (0..=m).rev() {
        let mut s = String::from("o");
        for c in 0..n {
            s.push_str(if maze.horizontal[line * n + c] {
                "---"
            } else {
                "   "
            });
            s.push('o');
        }
        out.push_str(&s);
        out.push('\n');
        if line == 0 {
            break;
        }
        let r = line - 1;
        let mut s = String::new();
        for v in 0..=n {
            s.push(if maze.vertical[r * (n + 1) + v] {
                '|'
            } else {
                ' '
            });
            if v < n {
                let cell = (v as u32, r as u32);
                s.push_str(if maze.starts.contains(&cell) {
                    " S "
                } else if maze.goals.contains(&cell) {
                    " G "
                } else {
                    "   "
                });
            }
        }
        out.push_str(s.trim_end());
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn the_text_reads_back_as_the_same_maze() {
        let mut rng = SimRng::new(4, super::super::STREAM);
        let text = generate(&mut rng);
        let maze = crate::arena::micromouse::parse_maze(Path::new("t.txt"), &text).expect("parses");
        assert_eq!(maze_text(&maze), text);
        assert_eq!(maze.starts, vec![(0, 0)]);
        assert_eq!(maze.goals.len(), 1);
    }
}
