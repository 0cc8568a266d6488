//! What `station plan` and `station segment` print: JSON for scripts, text and ASCII pictures
//! for people.
//!
//! Layer: pure formatting of a [`Planner`] and a [`PlanResult`]; no I/O. JSON keys are a
//! contract: `plan` always has `regions` (squares in the segmentation), `waypoints` ([x, y]
//! metres, map frame: start, region centres, goal), `length_m`, `segment_us`, `search_us`,
//! and `smoothed` {`waypoints`, `length_m`} only when smoothing was asked for; `segment` has
//! `width`, `height`, `cell_m`, `origin` and `squares` [{`x`, `y`, `size`} in cells]. Other keys
//! are extras. Metres are whole millimetres (the planner's unit).
//!
//! Pictures draw the top row (largest y) first, one character per cell: `#` obstacle, `?`
//! unknown; regions as letters, neighbours never sharing one (a greedy colouring of the region
//! graph); the path picture marks the cells the raw path crosses `*`, the smoothed path `+`
//! where it leaves the raw one, the start `S` and goal `G`. Grids wider than
//! [`MAX_PICTURE_SIDE`] are not drawn. Cannot fail.

use std::collections::HashSet;

use serde_json::{json, Value};

use robot_firmware::nav::Cell;

use super::map::NavMap;
use super::solve::{PlanResult, Planner};

/// Widest grid drawn as a picture.
pub const MAX_PICTURE_SIDE: u16 = 160;
/// Pictures go side by side up to this total width.
const SIDE_BY_SIDE: usize = 100;
/// Letters the region picture cycles through.
const LETTERS: &[u8] = b"abcdefghijklmnopqrstuvwxyz";

fn mm(v: f64) -> f64 {
    (v * 1000.0).round() / 1000.0
}

fn pt((x, y): (f64, f64)) -> Value {
    json!([mm(x), mm(y)])
}

fn pts(p: &[(f64, f64)]) -> Vec<Value> {
    p.iter().copied().map(pt).collect()
}

/// The `station plan --json` object.
pub fn plan_json(planner: &Planner, r: &PlanResult) -> Value {
    let map = planner.map();
    let mut v = json!({
        "regions": planner.squares().len(),
        "waypoints": pts(&r.waypoints),
        "length_m": mm(r.length_m),
        "segment_us": planner.segment_us(),
        "search_us": r.search_us,
        "map": map.source,
        "cell_m": map.cell_m(),
        "radius_m": map.radius_m,
        "width": map.grid.width(),
        "height": map.grid.height(),
        "start": pt(r.start()),
        "goal": pt(r.goal()),
        "path_regions": r.path,
    });
    if let (Some(s), Some(obj)) = (&r.smoothed, v.as_object_mut()) {
        obj.insert(
            "smoothed".into(),
            json!({
                "waypoints": pts(&s.waypoints),
                "length_m": mm(s.length_m),
                "smooth_us": s.smooth_us,
            }),
        );
    }
    v
}

/// The `station segment --json` object.
pub fn segment_json(planner: &Planner) -> Value {
    let map = planner.map();
    let (ox, oy) = map.origin();
    let c = map.cell_m();
    let squares: Vec<Value> = planner
        .squares()
        .iter()
        .map(|s| {
            let half = f64::from(s.size) / 2.0;
            json!({
                "x": s.x, "y": s.y, "size": s.size,
                "centre_m": [mm(ox + (f64::from(s.x) + half) * c), mm(oy + (f64::from(s.y) + half) * c)],
                "size_m": mm(f64::from(s.size) * c),
            })
        })
        .collect();
    json!({
        "width": map.grid.width(),
        "height": map.grid.height(),
        "cell_m": c,
        "origin": [mm(ox), mm(oy)],
        "map": map.source,
        "radius_m": map.radius_m,
        "regions": squares.len(),
        "edges": planner.edge_count() / 2,
        "segment_us": planner.segment_us(),
        "squares": squares,
    })
}

