//! `station plan` and `station segment`: planning on a map file, no robot needed.
//!
//! Layer: the binary's edge for planning (clap arguments, printing, exit codes); the work is
//! [`NavMap`] and [`Planner`]. Exit codes: 0 planned / segmented; 1 with one line on stderr
//! naming the map and the problem (a bad file, a point outside the map or in an obstacle, an
//! unreachable goal); 2 for usage errors (clap).

use std::process::ExitCode;

use anyhow::Context as _;
use clap::Args;

use station_core::plan::map::{GoalKind, MapOptions, NavMap};
use station_core::plan::report::{plan_json, plan_text, segment_json, segment_text};
use station_core::plan::solve::Planner;
use station_core::plan::NavError;

/// The map and how to grid it.
#[derive(Debug, Args, Clone, PartialEq)]
pub struct MapArgs {
    /// The map: a CiberRato lab (.xml), a micromouse maze (.txt), a ROS map (.yaml with its
    /// .pgm), an ASCII grid, a Map object (from download-map), or a built-in arena
    /// (builtin:micro-rato-99, builtin:forage, builtin:floor-grid).
    #[arg(long, short = 'm', value_name = "FILE")]
    pub map: String,
    /// Grid cell side, metres (rounded to whole mm).
    /// [default: 0.3, the paper's grid; half the pitch for micromouse mazes]
    #[arg(long, value_name = "M", value_parser = parse_cell)]
    pub cell: Option<f64>,
    /// Robot radius, metres: obstacles grow by it so the path keeps the robot clear
    /// (0: the paper's grid, the robot as a point).
    #[arg(long, value_name = "R", default_value_t = 0.0, value_parser = parse_radius)]
    pub radius: f64,
}

/// `station plan`.
#[derive(Debug, Args, Clone, PartialEq)]
pub struct PlanArgs {
    #[command(flatten)]
    pub map: MapArgs,
    /// Start point, metres in the map frame [default: the map's start marker].
    #[arg(long, value_name = "X,Y", value_parser = parse_point, allow_hyphen_values = true)]
    pub from: Option<(f64, f64)>,
    /// Goal point, metres [default: the map's goal; for a target area whose centre is an
    /// obstacle (the beacon), the free point of the area nearest its centre].
    #[arg(long, value_name = "X,Y", value_parser = parse_point, allow_hyphen_values = true)]
    pub to: Option<(f64, f64)>,
    /// Also smooth the path (reported separately; the raw region-centre path stays).
    #[arg(long)]
    pub smooth: bool,
    /// Print JSON: regions, waypoints, length_m, segment_us, search_us (and smoothed).
    #[arg(long)]
    pub json: bool,
    /// Also write the plan as a Plan object (PROTOCOL.md §12) for `station upload-plan`; its
    /// map id is that of this map as `station upload-map` sends it (same --cell, --radius).
    #[arg(long, value_name = "FILE")]
    pub out_object: Option<std::path::PathBuf>,
    /// Overwrite the --out-object file if it exists (a device, FIFO or directory is never
    /// replaced).
    #[arg(long, requires = "out_object")]
    pub force: bool,
}

/// `station segment`.
#[derive(Debug, Args, Clone, PartialEq)]
pub struct SegmentArgs {
    #[command(flatten)]
    pub map: MapArgs,
    /// Print JSON: width, height, cell_m, origin, squares [{x, y, size}] in cells.
    #[arg(long)]
    pub json: bool,
}

impl MapArgs {
    fn options(&self) -> MapOptions {
        MapOptions {
            cell_m: self.cell,
            radius_m: self.radius,
        }
    }
}

fn parse_cell(s: &str) -> Result<f64, String> {
    use station_core::plan::map::{MAX_CELL_M, MIN_CELL_M};
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && (MIN_CELL_M..=MAX_CELL_M).contains(&v) => Ok(v),
        Ok(v) => Err(format!(
            "{v} m is not a usable cell size ({MIN_CELL_M} ..= {MAX_CELL_M} m)"
        )),
        Err(_) => Err(format!("{s:?} is not a length in metres")),
    }
}

fn parse_radius(s: &str) -> Result<f64, String> {
    use station_core::plan::map::MAX_RADIUS_M;
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && (0.0..=MAX_RADIUS_M).contains(&v) => Ok(v),
        Ok(v) => Err(format!(
            "{v} m is not a usable radius (0 ..= {MAX_RADIUS_M} m)"
        )),
        Err(_) => Err(format!("{s:?} is not a length in metres")),
    }
}

