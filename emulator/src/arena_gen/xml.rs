//! A [`Layout`] as CiberRato XML: the `<Lab>` file and its `<Grid>` file, written the way
//! CiberRato's own labs are (e.g. `Ciber2005_FinalLab.xml`): lengths in CiberRato units
//! ([`CIBERRATO_UNIT_M`] metres each), walls 1 unit high, the beacon 2 units high (so, as in
//! the real labs, it is seen over the walls), start directions in degrees.

use std::fmt::Write as _;

use super::{ArenaText, Layout};
use crate::arena::CIBERRATO_UNIT_M;

/// Decimal places of a coordinate in units: 4 is 0.03 mm, finer than any rule here.
const PLACES: usize = 4;

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
    let _ = writeln!(
        lab,
        "  <Beacon X=\"{}\" Y=\"{}\" Height=\"2.0\"/>",
        x(l.beacon.x),
        y(l.beacon.y)
    );
    let (c, r) = l.target;
    let _ = writeln!(
        lab,
        "  <Target X=\"{}\" Y=\"{}\" Radius=\"{}\"/>",
        x(c.x),
        y(c.y),
        fmt(units(r))
    );
    for wall in &l.walls {
        let _ = writeln!(lab, "  <Wall Height=\"1.0\">");
        for p in wall {
            let _ = writeln!(lab, "    <Corner X=\"{}\" Y=\"{}\"/>", x(p.x), y(p.y));
        }
        let _ = writeln!(lab, "  </Wall>");
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