/// The map lines of both text reports.
fn map_summary(planner: &Planner, out: &mut String) {
    let map = planner.map();
    let (ox, oy) = map.origin();
    let (free, obstacle, unknown) = map.counts();
    out.push_str(&format!("map       {} ({})\n", map.name, map.source));
    out.push_str(&format!(
        "grid      {} x {} cells of {} m, origin ({ox:.3}, {oy:.3}), robot radius {} m\n",
        map.grid.width(),
        map.grid.height(),
        map.cell_m(),
        map.radius_m
    ));
    out.push_str(&format!(
        "cells     {free} free, {obstacle} obstacle, {unknown} unknown\n"
    ));
    for n in &map.notes {
        out.push_str(&format!("note      {n}\n"));
    }
    out.push_str(&format!(
        "regions   {} squares, {} adjacencies ({} µs with the graph)\n",
        planner.squares().len(),
        planner.edge_count() / 2,
        planner.segment_us()
    ));
}

fn xy((x, y): (f64, f64)) -> String {
    format!("({x:.3}, {y:.3})")
}

/// `station plan` without `--json`.
pub fn plan_text(planner: &Planner, r: &PlanResult, goal_note: &str) -> String {
    let mut out = String::new();
    map_summary(planner, &mut out);
    out.push_str(&format!("start     {}\n", xy(r.start())));
    out.push_str(&format!("goal      {}{goal_note}\n", xy(r.goal())));
    out.push_str(&format!(
        "plan      {} regions, {} waypoints, {:.3} m (A* {} µs)\n",
        r.path.len(),
        r.waypoints.len(),
        r.length_m,
        r.search_us
    ));
    let list = |w: &[(f64, f64)]| w.iter().map(|p| xy(*p)).collect::<Vec<_>>().join(" ");
    out.push_str(&format!("waypoints {}\n", list(&r.waypoints)));
    if let Some(s) = &r.smoothed {
        out.push_str(&format!(
            "smoothed  {} waypoints, {:.3} m ({} µs)\n",
            s.waypoints.len(),
            s.length_m,
            s.smooth_us
        ));
        out.push_str(&format!("          {}\n", list(&s.waypoints)));
    }
    out.push('\n');
    out.push_str(&pictures(
        planner,
        &[
            ("regions", region_picture(planner)),
            ("path", path_picture(planner.map(), Some(r))),
        ],
    ));
    out
}

/// `station segment` without `--json`.
pub fn segment_text(planner: &Planner) -> String {
    let mut out = String::new();
    map_summary(planner, &mut out);
    let mut sizes: Vec<(u16, usize)> = Vec::new();
    for s in planner.squares() {
        match sizes.iter_mut().find(|(k, _)| *k == s.size) {
            Some((_, n)) => *n += 1,
            None => sizes.push((s.size, 1)),
        }
    }
    sizes.sort_unstable_by_key(|s| std::cmp::Reverse(s.0));
    let list: Vec<String> = sizes.iter().map(|(s, n)| format!("{n} of {s}")).collect();
    out.push_str(&format!("sizes     {} (cells a side)\n\n", list.join(", ")));
    out.push_str(&pictures(
        planner,
        &[
            ("regions", region_picture(planner)),
            ("occupancy", path_picture(planner.map(), None)),
        ],
    ));
    out
}

/// Titled pictures side by side when they fit, else one after another, with a legend.
fn pictures(planner: &Planner, pics: &[(&str, Vec<String>)]) -> String {
    let w = planner.map().grid.width();
    if w > MAX_PICTURE_SIDE {
        return format!("(a {w}-cell-wide grid is too wide to draw; use --json)\n");
    }
    let w = usize::from(w);
    let mut out = String::new();
    if pics.len() * (w + 2) <= SIDE_BY_SIDE {
        let titles: Vec<String> = pics.iter().map(|(t, _)| format!("{t:<w$}")).collect();
        out.push_str(titles.join("  ").trim_end());
        out.push('\n');
        let rows = pics.first().map_or(0, |(_, p)| p.len());
        for i in 0..rows {
            let line: Vec<&str> = pics
                .iter()
                .map(|(_, p)| p.get(i).map_or("", String::as_str))
                .collect();
            out.push_str(&line.join("  "));
            out.push('\n');
        }
    } else {
        for (t, p) in pics {
            out.push_str(t);
            out.push('\n');
            for l in p {
                out.push_str(l);
                out.push('\n');
            }
        }
    }
    out.push_str(
        "legend: # obstacle  ? unknown  . free  letters: regions  * raw path  + smoothed  S start  G goal\n",
    );
    out
}