/// `X,Y` in metres.
pub fn parse_point(s: &str) -> Result<(f64, f64), String> {
    let bad = || format!("{s:?} is not a point: write X,Y in metres, e.g. 1.5,0.45");
    let (x, y) = s.split_once(',').ok_or_else(bad)?;
    let num = |t: &str| t.trim().parse::<f64>().ok().filter(|v| v.is_finite());
    match (num(x), num(y)) {
        (Some(x), Some(y)) if x.abs() <= 1e6 && y.abs() <= 1e6 => Ok((x, y)),
        _ => Err(bad()),
    }
}

/// The error line: the map first (load errors already name the file and line).
fn failure(spec: &str, e: &NavError) -> anyhow::Error {
    match e {
        NavError::Load(_) => anyhow::anyhow!("{e}"),
        _ => anyhow::anyhow!("{spec}: {e}"),
    }
}

fn planner(args: &MapArgs) -> anyhow::Result<Planner> {
    let map = NavMap::load(&args.map, &args.options()).map_err(|e| failure(&args.map, &e))?;
    Planner::new(map).map_err(|e| failure(&args.map, &e))
}

/// Runs `station plan`.
pub fn plan(args: &PlanArgs) -> anyhow::Result<ExitCode> {
    // Before the map is read: an output that cannot be written is refused at once.
    if let Some(out) = &args.out_object {
        crate::output_file::check(out, args.force).context("--out-object")?;
    }
    let planner = planner(&args.map)?;
    let r = planner
        .plan(args.from, args.to, args.smooth)
        .map_err(|e| failure(&args.map.map, &e))?;
    let object = match &args.out_object {
        Some(path) => Some(crate::commands::transfer::write_plan_object(
            &planner, &r, path, args.force,
        )?),
        None => None,
    };
    if args.json {
        let mut v = plan_json(&planner, &r);
        if let (Some(o), Some(m)) = (object, v.as_object_mut()) {
            m.insert("object".into(), o);
        }
        println!("{}", crate::json_text::pretty(&v)?);
    } else {
        // The map's name comes from the arena file.
        let text = plan_text(&planner, &r, &goal_note(planner.map(), args.to, r.goal()));
        print!("{}", crate::terminal_text::printable_text(&text));
        if let Some(o) = object {
            println!(
                "plan object: {} bytes, id {}, map id {} -> {}",
                o["bytes"],
                o["id_hex"].as_str().unwrap_or(""),
                o["map_id_hex"].as_str().unwrap_or(""),
                o["path"].as_str().unwrap_or("")
            );
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// Runs `station segment`.
pub fn segment(args: &SegmentArgs) -> anyhow::Result<ExitCode> {
    let planner = planner(&args.map)?;
    if args.json {
        println!("{}", crate::json_text::pretty(&segment_json(&planner))?);
    } else {
        print!(
            "{}",
            crate::terminal_text::printable_text(&segment_text(&planner))
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// Where the goal came from, for the text report.
pub fn goal_note(map: &NavMap, to: Option<(f64, f64)>, goal: (f64, f64)) -> String {
    let Some(area) = map.goal.filter(|_| to.is_none()) else {
        return String::new();
    };
    let (cx, cy) = area.centre;
    let what = match area.kind {
        GoalKind::Target => "target",
        GoalKind::Marker => "goal marker",
    };
    if (goal.0 - cx).abs() < 5e-4 && (goal.1 - cy).abs() < 5e-4 {
        format!("  (the map's {what})")
    } else {
        format!(
            "  (the free point nearest the {what} centre ({cx:.3}, {cy:.3}), within {:.3} m: \
             that cell is not free)",
            area.radius_m
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_parse_with_signs_and_spaces_and_refuse_junk() {
        assert_eq!(parse_point("1.5,-0.25"), Ok((1.5, -0.25)));
        assert_eq!(parse_point(" -2, 3 "), Ok((-2.0, 3.0)));
        for bad in ["1.5", "a,b", "nan,1", "1,inf", "1e9,0"] {
            assert!(parse_point(bad).is_err(), "{bad}");
        }
        assert!(parse_cell("0").is_err());
        assert!(parse_radius("-0.1").is_err());
    }
}
