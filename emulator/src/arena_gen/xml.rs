//! A [`Layout`] as CiberRato XML: the `<Lab>` file and its `<Grid>` file, written the way
//! CiberRato's own labs are (e.g. `Ciber2005_FinalLab.xml`): lengths in CiberRato units
//! ([`CIBERRATO_UNIT_M`] metres each), walls 1 unit high unless the layout says (so, as in
//! the Micro-Rato labs, the 2-unit beacon is seen over them), every beacon with its target
//! area, home areas after them, `<Row>` mazes as CiberRato writes them, start directions in
//! degrees.

use std::fmt::Write as _;

use super::{ArenaText, Layout};
use crate::arena::CIBERRATO_UNIT_M;

/// Decimal places of a coordinate in units: 4 is 0.03 mm, finer than any rule here.
const PLACES: usize = 4;

/// A wall's height when the layout gives none, units: below the beacon, which is seen over it.
pub(crate) const LOW_WALL: f64 = 1.0;
/// The beacons' height, units (CiberRato's labs: 2).
pub(crate) const BEACON_HEIGHT: f64 = 2.0;

pub(crate) fn ciberrato(l: &Layout) -> ArenaText {
    let units = |m: f64| round(m / CIBERRATO_UNIT_M);
    let (w, h) = (units(l.width_m), units(l.height_m));
    // Rounding must not put a corner outside the lab the importer checks against.
    let x = |m: f64| fmt(units(m).clamp(0.0, w));
    let y = |m: f64| fmt(units(m).clamp(0.0, h));
    let mut lab = String::new();
    // Writing to a String cannot fail.
    let _ = writeln!(
        lab,
        "<Lab Name=\"{}\" Width=\"{}\" Height=\"{}\">",
        l.name,
        fmt(w),
        fmt(h)
    );
    // Beacons first, each with its target area; then the areas without a beacon (homes).
    let beaconed = std::iter::once((l.beacon, l.target.1)).chain(l.more_beacons.iter().copied());
    let mut targets = Vec::new();
    for (b, r) in beaconed {
        let _ = writeln!(
            lab,
            "  <Beacon X=\"{}\" Y=\"{}\" Height=\"{BEACON_HEIGHT:.1}\"/>",
            x(b.x),
            y(b.y),
        );
        targets.push((b, r));
    }
    // The goal's own area first: the importer's first target is the arena's goal.
    targets[0] = l.target;
    targets.extend(l.homes.iter().copied());
    for (c, r) in targets {
        let _ = writeln!(
            lab,
            "  <Target X=\"{}\" Y=\"{}\" Radius=\"{}\"/>",
            x(c.x),
            y(c.y),
            fmt(units(r))
        );
    }
    for (i, wall) in l.walls.iter().enumerate() {
        let height = l.wall_heights.get(i).copied().unwrap_or(LOW_WALL);
        let _ = writeln!(lab, "  <Wall Height=\"{height:.1}\">");
        for p in wall {
            let _ = writeln!(lab, "    <Corner X=\"{}\" Y=\"{}\"/>", x(p.x), y(p.y));
        }
        let _ = writeln!(lab, "  </Wall>");
    }
    for (pos, pattern) in &l.rows {
        let _ = writeln!(lab, "  <Row Pos=\"{pos}\" Pattern=\"{pattern}\"/>");
    }
    lab.push_str("</Lab>\n");
    let mut grid = String::from("<Grid>\n");
    for s in &l.starts {
        let _ = writeln!(
            grid,
            "  <Position X=\"{}\" Y=\"{}\" Dir=\"{:.2}\"/>",
            x(s[0]),
            y(s[1]),
            s[2].to_degrees()
        );
    }
    grid.push_str("</Grid>\n");
    ArenaText::CiberRato { lab, grid }
}

fn round(v: f64) -> f64 {
    let k = 10f64.powi(PLACES as i32);
    (v * k).round() / k
}

fn fmt(v: f64) -> String {
    format!("{v:.PLACES$}")
}