/// Rows of cells, top row first, `f(x, y)` per cell.
fn rows(map: &NavMap, f: impl Fn(usize, usize) -> char) -> Vec<String> {
    let (w, h) = (
        usize::from(map.grid.width()),
        usize::from(map.grid.height()),
    );
    (0..h)
        .rev()
        .map(|y| (0..w).map(|x| f(x, y)).collect())
        .collect()
}

/// Letter per region, adjacent regions different (greedy, in id order).
pub fn region_letters(planner: &Planner) -> Vec<u8> {
    let n = planner.squares().len();
    let mut colour = vec![u8::MAX; n];
    for id in 0..n {
        let used: Vec<u8> = planner
            .neighbours(id as u32)
            .filter_map(|v| colour.get(v as usize).copied())
            .collect();
        let pick = (0u8..).find(|c| !used.contains(c)).unwrap_or(0);
        if let Some(slot) = colour.get_mut(id) {
            *slot = pick;
        }
    }
    colour
}

fn region_picture(planner: &Planner) -> Vec<String> {
    let map = planner.map();
    let letters = region_letters(planner);
    rows(map, |x, y| match map.grid.get(x, y) {
        Cell::Obstacle => '#',
        Cell::Unknown => '?',
        Cell::Free => planner
            .region_at(x as i32, y as i32)
            .and_then(|id| letters.get(id as usize))
            .map_or('.', |&c| {
                char::from(
                    LETTERS
                        .get(usize::from(c) % LETTERS.len())
                        .copied()
                        .unwrap_or(b'.'),
                )
            }),
    })
}

/// Cells a polyline crosses (sampled every eighth of a cell).
pub fn cells_on(map: &NavMap, points: &[(f64, f64)]) -> Vec<(u16, u16)> {
    let step = map.cell_m() / 8.0;
    let mut out = Vec::new();
    for w in points.windows(2) {
        let (a, b) = (w[0], w[1]);
        let n = ((b.0 - a.0).hypot(b.1 - a.1) / step).ceil().max(1.0) as usize;
        for i in 0..=n {
            let t = i as f64 / n as f64;
            let p = (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t);
            if let Some(c) = map.cell_of(p) {
                if out.last() != Some(&c) {
                    out.push(c);
                }
            }
        }
    }
    out
}

fn path_picture(map: &NavMap, r: Option<&PlanResult>) -> Vec<String> {
    let set = |p: &[(f64, f64)]| cells_on(map, p).into_iter().collect::<HashSet<_>>();
    let raw = r.map(|r| set(&r.waypoints)).unwrap_or_default();
    let smooth = r
        .and_then(|r| r.smoothed.as_ref())
        .map(|s| set(&s.waypoints))
        .unwrap_or_default();
    let start = r.and_then(|r| map.cell_of(r.start()));
    let goal = r.and_then(|r| map.cell_of(r.goal()));
    rows(map, |x, y| {
        let c = (x as u16, y as u16);
        if Some(c) == start {
            'S'
        } else if Some(c) == goal {
            'G'
        } else if raw.contains(&c) {
            '*'
        } else if smooth.contains(&c) {
            '+'
        } else {
            match map.grid.get(x, y) {
                Cell::Obstacle => '#',
                Cell::Unknown => '?',
                Cell::Free => '.',
            }
        }
    })
}
